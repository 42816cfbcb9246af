"""The landmark detector of the match: which landmarks in view are detected this tick, what
it measures of them, and the occasional false detection. Compiled, over N robots."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from activevision.geometry.angles import wrap_angle as wrap
from activevision.localisation.kernels import expected_rb


@njit(cache=True)
def segment_distance(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    """Distance from ``p`` to the segment ``a``-``b`` (a point when ``a == b``)."""
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0.0 else min(max(((px - ax) * dx + (py - ay) * dy) / length2, 0.0), 1.0)
    return math.hypot(ax + t * dx - px, ay + t * dy - py)


@njit(cache=True)
def detect_kernel(
    visible: np.ndarray,
    poses: np.ndarray,
    pans: np.ndarray,
    segments: np.ndarray,
    max_distance: np.ndarray,
    types: np.ndarray,
    noise: np.ndarray,
    point_ids: np.ndarray,
    miss: np.ndarray,
    normals: np.ndarray,
    false_draw: np.ndarray,
    rates: tuple[float, float, float, float],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Detections of N robots.

    ``visible`` (N, K) bool: landmarks in view (and not hidden) from the true ``poses`` (N, 3)
    with head pans ``pans`` (N,). A visible landmark at distance ``r`` (to its closest point)
    is detected when ``miss[n, k] < near + (far - near) * min(r / max_distance, 1)``; it
    measures its true ``(range, bearing)`` (``localisation.ukf`` models) plus the UKF's own
    noise at that range (``normals[n, k]`` (2,) standard normals, ``noise`` (T, 3) the
    per-type table). ``false_draw[n]`` (4,) uniforms: a false detection when ``u0 <
    false_rate``, of point landmark ``point_ids[int(u1 P)]`` at range 0.5-4 m and a bearing
    inside the image (``half_fov``). ``rates = (near, far, false_rate, half_fov)``.

    Returns ``(ids (N, K + 1) int64, padded with -1, closest first, a false detection last;
    z (N, K + 1, 2); count (N,))``.
    """
    near, far, false_rate, half_fov = rates
    n_robots, n_lm = visible.shape
    ids = np.full((n_robots, n_lm + 1), -1, dtype=np.int64)
    z = np.zeros((n_robots, n_lm + 1, 2))
    count = np.zeros(n_robots, dtype=np.int64)
    ranges = np.empty(n_lm)
    for n in range(n_robots):
        px, py, pth = poses[n, 0], poses[n, 1], poses[n, 2]
        found = 0
        for k in range(n_lm):
            if not visible[n, k]:
                continue
            ax, ay = segments[k, 0, 0], segments[k, 0, 1]
            bx, by = segments[k, 1, 0], segments[k, 1, 1]
            r = segment_distance(px, py, ax, ay, bx, by)
            if not miss[n, k] < near + (far - near) * min(r / max_distance[k], 1.0):
                continue
            zr, zb = expected_rb(px, py, pth, ax, ay, bx, by)
            t = types[k]
            sr = noise[t, 0] + noise[t, 1] * abs(zr)
            ids[n, found] = k
            ranges[found] = r
            z[n, found, 0] = zr + sr * normals[n, k, 0]
            z[n, found, 1] = wrap(zb + noise[t, 2] * normals[n, k, 1])
            found += 1
        order = np.argsort(ranges[:found], kind="mergesort")  # closest first, as Algorithm 1
        ids[n, :found] = ids[n, :found][order]
        z[n, :found] = z[n, :found][order]
        if false_draw[n, 0] < false_rate and point_ids.shape[0] > 0:
            k = point_ids[min(int(false_draw[n, 1] * point_ids.shape[0]), point_ids.shape[0] - 1)]
            ids[n, found] = k
            z[n, found, 0] = 0.5 + 3.5 * false_draw[n, 2]
            z[n, found, 1] = wrap(pans[n] + (2.0 * false_draw[n, 3] - 1.0) * half_fov)
            found += 1
        count[n] = found
    return ids, z, count
