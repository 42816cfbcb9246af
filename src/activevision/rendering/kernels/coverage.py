"""Pixel coverage: the exact box filter of a half-plane, the column spans of convex
polygons on a row, and the per-row coverage of quads, the centre-circle ring and the ball
(see :mod:`activevision.rendering.kernels` for the method)."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from activevision.geometry.jit import cached_njit
from activevision.rendering.kernels.bundles import JIT, Params


class RingRow(NamedTuple):
    """One image row of the ring: ``g = (gx, gy, gz)``, the ground point of the ray through
    ``(u, v)`` relative to the ring centre, is affine in ``u``: ``g0 + u * d_u`` (``d_v``: its
    change per row, for the gradient); ``k_out``, ``k_in``: squared radii."""

    gx0: float
    gy0: float
    gz0: float
    dxu: float
    dxv: float
    dyu: float
    dyv: float
    dzu: float
    dzv: float
    k_out: float
    k_in: float


@cached_njit(**JIT)
def _halfplane_coverage(d: float, hi: float, lo: float, inv_2hi: float, inv_8hilo: float) -> float:
    """Fraction of a unit pixel inside a half-plane; ``d``: signed distance (px) of the pixel
    centre, ``hi >= lo``: half-widths of the pixel's projection onto the normal."""
    r = hi + lo
    if d >= r:
        return 1.0
    if d <= -r:
        return 0.0
    if d > hi - lo:
        t = r - d
        return 1.0 - t * t * inv_8hilo
    if d < lo - hi:
        t = r + d
        return t * t * inv_8hilo
    return 0.5 + d * inv_2hi


@cached_njit(**JIT)
def _coverage_at(d: float, n0: float, n1: float) -> float:
    """:func:`_halfplane_coverage` for a unit normal ``(n0, n1)`` known per pixel."""
    a = 0.5 * abs(n0)
    b = 0.5 * abs(n1)
    hi = max(a, b)
    lo = max(min(a, b), 1e-7)
    return _halfplane_coverage(d, hi, lo, 0.5 / hi, 0.125 / (hi * lo))


@cached_njit(**JIT)
def fully_inside(edges: np.ndarray, n_edges: int, u: float, v: float) -> bool:
    """Whether the pixel centred at ``(u, v)`` lies entirely inside every edge."""
    for e in range(n_edges):
        if edges[e, 0] * u + edges[e, 1] * v + edges[e, 2] < edges[e, 3] + edges[e, 4]:
            return False
    return True


@cached_njit(**JIT)
def span(
    edges: np.ndarray, n_edges: int, v: float, threshold: float, width: int
) -> tuple[int, int]:
    """Columns ``[lo, hi)`` of row centre ``v`` whose pixel centres are at signed distance
    greater than ``threshold * r`` from every edge (``r``: the pixel's half-extent along the
    edge normal). ``threshold = -1``: pixels touching the polygon; ``+1``: pixels fully
    inside it."""
    lo = -1.0
    hi = width + 1.0
    for e in range(n_edges):
        l0 = edges[e, 0]
        c = edges[e, 1] * v + edges[e, 2]
        t = threshold * (edges[e, 3] + edges[e, 4])
        # l0 * (i + 0.5) + c > t
        if l0 > 1e-12:
            lo = max(lo, (t - c) * edges[e, 7] - 0.5)
        elif l0 < -1e-12:
            hi = min(hi, (t - c) * edges[e, 7] - 0.5)
        elif c <= t:
            return 0, 0
    lo = min(max(lo, -1.0), width + 1.0)
    hi = min(max(hi, -1.0), width + 1.0)
    i0 = max(math.floor(lo) + 1, 0)
    i1 = min(math.ceil(hi), width)
    if i1 < i0:
        i1 = i0
    return i0, i1


@cached_njit(**JIT)
def _edge_coverage(edge: np.ndarray, u: float, v: float) -> float:
    d = edge[0] * u + edge[1] * v + edge[2]
    return _halfplane_coverage(d, edge[3], edge[4], edge[5], edge[6])


@cached_njit(**JIT)
def quad_coverage(edges: np.ndarray, u: float, v: float) -> float:
    """Fraction of the pixel centred at ``(u, v)`` covered by a quad: product of its two
    bands, each ``F1 + F2 - 1``."""
    band_a = _edge_coverage(edges[0], u, v) + _edge_coverage(edges[2], u, v) - 1.0
    if band_a <= 0.0:
        return 0.0
    band_b = _edge_coverage(edges[1], u, v) + _edge_coverage(edges[3], u, v) - 1.0
    if band_b <= 0.0:
        return 0.0
    return band_a * band_b


@cached_njit(**JIT)
def paint_quad_pixels(
    edges: np.ndarray, v: float, i_start: int, i_end: int, paint: np.ndarray
) -> None:
    """Max-combine a quad's coverage of columns ``[i_start, i_end)`` of row ``v`` into
    ``paint``."""
    for i in range(i_start, i_end):
        c = quad_coverage(edges, i + 0.5, v)
        if c > paint[i]:
            paint[i] = c


@cached_njit(**JIT)
def _ring_pixels(i_start: int, i_end: int, g: RingRow, paint: np.ndarray) -> None:
    """The per-pixel part of :func:`ring_row` for columns ``[i_start, i_end)``; ``g``: the
    row's :class:`RingRow`."""
    gx0, gy0, gz0 = g.gx0, g.gy0, g.gz0
    dxu, dxv, dyu, dyv, dzu, dzv = g.dxu, g.dxv, g.dyu, g.dyv, g.dzu, g.dzv
    k_out, k_in = g.k_out, g.k_in
    for i in range(i_start, i_end):
        u = i + 0.5
        gx = gx0 + dxu * u
        gy = gy0 + dyu * u
        gz = gz0 + dzu * u
        rr = gx * gx + gy * gy
        common_u = gx * dxu + gy * dyu
        common_v = gx * dxv + gy * dyv
        # (q, qu, qv): q and half its gradient; the distance 0.5 q / |(qu, qv)|
        q_out = rr - k_out * gz * gz
        qu_out = common_u - k_out * gz * dzu
        qv_out = common_v - k_out * gz * dzv
        n2_out = qu_out * qu_out + qv_out * qv_out
        # Cheap rejection: distance beyond the largest pixel half-extent sqrt(2)/2.
        if q_out > 0.0 and q_out * q_out > 2.001 * n2_out:
            continue
        q_in = rr - k_in * gz * gz
        qu_in = common_u - k_in * gz * dzu
        qv_in = common_v - k_in * gz * dzv
        n2_in = qu_in * qu_in + qv_in * qv_in
        if q_in * q_in > 2.001 * n2_in:
            if q_in < 0.0:
                continue
            if q_out < 0.0 and q_out * q_out > 2.001 * n2_out:
                paint[i] = 1.0  # fully inside the ring
                continue
        inv_out = 1.0 / (math.sqrt(n2_out) + 1e-300)
        f_out = _coverage_at(-0.5 * q_out * inv_out, qu_out * inv_out, qv_out * inv_out)
        inv_in = 1.0 / (math.sqrt(n2_in) + 1e-300)
        f_in = _coverage_at(0.5 * q_in * inv_in, qu_in * inv_in, qv_in * inv_in)
        c = f_out + f_in - 1.0
        if c > paint[i]:
            paint[i] = c


@cached_njit(**JIT)
def ring_row(
    h: np.ndarray,
    v: float,
    columns: tuple[int, int],
    hole: tuple[int, int],
    params: Params,
    paint: np.ndarray,
) -> None:
    """Ring coverage of the pixels ``s0 <= i < s1`` (``columns``) of row centre ``v``,
    skipping the hole ``hole0 <= i < hole1`` (``hole``), max-combined into ``paint``. ``h``:
    pixel-to-ground homography (scaled so ``gz > 0`` below the horizon).

    The ring edges are the conics ``q = (gx - cx gz)^2 + (gy - cy gz)^2 - r^2 gz^2 = 0``; the
    signed distance is taken to first order, ``-q / |grad q|`` (px, positive inside)."""
    s0, s1 = columns
    hole0, hole1 = hole
    ring_x = params.ring_x
    ring_y = params.ring_y
    r_in = params.ring_in
    r_out = params.ring_out
    # g = (gx, gy, gz) is affine in u along the row; x, y relative to the ring centre
    dxu = h[0, 0] - ring_x * h[2, 0]
    dxv = h[0, 1] - ring_x * h[2, 1]
    dyu = h[1, 0] - ring_y * h[2, 0]
    dyv = h[1, 1] - ring_y * h[2, 1]
    dzu = h[2, 0]
    dzv = h[2, 1]
    gz0 = dzv * v + h[2, 2]
    gx0 = h[0, 1] * v + h[0, 2] - ring_x * gz0
    gy0 = h[1, 1] * v + h[1, 2] - ring_y * gz0
    k_out = r_out * r_out
    k_in = r_in * r_in
    if hole1 <= hole0:
        hole0 = s1
        hole1 = s1
    hole0 = min(max(hole0, s0), s1)
    hole1 = min(max(hole1, s0), s1)
    g = RingRow(gx0, gy0, gz0, dxu, dxv, dyu, dyv, dzu, dzv, k_out, k_in)
    _ring_pixels(s0, hole0, g, paint)
    _ring_pixels(hole1, s1, g, paint)


@cached_njit(**JIT)
def ball_shade(ball: np.ndarray, u: float, v: float, params: Params) -> tuple[float, float]:
    """``(coverage, grey)`` of the ball at pixel centre ``(u, v)``.

    ``ball``: centre ``c`` in camera coordinates, ``|c|^2 - r^2``, the world up axis in camera
    coordinates, ``c . up`` and ``1 / r``. With the pixel ray ``e = (u - cx, v - cy, f)`` the
    silhouette is the conic ``q = (e.c)^2 - (|c|^2 - r^2) |e|^2 = 0`` (``q > 0`` inside).
    Grey: half-Lambert lighting from straight above, ``shadow + (lit - shadow) (1 + n_z) / 2``,
    at the surface point hit by the ray (or nearest to it, for rim pixels the centre misses)."""
    ex = u - params.cx
    ey = v - params.cy
    ez = ball[9]
    c0 = ball[0]
    c1 = ball[1]
    c2 = ball[2]
    k = ball[3]
    ec = ex * c0 + ey * c1 + ez * c2
    if ec <= 0.0:
        return 0.0, 0.0
    ee = ex * ex + ey * ey + ez * ez
    q = ec * ec - k * ee
    qu = ec * c0 - k * ex
    qv = ec * c1 - k * ey
    n2 = qu * qu + qv * qv
    if q * q > 2.001 * n2:  # farther than the largest pixel half-extent sqrt(2)/2
        if q < 0.0:
            return 0.0, 0.0
        coverage = 1.0
    else:
        norm = math.sqrt(n2) + 1e-300
        coverage = _coverage_at(0.5 * q / norm, qu / norm, qv / norm)
        if coverage <= 0.0:
            return 0.0, 0.0
    up_x = ball[4]
    up_y = ball[5]
    up_z = ball[6]
    if q > 0.0:
        # surface point hit by the ray; its normal is (t e - c) / r
        t = (ec - math.sqrt(q)) / ee
        up = (t * (ex * up_x + ey * up_y + ez * up_z) - ball[7]) * ball[8]
    else:
        # rim pixel whose centre misses: normal towards the ray's closest approach
        t = ec / ee
        nx = t * ex - c0
        ny = t * ey - c1
        nz = t * ez - c2
        up = (nx * up_x + ny * up_y + nz * up_z) / (math.sqrt(nx * nx + ny * ny + nz * nz) + 1e-300)
    shadow = params.ball_shadow
    return coverage, shadow + (params.ball_lit - shadow) * (0.5 + 0.5 * up)
