"""Tests of the fast renderer against camera geometry and the supersampled ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

import activevision.rendering.renderer as renderer_module
from activevision.geometry import CameraConfig, FieldSpec, project_points
from activevision.rendering import (
    RenderConfig,
    Renderer,
    render_reference,
    render_supersampled,
)
from activevision.rendering.kernels.bundles import Cameras, Looks, allocate_scratch, allocate_work
from activevision.rendering.kernels.camera_setup import setup_camera
from activevision.rendering.kernels.garbage import GARBAGE_KINDS

CAM = CameraConfig()
CFG = RenderConfig()
SPEC = FieldSpec()
H, W = CAM.height, CAM.width


@pytest.fixture(scope="module")
def renderer() -> Renderer:
    return Renderer()


def random_states(n: int, seed: int):
    rng = np.random.default_rng(seed)
    pose = np.stack(
        [rng.uniform(-4.5, 4.5, n), rng.uniform(-3, 3, n), rng.uniform(-np.pi, np.pi, n)], 1
    )
    pan = rng.uniform(CAM.pan_min, CAM.pan_max, n)
    tilt = rng.uniform(CAM.tilt_min, CAM.tilt_max, n)
    bearing = pose[:, 2] + pan + rng.uniform(-0.4, 0.4, n)
    dist = rng.uniform(1, 3, n)
    ball = pose[:, :2] + dist[:, None] * np.stack([np.cos(bearing), np.sin(bearing)], 1)
    return pose, pan, tilt, ball


def project(point3, pose, pan, tilt):
    uv, _, inside = project_points(
        np.asarray([point3], float),
        np.asarray([pose], float),
        np.asarray([pan]),
        np.asarray([tilt]),
        CAM,
    )
    assert inside[0, 0]
    return uv[0, 0]


def dilate(mask: np.ndarray, radius: int) -> np.ndarray:
    """Binary dilation of the last two axes by a (2 radius + 1)^2 square."""
    out = mask.copy()
    padded = np.pad(mask, [(0, 0)] * (mask.ndim - 2) + [(radius, radius)] * 2)
    for dj in range(2 * radius + 1):
        for di in range(2 * radius + 1):
            out |= padded[..., dj : dj + mask.shape[-2], di : di + mask.shape[-1]]
    return out


def test_line_is_where_geometry_puts_it(renderer):
    # Looking along +x at the halfway line 1 m ahead.
    pose, pan, tilt = (-1.0, 0.2, 0.0), 0.0, 0.45
    img = renderer.render(np.array(pose), pan, tilt, None)[0]
    u, v = project((0.0, 0.4, 0.0), pose, pan, tilt)  # on the halfway line's centre
    assert img[int(v), int(u)] >= CFG.line - 25
    u, v = project((-0.3, 0.4, 0.0), pose, pan, tilt)  # 30 cm in front of it: grass
    assert img[int(v), int(u)] == round(CFG.grass)


def test_distant_goal_line_stays_connected(renderer):
    # The far goal line 5 m away is about 0.15 px thick; every column it crosses must still
    # show it (box-filtered: about grass + 0.15 (line - grass)), whereas a centre-sampled
    # renderer breaks it into dashes.
    pose, pan, tilt = (-0.5, 0.3, 0.0), 0.0, math.radians(8)
    img = renderer.render(np.array(pose), pan, tilt, None)[0].astype(int)
    ys = np.linspace(-SPEC.half_width, SPEC.half_width, 2001)
    pts = np.stack([np.full_like(ys, SPEC.half_length), ys, np.zeros_like(ys)], 1)
    uv, _, inside = project_points(pts, np.array([pose]), np.array([pan]), np.array([tilt]), CAM)
    uv = uv[0][inside[0]]
    columns = np.unique(uv[:, 0].astype(int))
    assert len(columns) > 100
    for col in columns:
        v_line = (
            np.interp(col + 0.5, uv[:, 0], uv[:, 1])
            if uv[0, 0] < uv[-1, 0]
            else np.interp(col + 0.5, uv[::-1, 0], uv[::-1, 1])
        )
        rows = img[max(int(v_line) - 2, 0) : int(v_line) + 3, col]
        assert rows.max() >= CFG.grass + 10, f"goal line gap at column {col}"

    # The centre-sampled reference does break it (so the test above is meaningful).
    ref = render_reference(np.array([pose]), pan, tilt)[0].astype(int)
    gaps = 0
    for col in columns:
        v_line = (
            np.interp(col + 0.5, uv[::-1, 0], uv[::-1, 1])
            if uv[0, 0] > uv[-1, 0]
            else np.interp(col + 0.5, uv[:, 0], uv[:, 1])
        )
        rows = ref[max(int(v_line) - 2, 0) : int(v_line) + 3, col]
        gaps += rows.max() < CFG.grass + 10
    assert gaps > 10


def test_batched_equals_single(renderer):
    pose, pan, tilt, ball = random_states(12, seed=3)
    batch = renderer.render(pose, pan, tilt, ball)
    assert batch.shape == (12, H, W) and batch.dtype == np.uint8
    for k in range(12):
        single = renderer.render(pose[k], pan[k], tilt[k], ball[k])
        assert single.shape == (1, H, W)
        np.testing.assert_array_equal(single[0], batch[k])


def test_one_thread_equals_parallel(renderer):
    pose, pan, tilt, ball = random_states(9, seed=6)
    serial = Renderer(parallel=False).render(pose, pan, tilt, ball)
    np.testing.assert_array_equal(serial, renderer.render(pose, pan, tilt, ball))


def test_out_buffer_is_filled_and_returned(renderer):
    pose, pan, tilt, ball = random_states(5, seed=4)
    out = np.zeros((5, H, W), dtype=np.uint8)
    result = renderer.render(pose, pan, tilt, ball, out=out)
    assert result is out
    np.testing.assert_array_equal(out, renderer.render(pose, pan, tilt, ball))


VIEWS = [  # (pose, pan, tilt, ball): along a touchline, centre circle, goal 2 m, steep tilt
    ((-4.0, 2.8, 0.0), 0.0, 0.15, (-2.5, 2.9)),
    ((-2.0, 0.0, 0.0), 0.0, 0.6, (-1.0, 0.3)),
    ((2.5, 0.5, 0.0), 0.3, 0.1, (3.5, 0.5)),
    ((3.0, 0.0, 0.8), 0.0, 1.1, (3.3, 0.3)),
    ((0.5, -1.5, 2.4), -0.3, 0.3, (-1.0, -0.5)),
]


def test_matches_supersampled_ground_truth_near_lines(renderer):
    pose = np.array([v[0] for v in VIEWS])
    pan = np.array([v[1] for v in VIEWS])
    tilt = np.array([v[2] for v in VIEWS])
    ball = np.array([v[3] for v in VIEWS])
    fast = renderer.render(pose, pan, tilt, ball).astype(float)
    ref = render_reference(pose, pan, tilt)
    flat = (fast == round(CFG.grass)) | (fast == round(CFG.background))
    # Pixels within 2 px of painted lines (centre-sampled) or of anything not flat.
    near = dilate((ref == round(CFG.line)) | ~flat, 2)
    truth = render_supersampled(pose, pan, tilt, ball, samples_per_axis=16, mask=near)
    for k in range(len(VIEWS)):
        err = np.abs(fast[k] - truth[k])[near[k]]
        assert near[k].sum() > 300
        assert err.mean() < 2.0, f"view {k}: MAE {err.mean():.2f}"
    assert np.abs(fast - truth)[near].mean() < 1.0


def ring_row_ranges(renderer, pose, pan, tilt) -> np.ndarray:
    """The setup pass's ``[first, end)`` image rows of the centre circle's outer polygon
    (``[0]``) and hole polygon (``[1]``) for one camera."""
    scene = renderer._kernel_scene
    work, scratch = allocate_work(1, scene, 0), allocate_scratch(1, scene, 0)
    cameras = Cameras(np.array([pose]), np.array([pan]), np.array([tilt]), np.zeros((1, 2)), False)
    looks = Looks(*renderer._looks(1, None, None, None))
    setup_camera(0, scene, renderer._kernel_params, cameras, looks, work, scratch)
    return work.ring_rows[0]


def test_ring_with_its_hole_off_image(renderer, monkeypatch):
    # Issue #14: with the hole polygon off the image (no rows) while the ring covers rows
    # 33-119, the hole span was cut from edges never written for this camera: whatever the
    # memory held (another camera's edges, in a batch) could blank the ring. Garbage of the
    # kind "an edge that takes every pixel" did so deterministically (MAE 7 vs the truth).
    pose, pan, tilt = (0.0, 1.0, -1.6), 1.55, 0.92
    rows = ring_row_ranges(renderer, pose, pan, tilt)
    assert rows[0, 1] - rows[0, 0] > 50 and rows[1, 1] <= rows[1, 0]
    alone = renderer.render(np.array(pose), pan, tilt, None)[0]
    # a batch big enough for the threaded kernel, the camera in the middle of it
    others = random_states(6, seed=11)[:3]
    batch_pose = np.insert(others[0], 3, pose, axis=0)
    batch_pan, batch_tilt = np.insert(others[1], 3, pan), np.insert(others[2], 3, tilt)
    renders = {"batch": renderer.render(batch_pose, batch_pan, batch_tilt, None)[3]}
    for seed in range(1, 1 + GARBAGE_KINDS):
        monkeypatch.setattr(renderer_module, "_WORK_GARBAGE_SEED", seed)
        renders[f"alone, garbage {seed}"] = renderer.render(np.array(pose), pan, tilt, None)[0]
        renders[f"batch, garbage {seed}"] = renderer.render(
            batch_pose, batch_pan, batch_tilt, None
        )[3]
    for name, img in renders.items():
        np.testing.assert_array_equal(img, alone, err_msg=name)

    fast = alone.astype(float)
    ring = fast > CFG.grass + 20
    assert ring.sum() > 500  # the ring is drawn
    near = dilate(ring[None] | (fast[None] != round(CFG.grass)), 2)
    truth = render_supersampled(np.array([pose]), pan, tilt, None, samples_per_axis=16, mask=near)[
        0
    ]
    err = np.abs(fast - truth)[near[0]]
    assert err.mean() < 2.0, f"MAE {err.mean():.2f}"
    assert err.max() < 20


def test_ball_appears_where_projected(renderer):
    pose, pan, tilt, ball = (1.0, -1.0, 0.5), 0.1, 0.5, (2.8, -0.2)
    img = renderer.render(np.array(pose), pan, tilt, np.array(ball))[0]
    no_ball = renderer.render(np.array(pose), pan, tilt, None)[0]
    u, v = project((ball[0], ball[1], SPEC.ball_radius), pose, pan, tilt)
    centre = int(img[int(v), int(u)])
    assert CFG.ball_shadow - 1 <= centre <= CFG.ball_lit + 1
    assert abs(centre - CFG.grass) > 20 and abs(centre - CFG.line) > 100
    changed = np.argwhere(img != no_ball)
    # The ball covers a disc of about f r / d pixels around its projection.
    radius_px = CAM.focal * SPEC.ball_radius / np.hypot(ball[0] - pose[0], ball[1] - pose[1])
    assert np.abs(changed[:, 1] + 0.5 - u).max() <= radius_px * 1.2 + 1
    assert np.abs(changed[:, 0] + 0.5 - v).max() <= radius_px * 1.5 + 1
    # lit from above: the top of the ball is brighter than its bottom
    top = int(img[int(v - 0.6 * radius_px), int(u)])
    bottom = int(img[int(v + 0.6 * radius_px), int(u)])
    assert top > bottom + 10


def test_sky_above_horizon_is_background(renderer):
    # From the centre looking along +y (no goal in view), tilted 5 degrees down.
    tilt = math.radians(5)
    img = renderer.render(np.array([0.0, 0.0, math.pi / 2]), 0.0, tilt, None)[0]
    horizon_v = CAM.height / 2 - CAM.focal * math.tan(tilt)
    above = math.floor(horizon_v) - 1
    assert above > 20
    assert (img[:above] == round(CFG.background)).all()
    assert (img[-5:] == round(CFG.grass)).any()


def test_goal_posts_are_drawn(renderer):
    pose, pan, tilt = (1.5, 0.0, 0.0), 0.0, 0.1
    img = renderer.render(np.array(pose), pan, tilt, None)[0]
    for y in (1.35, -1.35):
        u, v = project((SPEC.half_length, y, 0.8), pose, pan, tilt)
        assert img[int(v), int(u)] >= CFG.post - 30
    # crossbar just below its top
    u, v = project((SPEC.half_length, 0.0, SPEC.goal_height + 0.06), pose, pan, tilt)
    assert img[int(v), int(u)] >= CFG.post - 30


def test_noise_off_by_default_and_reproducible_when_on():
    pose, pan, tilt, ball = random_states(3, seed=5)
    plain = Renderer()
    assert not RenderConfig().has_noise
    a = plain.render(pose, pan, tilt, ball)
    np.testing.assert_array_equal(a, plain.render(pose, pan, tilt, ball))

    noisy = Renderer(
        config=RenderConfig(noise_std=4.0, brightness_jitter=10.0, contrast_jitter=0.1)
    )
    with pytest.raises(ValueError, match="rng"):
        noisy.render(pose, pan, tilt, ball)
    b1 = noisy.render(pose, pan, tilt, ball, rng=np.random.default_rng(7))
    b2 = noisy.render(pose, pan, tilt, ball, rng=np.random.default_rng(7))
    b3 = noisy.render(pose, pan, tilt, ball, rng=np.random.default_rng(8))
    np.testing.assert_array_equal(b1, b2)
    assert (b1 != b3).any()
    assert (b1 != a).mean() > 0.5
    assert abs(b1.astype(float) - a).mean() < 20


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"pose": np.zeros((2, 2))}, "pose"),
        ({"pose": np.zeros((2, 3, 1))}, "pose"),
        ({"pan": np.zeros(3)}, "pan"),
        ({"tilt": np.zeros((2, 1))}, "tilt"),
        ({"ball_xy": np.zeros((2, 3))}, "ball_xy"),
        ({"ball_xy": np.zeros(2)}, "ball_xy"),
        ({"out": np.zeros((2, H, W), dtype=np.float32)}, "out"),
        ({"out": np.zeros((3, H, W), dtype=np.uint8)}, "out"),
        ({"pan": np.array([0.0, np.nan])}, "pan"),
        ({"pose": "robot"}, "pose"),
        ({"ball_xy": [["a", "b"], ["c", "d"]]}, "ball_xy"),
    ],
)
def test_bad_inputs_raise_value_error_naming_the_argument(renderer, kwargs, name):
    args = {
        "pose": np.zeros((2, 3)),
        "pan": np.zeros(2),
        "tilt": np.full(2, 0.3),
        "ball_xy": np.ones((2, 2)),
    }
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        renderer.render(**args)


def test_render_config_validation():
    with pytest.raises(ValueError, match="grass"):
        RenderConfig(grass=300)
    with pytest.raises(ValueError, match="noise_std"):
        RenderConfig(noise_std=-1)
    with pytest.raises(ValueError, match="contrast_jitter"):
        RenderConfig(contrast_jitter=1.5)


def test_reference_renderer_agrees_roughly(renderer):
    pose, pan, tilt, _ = random_states(6, seed=9)
    fast = renderer.render(pose, pan, tilt, None).astype(int)
    ref = render_reference(pose, pan, tilt).astype(int)
    # Differences only at anti-aliased edges (and goals, which the reference omits).
    assert (np.abs(fast - ref) > 60).mean() < 0.03


def test_other_fields_and_cameras_render():
    r = Renderer(field=FieldSpec.paper_2019(), camera=CameraConfig(width=64, height=48))
    img = r.render(np.array([0.0, 0.0, 0.0]), 0.0, 0.4, np.array([1.0, 0.0]))
    assert img.shape == (1, 48, 64)
    assert (img == round(CFG.grass)).any()
