"""Which landmarks and whether the ball a camera sees; exactly consistent with the renderer.

A landmark is visible when part of it lies inside the image (projected onto the ground,
the image is the intersection of four half-planes, see :func:`image_halfplanes`) and within
its type's detection range of the robot. Its measured point is the point of that visible
part closest to the robot; for point landmarks, the point itself. Occlusion is not
modelled (the field holds no other robots).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from activevision.geometry.camera import CameraConfig, image_halfplanes, project_points
from activevision.geometry.landmarks import LandmarkSet


@dataclass(frozen=True)
class Visibility:
    """Landmarks seen by N cameras."""

    visible: np.ndarray  #: (N, K) bool
    points: np.ndarray  #: (N, K, 2) measured ground point of each landmark (NaN if unseen)


def clip_segments(
    segments: np.ndarray, halfplanes: np.ndarray, centre: np.ndarray, max_distance: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Parameter interval ``[t0, t1]`` of each segment ``a + t (b - a)``, ``t`` in [0, 1],
    inside all half-planes and within ``max_distance`` of ``centre``.

    Args:
        segments: (K, 2, 2); halfplanes: (N, P, 3); centre: (N, 2); max_distance: (K,).

    Returns:
        ``(t0, t1)`` each (N, K); the clipped part is empty where ``t0 > t1``.
    """
    a, b = segments[:, 0], segments[:, 1]
    f_a = np.einsum("npj,kj->nkp", halfplanes[..., :2], a) + halfplanes[:, None, :, 2]
    f_b = np.einsum("npj,kj->nkp", halfplanes[..., :2], b) + halfplanes[:, None, :, 2]
    # Cyrus-Beck: each half-plane bounds t from below (entering) or above (leaving).
    with np.errstate(divide="ignore", invalid="ignore"):
        t_cross = f_a / (f_a - f_b)
    lower = np.where((f_a < 0) & (f_b >= 0), t_cross, 0.0)
    upper = np.where((f_b < 0) & (f_a >= 0), t_cross, 1.0)
    outside = ((f_a < 0) & (f_b < 0)).any(axis=-1)
    t0, t1 = lower.max(axis=-1), upper.min(axis=-1)

    # Range disc: |a + t d - c|^2 <= r^2, a quadratic in t.
    d = b - a
    rel = a[None] - centre[:, None, :]
    qa = np.sum(d * d, axis=-1)[None]
    qb = 2 * np.sum(rel * d[None], axis=-1)
    qc = np.sum(rel * rel, axis=-1) - max_distance[None] ** 2
    disc = qb * qb - 4 * qa * qc
    degenerate = qa < 1e-18
    sq = np.sqrt(np.maximum(disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        r0 = np.where(degenerate, 0.0, (-qb - sq) / (2 * qa))
        r1 = np.where(degenerate, 1.0, (-qb + sq) / (2 * qa))
    in_range = np.where(degenerate, qc <= 0, disc >= 0)
    t0 = np.maximum(t0, r0)
    t1 = np.minimum(t1, r1)
    empty = outside | ~in_range
    return np.where(empty, np.inf, t0), np.where(empty, -np.inf, t1)


def closest_points(
    segments: np.ndarray, centre: np.ndarray, t0: np.ndarray, t1: np.ndarray
) -> np.ndarray:
    """Point of each clipped segment ``[t0, t1]`` closest to ``centre``: (N, K, 2)."""
    a, b = segments[:, 0], segments[:, 1]
    d = b - a
    qa = np.sum(d * d, axis=-1)
    t_star = np.sum((centre[:, None, :] - a[None]) * d[None], axis=-1) / np.maximum(qa, 1e-18)
    t = np.clip(t_star, t0, t1)
    points: np.ndarray = a[None] + t[..., None] * d[None]
    return points


def visible_landmarks(
    landmarks: LandmarkSet,
    pose: npt.ArrayLike,
    pan: npt.ArrayLike,
    tilt: npt.ArrayLike,
    cam: CameraConfig,
) -> Visibility:
    """Landmarks each of N cameras sees, and their measured ground points."""
    pose = np.atleast_2d(np.asarray(pose, float))
    pan = np.broadcast_to(np.asarray(pan, float), pose.shape[:1])
    tilt = np.broadcast_to(np.asarray(tilt, float), pose.shape[:1])
    planes = image_halfplanes(pose, pan, tilt, cam)
    t0, t1 = clip_segments(landmarks.segments, planes, pose[:, :2], landmarks.max_distance)
    visible = t0 <= t1
    points = closest_points(
        landmarks.segments, pose[:, :2], np.where(visible, t0, 0.0), np.where(visible, t1, 1.0)
    )
    points = np.where(visible[..., None], points, np.nan)
    return Visibility(visible=visible, points=points)


def ball_visible(
    ball_xy: npt.ArrayLike,
    pose: npt.ArrayLike,
    pan: npt.ArrayLike,
    tilt: npt.ArrayLike,
    cam: CameraConfig,
    ball_radius: float,
) -> np.ndarray:
    """Whether each camera sees the ball: its centre ``(x, y, radius)`` projects inside the
    image (so at least about half of the ball is in view). ``ball_xy``: (N, 2) or (2,)."""
    pose = np.atleast_2d(np.asarray(pose, float))
    ball = np.broadcast_to(np.asarray(ball_xy, float), (len(pose), 2))
    centre = np.concatenate([ball, np.full((len(pose), 1), ball_radius)], axis=-1)[:, None, :]
    _, _, inside = project_points(centre, pose, pan, tilt, cam)
    return inside[:, 0]
