import numpy as np

from activevision.geometry import (
    CameraConfig,
    FieldSpec,
    LandmarkType,
    ball_visible,
    field_landmarks,
    project_points,
    visible_landmarks,
)

CAM = CameraConfig()
LM = field_landmarks(FieldSpec())


def random_cameras(rng, n):
    pose = np.stack(
        [rng.uniform(-4.5, 4.5, n), rng.uniform(-3, 3, n), rng.uniform(-np.pi, np.pi, n)], 1
    )
    return (
        pose,
        rng.uniform(CAM.pan_min, CAM.pan_max, n),
        rng.uniform(CAM.tilt_min, CAM.tilt_max, n),
    )


def brute_force_visibility(pose, pan, tilt, samples=4001):
    """Independent reference: sample every segment densely, project each sample."""
    t = np.linspace(0, 1, samples)
    a, b = LM.segments[:, 0], LM.segments[:, 1]
    pts = a[:, None] + t[None, :, None] * (b - a)[:, None]  # (K, S, 2)
    flat = np.concatenate([pts.reshape(-1, 2), np.zeros((pts.shape[0] * samples, 1))], 1)
    _, _, inside = project_points(flat, pose, pan, tilt, CAM)
    inside = inside.reshape(len(pose), len(LM), samples)
    dist = np.linalg.norm(pts[None] - pose[:, None, None, :2], axis=-1)
    return (inside & (dist <= LM.max_distance[None, :, None])).any(-1)


def test_visibility_agrees_with_dense_sampling():
    rng = np.random.default_rng(3)
    pose, pan, tilt = random_cameras(rng, 150)
    vis = visible_landmarks(LM, pose, pan, tilt, CAM)
    ref = brute_force_visibility(pose, pan, tilt)
    # Sampling can only miss slivers: the exact clipper may see more, never less.
    assert not (ref & ~vis.visible).any()
    disagree = vis.visible & ~ref
    assert disagree.sum() <= 0.01 * vis.visible.sum()
    assert vis.visible.any(axis=1).mean() > 0.5


def test_visible_landmark_points_project_inside_the_image_within_range():
    rng = np.random.default_rng(4)
    pose, pan, tilt = random_cameras(rng, 200)
    vis = visible_landmarks(LM, pose, pan, tilt, CAM)
    n, k = np.nonzero(vis.visible)
    pts = np.c_[vis.points[n, k], np.zeros(len(n))]
    uv, depth, _ = project_points(pts[:, None], pose[n], pan[n], tilt[n], CAM)
    assert (depth > 0).all()
    assert (uv[..., 0] >= -1e-6).all() and (uv[..., 0] <= 160 + 1e-6).all()
    assert (uv[..., 1] >= -1e-6).all() and (uv[..., 1] <= 120 + 1e-6).all()
    dist = np.linalg.norm(vis.points[n, k] - pose[n, :2], axis=1)
    assert (dist <= LM.max_distance[k] + 1e-9).all()
    assert np.isnan(vis.points[~vis.visible]).all()


def test_measured_point_of_a_line_is_its_closest_visible_point():
    # Robot at the centre looking along +y at the touchline y = 3 (too far: 3 m range) and
    # the halfway line x = 0 it stands on.
    pose = np.array([[0.5, 1.0, np.pi / 2]])
    vis = visible_landmarks(LM, pose, [0.0], [0.35], CAM)
    halfway = LM.names.index("halfway_line")
    # The halfway line runs 0.5 m to the left of the camera's axis... it is visible only if in
    # view; its measured point must lie on x = 0.
    if vis.visible[0, halfway]:
        assert abs(vis.points[0, halfway, 0]) < 1e-12
    touch = LM.names.index("touchline+y")
    assert vis.visible[0, touch]
    np.testing.assert_allclose(vis.points[0, touch], [0.5, 3.0], atol=1e-9)


def test_point_landmark_out_of_range_is_invisible():
    # Looking from 4.5 m straight at the centre circle's centre: in the image, but beyond 4 m.
    c = LM.names.index("centre_circle")
    assert LM.types[c] == LandmarkType.CENTRE_CIRCLE
    near = visible_landmarks(LM, np.array([[-2.0, 0.0, 0.0]]), [0.0], [0.2], CAM)
    far = visible_landmarks(LM, np.array([[-4.4, 0.0, 0.0]]), [0.0], [0.12], CAM)
    assert near.visible[0, c] and not far.visible[0, c]


def test_ball_visibility_matches_projection():
    rng = np.random.default_rng(5)
    pose, pan, tilt = random_cameras(rng, 300)
    ball = pose[:, :2] + rng.uniform(-3, 3, (300, 2))
    seen = ball_visible(ball, pose, pan, tilt, CAM, 0.07)
    _, _, inside = project_points(np.c_[ball, np.full(300, 0.07)][:, None], pose, pan, tilt, CAM)
    np.testing.assert_array_equal(seen, inside[:, 0])
    assert 0 < seen.mean() < 1
