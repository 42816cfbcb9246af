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

import math

import numpy as np

from activevision.geometry.jit import cached_njit
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
    cylinder's ``[bottom, top]`` and lies between the camera and the point. Compiled
    (:func:`_sight_line_hidden`): the envs ask every tick for every landmark of every match,
    and a NumPy version's temporaries over (N, points, cylinders) cost most of a tick."""
    camera, points, cylinders = _float64(camera), _float64(points), _float64(cylinders)
    hidden = np.zeros(points.shape[:2], dtype=bool)
    _hidden_points_kernel(camera, points, cylinders, hidden)
    return hidden


def hidden_landmarks(
    landmarks: LandmarkSet, camera: np.ndarray, cylinders: np.ndarray
) -> np.ndarray:
    """(N, K) bool: the landmarks each camera (N, 3) cannot see at all past ``cylinders``
    (N, C, 6), sampled at :data:`LANDMARK_SAMPLES` points along each (on the ground)."""
    f = np.linspace(0.0, 1.0, LANDMARK_SAMPLES)
    seg = landmarks.segments  # K, 2, 2
    along = seg[:, None, 0] + f[None, :, None] * (seg[:, None, 1] - seg[:, None, 0])  # K, S, 2
    hidden = np.zeros((len(camera), len(landmarks)), dtype=bool)
    _hidden_landmarks_kernel(_float64(camera), _float64(along), _float64(cylinders), hidden)
    return hidden


def _float64(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64)


@cached_njit()
def _sight_line_hidden(
    cx: float, cy: float, cz: float, px: float, py: float, pz: float, cylinders: np.ndarray
) -> bool:
    """Whether the segment from the camera ``(cx, cy, cz)`` to ``(px, py, pz)`` passes
    through one of ``cylinders`` (C, 6) (see :func:`hidden_points`)."""
    dx, dy, dz = px - cx, py - cy, pz - cz
    dxy2 = dx * dx + dy * dy
    if dxy2 <= 0.0:  # a point straight below the camera: nothing stands between
        return False
    for c in range(cylinders.shape[0]):
        r = cylinders[c, 2]
        if r <= 0.0:
            continue
        rel_x, rel_y = cylinders[c, 0] - cx, cylinders[c, 1] - cy
        t_mid = (rel_x * dx + rel_y * dy) / dxy2  # closest approach to the axis
        mx, my = rel_x - t_mid * dx, rel_y - t_mid * dy
        miss2 = mx * mx + my * my
        if miss2 >= r * r:
            continue
        half = math.sqrt((r * r - miss2) / dxy2)
        t0 = min(max(t_mid - half, 0.0), 1.0)
        t1 = min(max(t_mid + half, 0.0), 1.0)
        if t1 <= t0:
            continue
        z0, z1 = cz + t0 * dz, cz + t1 * dz
        if min(z0, z1) < cylinders[c, 4] and max(z0, z1) > cylinders[c, 3]:
            return True
    return False


@cached_njit()
def _hidden_points_kernel(
    camera: np.ndarray, points: np.ndarray, cylinders: np.ndarray, hidden: np.ndarray
) -> None:
    for n in range(points.shape[0]):
        cx, cy, cz = camera[n, 0], camera[n, 1], camera[n, 2]
        for m in range(points.shape[1]):
            p = points[n, m]
            hidden[n, m] = _sight_line_hidden(cx, cy, cz, p[0], p[1], p[2], cylinders[n])


@cached_njit()
def _hidden_landmarks_kernel(
    camera: np.ndarray, samples: np.ndarray, cylinders: np.ndarray, hidden: np.ndarray
) -> None:
    """``hidden`` (N, K): every sample (K, S, 2) of landmark k hidden from camera n (the
    first sample in view ends the landmark's test)."""
    for n in range(camera.shape[0]):
        cx, cy, cz = camera[n, 0], camera[n, 1], camera[n, 2]
        for k in range(samples.shape[0]):
            every = True
            for s in range(samples.shape[1]):
                q = samples[k, s]
                if not _sight_line_hidden(cx, cy, cz, q[0], q[1], 0.0, cylinders[n]):
                    every = False
                    break
            hidden[n, k] = every
