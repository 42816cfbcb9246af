"""Benchmark: does a rendered frame depend on its camera only?

Renders many random cameras (robots on and around the carpet, a third of them near the
centre circle; heading, pan and tilt over their full ranges; half the cameras with a ball
at 0.1-4 m near the view direction, half without) one at a time, which is what the single
env does, and compares every other path against that, byte for byte: one big batch (the
vector env, threaded), the batch shuffled, batches of 4 and 16 (other thread splits), the
batch on the calling thread only (``parallel=False``), and each of these kinds of garbage
in the kernels' uninitialised work memory (``renderer._WORK_GARBAGE_SEED``), alone and
batched. Prints a table, then one JSON line.

    python bench/render_determinism.py [--cameras 12000] [--seed 0]
"""

from __future__ import annotations

import json
import time

import numba
import numpy as np

import activevision.rendering.renderer as renderer_module
from activevision.cli.args import ArgumentParser, int_in
from activevision.cli.args import seed as seed_arg
from activevision.geometry import CameraConfig, FieldSpec
from activevision.rendering import Renderer
from activevision.rendering.kernels.garbage import GARBAGE_KINDS


def random_cameras(n: int, rng: np.random.Generator, camera: CameraConfig, field: FieldSpec):
    """``(pose, pan, tilt, ball_xy)`` of ``n`` random cameras."""
    half_x, half_y = field.carpet_half_extent
    xy = np.stack(
        [rng.uniform(-half_x - 1, half_x + 1, n), rng.uniform(-half_y - 1, half_y + 1, n)], 1
    )
    near_centre = rng.random(n) < 1 / 3  # where the hole polygon leaves the image first
    xy[near_centre] = rng.uniform(-1.5, 1.5, (int(near_centre.sum()), 2))
    pose = np.column_stack([xy, rng.uniform(-np.pi, np.pi, n)])
    pan = rng.uniform(camera.pan_min, camera.pan_max, n)
    tilt = rng.uniform(camera.tilt_min, camera.tilt_max, n)
    bearing = pose[:, 2] + pan + rng.uniform(-1.0, 1.0, n)
    distance = rng.uniform(0.1, 4.0, n)
    ball = pose[:, :2] + distance[:, None] * np.stack([np.cos(bearing), np.sin(bearing)], 1)
    return pose, pan, tilt, ball


def alone(renderer, pose, pan, tilt, ball) -> np.ndarray:
    return np.concatenate(
        [
            renderer.render(pose[k], pan[k], tilt[k], None if ball is None else ball[k])
            for k in range(len(pose))
        ]
    )


def chunks(size: int):
    def render(renderer, pose, pan, tilt, ball) -> np.ndarray:
        return np.concatenate(
            [
                renderer.render(
                    pose[s : s + size],
                    pan[s : s + size],
                    tilt[s : s + size],
                    None if ball is None else ball[s : s + size],
                )
                for s in range(0, len(pose), size)
            ]
        )

    return render


def batch(renderer, pose, pan, tilt, ball) -> np.ndarray:
    return renderer.render(pose, pan, tilt, ball)


def shuffled(renderer, pose, pan, tilt, ball) -> np.ndarray:
    order = np.random.default_rng(len(pose)).permutation(len(pose))
    images = np.empty((len(pose), *renderer.image_shape), dtype=np.uint8)
    images[order] = renderer.render(
        pose[order], pan[order], tilt[order], None if ball is None else ball[order]
    )
    return images


def with_garbage(seed: int, path):
    def render(renderer, *cameras) -> np.ndarray:
        renderer_module._WORK_GARBAGE_SEED = seed
        try:
            return path(renderer, *cameras)
        finally:
            renderer_module._WORK_GARBAGE_SEED = 0

    return render


def main() -> None:
    parser = ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cameras", type=int_in(2, 10**7), default=12000)
    parser.add_argument("--seed", type=seed_arg, default=0)
    args = parser.parse_args()

    camera, field = CameraConfig(), FieldSpec()
    threaded = Renderer(field, camera)
    serial = Renderer(field, camera, parallel=False)
    pose, pan, tilt, ball = random_cameras(
        args.cameras, np.random.default_rng(args.seed), camera, field
    )
    paths = {
        "batch": (threaded, batch),
        "shuffled batch": (threaded, shuffled),
        "batches of 4": (threaded, chunks(4)),
        "batches of 16": (threaded, chunks(16)),
        "serial batch": (serial, batch),
    }
    for seed in range(1, 1 + GARBAGE_KINDS):
        paths[f"alone, garbage {seed}"] = (threaded, with_garbage(seed, alone))
        paths[f"batch, garbage {seed}"] = (threaded, with_garbage(seed, batch))

    half = args.cameras // 2  # the first half with a ball, the rest without
    groups = [(slice(0, half), ball[:half]), (slice(half, None), None)]
    frames = dict.fromkeys(paths, 0)
    pixels = dict.fromkeys(paths, 0)
    t0 = time.perf_counter()
    for sl, group_ball in groups:
        cameras = (pose[sl], pan[sl], tilt[sl], group_ball)
        reference = alone(threaded, *cameras)
        for name, (renderer, path) in paths.items():
            differ = path(renderer, *cameras) != reference
            frames[name] += int(differ.any(axis=(1, 2)).sum())
            pixels[name] += int(differ.sum())
    seconds = time.perf_counter() - t0

    print(f"{args.cameras} cameras ({half} with a ball), each path vs one frame at a time:")
    for name in paths:
        print(f"  {name:20s}: {frames[name]:6d} frames, {pixels[name]:8d} pixels differ")
    total_frames, total_pixels = sum(frames.values()), sum(pixels.values())
    print(
        f"all paths: {total_frames} differing frames, {total_pixels} differing pixels "
        f"({seconds:.1f} s, {numba.get_num_threads()} threads)"
    )
    print(
        json.dumps(
            {
                "cameras": args.cameras,
                "cameras_with_ball": half,
                "paths": len(paths),
                "differing_frames": total_frames,
                "differing_pixels": total_pixels,
                "differing_frames_by_path": frames,
                "differing_pixels_by_path": pixels,
                "threads": numba.get_num_threads(),
                "seconds": seconds,
            }
        )
    )


if __name__ == "__main__":
    main()
