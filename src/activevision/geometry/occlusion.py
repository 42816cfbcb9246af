"""What other robots hide: vertical cylinders between the camera and a point.

A robot's body is one or more vertical cylinders (:func:`robot_cylinders`: a body and a
narrower head). A target point is hidden when the straight sight line from the camera's
optical centre to it passes through a cylinder: inside its circle on the ground plan and,
there, between its bottom and top. Because the camera sits above the robot's ground position
whatever the head angles (:mod:`activevision.geometry.camera`), what a robot hides does not
depend on where the head looks: it is fixed for an episode of a standing robot.

A landmark (a segment, or a point: both ends equal) counts as hidden when every one of
:data:`LANDMARK_SAMPLES` points spread along it is hidden: a line that a robot crosses is
still detected on either side of it.
"""

from __future__ import annotations

import numpy as np

from activevision.geometry.landmarks import LandmarkSet

#: Points along a landmark that must all be hidden for the landmark to be.
LANDMARK_SAMPLES = 17
#: A robot's head: the top share of its height, at this share of the body's radius.
HEAD_SHARE = 0.15
HEAD_RADIUS_SHARE = 0.6


def robot_cylinders(robots: np.ndarray, radius: float) -> np.ndarray:
    """The cylinders ``(x, y, radius, bottom z, top z, grey)`` of robots ``(x, y, height,
    grey)`` (..., R, 4): a body from the ground to ``1 - HEAD_SHARE`` of the height, and a
    head of ``HEAD_RADIUS_SHARE`` of the radius above it. (..., 2R, 6); a robot of height 0
    (an unused slot) gives two cylinders of radius 0."""
    robots = np.asarray(robots, dtype=np.float64)
    x, y, h, grey = (robots[..., i] for i in range(4))
    used = h > 0
    neck = (1.0 - HEAD_SHARE) * h
    zero = np.zeros_like(h)
    body = np.stack([x, y, np.where(used, radius, 0.0), zero, neck, grey], axis=-1)
    head_grey = np.clip(grey + np.where(grey < 128, 25.0, -25.0), 0.0, 255.0)
    head = np.stack(
        [x, y, np.where(used, radius * HEAD_RADIUS_SHARE, 0.0), neck, h, head_grey], axis=-1
    )
    out: np.ndarray = np.concatenate([body, head], axis=-1).reshape(*robots.shape[:-1], -1, 6)
    # interleaved (body, head) per robot
    return np.ascontiguousarray(out.reshape(*robots.shape[:-2], -1, 6))


def hidden_points(camera: np.ndarray, points: np.ndarray, cylinders: np.ndarray) -> np.ndarray:
    """Whether each sight line from ``camera`` (N, 3) to ``points`` (N, M, 3) passes through
    one of ``cylinders`` (N, C, 6) (``x, y, radius, bottom z, top z``, grey unused; radius 0:
    none): (N, M) bool.

    The part of the sight line inside a cylinder's circle (on the ground plan) spans the
    heights between its entry and exit; the point is hidden when that span meets the
    cylinder's ``[bottom, top]`` and lies between the camera and the point."""
    cam = camera[:, None, None, :]  # N, 1, 1, 3
    pts = points[:, :, None, :]  # N, M, 1, 3
    cyl = cylinders[:, None, :, :]  # N, 1, C, 6
    d = pts - cam  # sight lines, t in [0, 1]
    dxy2 = d[..., 0] ** 2 + d[..., 1] ** 2
    rel_x = cyl[..., 0] - cam[..., 0]
    rel_y = cyl[..., 1] - cam[..., 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        t_mid = np.where(dxy2 > 0, (rel_x * d[..., 0] + rel_y * d[..., 1]) / dxy2, 0.0)
        miss2 = (rel_x - t_mid * d[..., 0]) ** 2 + (rel_y - t_mid * d[..., 1]) ** 2
        half = np.sqrt(np.maximum(cyl[..., 2] ** 2 - miss2, 0.0) / np.maximum(dxy2, 1e-300))
    crosses = (cyl[..., 2] > 0) & (miss2 < cyl[..., 2] ** 2) & (dxy2 > 0)
    t0 = np.clip(t_mid - half, 0.0, 1.0)
    t1 = np.clip(t_mid + half, 0.0, 1.0)
    z0 = cam[..., 2] + t0 * d[..., 2]
    z1 = cam[..., 2] + t1 * d[..., 2]
    low, high = np.minimum(z0, z1), np.maximum(z0, z1)
    hit = crosses & (t1 > t0) & (low < cyl[..., 4]) & (high > cyl[..., 3])
    hidden: np.ndarray = hit.any(axis=-1)
    return hidden


def hidden_landmarks(
    landmarks: LandmarkSet, camera: np.ndarray, cylinders: np.ndarray
) -> np.ndarray:
    """(N, K) bool: the landmarks each camera (N, 3) cannot see at all past ``cylinders``
    (N, C, 6), sampled at :data:`LANDMARK_SAMPLES` points along each (on the ground)."""
    n, k = len(camera), len(landmarks)
    f = np.linspace(0.0, 1.0, LANDMARK_SAMPLES)
    seg = landmarks.segments  # K, 2, 2
    along = seg[:, None, 0] + f[None, :, None] * (seg[:, None, 1] - seg[:, None, 0])  # K, S, 2
    pts = np.zeros((n, k * LANDMARK_SAMPLES, 3))
    pts[..., :2] = along.reshape(-1, 2)[None]
    hidden = hidden_points(camera, pts, cylinders).reshape(n, k, LANDMARK_SAMPLES)
    return np.asarray(hidden.all(axis=-1))
