"""Benchmark: best-viewpoint searches (Algorithm 1) per second on the KidSize field.

Compiled search (numba) against the straightforward loop (Python over candidates and
landmarks, NumPy UKF, geometry visibility) in the same run, on random realistic episode
starts: robot on the field, any heading, ball 1-3 m away in front (inside the horizontal
field of view) and on the field. Times are the best of ``--repeats`` passes (other jobs may
share the machine). The last line printed is a JSON summary.

    python bench/viewpoint.py [--starts 512] [--loop-starts 40] [--repeats 5] [--seed 0]
"""

from __future__ import annotations

import json
import os
import platform
import time

import numpy as np

from activevision.cli.args import ArgumentParser, int_in, positive_int, seed
from activevision.geometry import CameraConfig, FieldSpec, field_landmarks, visible_landmarks
from activevision.localisation import (
    DEFAULT_UKF,
    ViewpointGrid,
    best_viewpoint,
    best_viewpoint_loop,
    best_viewpoints,
)


def random_starts(rng: np.random.Generator, n: int, field: FieldSpec, cam: CameraConfig):
    """``(means (n, 3), balls (n, 2))``: robots on the field, balls 1-3 m in front."""
    means, balls = [], []
    while len(means) < n:
        mean = np.array(
            [
                rng.uniform(-field.half_length, field.half_length),
                rng.uniform(-field.half_width, field.half_width),
                rng.uniform(-np.pi, np.pi),
            ]
        )
        d = rng.uniform(1.0, 3.0)
        a = mean[2] + rng.uniform(-cam.hfov / 2, cam.hfov / 2)
        ball = mean[:2] + d * np.array([np.cos(a), np.sin(a)])
        if abs(ball[0]) <= field.half_length and abs(ball[1]) <= field.half_width:
            means.append(mean)
            balls.append(ball)
    return np.array(means), np.array(balls)


def _best_time(fn, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def main() -> None:
    parser = ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=positive_int, default=512)
    parser.add_argument("--loop-starts", type=positive_int, default=40)
    parser.add_argument("--batch", type=positive_int, default=64, help="at most --starts")
    parser.add_argument(
        "--repeats", type=int_in(2, 10**4), default=5, help="the first of them compiles"
    )
    parser.add_argument("--seed", type=seed, default=0)
    args = parser.parse_args()
    if args.batch > args.starts:
        parser.error(f"--batch {args.batch} is more than --starts {args.starts}")

    field, cam, grid, ukf = FieldSpec(), CameraConfig(), ViewpointGrid(), DEFAULT_UKF
    landmarks = field_landmarks(field)
    cov = ukf.initial_cov
    means, balls = random_starts(np.random.default_rng(args.seed), args.starts, field, cam)
    t0 = time.perf_counter()
    best_viewpoint(means[0], cov, balls[0], landmarks, cam)  # compile or load the cache
    warmup_s = time.perf_counter() - t0

    def fast():
        for m, b in zip(means, balls, strict=True):
            best_viewpoint(m, cov, b, landmarks, cam, grid, ukf)

    def loop():
        for m, b in zip(means[: args.loop_starts], balls[: args.loop_starts], strict=True):
            best_viewpoint_loop(m, cov, b, landmarks, cam, grid, ukf)

    nb = args.batch
    batches = [(means[i : i + nb], balls[i : i + nb]) for i in range(0, len(means) - nb + 1, nb)]

    def batched(**options):
        for m, b in batches:
            best_viewpoints(m, cov, b, landmarks, cam, grid, ukf, **options)

    def goal_only():  # what the environment runs at its resets
        batched(parallel=True, ball_views_only=True)

    poses40 = np.broadcast_to(means[0], (len(grid), 3))

    def visibility_numpy():
        for _ in range(50):
            visible_landmarks(landmarks, poses40, grid.pans, grid.tilts, cam)

    fast_ms = _best_time(fast, args.repeats) / len(means) * 1e3
    loop_ms = _best_time(loop, max(1, args.repeats // 2)) / args.loop_starts * 1e3
    batch_ms = _best_time(batched, args.repeats) / (len(batches) * nb) * 1e3
    goal_ms = _best_time(goal_only, args.repeats) / (len(batches) * nb) * 1e3
    vis_ms = _best_time(visibility_numpy, args.repeats) / 50 * 1e3

    worst, same_goal = 0.0, 0
    for m, b in zip(means[: args.loop_starts], balls[: args.loop_starts], strict=True):
        f = best_viewpoint(m, cov, b, landmarks, cam, grid, ukf)
        s = best_viewpoint_loop(m, cov, b, landmarks, cam, grid, ukf)
        worst = max(worst, float(np.abs(f.entropies - s.entropies).max()))
        same_goal += int(f.index == s.index)
    batch = best_viewpoints(means, cov, balls, landmarks, cam, grid, ukf)

    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cpus, "
        f"load average {os.getloadavg()[0]:.2f}; numba warm-up {warmup_s:.2f} s"
    )
    print(f"straightforward loop : {loop_ms:8.3f} ms/search  ({args.loop_starts} starts)")
    print(
        f"compiled, one start  : {fast_ms:8.3f} ms/search  ({1e3 / fast_ms:,.0f}/s, "
        f"{len(means)} starts)"
    )
    print(f"compiled, batch {nb:<4} : {batch_ms:8.3f} ms/start   ({1e3 / batch_ms:,.0f}/s)")
    print(
        f"  threaded, goal only : {goal_ms:8.3f} ms/start   ({1e3 / goal_ms:,.0f}/s; filter only "
        "for candidates showing the ball, as the environment's resets)"
    )
    print(f"numpy visibility alone (40 cameras, geometry.visible_landmarks): {vis_ms:.3f} ms")
    print(
        f"speed-up vs loop: {loop_ms / fast_ms:.0f}x; max |dH| fast vs loop {worst:.1e}; "
        f"same goal {same_goal}/{args.loop_starts}; goal found for "
        f"{batch.ok.mean():.1%} of starts; mean landmarks in goal view "
        f"{batch.visible[np.arange(len(batch)), np.maximum(batch.index, 0)].sum(1).mean():.1f}"
    )
    print(
        json.dumps(
            {
                "search_ms": round(fast_ms, 4),
                "searches_per_s": round(1e3 / fast_ms),
                "loop_ms": round(loop_ms, 3),
                "speedup_vs_loop": round(loop_ms / fast_ms, 1),
                f"batched_ms_per_start_n{nb}": round(batch_ms, 4),
                f"env_goal_search_ms_per_start_n{nb}": round(goal_ms, 4),
                "numpy_visibility_40_cameras_ms": round(vis_ms, 3),
                "max_abs_entropy_diff_vs_loop": worst,
                "starts": len(means),
                "load_average": round(os.getloadavg()[0], 2),
            }
        )
    )


if __name__ == "__main__":
    main()
