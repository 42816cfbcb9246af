"""The compiled visibility and ball tests agree exactly with the NumPy geometry."""

import numpy as np

from activevision.geometry import (
    CameraConfig,
    FieldSpec,
    ball_visible,
    field_landmarks,
    visible_landmarks,
)
from activevision.geometry.kernels import ball_visible_mask, visible_mask

CAM = CameraConfig()


def _random_cameras(rng, n):
    poses = np.column_stack([rng.uniform(-6, 6, n), rng.uniform(-4, 4, n), rng.uniform(-4, 4, n)])
    return poses, rng.uniform(-1.7, 1.7, n), rng.uniform(-0.2, 1.3, n)


def test_compiled_visibility_equals_numpy():
    landmarks = field_landmarks(FieldSpec())
    poses, pans, tilts = _random_cameras(np.random.default_rng(0), 3000)
    expected = visible_landmarks(landmarks, poses, pans, tilts, CAM).visible
    got = visible_mask(landmarks, poses, pans, tilts, CAM)
    assert expected.any() and not expected.all()
    assert np.array_equal(got, expected)


def test_compiled_ball_test_equals_numpy():
    rng = np.random.default_rng(1)
    poses, pans, tilts = _random_cameras(rng, 5000)
    balls = poses[:, :2] + rng.uniform(-3, 3, size=(5000, 2))
    expected = ball_visible(balls, poses, pans, tilts, CAM, 0.07)
    got = ball_visible_mask(balls, poses, pans, tilts, CAM, 0.07)
    assert expected.any() and not expected.all()
    assert np.array_equal(got, expected)
