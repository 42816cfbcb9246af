"""The renderer and the visibility model agree: a landmark reported visible is painted there."""

import numpy as np

from activevision.geometry import (
    CameraConfig,
    FieldSpec,
    LandmarkType,
    field_landmarks,
    project_points,
    visible_landmarks,
)
from activevision.rendering import RenderConfig, Renderer

PAINTED = [
    LandmarkType.L_CORNER,
    LandmarkType.T_JUNCTION,
    LandmarkType.X_CROSSING,
    LandmarkType.PENALTY_MARK,
]


def test_every_visible_painted_landmark_is_line_coloured_in_the_image():
    spec, cam, colours = FieldSpec(), CameraConfig(), RenderConfig()
    landmarks = field_landmarks(spec)
    rng = np.random.default_rng(0)
    n = 400
    pose = np.stack(
        [rng.uniform(-4, 4, n), rng.uniform(-2.5, 2.5, n), rng.uniform(-np.pi, np.pi, n)], 1
    )
    pan = rng.uniform(cam.pan_min, cam.pan_max, n)
    tilt = rng.uniform(cam.tilt_min, cam.tilt_max, n)
    # No ball: it could hide a landmark (occlusion is not part of the visibility model).
    images = Renderer(spec, cam, parallel=False).render(pose, pan, tilt, ball_xy=None)
    vis = visible_landmarks(landmarks, pose, pan, tilt, cam)
    painted = np.isin(landmarks.types, PAINTED)
    checked = 0
    for i, k in zip(*np.nonzero(vis.visible & painted[None]), strict=True):
        point = np.r_[landmarks.segments[k, 0], 0.0][None]
        uv, _, _ = project_points(point, pose[i : i + 1], pan[i : i + 1], tilt[i : i + 1], cam)
        u, v = np.clip(uv[0, 0].astype(int), [1, 1], [cam.width - 2, cam.height - 2])
        brightest = images[i, v - 1 : v + 2, u - 1 : u + 2].max()
        dist = np.linalg.norm(landmarks.segments[k, 0] - pose[i, :2])
        # Lines 4 m away are a fifth of a pixel wide: faint, but always above the grass.
        need = colours.grass + (0.5 if dist < 2.0 else 0.1) * (colours.line - colours.grass)
        assert brightest >= need, (landmarks.names[k], i, dist, brightest)
        checked += 1
    assert checked > 100
