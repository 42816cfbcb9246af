"""Compiled (numba) scalar versions of the camera and visibility maths, for hot loops (the
environment's per-step visibility test, the best-viewpoint search).

They re-implement :mod:`activevision.geometry.camera` and
:mod:`activevision.geometry.visibility` operation for operation, so the visible masks agree
exactly (tests/geometry/test_kernels.py checks it on random cameras). The camera goes in as a
:class:`CameraModel` bundle (from Python: a plain tuple of its fields, see
:func:`camera_fields`).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from activevision.geometry.camera import CameraConfig
from activevision.geometry.jit import cached_njit
from activevision.geometry.landmarks import LandmarkSet


class CameraModel(NamedTuple):
    """The head camera as the kernels see it: a pinhole of ``focal`` px on a
    ``width`` x ``height`` image, ``cam_height`` m above the ground."""

    focal: float
    width: float
    height: float
    cam_height: float


def camera_fields(cam: CameraConfig) -> tuple[float, ...]:
    """The fields of ``cam``'s :class:`CameraModel` as a plain tuple, what a kernel called
    from Python takes: numba types a plain tuple in C but a namedtuple in Python (about
    2.5 us per call). The last camera's are kept (an environment asks for the same camera
    several times per step; hashing the config would cost more than the kernel call)."""
    global _last_camera
    last, fields = _last_camera
    if cam is not last:
        fields = _camera_fields(cam)
        _last_camera = (cam, fields)
    return fields


@lru_cache(maxsize=16)
def _camera_fields(cam: CameraConfig) -> tuple[float, ...]:
    model = CameraModel(
        float(cam.focal), float(cam.width), float(cam.height), float(cam.camera_height)
    )
    return tuple(model)


#: The last camera :func:`camera_fields` was asked for, and its fields.
_last_camera: tuple[CameraConfig | None, tuple[float, ...]] = (None, ())


@cached_njit()
def camera_rotation(yaw: float, tilt: float, rot: np.ndarray) -> None:
    """Rows: camera right, down, forward (as ``geometry.camera.world_to_camera_rotation``)."""
    cy, sy, ct, st = math.cos(yaw), math.sin(yaw), math.cos(tilt), math.sin(tilt)
    rot[0, 0], rot[0, 1], rot[0, 2] = sy, -cy, 0.0
    rot[1, 0], rot[1, 1], rot[1, 2] = -cy * st, -sy * st, -ct
    rot[2, 0], rot[2, 1], rot[2, 2] = cy * ct, sy * ct, -st


@cached_njit()
def image_halfplanes(
    x: float, y: float, rot: np.ndarray, cam: CameraModel, planes: np.ndarray
) -> None:
    """The four image half-planes on the ground (as ``geometry.camera.image_halfplanes``) of
    the :class:`CameraModel` ``cam`` at ``(x, y)`` turned by ``rot``, into ``planes``."""
    focal, width, height, cam_height = cam
    # M has rows (r_i0, r_i1, t_i) with t = -R c; G = K M, K = [[f, 0, w/2], [0, f, h/2], [0, 0, 1]]
    m = np.empty((3, 3))
    for i in range(3):
        m[i, 0], m[i, 1] = rot[i, 0], rot[i, 1]
        m[i, 2] = -(rot[i, 0] * x + rot[i, 1] * y + rot[i, 2] * cam_height)
    for k in range(3):
        u = focal * m[0, k] + 0.5 * width * m[2, k]
        v = focal * m[1, k] + 0.5 * height * m[2, k]
        w = m[2, k]
        planes[0, k] = u
        planes[1, k] = width * w - u
        planes[2, k] = v
        planes[3, k] = height * w - v


@cached_njit()
def range_interval(
    ax: float, ay: float, bx: float, by: float, cx: float, cy: float, max_distance: float
) -> tuple[bool, float, float]:
    """``(in_range, r0, r1)``: the parameters ``t`` of segment ``a + t (b - a)`` within
    ``max_distance`` of ``(cx, cy)`` (the range-disc part of
    ``geometry.visibility.clip_segments``; it does not depend on the head angles)."""
    dx, dy = bx - ax, by - ay
    rx, ry = ax - cx, ay - cy
    qa = dx * dx + dy * dy
    qb = 2 * (rx * dx + ry * dy)
    qc = rx * rx + ry * ry - max_distance**2
    if qa < 1e-18:
        return qc <= 0.0, 0.0, 1.0
    disc = qb * qb - 4 * qa * qc
    sq = math.sqrt(max(disc, 0.0))
    return disc >= 0.0, (-qb - sq) / (2 * qa), (-qb + sq) / (2 * qa)


@cached_njit()
def clip_visible(
    ax: float, ay: float, bx: float, by: float, planes: np.ndarray, r0: float, r1: float
) -> bool:
    """Whether the part ``[r0, r1]`` of segment ``a b`` meets all image half-planes
    (Cyrus-Beck, as ``geometry.visibility.clip_segments``, then ``t0 <= t1``)."""
    t0, t1 = 0.0, 1.0
    for p in range(planes.shape[0]):
        fa = planes[p, 0] * ax + planes[p, 1] * ay + planes[p, 2]
        fb = planes[p, 0] * bx + planes[p, 1] * by + planes[p, 2]
        if fa < 0.0 and fb < 0.0:
            return False
        if fa < 0.0 and fb >= 0.0:
            t0 = max(t0, fa / (fa - fb))
        elif fb < 0.0 and fa >= 0.0:
            t1 = min(t1, fa / (fa - fb))
    return max(t0, r0) <= min(t1, r1)


@cached_njit()
def ball_in_image(
    bx: float, by: float, radius: float, x: float, y: float, rot: np.ndarray, cam: CameraModel
) -> bool:
    """Whether the ball centre projects into the image of the :class:`CameraModel` ``cam`` at
    ``(x, y)`` turned by ``rot`` (as ``geometry.visibility.ball_visible``)."""
    focal, width, height, cam_height = cam
    r0, r1, r2 = bx - x, by - y, radius - cam_height
    p0 = rot[0, 0] * r0 + rot[0, 1] * r1 + rot[0, 2] * r2
    p1 = rot[1, 0] * r0 + rot[1, 1] * r1 + rot[1, 2] * r2
    depth = rot[2, 0] * r0 + rot[2, 1] * r1 + rot[2, 2] * r2
    if not depth > 0.0:
        return False
    u: float = focal * p0 / depth + width / 2
    v: float = focal * p1 / depth + height / 2
    return u >= 0.0 and u <= width and v >= 0.0 and v <= height


@cached_njit()
def visible_landmarks(
    segments: np.ndarray,
    max_distance: np.ndarray,
    x: float,
    y: float,
    planes: np.ndarray,
    out: np.ndarray,
) -> None:
    """Which landmarks (K,) one camera at ``(x, y)`` sees, into ``out``: within each one's
    ``max_distance`` and inside the image's half-planes ``planes`` (:func:`image_halfplanes`)."""
    for k in range(segments.shape[0]):
        ax, ay = segments[k, 0, 0], segments[k, 0, 1]
        bx, by = segments[k, 1, 0], segments[k, 1, 1]
        ok, r0, r1 = range_interval(ax, ay, bx, by, x, y, max_distance[k])
        out[k] = ok and clip_visible(ax, ay, bx, by, planes, r0, r1)


@cached_njit()
def visibility_kernel(
    segments: np.ndarray,
    max_distance: np.ndarray,
    poses: np.ndarray,
    pans: np.ndarray,
    tilts: np.ndarray,
    cam: tuple[float, ...],
) -> np.ndarray:
    """Visible mask (N, K) of the landmarks for N cameras (``cam``: the fields of a
    :class:`CameraModel`)."""
    cam = CameraModel(*cam)
    n, n_lm = poses.shape[0], segments.shape[0]
    out = np.zeros((n, n_lm), dtype=np.bool_)
    rot = np.empty((3, 3))
    planes = np.empty((4, 3))
    for i in range(n):
        camera_rotation(poses[i, 2] + pans[i], tilts[i], rot)
        image_halfplanes(poses[i, 0], poses[i, 1], rot, cam, planes)
        visible_landmarks(segments, max_distance, poses[i, 0], poses[i, 1], planes, out[i])
    return out


@cached_njit()
def ball_kernel(
    balls: np.ndarray,
    poses: np.ndarray,
    pans: np.ndarray,
    tilts: np.ndarray,
    cam: tuple[float, ...],
    radius: float,
) -> np.ndarray:
    """Ball-visible flags (N,) for N cameras (``cam``: the fields of a
    :class:`CameraModel`)."""
    cam = CameraModel(*cam)
    out = np.zeros(poses.shape[0], dtype=np.bool_)
    rot = np.empty((3, 3))
    for i in range(poses.shape[0]):
        camera_rotation(poses[i, 2] + pans[i], tilts[i], rot)
        out[i] = ball_in_image(balls[i, 0], balls[i, 1], radius, poses[i, 0], poses[i, 1], rot, cam)
    return out


def _per_camera(values: ArrayLike, n: int) -> np.ndarray:
    """``values`` as a contiguous float64 array of length ``n`` (scalars repeated)."""
    out = np.ascontiguousarray(values, dtype=np.float64)
    return out if out.shape == (n,) else np.ascontiguousarray(np.broadcast_to(out, n))


def _cameras(
    pose: ArrayLike, pan: ArrayLike, tilt: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(pose (N, 3), pan (N,), tilt (N,))`` as contiguous float64 arrays."""
    pose = np.ascontiguousarray(np.atleast_2d(pose), dtype=np.float64)
    n = len(pose)
    return pose, _per_camera(pan, n), _per_camera(tilt, n)


def visible_mask(
    landmarks: LandmarkSet, pose: ArrayLike, pan: ArrayLike, tilt: ArrayLike, cam: CameraConfig
) -> np.ndarray:
    """Compiled :func:`~activevision.geometry.visibility.visible_landmarks` ``.visible``:
    (N, K) bool for N cameras (no measured points; use the NumPy version for those)."""
    return visibility_kernel(
        landmarks.segments, landmarks.max_distance, *_cameras(pose, pan, tilt), camera_fields(cam)
    )


def ball_visible_mask(
    ball_xy: ArrayLike,
    pose: ArrayLike,
    pan: ArrayLike,
    tilt: ArrayLike,
    cam: CameraConfig,
    ball_radius: float,
) -> np.ndarray:
    """Compiled :func:`~activevision.geometry.visibility.ball_visible`: (N,) bool."""
    poses, pans, tilts = _cameras(pose, pan, tilt)
    n = len(poses)
    balls = np.ascontiguousarray(ball_xy, dtype=np.float64)
    if balls.shape != (n, 2):
        balls = np.ascontiguousarray(np.broadcast_to(balls, (n, 2)))
    return ball_kernel(balls, poses, pans, tilts, camera_fields(cam), ball_radius)
