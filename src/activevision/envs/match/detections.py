"""The landmark detector of the match: which landmarks in view are detected this tick, what
it measures of them, and the occasional false detection. Compiled, over N robots."""

from __future__ import annotations

import math

import numpy as np

from activevision.geometry.angles import wrap_angle as wrap
from activevision.geometry.jit import cached_njit
from activevision.localisation.kernels import expected_rb


@cached_njit()
def segment_distance(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    """Distance from ``p`` to the segment ``a``-``b`` (a point when ``a == b``)."""
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0.0 else min(max(((px - ax) * dx + (py - ay) * dy) / length2, 0.0), 1.0)
    return math.hypot(ax + t * dx - px, ay + t * dy - py)


@cached_njit()
def detect_one(
    pose: np.ndarray,
    pan: float,
    visible: np.ndarray,
    segments: np.ndarray,
    max_distance: np.ndarray,
    types: np.ndarray,
    noise: np.ndarray,
    point_ids: np.ndarray,
    miss: np.ndarray,
    normals: np.ndarray,
    false_draw: np.ndarray,
    rates: tuple[float, float, float, float],
    ids: np.ndarray,
    z: np.ndarray,
    ranges: np.ndarray,
) -> int:
    """One robot's detections into ``ids`` (K + 1,) (padded with -1) and ``z`` (K + 1, 2);
    returns their count.

    ``visible`` (K,) bool: landmarks in view (and not hidden) from the true ``pose`` (3,)
    with head pan ``pan``. A visible landmark at distance ``r`` (to its closest point) is
    detected when ``miss[k] < near + (far - near) * min(r / max_distance, 1)``; it measures
    its true ``(range, bearing)`` (``localisation.ukf`` models) plus the UKF's own noise at
    that range (``normals[k]`` (2,) standard normals, ``noise`` (T, 3) the per-type table).
    Detections come closest first (as Algorithm 1 takes them). ``false_draw`` (4,) uniforms:
    a false detection, last, when ``u0 < false_rate``: point landmark ``point_ids[int(u1
    P)]`` at range 0.5-4 m and a bearing inside the image (``half_fov``). ``rates = (near,
    far, false_rate, half_fov)``; ``ranges`` (K,) is scratch.
    """
    near, far, false_rate, half_fov = rates
    px, py, pth = pose[0], pose[1], pose[2]
    ids[:] = -1
    found = 0
    for k in range(visible.shape[0]):
        if not visible[k]:
            continue
        ax, ay = segments[k, 0, 0], segments[k, 0, 1]
        bx, by = segments[k, 1, 0], segments[k, 1, 1]
        r = segment_distance(px, py, ax, ay, bx, by)
        if not miss[k] < near + (far - near) * min(r / max_distance[k], 1.0):
            continue
        zr, zb = expected_rb(px, py, pth, ax, ay, bx, by)
        t = types[k]
        sr = noise[t, 0] + noise[t, 1] * abs(zr)
        ids[found] = k
        ranges[found] = r
        z[found, 0] = zr + sr * normals[k, 0]
        z[found, 1] = wrap(zb + noise[t, 2] * normals[k, 1])
        found += 1
    order = np.argsort(ranges[:found], kind="mergesort")
    ids[:found] = ids[:found][order]
    z[:found] = z[:found][order]
    if false_draw[0] < false_rate and point_ids.shape[0] > 0:
        k = point_ids[min(int(false_draw[1] * point_ids.shape[0]), point_ids.shape[0] - 1)]
        ids[found] = k
        z[found, 0] = 0.5 + 3.5 * false_draw[2]
        z[found, 1] = wrap(pan + (2.0 * false_draw[3] - 1.0) * half_fov)
        found += 1
    return found
