"""Do all vectorizers agree? ``gymnasium.make_vec("ActiveVision-v0")`` in its three modes
(``sync``, ``async``, ``vector_entry_point``) against N single envs stepped by hand with
Gymnasium's NEXT_STEP autoreset: same seeds, same random actions, 1,000 steps. Counts the
frames and info entries that are not byte-identical (dtypes included). Last line: JSON."""

from __future__ import annotations

import json
import time
from typing import Any

import gymnasium as gym
import numpy as np

import activevision.envs  # noqa: F401
from activevision.cli.args import ArgumentParser, positive_int

N, SEED = 4, 0
MODES = ("sync", "async", "vector_entry_point")

#: (observations, rewards, terminated, truncated, infos) of one reset or step of N envs
Batch = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]


def vector_rollout(mode: str, actions: np.ndarray) -> list[Batch]:
    envs = gym.make_vec("ActiveVision-v0", num_envs=N, vectorization_mode=mode)
    obs, infos = envs.reset(seed=SEED)
    out = [(obs, np.zeros(N), np.zeros(N, bool), np.zeros(N, bool), infos)]
    out += [envs.step(a) for a in actions]
    envs.close()
    return out


def singles_rollout(actions: np.ndarray) -> list[Batch]:
    envs = [gym.make("ActiveVision-v0") for _ in range(N)]
    steps = [(*env.reset(seed=SEED + i), 0.0, False, False) for i, env in enumerate(envs)]
    out = [stack(steps)]
    for row in actions:
        # NEXT_STEP autoreset: the step after an episode ends resets, ignoring the action
        steps = [
            (*env.reset(), 0.0, False, False) if s[3] or s[4] else _reorder(env.step(int(a)))
            for env, a, s in zip(envs, row, steps, strict=True)
        ]
        out.append(stack(steps))
    return out


def _reorder(step: tuple) -> tuple:
    """``(obs, reward, terminated, truncated, info)`` as ``(obs, info, reward, ...)``."""
    obs, reward, terminated, truncated, info = step
    return obs, info, reward, terminated, truncated


def stack(steps: list[tuple]) -> Batch:
    obs, infos, reward, terminated, truncated = zip(*steps, strict=True)
    batch: dict[str, Any] = {key: np.array([info[key] for info in infos]) for key in infos[0]}
    batch.update({f"_{key}": np.ones(N, bool) for key in infos[0]})
    return np.stack(obs), np.array(reward), np.array(terminated), np.array(truncated), batch


def same(a: Any, b: Any) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def compare(got: list[Batch], want: list[Batch]) -> dict[str, Any]:
    """Mismatch counts: frames (per sub-env and step), steps with any other field
    differing, and the info keys that ever differ."""
    frames = sum(
        not same(g[0][i], w[0][i]) for g, w in zip(got, want, strict=True) for i in range(N)
    )
    others = sum(
        not all(same(a, b) for a, b in zip(g[1:4], w[1:4], strict=True))
        for g, w in zip(got, want, strict=True)
    )
    keys = sorted(
        {
            k
            for g, w in zip(got, want, strict=True)
            for k in w[4] | g[4]
            if k not in g[4] or k not in w[4] or not same(g[4][k], w[4][k])
        }
    )
    return {
        "frames_differing": frames,
        "steps_rewards_dones_differing": others,
        "info_keys_differing": keys,
    }


def main() -> None:
    parser = ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=positive_int, default=1000, help="steps of every rollout")
    steps = parser.parse_args().steps
    actions = np.random.default_rng(1).integers(0, 9, (steps, N))
    singles_rollout(actions[:1])  # compile / load the caches outside the timings
    vector_rollout("vector_entry_point", actions[:1])
    t0 = time.perf_counter()
    reference = singles_rollout(actions)
    singles_s = time.perf_counter() - t0
    print(f"{N} single envs, {steps} steps: {singles_s:.1f} s")
    episodes = int(sum((b[2] | b[3]).sum() for b in reference))
    print(f"  {episodes} episodes ended (terminated or truncated)")
    results: dict[str, Any] = {}
    for mode in MODES:
        t0 = time.perf_counter()
        results[mode] = compare(vector_rollout(mode, actions), reference)
        seconds = time.perf_counter() - t0
        r = results[mode]
        r["time_vs_singles"] = round(seconds / singles_s, 3)
        print(
            f"make_vec {mode:>18}: {seconds:5.1f} s ({seconds / singles_s:.2f}x the singles');"
            f" frames differing "
            f"{r['frames_differing']}/{N * (steps + 1)}, steps with rewards/dones differing "
            f"{r['steps_rewards_dones_differing']}, info keys differing "
            f"{r['info_keys_differing'] or 'none'}"
        )
    identical = all(
        r["frames_differing"] == r["steps_rewards_dones_differing"] == 0
        and not r["info_keys_differing"]
        for r in results.values()
    )
    print("all byte-identical" if identical else "NOT all byte-identical")
    print(
        json.dumps(
            {
                "num_envs": N,
                "steps": steps,
                "episodes_ended": episodes,
                "byte_identical": identical,
                **results,
            }
        )
    )


if __name__ == "__main__":
    main()
