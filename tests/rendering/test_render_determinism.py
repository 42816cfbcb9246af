"""A frame depends on its camera only: not on the batch around it, its place in the batch,
the code path (one frame, serial batch, threads) or what the kernels' work memory held."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import activevision.rendering.renderer as renderer_module
from activevision.geometry import CameraConfig, FieldSpec
from activevision.rendering import Renderer
from activevision.rendering.kernels import raster
from activevision.rendering.kernels.bundles import allocate_scratch, allocate_work
from activevision.rendering.kernels.garbage import GARBAGE_KINDS, fill_garbage

CAM = CameraConfig()
SPEC = FieldSpec()
CARPET_X, CARPET_Y = SPEC.carpet_half_extent
#: One seed per kind of garbage of ``kernels.garbage.fill_garbage``.
GARBAGE_SEEDS = tuple(range(101, 101 + GARBAGE_KINDS))


@pytest.fixture(scope="module")
def parallel() -> Renderer:
    r = Renderer()
    r.render(np.zeros((4, 3)), np.zeros(4), np.full(4, 0.3), np.ones((4, 2)))  # compile
    return r


@pytest.fixture(scope="module")
def serial() -> Renderer:
    return Renderer(parallel=False)


def render_alone(renderer, pose, pan, tilt, ball) -> np.ndarray:
    """Each camera in its own call (the single env's path)."""
    return np.concatenate(
        [
            renderer.render(pose[k], pan[k], tilt[k], None if ball is None else ball[k])
            for k in range(len(pose))
        ]
    )


def render_chunks(renderer, pose, pan, tilt, ball, size: int) -> np.ndarray:
    """Batches of ``size`` cameras (other thread splits: row_blocks depends on the size)."""
    parts = []
    for s in range(0, len(pose), size):
        sl = slice(s, s + size)
        parts.append(
            renderer.render(pose[sl], pan[sl], tilt[sl], None if ball is None else ball[sl])
        )
    return np.concatenate(parts)


def garbage_renders(renderer, pose, pan, tilt, ball):
    """``(name, images)`` rendered alone and batched with each kind of garbage in the work
    memory."""
    for seed in GARBAGE_SEEDS:
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(renderer_module, "_WORK_GARBAGE_SEED", seed)
            yield f"alone, garbage {seed}", render_alone(renderer, pose, pan, tilt, ball)
            yield f"batch, garbage {seed}", renderer.render(pose, pan, tilt, ball)


def all_renders(parallel, serial, pose, pan, tilt, ball):
    """``(name, images)`` of the same cameras along every path."""
    n = len(pose)
    yield "batch", parallel.render(pose, pan, tilt, ball)
    order = np.random.default_rng(n).permutation(n)
    shuffled = parallel.render(
        pose[order], pan[order], tilt[order], None if ball is None else ball[order]
    )
    unshuffled = np.empty_like(shuffled)
    unshuffled[order] = shuffled
    yield "shuffled batch", unshuffled
    yield "threads, batches of 4", render_chunks(parallel, pose, pan, tilt, ball, 4)
    yield "serial batch", serial.render(pose, pan, tilt, ball)
    yield from garbage_renders(parallel, pose, pan, tilt, ball)


def assert_same_everywhere(parallel, serial, pose, pan, tilt, ball) -> None:
    alone = render_alone(parallel, pose, pan, tilt, ball)
    for name, images in all_renders(parallel, serial, pose, pan, tilt, ball):
        differ = np.flatnonzero((images != alone).any(axis=(1, 2)))
        assert differ.size == 0, f"{name}: cameras {differ.tolist()} differ from alone"


# A camera: position on or around the carpet (often near the centre circle, where the hole
# polygon leaves the image first), heading, head angles over their full limits, and a ball
# at some distance and bearing from the view direction.
_near_centre = st.tuples(st.floats(-1.5, 1.5), st.floats(-1.5, 1.5))
_anywhere = st.tuples(
    st.floats(-CARPET_X - 1, CARPET_X + 1), st.floats(-CARPET_Y - 1, CARPET_Y + 1)
)
_camera = st.tuples(
    st.one_of(_near_centre, _anywhere),
    st.floats(-math.pi, math.pi),
    st.floats(CAM.pan_min, CAM.pan_max),
    st.floats(CAM.tilt_min, CAM.tilt_max),
    st.floats(0.1, 4.0),
    st.floats(-1.0, 1.0),
)


def _arrays(cameras, has_ball: bool):
    pose = np.array([(x, y, theta) for (x, y), theta, *_ in cameras])
    pan = np.array([c[2] for c in cameras])
    tilt = np.array([c[3] for c in cameras])
    bearing = pose[:, 2] + pan + np.array([c[5] for c in cameras])
    dist = np.array([c[4] for c in cameras])
    ball = pose[:, :2] + dist[:, None] * np.stack([np.cos(bearing), np.sin(bearing)], 1)
    return pose, pan, tilt, ball if has_ball else None


@settings(max_examples=100, deadline=None)
@given(cameras=st.lists(_camera, min_size=4, max_size=12), has_ball=st.booleans())
def test_frame_depends_on_its_camera_only(parallel, serial, cameras, has_ball):
    pose, pan, tilt, ball = _arrays(cameras, has_ball)
    assert_same_everywhere(parallel, serial, pose, pan, tilt, ball)


@pytest.mark.parametrize("seed", GARBAGE_SEEDS)
def test_garbage_overwrites_every_work_buffer(seed):
    # The garbage test above is only as strong as its reach: every buffer of allocate_work,
    # allocate_scratch and the row scratch must be overwritten entirely.
    scene = Renderer()._kernel_scene
    work, scratch = allocate_work(3, scene, 2), allocate_scratch(3, scene, 2)
    value = np.empty(CAM.width, dtype=np.float32)
    sentinel = 7777
    for arr in (*work, *scratch, value):
        arr[...] = sentinel
    fill_garbage(work, scratch, value, seed)
    buffers = {**work._asdict(), **scratch._asdict(), "value": value}
    for name, arr in buffers.items():
        assert not (arr == sentinel).any(), f"work buffer {name} keeps entries"


def test_renderer_hands_the_garbage_seed_to_both_kernels(monkeypatch):
    seen = []
    for name in ("render_kernel", "render_kernel_serial"):
        kernel = getattr(raster, name)

        def spy(*args, _kernel_fn=kernel):
            seen.append(args[-1])
            return _kernel_fn(*args)

        monkeypatch.setattr(raster, name, spy)
    monkeypatch.setattr(renderer_module, "_WORK_GARBAGE_SEED", GARBAGE_SEEDS[1])
    r = Renderer()
    r.render(np.zeros(3), 0.0, 0.3, None)
    r.render(np.zeros((8, 3)), np.zeros(8), np.full(8, 0.3), None)
    assert seen == [GARBAGE_SEEDS[1]] * 2
