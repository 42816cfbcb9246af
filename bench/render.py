"""Benchmark: frames/s of the fast renderer vs the straightforward NumPy reference.

Renders random realistic camera states (robot on the field, head within its limits, ball
1-3 m ahead in roughly the viewing direction), clean and in a randomised world (every
appearance factor on at its robust range, 4 other robots), and prints the randomised
world's speed as a ratio of the clean one's measured in the same run. Every figure is the
best of several timed chunks over several rounds (the machine's capability; medians are
printed too, and differ when other processes compete for the cores). ``--factors`` also
times each appearance factor alone (the time it adds as a share of a clean frame's), and the
factors of each of the two passes together (the row pass's: lighting, textures, lines, hall,
mount; the finish pass's: blur, noise, tone curve). ``--floor`` times two of the finish pass's
factors alone, written here as bare loops (:func:`floor_costs`), against the time the 0.60
target leaves for all of them. Prints a table, then one JSON line.

    python bench/render.py [--seconds 1] [--rounds 3] [--reference-frames 50] [--factors]
                           [--floor]
"""

from __future__ import annotations

import json
import os
import platform
import time

import numba
import numpy as np
from numba import njit

from activevision.cli.args import ArgumentParser, positive_float, positive_int, seed
from activevision.geometry.camera import CameraConfig
from activevision.geometry.occlusion import robot_cylinders
from activevision.rendering import Renderer
from activevision.rendering.appearance import (
    FACTORS,
    LOOK,
    AppearanceConfig,
    draw_looks,
    tone_curves,
)
from activevision.rendering.kernels.looks import _filter_column_by, _filter_rows_by
from activevision.rendering.reference import render_reference

#: The paper's simulator pace: one image per head command of 320 ms.
PAPER_SECONDS_PER_IMAGE = 0.320
#: The factors the finish pass applies to whole frames (kernels.looks.finish_frame); the
#: rest act in the row pass.
FINISH = ("read_noise", "shot_noise", "defocus", "motion_blur", "gamma")
ROW_PASS = "row-pass factors together"
FINISH_PASS = "finish-pass factors together"


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


def time_calls(fn, seconds: float, chunk: int = 5) -> tuple[float, float]:
    """Seconds per call of ``fn``: ``(best, median)`` over chunks of ``chunk`` calls run for
    about ``seconds`` of wall time. The best chunk is the machine's capability when other
    processes compete for the cores; the median shows how much they did."""
    chunks = []
    start = time.perf_counter()
    while len(chunks) < 3 or time.perf_counter() - start < seconds:
        t0 = time.perf_counter()
        for _ in range(chunk):
            fn()
        chunks.append((time.perf_counter() - t0) / chunk)
    return float(np.min(chunks)), float(np.median(chunks))


def frame_looks(
    config: AppearanceConfig, pool: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """``pool`` looks drawn from ``config`` with a 3-degree head move per frame (or none) on
    each axis, and their tone curves."""
    looks = np.stack([draw_looks(config, rng) for _ in range(pool)])
    looks[:, LOOK["move_pan"]] = np.radians(3.0) * rng.choice([-1.0, 0.0, 1.0], pool)
    looks[:, LOOK["move_tilt"]] = np.radians(3.0) * rng.choice([-1.0, 0.0, 1.0], pool)
    looks[:, LOOK["frame"]] = rng.integers(0, 20, pool)
    return looks, tone_curves(looks)


def factor_costs(renderer, pose, pan, tilt, ball, rng, args) -> dict[str, float]:
    """Batched (N = 64) time per frame that each appearance factor adds alone, at its robust
    range, as a share of a clean frame's time measured in the same rounds: where the
    randomised world's time goes."""
    full = AppearanceConfig.randomised()
    pool = len(pose)
    out = np.empty((64, *renderer.image_shape), dtype=np.uint8)
    counter = [0]

    def batch_of(looks, tone):
        def batch() -> None:
            k = counter[0] = (counter[0] + 64) % (pool - 64)
            s = slice(k, k + 64)
            renderer.render(
                pose[s], pan[s], tilt[s], ball[s], out=out, looks=looks[s], tone=tone[s]
            )

        return batch

    def clean() -> None:
        k = counter[0] = (counter[0] + 64) % (pool - 64)
        s = slice(k, k + 64)
        renderer.render(pose[s], pan[s], tilt[s], ball[s], out=out)

    calls = {"clean": clean}
    for name in FACTORS:
        if name == "stripe_width":  # the stripes' width, not a factor of its own
            continue
        config = AppearanceConfig().replace(**{name: getattr(full, name)})
        if name == "stripes":
            config = config.replace(stripe_width=full.stripe_width)
        calls[name] = batch_of(*frame_looks(config, pool, rng))
    # the two passes' factors together (what a pass costs once it runs at all)
    neutral = AppearanceConfig()
    finish_only = full.replace(**{n: getattr(neutral, n) for n in FACTORS if n not in FINISH})
    row_only = full.replace(**{n: getattr(neutral, n) for n in FINISH})
    calls[ROW_PASS] = batch_of(*frame_looks(row_only, pool, rng))
    calls[FINISH_PASS] = batch_of(*frame_looks(finish_only, pool, rng))
    for fn in calls.values():
        fn()  # compile
    best = dict.fromkeys(calls, np.inf)
    for _ in range(args.rounds):
        for name, fn in calls.items():
            best[name] = min(best[name], time_calls(fn, args.seconds / 4)[0])
    return {
        name: (t - best["clean"]) / best["clean"] for name, t in best.items() if name != "clean"
    }


def print_factor_costs(shares: dict[str, float]) -> None:
    """:func:`factor_costs`' shares, the largest first, then the two passes'."""
    print("time each appearance factor adds alone, as a share of a clean frame (N=64):")
    passes = (ROW_PASS, FINISH_PASS)
    for name, share in sorted(shares.items(), key=lambda kv: -kv[1]):
        if name not in passes:
            print(f"  {name:15s} {share:+6.2f}")
    for name in passes:
        print(f"  {name}: {shares[name]:+.2f}")


@njit(fastmath=True, nogil=True)
def _noise_and_tone(images, noise, tone, read2, shot) -> None:
    """Sensor noise and the tone curve and nothing else, as the renderer's finish pass splits
    them (the arithmetic in one vectorised loop a row, the table reads in a plain one)."""
    height, width = images.shape[1], images.shape[2]
    levels = np.empty(width, np.int32)
    r2, sh = np.float32(read2), np.float32(shot)
    zero, top, half = np.float32(0.0), np.float32(255.0), np.float32(0.5)
    for n in range(images.shape[0]):
        start = (n * 7919) % (noise.shape[0] - height * width)
        for j in range(height):
            first = start + j * width
            for i in range(width):
                x = np.float32(images[n, j, i])
                y = x + np.sqrt(r2 + sh * x) * noise[first + i] + half
                levels[i] = np.int32(zero if y < zero else (top if y > top else y))
            for i in range(width):
                images[n, j, i] = tone[levels[i]]


@njit(fastmath=True, nogil=True)
def _blur(images, taps, rows) -> None:
    """A separable blur of ``len(taps)`` taps along each axis and nothing else (the defocus
    at the robust range's widest sigma, 1.2 px, has 7): the renderer's own blur kernels
    (``taps`` a tuple, ``rows``: (H + len(taps) - 1, W) float32), rounded to grey levels."""
    height, width = images.shape[1], images.shape[2]
    row = np.empty(width, np.float32)
    for m in range(images.shape[0]):
        _filter_rows_by(images[m], rows, taps)
        for j in range(height):
            _filter_column_by(rows, taps, row, j)
            for i in range(width):
                images[m, j, i] = np.uint8(row[i] + np.float32(0.5))


def floor_costs(pose, pan, tilt, ball, camera: CameraConfig, args) -> dict[str, float]:
    """The time (one thread, N = 64) two finish-pass factors take alone as bare loops, as a
    share of what the 0.60 target leaves for every factor and 4 robots together: a clean
    frame's time x (1 / 0.60 - 1), measured in the same rounds. A share near or above 1 says
    that factor alone spends the budget of all when computed per pixel as the renderer does;
    not a proof that no kernel could do it in less (a table per frame instead of the square
    root, say, which changes the frames' bytes)."""
    serial = Renderer(camera=camera, parallel=False)
    images = np.empty((64, camera.height, camera.width), np.uint8)
    noise = np.random.default_rng(0).standard_normal(1 << 20).astype(np.float32)
    tone = np.arange(256, dtype=np.uint8)
    taps = tuple(np.float32(t) for t in (0.04, 0.11, 0.21, 0.28, 0.21, 0.11, 0.04))
    rows = np.empty((camera.height + len(taps) - 1, camera.width), np.float32)
    counter = [0]

    def clean() -> None:
        k = counter[0] = (counter[0] + 64) % (len(pose) - 64)
        s = slice(k, k + 64)
        serial.render(pose[s], pan[s], tilt[s], ball[s], out=images)

    calls = {
        "clean": clean,
        "noise_and_tone": lambda: _noise_and_tone(images, noise, tone, 9.0, 0.3),
        "blur": lambda: _blur(images, taps, rows),
    }
    for fn in calls.values():
        fn()  # compile
    best = dict.fromkeys(calls, np.inf)
    for _ in range(args.rounds):
        for name, fn in calls.items():
            best[name] = min(best[name], time_calls(fn, args.seconds / 3)[0] / 64)
    budget = best["clean"] * (1 / 0.60 - 1)
    print(
        f"bare loops, one thread: a clean frame {best['clean'] * 1e6:.1f} us, so the 0.60 target"
        f" leaves {budget * 1e6:.1f} us a frame for every factor and 4 robots together;"
    )
    shares = {}
    for name in ("noise_and_tone", "blur"):
        shares[name] = best[name] / budget
        print(f"  {name:15s} alone, as bare loops: {best[name] * 1e6:5.1f} us = {shares[name]:.2f}")
    return shares


def randomised_world(renderer, pose, pan, tilt, ball, rng, args) -> dict[str, float]:
    """Single-frame and N=64 batched speed with every appearance factor drawn at its robust
    range (``AppearanceConfig.randomised()``), a 3-degree head move per frame (motion blur)
    and 4 other robots 1-4 m around each camera."""
    pool = len(pose)
    looks, tone = frame_looks(AppearanceConfig.randomised(), pool, rng)
    angle = rng.uniform(-np.pi, np.pi, (pool, 4))
    dist = rng.uniform(1.0, 4.0, (pool, 4))
    robots = np.stack(
        [
            pose[:, None, 0] + dist * np.cos(angle),
            pose[:, None, 1] + dist * np.sin(angle),
            rng.uniform(0.4, 1.0, (pool, 4)),
            rng.uniform(25, 230, (pool, 4)),
        ],
        axis=-1,
    )
    cylinders = robot_cylinders(robots, 0.12)
    counter = [0]

    def single() -> None:
        k = counter[0] = (counter[0] + 1) % pool
        s = slice(k, k + 1)
        renderer.render(
            pose[k], pan[k], tilt[k], ball[k], looks=looks[s], tone=tone[s], cylinders=cylinders[s]
        )

    out = np.empty((64, *renderer.image_shape), dtype=np.uint8)

    def batch() -> None:
        k = counter[0] = (counter[0] + 64) % (pool - 64)
        s = slice(k, k + 64)
        renderer.render(
            pose[s],
            pan[s],
            tilt[s],
            ball[s],
            out=out,
            looks=looks[s],
            tone=tone[s],
            cylinders=cylinders[s],
        )

    def clean_single() -> None:
        k = counter[0] = (counter[0] + 1) % pool
        renderer.render(pose[k], pan[k], tilt[k], ball[k])

    def clean_batch() -> None:
        k = counter[0] = (counter[0] + 64) % (pool - 64)
        s = slice(k, k + 64)
        renderer.render(pose[s], pan[s], tilt[s], ball[s], out=out)

    single()
    batch()  # compile
    # clean and randomised alternate within every round, so that a slow spell of the
    # machine spoils both alike (these machines vary by 2-3x from minute to minute)
    best = {"single": np.inf, "batch": np.inf, "clean_single": np.inf, "clean_batch": np.inf}
    calls = {
        "single": single,
        "batch": batch,
        "clean_single": clean_single,
        "clean_batch": clean_batch,
    }
    for _ in range(2 * args.rounds):
        for name, fn in calls.items():
            chunk = 20 if "single" in name else 5
            best[name] = min(best[name], time_calls(fn, args.seconds / 2, chunk=chunk)[0])
    return {
        "randomised_single_frame_ms": best["single"] * 1e3,
        "randomised_batched_frames_per_s": 64 / best["batch"],
        "randomised_single_ratio": best["single"] / best["clean_single"],
        "randomised_batched_ratio": best["clean_batch"] / best["batch"],
    }


def main() -> None:
    parser = ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=positive_float, default=1.0, help="time per measurement")
    parser.add_argument("--rounds", type=positive_int, default=3, help="rounds of all measurements")
    parser.add_argument("--reference-frames", type=positive_int, default=50)
    parser.add_argument("--seed", type=seed, default=0)
    parser.add_argument(
        "--factors", action="store_true", help="also time each appearance factor alone"
    )
    parser.add_argument(
        "--floor",
        action="store_true",
        help="also time noise + tone curve and blur alone as bare loops against the target's"
        " budget",
    )
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

    def batch_fn(n: int):
        out = np.empty((n, camera.height, camera.width), dtype=np.uint8)
        starts = [0]

        def batch() -> None:
            s = starts[0] = (starts[0] + n) % (pool - n)
            renderer.render(
                pose[s : s + n], pan[s : s + n], tilt[s : s + n], ball[s : s + n], out=out
            )

        return batch

    sizes = (16, 64, 256)
    batch_fns = {n: batch_fn(n) for n in sizes}
    single_best, single_median = np.inf, []
    best = dict.fromkeys(sizes, np.inf)
    medians: dict[int, list[float]] = {n: [] for n in sizes}
    # Several rounds of every measurement: a competing process then spoils only some.
    for _ in range(args.rounds):
        b, m = time_calls(single, args.seconds, chunk=20)
        single_best = min(single_best, b)
        single_median.append(m)
        for n in sizes:
            b, m = time_calls(batch_fns[n], args.seconds)
            best[n] = min(best[n], b)
            medians[n].append(m)
    single_med = float(np.median(single_median))
    results = {
        "single_frame_ms": single_best * 1e3,
        "single_frame_ms_median": single_med * 1e3,
        "single_frames_per_s": 1.0 / single_best,
    }
    print(
        f"fast renderer, single frame : {single_best * 1e3:8.4f} ms  "
        f"({1 / single_best:9.0f} frames/s; median {single_med * 1e3:.4f} ms)"
    )
    batched = {n: n / best[n] for n in sizes}
    batched_median = {n: n / float(np.median(medians[n])) for n in sizes}
    for n in sizes:
        print(
            f"fast renderer, batch N={n:<4d}: {batched[n]:9.0f} frames/s "
            f"({1e6 / batched[n]:6.2f} us/frame; median {batched_median[n]:9.0f} frames/s)"
        )

    # The same batches on the calling thread only (Renderer(parallel=False)).
    serial = Renderer(camera=camera, parallel=False)
    serial_out = np.empty((64, camera.height, camera.width), dtype=np.uint8)
    serial_start = [0]

    def serial_batch() -> None:
        s = serial_start[0] = (serial_start[0] + 64) % (pool - 64)
        serial.render(
            pose[s : s + 64], pan[s : s + 64], tilt[s : s + 64], ball[s : s + 64], out=serial_out
        )

    serial_best = min(time_calls(serial_batch, args.seconds)[0] for _ in range(args.rounds))
    serial_fps = 64 / serial_best
    print(f"fast renderer, batch N=64 on one thread (parallel=False): {serial_fps:9.0f} frames/s")

    looked = randomised_world(renderer, pose, pan, tilt, ball, rng, args)
    print(
        f"randomised world (every appearance factor on, 4 robots): single frame "
        f"{looked['randomised_single_frame_ms']:.4f} ms ({looked['randomised_single_ratio']:.2f}x "
        f"a clean frame's time, alternating with it; target < 2x), batch N=64 "
        f"{looked['randomised_batched_frames_per_s']:9.0f} frames/s "
        f"({looked['randomised_batched_ratio']:.2f} of the clean batch's; target >= 0.60)"
    )
    results.update(looked)
    if args.factors:
        shares = factor_costs(renderer, pose, pan, tilt, ball, rng, args)
        print_factor_costs(shares)
        results["factor_extra_share"] = shares
    if args.floor:
        results["floor_share_of_budget"] = floor_costs(pose, pan, tilt, ball, camera, args)

    m = args.reference_frames
    render_reference(pose[:1], pan[:1], tilt[:1])
    ref_best = np.inf
    for rep in range(3):  # best of three runs, as for the fast renderer
        sl = slice(rep * m, (rep + 1) * m)
        t0 = time.perf_counter()
        render_reference(pose[sl], pan[sl], tilt[sl])
        ref_best = min(ref_best, time.perf_counter() - t0)
    reference_fps = m / ref_best
    print(f"numpy reference (centre-sampled, no AA, no goals/ball): {reference_fps:9.0f} frames/s")

    speedup = batched[64] / reference_fps
    paper = batched[64] * PAPER_SECONDS_PER_IMAGE
    print(f"speed-up over the reference (N=64): {speedup:.1f}x")
    print(f"speed-up over the paper's simulator pace (1 image / 320 ms): {paper:,.0f}x")
    results.update(
        batched_frames_per_s=batched[64],
        batched_frames_per_s_by_n={str(k): v for k, v in batched.items()},
        batched_frames_per_s_median={str(k): v for k, v in batched_median.items()},
        batched_frames_per_s_one_thread=serial_fps,
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
