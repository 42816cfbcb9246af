"""Image edge lines of 3D polygons: a segment's image line in unit normal form with its
pixel-coverage constants, Sutherland-Hodgman clipping to the view frustum, and the image rows
a convex polygon's projection touches (see :mod:`activevision.rendering.kernels`)."""

from __future__ import annotations

import math

import numpy as np

from activevision.geometry.jit import cached_njit
from activevision.rendering.kernels.bundles import JIT, Z_NEAR, Optics


@cached_njit(**JIT)
def store_edge(
    a: np.ndarray,
    b: np.ndarray,
    inner: tuple[float, float, float],
    optics: Optics,
    out: np.ndarray,
) -> None:
    """Image line of the 3D segment ``a``-``b`` (camera frame), oriented so that the 3D
    point ``inner = (ix, iy, iz)`` is on its positive side, into ``out`` (EDGE_PARAMS,)."""
    ix, iy, iz = inner
    focal = optics.focal
    cx = optics.cx
    cy = optics.cy
    n0 = a[1] * b[2] - a[2] * b[1]
    n1 = a[2] * b[0] - a[0] * b[2]
    n2 = a[0] * b[1] - a[1] * b[0]
    if n0 * ix + n1 * iy + n2 * iz < 0.0:
        n0, n1, n2 = -n0, -n1, -n2
    l0 = n0 / focal
    l1 = n1 / focal
    l2 = n2 - (n0 * cx + n1 * cy) / focal
    norm = math.sqrt(l0 * l0 + l1 * l1)
    if norm <= 1e-12 * abs(l2):
        # The plane is parallel to the image plane: all pixels on one side.
        l0 = 0.0
        l1 = 0.0
        l2 = 1e30 if l2 > 0 else -1e30
    else:
        l0 /= norm
        l1 /= norm
        l2 /= norm
    hi = 0.5 * max(abs(l0), abs(l1))
    lo = max(0.5 * min(abs(l0), abs(l1)), 1e-7)
    out[0] = l0
    out[1] = l1
    out[2] = l2
    out[3] = hi
    out[4] = lo
    out[5] = 0.5 / hi
    out[6] = 0.125 / (hi * lo)
    out[7] = 1.0 / l0 if abs(l0) > 1e-12 else 0.0


@cached_njit(**JIT)
def _clip_plane(
    src: np.ndarray, n_src: int, dst: np.ndarray, a: float, b: float, c: float, e: float
) -> int:
    """Sutherland-Hodgman: clip polygon ``src[:n_src]`` to ``a x + b y + c z + e >= 0``
    into ``dst``; returns the new vertex count."""
    n_dst = 0
    for k in range(n_src):
        p = src[k]
        q = src[(k + 1) % n_src]
        dp = a * p[0] + b * p[1] + c * p[2] + e
        dq = a * q[0] + b * q[1] + c * q[2] + e
        if dp >= 0.0:
            dst[n_dst, 0] = p[0]
            dst[n_dst, 1] = p[1]
            dst[n_dst, 2] = p[2]
            n_dst += 1
        if (dp >= 0.0) != (dq >= 0.0):
            t = dp / (dp - dq)
            dst[n_dst, 0] = p[0] + t * (q[0] - p[0])
            dst[n_dst, 1] = p[1] + t * (q[1] - p[1])
            dst[n_dst, 2] = p[2] + t * (q[2] - p[2])
            n_dst += 1
    return n_dst


@cached_njit(**JIT)
def store_empty(edges: np.ndarray, n_edges: int, rows: np.ndarray) -> None:
    """Mark a shape out of view: no rows, and ``n_edges`` edges that no pixel touches.

    The row range alone already tells the row passes to skip the shape; the edges are
    written too so that no pass can ever read a previous camera's (or uninitialised) edges:
    ``l = (0, 0, -1e30)`` puts every pixel far outside, so ``span`` is empty and every
    coverage 0. The pixel half-widths are kept finite (fastmath assumes no inf)."""
    rows[0] = 0
    rows[1] = 0
    for e in range(n_edges):
        edge = edges[e]
        edge[0] = 0.0
        edge[1] = 0.0
        edge[2] = -1e30
        edge[3] = 0.5
        edge[4] = 0.5
        edge[5] = 1.0
        edge[6] = 0.5
        edge[7] = 0.0


@cached_njit(**JIT)
def polygon_edges_and_rows(
    pts: np.ndarray,
    n_pts: int,
    optics: Optics,
    edges: np.ndarray,
    rows: np.ndarray,
    clip: np.ndarray,
) -> None:
    """Edge lines of the convex 3D polygon ``pts[:n_pts]`` (camera frame) into ``edges`` and
    the image rows ``[rows[0], rows[1])`` its projection touches: the polygon is clipped to
    the view frustum (image borders and depth >= Z_NEAR) and the clipped vertices projected.
    Off-image polygons get no rows and empty edges (:func:`store_empty`), so both outputs
    are always written. ``clip``: (2, >= n_pts + 5, 3) scratch."""
    focal = optics.focal
    cx = optics.cx
    cy = optics.cy
    width = optics.width
    height = optics.height
    # Trivial rejection: every vertex outside the same frustum plane.
    out_near = True
    out_left = True
    out_right = True
    out_top = True
    out_bottom = True
    for k in range(n_pts):
        x = pts[k, 0]
        y = pts[k, 1]
        z = pts[k, 2]
        out_near &= z < Z_NEAR
        out_left &= focal * x + cx * z < 0.0
        out_right &= (width - cx) * z - focal * x < 0.0
        out_top &= focal * y + cy * z < 0.0
        out_bottom &= (height - cy) * z - focal * y < 0.0
    if out_near or out_left or out_right or out_top or out_bottom:
        store_empty(edges, n_pts, rows)
        return
    src = clip[0]
    dst = clip[1]
    for k in range(n_pts):
        src[k, 0] = pts[k, 0]
        src[k, 1] = pts[k, 1]
        src[k, 2] = pts[k, 2]
    m = _clip_plane(src, n_pts, dst, 0.0, 0.0, 1.0, -Z_NEAR)
    m = _clip_plane(dst, m, src, focal, 0.0, cx, 0.0)  # u >= 0
    m = _clip_plane(src, m, dst, -focal, 0.0, width - cx, 0.0)  # u <= width
    m = _clip_plane(dst, m, src, 0.0, focal, cy, 0.0)  # v >= 0
    m = _clip_plane(src, m, dst, 0.0, -focal, height - cy, 0.0)  # v <= height
    if m < 3:
        store_empty(edges, n_pts, rows)
        return
    v_min = 1e300
    v_max = -1e300
    for k in range(m):
        v = cy + focal * dst[k, 1] / dst[k, 2]
        v_min = min(v_min, v)
        v_max = max(v_max, v)
    rows[0] = max(math.floor(v_min), 0)
    rows[1] = min(math.ceil(v_max), height)
    if rows[1] <= rows[0]:
        store_empty(edges, n_pts, rows)
        return
    gx = 0.0
    gy = 0.0
    gz = 0.0
    for k in range(n_pts):
        gx += pts[k, 0]
        gy += pts[k, 1]
        gz += pts[k, 2]
    gx /= n_pts
    gy /= n_pts
    gz /= n_pts
    for k in range(n_pts):
        store_edge(pts[k], pts[(k + 1) % n_pts], (gx, gy, gz), optics, edges[k])
