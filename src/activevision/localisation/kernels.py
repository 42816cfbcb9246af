"""Compiled (numba) inner loops of the best-viewpoint search.

Scalar re-implementations of exactly what the NumPy reference does -- the camera's image
half-planes and Cyrus-Beck clipping of :mod:`activevision.geometry.visibility`, the ball test
of :func:`activevision.geometry.visibility.ball_visible`, and :func:`ukf_update` -- written
operation for operation in the same order, so the visibility masks agree exactly and the
entropies to rounding (tests/localisation/test_kernels.py checks both). Nothing here is
public API; :mod:`activevision.localisation.viewpoint` wraps it.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from activevision.geometry.kernels import (
    ball_in_image,
    camera_rotation,
    clip_visible,
    image_halfplanes,
    range_interval,
)

PI = math.pi
TWO_PI = 2.0 * math.pi
LOG_2PIE = math.log(2.0 * math.pi * math.e)

#: error codes written by :func:`search_kernel`
OK = 0
NOT_PD = 1


@njit(cache=True)
def wrap(a):
    """``a`` wrapped to ``(-pi, pi]`` (same arithmetic as ``angles.wrap_angle``)."""
    w = PI - ((PI - a) % TWO_PI)
    if w <= -PI:
        w += TWO_PI
    return w


@njit(cache=True)
def chol3(A, L):
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


@njit(cache=True)
def point_rb(px, py, pth, ax, ay):
    """Range and bearing of the point ``a`` from pose ``(px, py, pth)``."""
    ex, ey = ax - px, ay - py
    return math.hypot(ex, ey), wrap(math.atan2(ey, ex) - pth)


@njit(cache=True)
def unit_normal(ax, ay, bx, by):
    dx, dy = bx - ax, by - ay
    length = math.hypot(dx, dy)
    return -dy / length, dx / length


@njit(cache=True)
def expected_rb(px, py, pth, ax, ay, bx, by):
    """What pose ``(px, py, pth)`` measures of a landmark (as ``ukf.hx_range_bearing`` with
    the default normal): a point's range-bearing, a line's polar form towards the line."""
    if ax == bx and ay == by:
        return point_rb(px, py, pth, ax, ay)
    nx, ny = unit_normal(ax, ay, bx, by)
    if not nx * (ax - px) + ny * (ay - py) >= 0.0:
        nx, ny = -nx, -ny
    return nx * (ax - px) + ny * (ay - py), wrap(math.atan2(ny, nx) - pth)


@njit(cache=True)
def ukf_update_rb(x, P, z0, z1, ax, ay, bx, by, var_r, var_b, Wm, Wc, n_lambda, L, sig, hz):
    """One UKF range-bearing update of ``x`` (3,) and ``P`` (3, 3) in place (as
    ``ukf.ukf_update``). ``L``, ``sig`` (7, 3), ``hz`` (7, 2) are scratch. False if a
    covariance is not positive definite."""
    A = n_lambda * P
    if not chol3(A, L):
        return False
    for j in range(3):
        sig[0, j] = x[j]
        for k in range(3):
            sig[k + 1, j] = x[j] + L[j, k]
            sig[k + 4, j] = x[j] - L[j, k]
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
        return False
    i00, i01, i11 = s11 / det, -s01 / det, s00 / det
    k00, k01 = c00 * i00 + c01 * i01, c00 * i01 + c01 * i11
    k10, k11 = c10 * i00 + c11 * i01, c10 * i01 + c11 * i11
    k20, k21 = c20 * i00 + c21 * i01, c20 * i01 + c21 * i11
    y0, y1 = z0 - zr, wrap(z1 - zb)
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
    return chol3(P, L)


@njit(cache=True)
def plan_start(mx, my, mth, segments, max_distance, types, noise_table, zs, var_r, var_b,
               in_range, r_lo, r_hi):
    """Planning for one believed pose: the expected detection ``z = h(mu)`` of every
    landmark, its noise and range interval, written into the given rows; returns the
    landmark order (closest first, ties by id)."""
    for k in range(segments.shape[0]):
        r, b = expected_rb(
            mx,
            my,
            mth,
            segments[k, 0, 0],
            segments[k, 0, 1],
            segments[k, 1, 0],
            segments[k, 1, 1],
        )
        zs[k, 0], zs[k, 1] = r, b
        in_range[k], r_lo[k], r_hi[k] = range_interval(
            segments[k, 0, 0],
            segments[k, 0, 1],
            segments[k, 1, 0],
            segments[k, 1, 1],
            mx,
            my,
            max_distance[k],
        )
        t = types[k]
        sr = noise_table[t, 0] + noise_table[t, 1] * r
        var_r[k] = sr * sr
        var_b[k] = noise_table[t, 2] * noise_table[t, 2]
    return np.argsort(zs[:, 0], kind="mergesort")


@njit(cache=True)
def plan_starts(means, segments, max_distance, types, noise_table):
    """:func:`plan_start` for every start: ``(zs (N, K, 2), var_r, var_b, in_range, r_lo,
    r_hi, order)``, each (N, K) but ``zs``."""
    n_starts, n_lm = means.shape[0], segments.shape[0]
    zs = np.empty((n_starts, n_lm, 2))
    var_r = np.empty((n_starts, n_lm))
    var_b = np.empty((n_starts, n_lm))
    in_range = np.empty((n_starts, n_lm), dtype=np.bool_)
    r_lo = np.empty((n_starts, n_lm))
    r_hi = np.empty((n_starts, n_lm))
    order = np.empty((n_starts, n_lm), dtype=np.int64)
    for s in range(n_starts):
        order[s] = plan_start(
            means[s, 0],
            means[s, 1],
            means[s, 2],
            segments,
            max_distance,
            types,
            noise_table,
            zs[s],
            var_r[s],
            var_b[s],
            in_range[s],
            r_lo[s],
            r_hi[s],
        )
    return zs, var_r, var_b, in_range, r_lo, r_hi, order


@njit(cache=True)
def search_block(
    block,
    n_blocks,
    means,
    covs,
    balls,
    segments,
    pans,
    tilts,
    focal,
    width,
    height,
    cam_height,
    ball_radius,
    Wm,
    Wc,
    n_lambda,
    plan,
    entropies,
    ball_vis,
    visible,
    post,
    errors,
    ball_views_only,
):
    """Block ``block`` of ``n_blocks`` contiguous blocks of the N x V (start, view) pairs:
    ball test, visible landmarks and the sequential UKF updates of each pair (Algorithm 1,
    lines 3-8), written into the output arrays. Pairs are independent, so blocks can run on
    different threads. With ``ball_views_only``, pairs whose view misses the ball (never a
    goal) skip the filter: entropy and posterior NaN, no visible landmarks."""
    zs, var_r, var_b, in_range, r_lo, r_hi, order = plan
    n_views, n_lm = pans.shape[0], segments.shape[0]
    n_items = means.shape[0] * n_views
    rot = np.empty((3, 3))
    planes = np.empty((4, 3))
    L = np.empty((3, 3))
    sig = np.empty((7, 3))
    hz = np.empty((7, 2))
    x = np.empty(3)
    for item in range(block * n_items // n_blocks, (block + 1) * n_items // n_blocks):
        s = item // n_views
        v = item - s * n_views
        mx, my, mth = means[s, 0], means[s, 1], means[s, 2]
        camera_rotation(mth + pans[v], tilts[v], rot)
        image_halfplanes(mx, my, rot, focal, width, height, cam_height, planes)
        ball_vis[s, v] = ball_in_image(
            balls[s, 0],
            balls[s, 1],
            ball_radius,
            mx,
            my,
            rot,
            focal,
            width,
            height,
            cam_height,
        )
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
            if not (
                in_range[s, k]
                and clip_visible(
                    segments[k, 0, 0],
                    segments[k, 0, 1],
                    segments[k, 1, 0],
                    segments[k, 1, 1],
                    planes,
                    r_lo[s, k],
                    r_hi[s, k],
                )
            ):
                continue
            visible[s, v, k] = True
            ok = ukf_update_rb(
                x,
                P,
                zs[s, k, 0],
                zs[s, k, 1],
                segments[k, 0, 0],
                segments[k, 0, 1],
                segments[k, 1, 0],
                segments[k, 1, 1],
                var_r[s, k],
                var_b[s, k],
                Wm,
                Wc,
                n_lambda,
                L,
                sig,
                hz,
            )
        if ok:
            entropies[s, v] = 0.5 * (3 * LOG_2PIE) + math.log(L[0, 0] * L[1, 1] * L[2, 2])
        else:
            entropies[s, v] = np.nan
            errors[s, v] = NOT_PD


@njit(cache=True)
def search_outputs(n_starts, n_views, n_lm):
    """Empty ``(entropies, ball_visible, visible, posteriors, errors)`` of a search."""
    return (
        np.empty((n_starts, n_views)),
        np.zeros((n_starts, n_views), dtype=np.bool_),
        np.zeros((n_starts, n_views, n_lm), dtype=np.bool_),
        np.empty((n_starts, n_views, 3, 3)),
        np.zeros((n_starts, n_views), dtype=np.int8),
    )


@njit(cache=True)
def search_kernel(
    means,
    covs,
    balls,
    segments,
    max_distance,
    types,
    noise_table,
    pans,
    tilts,
    focal,
    width,
    height,
    cam_height,
    ball_radius,
    Wm,
    Wc,
    n_lambda,
    ball_views_only,
):
    """Algorithm 1 for N starts and V candidate views, on the calling thread.

    Returns ``(entropies (N, V), ball_visible (N, V), visible (N, V, K), posterior covariances
    (N, V, 3, 3), errors (N, V))``; ``errors`` is :data:`NOT_PD` where a covariance lost
    positive definiteness (the caller raises). ``ball_views_only``: see :func:`search_block`.
    """
    out = search_outputs(means.shape[0], pans.shape[0], segments.shape[0])
    plan = plan_starts(means, segments, max_distance, types, noise_table)
    search_block(0, 1, means, covs, balls, segments, pans, tilts, focal, width, height,
                 cam_height, ball_radius, Wm, Wc, n_lambda, plan, *out, ball_views_only)
    return out


@njit(cache=True, parallel=True)
def search_kernel_parallel(
    means,
    covs,
    balls,
    segments,
    max_distance,
    types,
    noise_table,
    pans,
    tilts,
    focal,
    width,
    height,
    cam_height,
    ball_radius,
    Wm,
    Wc,
    n_lambda,
    ball_views_only,
    n_blocks,
):
    """:func:`search_kernel` with the (start, view) pairs split into ``n_blocks`` blocks
    spread over the numba threads (identical results)."""
    out = search_outputs(means.shape[0], pans.shape[0], segments.shape[0])
    plan = plan_starts(means, segments, max_distance, types, noise_table)
    n_blocks = max(1, min(n_blocks, means.shape[0] * pans.shape[0]))
    for block in prange(n_blocks):
        search_block(block, n_blocks, means, covs, balls, segments, pans, tilts, focal, width,
                     height, cam_height, ball_radius, Wm, Wc, n_lambda, plan, *out,
                     ball_views_only)
    return out
