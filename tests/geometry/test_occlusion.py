"""Occlusion by other robots: hand-computed sight lines, and a brute-force reference that
walks each sight line in small steps."""

from __future__ import annotations

import numpy as np
import pytest

from activevision.geometry import field_landmarks
from activevision.geometry.field import FieldSpec
from activevision.geometry.occlusion import hidden_landmarks, hidden_points, robot_cylinders

CAM = np.array([[0.0, 0.0, 0.5]])


def cylinder(x, y, r, z0, z1):
    return np.array([[[x, y, r, z0, z1, 100.0]]])


@pytest.mark.parametrize(
    "cyl, hidden",
    [
        (cylinder(2.0, 0.0, 0.1, 0.0, 1.0), True),  # tall robot halfway
        (cylinder(2.0, 0.2, 0.1, 0.0, 1.0), False),  # beside the sight line
        (cylinder(2.0, 0.0, 0.1, 0.0, 0.2), False),  # the line passes over it (z 0.24-0.26)
        (cylinder(2.0, 0.0, 0.1, 0.0, 0.26), True),  # ... and just under this one's top
        (cylinder(5.0, 0.0, 0.1, 0.0, 1.0), False),  # behind the point
        (cylinder(-1.0, 0.0, 0.1, 0.0, 1.0), False),  # behind the camera
        (cylinder(1.0, 0.0, 0.1, 0.3, 0.4), True),  # a head: the line is at z 0.375 there
        (cylinder(2.0, 0.0, 0.1, 0.3, 0.4), False),  # the line is at z 0.25, under the head
        (cylinder(2.0, 0.0, 0.0, 0.0, 1.0), False),  # radius 0: no robot
    ],
)
def test_hand_computed_sight_lines(cyl, hidden):
    point = np.array([[[4.0, 0.0, 0.0]]])
    assert hidden_points(CAM, point, cyl)[0, 0] == hidden


def brute_force(camera, point, cyl, steps=4000):
    t = (np.arange(steps) + 0.5) / steps
    line = camera[None] + t[:, None] * (point - camera)[None]
    inside = np.hypot(line[:, 0] - cyl[0], line[:, 1] - cyl[1]) < cyl[2]
    return bool((inside & (line[:, 2] > cyl[3]) & (line[:, 2] < cyl[4])).any())


def test_agrees_with_walking_the_sight_line():
    rng = np.random.default_rng(4)
    n, m = 200, 6
    cams = np.column_stack([rng.uniform(-3, 3, (n, 2)), np.full(n, 0.5)])
    pts = np.concatenate(
        [cams[:, None, :2] + rng.uniform(-4, 4, (n, m, 2)), rng.uniform(0, 0.2, (n, m, 1))],
        axis=-1,
    )
    robots = np.column_stack(
        [cams[:, :2] + rng.uniform(-2, 2, (n, 2)), rng.uniform(0.4, 1.0, n), np.full(n, 80.0)]
    )[:, None]
    cyls = robot_cylinders(robots, 0.15)
    got = hidden_points(cams, pts, cyls)
    want = np.array(
        [
            [any(brute_force(cams[i], pts[i, j], c) for c in cyls[i]) for j in range(m)]
            for i in range(n)
        ]
    )
    disagree = got != want
    assert want.sum() > 20  # the cases exercise occlusion
    assert disagree.sum() <= 2  # a sight line grazing an edge within the walk's step


def test_robot_cylinders_body_and_head():
    cyl = robot_cylinders(np.array([[[1.0, 2.0, 0.8, 40.0], [0, 0, 0, 0]]]), 0.12)
    assert cyl.shape == (1, 4, 6)
    body, head, unused_body, unused_head = cyl[0]
    np.testing.assert_allclose(body[:5], [1.0, 2.0, 0.12, 0.0, 0.68])
    np.testing.assert_allclose(head[:5], [1.0, 2.0, 0.072, 0.68, 0.8])
    assert unused_body[2] == 0 and unused_head[2] == 0


def test_a_robot_hides_a_corner_but_not_a_line_it_stands_on():
    spec = FieldSpec()
    landmarks = field_landmarks(spec)
    points = landmarks.segments[:, 0] == landmarks.segments[:, 1]
    corner = int(np.flatnonzero(points.all(axis=1))[0])
    target = landmarks.segments[corner, 0]
    camera = np.array([[target[0] * 0.5, target[1] * 0.5, 0.5]])
    between = (camera[0, :2] + target) / 2
    robots = np.array([[[between[0], between[1], 0.9, 50.0]]])
    hidden = hidden_landmarks(landmarks, camera, robot_cylinders(robots, 0.15))[0]
    assert hidden[corner]
    lines = ~points.all(axis=1)
    assert not hidden[lines].any()  # lines are long: a robot never hides all of one here
    assert hidden.sum() <= 3
