"""Compiled (numba) inner loops of the best-viewpoint search.

Scalar re-implementations of exactly what the NumPy reference does -- the camera's image
half-planes and Cyrus-Beck clipping of :mod:`activevision.geometry.visibility`, the ball test
of :func:`activevision.geometry.visibility.ball_visible`, and :func:`ukf_update` -- written
operation for operation in the same order, so the visibility masks agree exactly and the
entropies to rounding (tests/localisation/test_viewpoint.py checks both). Nothing here is
public API; :mod:`activevision.localisation.viewpoint` wraps it.

The kernels take small typed bundles (numba namedtuples, below) instead of long argument
lists; the entry points :func:`search_kernel` and :func:`search_kernel_parallel` are handed
each as a plain tuple of its fields (``tuple(bundle)``; numba types a plain tuple in C but a
namedtuple in Python, which costs microseconds per call) and rebuild it inside. Headings are
wrapped by :func:`activevision.geometry.angles.wrap_angle`, the package's one convention.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import prange

from activevision.geometry.angles import wrap_angle as wrap
from activevision.geometry.jit import cached_njit
from activevision.geometry.kernels import (
    CameraModel,
    ball_in_image,
    camera_rotation,
    clip_visible,
    image_halfplanes,
    range_interval,
)
from activevision.localisation.bundles import (
    Landmarks,
    Plan,
    SearchOutput,
    SigmaWeights,
    Starts,
    UKFScratch,
    Views,
)

LOG_2PIE = math.log(2.0 * math.pi * math.e)

#: A bundle as the entry points take it from Python: the plain tuple of its fields
#: (``tuple(bundle)``), rebuilt into the namedtuple inside. (To mypy, ``tuple()`` of a
#: namedtuple is a homogeneous tuple; the field types are checked where the bundle is made.)
Fields = tuple[Any, ...]

#: error codes written by :func:`search_kernel` and returned by :func:`ukf_update_rb`
OK = 0
NOT_PD = 1
#: :func:`ukf_update_rb` left the belief as it was: the detection failed the innovation gate
GATED = 2


@cached_njit()
def chol3(A: np.ndarray, L: np.ndarray) -> bool:
    """Lower Cholesky factor of the 3x3 ``A`` into ``L``; False if ``A`` is not PD."""
    d0 = A[0, 0]
    if not d0 > 0.0:
        return False
    l00 = math.sqrt(d0)
    l10 = A[1, 0] / l00
    l20 = A[2, 0] / l00
    d1 = A[1, 1] - l10 * l10
    if not d1 > 0.0:
        return False
    l11 = math.sqrt(d1)
    l21 = (A[2, 1] - l20 * l10) / l11
    d2 = A[2, 2] - l20 * l20 - l21 * l21
    if not d2 > 0.0:
        return False
    L[0, 0], L[0, 1], L[0, 2] = l00, 0.0, 0.0
    L[1, 0], L[1, 1], L[1, 2] = l10, l11, 0.0
    L[2, 0], L[2, 1], L[2, 2] = l20, l21, math.sqrt(d2)
    return True


@cached_njit()
def point_rb(px: float, py: float, pth: float, ax: float, ay: float) -> tuple[float, float]:
    """Range and bearing of the point ``a`` from pose ``(px, py, pth)``."""
    ex, ey = ax - px, ay - py
    return math.hypot(ex, ey), wrap(math.atan2(ey, ex) - pth)


@cached_njit()
def unit_normal(ax: float, ay: float, bx: float, by: float) -> tuple[float, float]:
    dx, dy = bx - ax, by - ay
    length = math.hypot(dx, dy)
    return -dy / length, dx / length


@cached_njit()
def expected_rb(
    px: float, py: float, pth: float, ax: float, ay: float, bx: float, by: float
) -> tuple[float, float]:
    """What pose ``(px, py, pth)`` measures of a landmark (as ``ukf.hx_range_bearing`` with
    the default normal): a point's range-bearing, a line's polar form towards the line."""
    if ax == bx and ay == by:
        return point_rb(px, py, pth, ax, ay)
    nx, ny = unit_normal(ax, ay, bx, by)
    if not nx * (ax - px) + ny * (ay - py) >= 0.0:
        nx, ny = -nx, -ny
    return nx * (ax - px) + ny * (ay - py), wrap(math.atan2(ny, nx) - pth)


@cached_njit()
def sigma_points3(x: np.ndarray, L: np.ndarray, sig: np.ndarray) -> None:
    """Merwe's 7 sigma points of a pose into ``sig`` (7, 3): ``x``, ``x + L[:, k]``,
    ``x - L[:, k]`` (``L``: the Cholesky factor of ``(n + lambda) P``)."""
    for j in range(3):
        sig[0, j] = x[j]
        for k in range(3):
            sig[k + 1, j] = x[j] + L[j, k]
            sig[k + 4, j] = x[j] - L[j, k]


@cached_njit()
def ukf_update_rb(
    x: np.ndarray,
    P: np.ndarray,
    z: tuple[float, float],
    segment: tuple[float, float, float, float],
    noise: tuple[float, float],
    weights: SigmaWeights,
    scratch: UKFScratch,
    gate: float = math.inf,
) -> tuple[int, float]:
    """One UKF range-bearing update of ``x`` (3,) and ``P`` (3, 3) in place (as
    ``ukf.ukf_update``) by the detection ``z = (range, bearing)`` of the landmark ``segment =
    (ax, ay, bx, by)`` with variances ``noise = (var_r, var_b)``, with the
    :class:`SigmaWeights` ``weights`` and the :class:`UKFScratch` ``scratch``.

    Returns ``(status, distance)``: the squared Mahalanobis distance of the innovation,
    ``y^T S^-1 y`` (NaN if not computed), and the status :data:`OK`, :data:`NOT_PD` if a
    covariance is not positive definite, or :data:`GATED` (nothing changed) when the
    distance exceeds ``gate`` (a chi-square quantile with 2 degrees of freedom: the standard
    validation gate against false detections; the search never gates)."""
    z0, z1 = z
    ax, ay, bx, by = segment
    var_r, var_b = noise
    Wm, Wc = weights.Wm, weights.Wc
    L, sig, hz = scratch
    A = weights.n_lambda * P
    if not chol3(A, L):
        return NOT_PD, math.nan
    sigma_points3(x, L, sig)
    point = ax == bx and ay == by
    nx = ny = phi = 0.0
    if not point:  # the line's normal, oriented as the detection (``ukf.line_normal``)
        nx, ny = unit_normal(ax, ay, bx, by)
        if not nx * math.cos(x[2] + z1) + ny * math.sin(x[2] + z1) >= 0.0:
            nx, ny = -nx, -ny
        phi = math.atan2(ny, nx)
    zr, sb, cb = 0.0, 0.0, 0.0
    for i in range(7):
        if point:
            r, b = point_rb(sig[i, 0], sig[i, 1], sig[i, 2], ax, ay)
        else:
            r = nx * (ax - sig[i, 0]) + ny * (ay - sig[i, 1])
            b = wrap(phi - sig[i, 2])
        hz[i, 0], hz[i, 1] = r, b
        zr += Wm[i] * r
        sb += Wm[i] * math.sin(b)
        cb += Wm[i] * math.cos(b)
    zb = wrap(math.atan2(sb, cb))
    s00, s01, s11 = var_r, 0.0, var_b
    c00 = c01 = c10 = c11 = c20 = c21 = 0.0
    for i in range(7):
        w = Wc[i]
        dr = hz[i, 0] - zr
        db = wrap(hz[i, 1] - zb)
        s00 += w * dr * dr
        s01 += w * dr * db
        s11 += w * db * db
        e0, e1, e2 = sig[i, 0] - x[0], sig[i, 1] - x[1], wrap(sig[i, 2] - x[2])
        c00 += w * e0 * dr
        c01 += w * e0 * db
        c10 += w * e1 * dr
        c11 += w * e1 * db
        c20 += w * e2 * dr
        c21 += w * e2 * db
    det = s00 * s11 - s01 * s01
    if not det > 0.0:
        return NOT_PD, math.nan
    i00, i01, i11 = s11 / det, -s01 / det, s00 / det
    y0, y1 = z0 - zr, wrap(z1 - zb)
    distance = y0 * (i00 * y0 + i01 * y1) + y1 * (i01 * y0 + i11 * y1)
    if distance > gate:
        return GATED, distance
    k00, k01 = c00 * i00 + c01 * i01, c00 * i01 + c01 * i11
    k10, k11 = c10 * i00 + c11 * i01, c10 * i01 + c11 * i11
    k20, k21 = c20 * i00 + c21 * i01, c20 * i01 + c21 * i11
    x[0] += k00 * y0 + k01 * y1
    x[1] += k10 * y0 + k11 * y1
    x[2] = wrap(x[2] + (k20 * y0 + k21 * y1))
    # P -= K S K^T, and K S = Pxz, so K S K^T = Pxz K^T (symmetric by construction)
    C = ((c00, c01), (c10, c11), (c20, c21))
    Kg = ((k00, k01), (k10, k11), (k20, k21))
    for i in range(3):
        for j in range(i + 1):
            v = P[i, j] - 0.5 * (
                C[i][0] * Kg[j][0] + C[i][1] * Kg[j][1] + C[j][0] * Kg[i][0] + C[j][1] * Kg[i][1]
            )
            P[i, j] = v
            P[j, i] = v
    return (OK if chol3(P, L) else NOT_PD), distance


@cached_njit()
def plan_start(s: int, means: np.ndarray, landmarks: Landmarks, plan: Plan) -> None:
    """Planning for start ``s`` (believed pose ``means[s]``): the expected detection ``z =
    h(mu)`` of every landmark, its noise and range interval, and the landmark order (closest
    first, ties by id), into row ``s`` of the :class:`Plan` ``plan``."""
    mx, my, mth = means[s, 0], means[s, 1], means[s, 2]
    segments, max_distance, types, noise = landmarks
    zs, var_r, var_b, in_range, r_lo, r_hi, order = plan  # (array fields: see search_block)
    for k in range(segments.shape[0]):
        ax, ay = segments[k, 0, 0], segments[k, 0, 1]
        bx, by = segments[k, 1, 0], segments[k, 1, 1]
        r, b = expected_rb(mx, my, mth, ax, ay, bx, by)
        zs[s, k, 0], zs[s, k, 1] = r, b
        in_range[s, k], r_lo[s, k], r_hi[s, k] = range_interval(
            ax, ay, bx, by, mx, my, max_distance[k]
        )
        t = types[k]
        sr = noise[t, 0] + noise[t, 1] * r
        var_r[s, k] = sr * sr
        var_b[s, k] = noise[t, 2] * noise[t, 2]
    order[s] = np.argsort(zs[s, :, 0], kind="mergesort")


@cached_njit()
def plan_starts(means: np.ndarray, hidden: np.ndarray, landmarks: Landmarks) -> Plan:
    """:func:`plan_start` for every start: the :class:`Plan`. A landmark ``hidden[s]`` from
    start ``s`` counts as out of range (never seen, whatever the view)."""
    n_starts, n_lm = means.shape[0], landmarks.segments.shape[0]
    plan = Plan(
        np.empty((n_starts, n_lm, 2)),
        np.empty((n_starts, n_lm)),
        np.empty((n_starts, n_lm)),
        np.empty((n_starts, n_lm), dtype=np.bool_),
        np.empty((n_starts, n_lm)),
        np.empty((n_starts, n_lm)),
        np.empty((n_starts, n_lm), dtype=np.int64),
    )
    for s in range(n_starts):
        plan_start(s, means, landmarks, plan)
        for k in range(n_lm):
            if hidden[s, k]:
                plan.in_range[s, k] = False
    return plan


@cached_njit()
def search_block(
    block: int,
    n_blocks: int,
    starts: Starts,
    landmarks: Landmarks,
    weights: SigmaWeights,
    views: Views,
    camera: CameraModel,
    plan: Plan,
    out: SearchOutput,
) -> None:
    """Block ``block`` of ``n_blocks`` contiguous blocks of the N x V (start, view) pairs:
    ball test, visible landmarks and the sequential UKF updates of each pair (Algorithm 1,
    lines 3-8), written into the :class:`SearchOutput` ``out``. Pairs are independent, so
    blocks can run on different threads. With ``views.ball_views_only``, pairs whose view
    misses the ball (never a goal) skip the filter: entropy and posterior NaN, no visible
    landmarks."""
    # Fields into locals once: reading an array field of a bundle counts a reference to it,
    # which costs in the inner loops.
    means, covs, balls, ball_radius, _ = starts
    segments = landmarks.segments
    pans, tilts, ball_views_only = views
    zs, var_r, var_b, in_range, r_lo, r_hi, order = plan
    entropies, ball_vis, visible, post, errors = out
    n_views, n_lm = pans.shape[0], segments.shape[0]
    n_items = means.shape[0] * n_views
    rot = np.empty((3, 3))
    planes = np.empty((4, 3))
    x = np.empty(3)
    scratch = UKFScratch(np.empty((3, 3)), np.empty((7, 3)), np.empty((7, 2)))
    L = scratch.L
    for item in range(block * n_items // n_blocks, (block + 1) * n_items // n_blocks):
        s = item // n_views
        v = item - s * n_views
        mx, my, mth = means[s, 0], means[s, 1], means[s, 2]
        camera_rotation(mth + pans[v], tilts[v], rot)
        image_halfplanes(mx, my, rot, camera, planes)
        ball_vis[s, v] = ball_in_image(balls[s, 0], balls[s, 1], ball_radius, mx, my, rot, camera)
        P = post[s, v]
        if ball_views_only and not ball_vis[s, v]:
            entropies[s, v] = np.nan
            P[:, :] = np.nan
            continue
        P[:, :] = covs[s]
        x[0], x[1], x[2] = mx, my, mth
        ok = chol3(P, L)
        for j in range(n_lm):
            k = order[s, j]
            if not ok:
                break
            ax, ay = segments[k, 0, 0], segments[k, 0, 1]
            bx, by = segments[k, 1, 0], segments[k, 1, 1]
            # (arguments written out: a star call here costs about 7% of the whole search)
            if not in_range[s, k]:
                continue
            if not clip_visible(ax, ay, bx, by, planes, r_lo[s, k], r_hi[s, k]):
                continue
            visible[s, v, k] = True
            ok = (
                ukf_update_rb(
                    x,
                    P,
                    (zs[s, k, 0], zs[s, k, 1]),
                    (ax, ay, bx, by),
                    (var_r[s, k], var_b[s, k]),
                    weights,
                    scratch,
                )[0]
                == OK
            )
        if ok:
            entropies[s, v] = 0.5 * (3 * LOG_2PIE) + math.log(L[0, 0] * L[1, 1] * L[2, 2])
        else:
            entropies[s, v] = np.nan
            errors[s, v] = NOT_PD


@cached_njit()
def search_outputs(n_starts: int, n_views: int, n_lm: int) -> SearchOutput:
    """An empty :class:`SearchOutput` of a search."""
    return SearchOutput(
        np.empty((n_starts, n_views)),
        np.zeros((n_starts, n_views), dtype=np.bool_),
        np.zeros((n_starts, n_views, n_lm), dtype=np.bool_),
        np.empty((n_starts, n_views, 3, 3)),
        np.zeros((n_starts, n_views), dtype=np.int8),
    )


@cached_njit()
def search_kernel(
    starts: Fields,
    landmarks: Fields,
    weights: Fields,
    views: Fields,
    camera: tuple[float, ...],
) -> SearchOutput:
    """Algorithm 1 for N starts and V candidate views, on the calling thread. Arguments: the
    fields of a :class:`Starts`, :class:`Landmarks`, :class:`SigmaWeights`, :class:`Views` and
    ``geometry.kernels.CameraModel``.

    Returns the :class:`SearchOutput`; its ``errors`` are :data:`NOT_PD` where a covariance
    lost positive definiteness (the caller raises)."""
    starts, landmarks, weights = Starts(*starts), Landmarks(*landmarks), SigmaWeights(*weights)
    views, camera = Views(*views), CameraModel(*camera)
    out = search_outputs(starts.means.shape[0], views.pans.shape[0], landmarks.segments.shape[0])
    plan = plan_starts(starts.means, starts.hidden, landmarks)
    search_block(0, 1, starts, landmarks, weights, views, camera, plan, out)
    return out


@cached_njit(parallel=True)
def search_kernel_parallel(
    starts: Fields,
    landmarks: Fields,
    weights: Fields,
    views: Fields,
    camera: tuple[float, ...],
    n_blocks: int,
) -> SearchOutput:
    """:func:`search_kernel` with the (start, view) pairs split into ``n_blocks`` blocks
    spread over the numba threads (identical results)."""
    # Every bundle is made by its class right here: numba's parfor lowering finds the class
    # of a namedtuple used in a prange body only from the call that made it.
    starts, landmarks, weights = Starts(*starts), Landmarks(*landmarks), SigmaWeights(*weights)
    views, camera = Views(*views), CameraModel(*camera)
    n_starts, n_views = starts.means.shape[0], views.pans.shape[0]
    out = SearchOutput(*search_outputs(n_starts, n_views, landmarks.segments.shape[0]))
    plan = Plan(*plan_starts(starts.means, starts.hidden, landmarks))
    n_blocks = max(1, min(n_blocks, n_starts * n_views))
    for block in prange(n_blocks):
        search_block(block, n_blocks, starts, landmarks, weights, views, camera, plan, out)
    return out
