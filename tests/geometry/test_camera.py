import math

import numpy as np
import pytest

from activevision.geometry import (
    CameraConfig,
    clip_head,
    footprint_polygon,
    ground_to_pixel_homography,
    head_in_limits,
    pixel_to_ground,
    pixel_to_ground_homography,
    project_points,
)

CAM = CameraConfig()


def random_cameras(rng, n):
    pose = np.stack(
        [rng.uniform(-4, 4, n), rng.uniform(-3, 3, n), rng.uniform(-np.pi, np.pi, n)], 1
    )
    return (
        pose,
        rng.uniform(CAM.pan_min, CAM.pan_max, n),
        rng.uniform(CAM.tilt_min, CAM.tilt_max, n),
    )


def test_focal_length_gives_the_field_of_view():
    assert CAM.focal == pytest.approx(80 / math.tan(math.radians(29)), rel=1e-3)


def test_pixel_ground_round_trip():
    rng = np.random.default_rng(0)
    pose, pan, tilt = random_cameras(rng, 50)
    # Pixels in the lower half of the image always see the ground at these tilts.
    uv = np.stack([rng.uniform(0, 160, 30), rng.uniform(70, 120, 30)], 1)
    xy, valid = pixel_to_ground(uv, pose, pan, tilt, CAM)
    assert valid.all()
    pts = np.concatenate([xy, np.zeros(xy.shape[:-1] + (1,))], -1)
    uv_back, depth, _ = project_points(pts, pose, pan, tilt, CAM)
    assert (depth > 0).all()
    np.testing.assert_allclose(uv_back, np.broadcast_to(uv, uv_back.shape), atol=1e-8)


def test_homographies_agree_with_projection():
    rng = np.random.default_rng(1)
    pose, pan, tilt = random_cameras(rng, 20)
    g = ground_to_pixel_homography(pose, pan, tilt, CAM)
    pts = np.stack([rng.uniform(-4, 4, 10), rng.uniform(-3, 3, 10), np.zeros(10)], 1)
    hom = np.einsum("nij,mj->nmi", g, np.c_[pts[:, :2], np.ones(10)])
    uv, depth, _ = project_points(pts, pose, pan, tilt, CAM)
    np.testing.assert_allclose(hom[..., 2], depth, atol=1e-9)
    np.testing.assert_allclose(hom[..., :2] / hom[..., 2:], uv, atol=1e-6)
    inv = pixel_to_ground_homography(pose, pan, tilt, CAM)
    np.testing.assert_allclose(
        np.einsum("nij,njk->nik", inv, g), np.broadcast_to(np.eye(3), g.shape), atol=1e-9
    )


def test_camera_looking_straight_down_sees_a_line_where_geometry_says():
    # Camera 0.5 m above (1, 0), yaw 0, looking straight down: image right = world -y,
    # image down = world -x. A line y = 0.1 therefore sits f * 0.1 / 0.5 px left of centre.
    pose = np.array([[1.0, 0.0, 0.0]])
    pts = np.array([[0.9, 0.1, 0.0], [1.0, 0.1, 0.0], [1.2, 0.1, 0.0]])
    uv, depth, inside = project_points(pts, pose, [0.0], [math.pi / 2], CAM)
    expected_u = 80 - CAM.focal * 0.1 / 0.5
    np.testing.assert_allclose(uv[0, :, 0], expected_u)
    np.testing.assert_allclose(uv[0, :, 1], 60 - CAM.focal * np.array([-0.1, 0.0, 0.2]) / 0.5)
    np.testing.assert_allclose(depth, 0.5)
    assert inside.all()


def test_points_behind_the_camera_are_not_in_the_image():
    pose = np.array([[0.0, 0.0, 0.0]])
    _, depth, inside = project_points(np.array([[-2.0, 0.0, 0.0]]), pose, [0.0], [0.3], CAM)
    assert depth[0, 0] < 0 and not inside[0, 0]


def test_pixels_above_the_horizon_do_not_hit_the_ground():
    xy, valid = pixel_to_ground(
        np.array([[80.0, 0.0]]), np.zeros((1, 3)), [0.0], [CAM.tilt_min], CAM
    )
    assert not valid[0, 0] and np.isnan(xy).all()


def test_head_limits_enforced():
    pan, tilt = clip_head(np.array([-2.0, 0.0, 2.0]), np.array([0.0, 0.5, 1.5]), CAM)
    np.testing.assert_allclose(pan, [CAM.pan_min, 0.0, CAM.pan_max])
    np.testing.assert_allclose(tilt, [CAM.tilt_min, 0.5, CAM.tilt_max])
    assert head_in_limits(pan, tilt, CAM).all()
    assert not head_in_limits(0.0, math.radians(70), CAM)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"width": 0}, "width"),
        ({"hfov": 4.0}, "hfov"),
        ({"camera_height": -1.0}, "camera_height"),
        ({"tilt_min": 1.0, "tilt_max": 0.5}, "tilt"),
    ],
)
def test_invalid_camera_config(kwargs, name):
    with pytest.raises(ValueError, match=name):
        CameraConfig(**kwargs)


def test_footprint_polygon_projects_onto_the_image_border():
    pose = np.array([[0.0, 0.0, 0.4]])
    poly = footprint_polygon(pose, [0.2], [CAM.tilt_max], CAM, max_distance=10.0, points_per_side=8)
    # At 65 deg tilt every border ray hits the ground close by: vertices map to the border.
    uv, _, _ = project_points(
        np.c_[poly[0], np.zeros(len(poly[0]))], pose, [0.2], [CAM.tilt_max], CAM
    )
    on_border = np.minimum.reduce(
        [
            np.abs(uv[0, :, 0]),
            np.abs(uv[0, :, 0] - 160),
            np.abs(uv[0, :, 1]),
            np.abs(uv[0, :, 1] - 120),
        ]
    )
    assert on_border.max() < 1e-6
    # A flat view is cut at the range limit.
    far = footprint_polygon(pose, [0.0], [CAM.tilt_min], CAM, max_distance=3.0)
    assert np.linalg.norm(far[0] - pose[0, :2], axis=1).max() <= 3.0 + 1e-9
