"""Match env throughput: ``ActiveVisionMatch-v0``'s native vector env (N = 64: walking,
ball, rendering, detection and a UKF update every tick) against the episodic
``ActiveVision-v0`` vector env at the same N, measured alternately in the same run; the
ratio is the figure (issue: >= 0.40). Also the single match env, and the vector env with
four other robots walking (occlusion tested for every landmark every tick, the ball
bouncing off them). Last line: JSON.

    python bench/match.py [--rounds 3] [--batches 200]
"""

from __future__ import annotations

import json
import time

import gymnasium as gym
import numpy as np

import activevision.envs  # noqa: F401  (registers both envs)
from activevision.cli.args import ArgumentParser, positive_int
from activevision.envs.match.config import MatchConfig, OthersConfig
from activevision.envs.robots import RobotsConfig

N = 64


#: four other robots walking at 0.2 m/s
ROBOTS = MatchConfig(robots=RobotsConfig(count=(4, 4)), others=OthersConfig(speed=0.2))


def vector_steps_per_s(env_id: str, n: int, batches: int, **kwargs) -> float:
    envs = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    envs.reset(seed=0)
    actions = np.random.default_rng(1).integers(0, 9, (batches, n))
    envs.step(actions[0])  # warm-up
    t0 = time.perf_counter()
    for a in actions:
        envs.step(a)
    rate = n * batches / (time.perf_counter() - t0)
    envs.close()
    return rate


def single_match_ticks_per_s(ticks: int = 2000) -> float:
    env = gym.make("ActiveVisionMatch-v0")
    env.reset(seed=0)
    actions = np.random.default_rng(0).integers(0, 9, ticks)
    t0 = time.perf_counter()
    for a in actions:
        env.step(int(a))
    return ticks / (time.perf_counter() - t0)


def main() -> None:
    parser = ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=positive_int, default=3, help="alternating rounds")
    parser.add_argument("--batches", type=positive_int, default=200, help="N-env steps a round")
    args = parser.parse_args()
    for env_id in ("ActiveVision-v0", "ActiveVisionMatch-v0"):  # compile / load the caches
        vector_steps_per_s(env_id, N, 5)
    episodic, match = [], []
    for _ in range(args.rounds):  # alternate, so a slow minute hits both
        episodic.append(vector_steps_per_s("ActiveVision-v0", N, args.batches))
        match.append(vector_steps_per_s("ActiveVisionMatch-v0", N, args.batches))
    best_episodic, best_match = max(episodic), max(match)
    ratio = best_match / best_episodic
    single = max(single_match_ticks_per_s(10 * args.batches) for _ in range(2))
    robots = max(
        vector_steps_per_s("ActiveVisionMatch-v0", N, args.batches, config=ROBOTS) for _ in range(2)
    )
    print(f"episodic vector env N={N}: {best_episodic:,.0f} steps/s")
    print(
        f"match vector env    N={N}: {best_match:,.0f} ticks/s"
        f"  ({ratio:.2f} of episodic; target >= 0.40)"
    )
    print(f"single match env: {single:,.0f} ticks/s")
    print(
        f"match vector env    N={N}, 4 robots walking: {robots:,.0f} ticks/s"
        f"  ({robots / best_match:.2f} of the empty field's)"
    )
    print(
        json.dumps(
            {
                "episodic_vector_steps_per_s": round(best_episodic, 1),
                "match_vector_ticks_per_s": round(best_match, 1),
                "match_vs_episodic": round(ratio, 3),
                "single_match_ticks_per_s": round(single, 1),
                "match_vector_4_robots_ticks_per_s": round(robots, 1),
            }
        )
    )


if __name__ == "__main__":
    main()
