"""Environment throughput: single ActiveVision-v0 steps/s (resets included, each with its
best-viewpoint search) and the native vector env at N = 1, 16, 64, against the paper's
simulator pace (one head action per 320 ms in Webots). Last line: JSON."""

from __future__ import annotations

import json
import time

import gymnasium as gym
import numpy as np

import activevision.envs  # noqa: F401

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
    single_env_steps_per_s(300)  # compile / load numba caches
    single, reset_fraction = max(single_env_steps_per_s() for _ in range(3))
    print(
        f"single env: {single:,.0f} steps/s (resets in {reset_fraction:.0%} of steps), "
        f"{single * PAPER_STEP_S:,.0f}x the paper's simulator"
    )
    batched = {}
    for n, batches in ((1, 3000), (16, 600), (64, 300)):
        batched[n] = max(vector_env_steps_per_s(n, batches) for _ in range(3))
        print(
            f"vector env N={n:3d}: {batched[n]:,.0f} steps/s, "
            f"{batched[n] * PAPER_STEP_S:,.0f}x the paper's simulator"
        )
    print(
        json.dumps(
            {
                "single_env_steps_per_s": round(single, 1),
                "batched_env_steps_per_s": round(batched[64], 1),
                "batched_env_steps_per_s_n1": round(batched[1], 1),
                "batched_env_steps_per_s_n16": round(batched[16], 1),
                "speedup_vs_paper_simulator": round(batched[64] * PAPER_STEP_S, 1),
            }
        )
    )


if __name__ == "__main__":
    main()
