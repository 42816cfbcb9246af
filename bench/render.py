"""Benchmark: frames/s of the fast renderer vs the straightforward NumPy reference.

Renders random realistic camera states (robot on the field, head within its limits, ball
1-3 m ahead in roughly the viewing direction). Prints a table, then one JSON line.

    python bench/render.py [--seconds 2] [--reference-frames 200]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time

import numba
import numpy as np

from activevision.geometry.camera import CameraConfig
from activevision.rendering import Renderer
from activevision.rendering.reference import render_reference

#: The paper's simulator pace: one image per head command of 320 ms.
PAPER_SECONDS_PER_IMAGE = 0.320


def random_states(n: int, rng: np.random.Generator, camera: CameraConfig):
    """``(pose, pan, tilt, ball_xy)`` of ``n`` random realistic camera states."""
    pose = np.stack(
        [rng.uniform(-4.5, 4.5, n), rng.uniform(-3.0, 3.0, n), rng.uniform(-np.pi, np.pi, n)],
        axis=1,
    )
    pan = rng.uniform(camera.pan_min, camera.pan_max, n)
    tilt = rng.uniform(camera.tilt_min, camera.tilt_max, n)
    bearing = pose[:, 2] + pan + rng.uniform(-0.4, 0.4, n)
    distance = rng.uniform(1.0, 3.0, n)
    ball = pose[:, :2] + distance[:, None] * np.stack([np.cos(bearing), np.sin(bearing)], 1)
    return pose, pan, tilt, ball


def time_calls(fn, seconds: float, min_calls: int = 3) -> float:
    """Best-of-chunks seconds per call of ``fn`` over about ``seconds`` of wall time."""
    best = np.inf
    calls = 0
    start = time.perf_counter()
    while calls < min_calls or time.perf_counter() - start < seconds:
        t0 = time.perf_counter()
        for _ in range(10):
            fn()
        best = min(best, (time.perf_counter() - t0) / 10)
        calls += 10
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=2.0, help="time per measurement")
    parser.add_argument("--reference-frames", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    camera = CameraConfig()
    renderer = Renderer(camera=camera)
    rng = np.random.default_rng(args.seed)
    pool = 4096
    pose, pan, tilt, ball = random_states(pool, rng, camera)

    t0 = time.perf_counter()
    renderer.render(pose[:2], pan[:2], tilt[:2], ball[:2])  # compile or load the cache
    warmup_s = time.perf_counter() - t0

    # Single frame: cycle through different states.
    counter = [0]

    def single() -> None:
        k = counter[0] = (counter[0] + 1) % pool
        renderer.render(pose[k], pan[k], tilt[k], ball[k])

    single_s = time_calls(single, args.seconds)
    results = {"single_frame_ms": single_s * 1e3, "single_frames_per_s": 1.0 / single_s}
    print(f"fast renderer, single frame : {single_s * 1e3:8.4f} ms  ({1 / single_s:9.0f} frames/s)")

    batched = {}
    for n in (16, 64, 256):
        out = np.empty((n, camera.height, camera.width), dtype=np.uint8)
        starts = [0]

        def batch(n=n, out=out) -> None:
            s = starts[0] = (starts[0] + n) % (pool - n)
            renderer.render(pose[s : s + n], pan[s : s + n], tilt[s : s + n],
                            ball[s : s + n], out=out)

        per_call = time_calls(batch, args.seconds)
        batched[n] = n / per_call
        print(f"fast renderer, batch N={n:<4d}: {batched[n]:9.0f} frames/s "
              f"({per_call / n * 1e6:6.2f} us/frame)")

    m = args.reference_frames
    t0 = time.perf_counter()
    render_reference(pose[:m], pan[:m], tilt[:m])
    reference_fps = m / (time.perf_counter() - t0)
    print(f"numpy reference (centre-sampled, no AA, no goals/ball): {reference_fps:9.0f} frames/s")

    speedup = batched[64] / reference_fps
    paper = batched[64] * PAPER_SECONDS_PER_IMAGE
    print(f"speed-up over the reference (N=64): {speedup:.1f}x")
    print(f"speed-up over the paper's simulator pace (1 image / 320 ms): {paper:,.0f}x")
    results.update(
        batched_frames_per_s=batched[64],
        batched_frames_per_s_by_n={str(k): v for k, v in batched.items()},
        reference_frames_per_s=reference_fps,
        speedup_vs_reference=speedup,
        speedup_vs_paper_simulator=paper,
        warmup_s=warmup_s,
        threads=numba.get_num_threads(),
        threading_layer=numba.threading_layer(),
        cpu_count=os.cpu_count(),
        machine=platform.machine(),
    )
    print(json.dumps(results))


if __name__ == "__main__":
    main()
