"""Environment throughput: single ActiveVision-v0 steps/s (resets included, each with its
best-viewpoint search) and the native vector env at N = 1, 16, 64, against the paper's
simulator pace (one head action per 320 ms in Webots); the vector env's speed-up over the
single env measured in the same run is the reference. Last line: JSON.

    python bench/env.py [--rounds 3] [--scale 1]
"""

from __future__ import annotations

import json
import time

import gymnasium as gym
import numpy as np

import activevision.envs  # noqa: F401
from activevision.cli.args import ArgumentParser, positive_float, positive_int

PAPER_STEP_S = 0.320


def single_env_steps_per_s(steps: int = 6000) -> tuple[float, float]:
    env = gym.make("ActiveVision-v0")
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    actions = rng.integers(0, 9, steps)
    resets = 0
    t0 = time.perf_counter()
    for a in actions:
        _, _, term, trunc, _ = env.step(int(a))
        if term or trunc:
            env.reset()
            resets += 1
    dt = time.perf_counter() - t0
    return steps / dt, resets / steps


def vector_env_steps_per_s(n: int, batches: int) -> float:
    envs = gym.make_vec("ActiveVision-v0", num_envs=n, vectorization_mode="vector_entry_point")
    envs.reset(seed=0)
    actions = np.random.default_rng(1).integers(0, 9, (batches, n))
    envs.step(actions[0])  # warm-up
    t0 = time.perf_counter()
    for a in actions:
        envs.step(a)
    return n * batches / (time.perf_counter() - t0)


def main() -> None:
    parser = ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=positive_int, default=3, help="best of this many")
    parser.add_argument(
        "--scale", type=positive_float, default=1.0, help="steps per measurement, x the default"
    )
    args = parser.parse_args()
    rounds = args.rounds

    def scaled(steps: int) -> int:
        return max(2, round(steps * args.scale))

    single_env_steps_per_s(300)  # compile / load numba caches
    single, reset_fraction = max(single_env_steps_per_s(scaled(6000)) for _ in range(rounds))
    print(
        f"single env: {single:,.0f} steps/s (resets in {reset_fraction:.0%} of steps), "
        f"{single * PAPER_STEP_S:,.0f}x the paper's simulator"
    )
    batched = {}
    for n, batches in ((1, 3000), (16, 600), (64, 300)):
        batched[n] = max(vector_env_steps_per_s(n, scaled(batches)) for _ in range(rounds))
        print(
            f"vector env N={n:3d}: {batched[n]:,.0f} steps/s, {batched[n] / single:.2f}x the"
            f" single env, {batched[n] * PAPER_STEP_S:,.0f}x the paper's simulator"
        )
    print(
        json.dumps(
            {
                "single_env_steps_per_s": round(single, 1),
                "batched_env_steps_per_s": round(batched[64], 1),
                "batched_env_steps_per_s_n1": round(batched[1], 1),
                "batched_env_steps_per_s_n16": round(batched[16], 1),
                "batched_vs_single_env": round(batched[64] / single, 2),
                "speedup_vs_paper_simulator": round(batched[64] * PAPER_STEP_S, 1),
            }
        )
    )


if __name__ == "__main__":
    main()
