"""Numba kernels of the fast renderer.

How a frame is drawn
--------------------
Every straight edge in the scene (a side of a painted line, of a penalty mark, of the carpet,
the silhouette edge of a post or crossbar) is a straight line in the image too. For a 3D
segment ``A B`` in camera coordinates, the plane through the optical centre, ``A`` and ``B``
has normal ``n = A x B``; a pixel ray ``d = K^-1 (u, v, 1)`` lies on the inner side iff
``n . d > 0``, which is the image half-plane ``l . (u, v, 1) > 0`` with ``l = K^-T n``.
Scaling ``l`` so that ``(l0, l1)`` is a unit vector makes ``l . (u, v, 1)`` the signed
distance in pixels. Because this only uses rays with positive depth, the intersection of a
convex polygon's edge half-planes is *exactly* its projection, even when part of the
polygon lies behind the camera.

Anti-aliasing is an exact box filter per half-plane: projected onto the line's normal, the
unit pixel square spreads as the sum of two uniform variables of half-widths ``|l0|/2`` and
``|l1|/2`` (a trapezoid), so the covered fraction is that trapezoid's CDF at the centre's
signed distance (:func:`_halfplane_coverage`). A band between two edges that do not cross
inside the pixel covers ``F1 + F2 - 1`` of it (exact); a quad covers the product of its two
bands (exact for axis-aligned rectangles, a tiny error only at line ends). The centre circle
ring and the ball use the same formula with the signed distance to their image conics taken
to first order (``q / |grad q|``).

Work per frame: a setup pass computes, per camera, every shape's edge lines and the range of
image rows it touches (its polygon clipped to the view frustum and projected; shapes out of
view are dropped). Then each row is filled with background/grass in runs, and each shape in
range shades only the columns its edges allow (linear inequalities per row, ``_span``):
pixels fully inside are filled directly, per-pixel coverage is computed only for the
partly covered ones. The ring is bounded by a 16-gon around it and one inside its hole. Row
work is handed to the threads in interleaved sets (rows ``b, b + B, b + 2B, ...``) so
sky-only rows do not pile up on one thread; single frames skip the threads altogether
(``render_kernel_serial``). The painted coverages of one row combine with ``max``; posts,
crossbars and the ball are composited over the ground far-to-near (painter's order by
distance) with their coverage as alpha. Values are rounded to uint8 once per pixel.

The work arrays are uninitialised (``np.empty``): for each camera the setup pass writes
every entry that the row pass reads (a shape out of view gets an empty row range *and* edges
no pixel touches), and the row pass reads a shape's edges only on rows in its range, so a
frame never depends on what the memory held before, i.e. on the other frames of its batch.

Goal posts are drawn as their silhouette: the quad between the two vertical generators
tangent to the sight lines from the camera (exact side edges); the bottom and top edges,
really arcs of the end circles, are straight lines moved 2/3 of the arc's sagitta towards
the camera (equal area). Crossbars likewise, around their horizontal axis. Their ends lie
inside the posts.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

#: Depth (m) at which polygons are clipped before projection.
Z_NEAR = 1e-3
#: Parameters stored per edge: l0, l1, l2 (unit normal form), hi, lo (trapezoid half-widths),
#: 1 / (2 hi), 1 / (8 hi lo), 1 / l0 (0 when l0 is 0).
EDGE_PARAMS = 8
# Indices into the float64 ``params`` vector handed to the kernel.
P_FOCAL, P_CX, P_CY, P_CAM_H = 0, 1, 2, 3
P_RING_X, P_RING_Y, P_RING_IN, P_RING_OUT, P_BALL_R = 4, 5, 6, 7, 8
P_GRASS, P_LINE, P_BACKGROUND, P_POST, P_BALL_LIT, P_BALL_SHADOW = 9, 10, 11, 12, 13, 14
N_PARAMS = 15

_JIT = {"cache": True, "fastmath": True, "nogil": True}


@njit(**_JIT)
def _halfplane_coverage(d, hi, lo, inv_2hi, inv_8hilo):
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


@njit(**_JIT)
def _coverage_at(d, n0, n1):
    """:func:`_halfplane_coverage` for a unit normal ``(n0, n1)`` known per pixel."""
    a = 0.5 * abs(n0)
    b = 0.5 * abs(n1)
    hi = max(a, b)
    lo = max(min(a, b), 1e-7)
    return _halfplane_coverage(d, hi, lo, 0.5 / hi, 0.125 / (hi * lo))


@njit(**_JIT)
def _store_edge(a, b, ix, iy, iz, focal, cx, cy, out):
    """Image line of the 3D segment ``a``-``b`` (camera frame), oriented so that the 3D
    point ``(ix, iy, iz)`` is on its positive side, into ``out`` (EDGE_PARAMS,)."""
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


@njit(**_JIT)
def _clip_plane(src, n_src, dst, a, b, c, e):
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


@njit(**_JIT)
def _store_empty(edges, n_edges, rows):
    """Mark a shape out of view: no rows, and ``n_edges`` edges that no pixel touches.

    The row range alone already tells the row passes to skip the shape; the edges are
    written too so that no pass can ever read a previous camera's (or uninitialised) edges:
    ``l = (0, 0, -1e30)`` puts every pixel far outside, so ``_span`` is empty and every
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


@njit(**_JIT)
def _polygon_edges_and_rows(pts, n_pts, focal, cx, cy, width, height, edges, rows, clip):
    """Edge lines of the convex 3D polygon ``pts[:n_pts]`` (camera frame) into ``edges`` and
    the image rows ``[rows[0], rows[1])`` its projection touches: the polygon is clipped to
    the view frustum (image borders and depth >= Z_NEAR) and the clipped vertices projected.
    Off-image polygons get no rows and empty edges (:func:`_store_empty`), so both outputs
    are always written. ``clip``: (2, >= n_pts + 5, 3) scratch."""
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
        _store_empty(edges, n_pts, rows)
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
        _store_empty(edges, n_pts, rows)
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
        _store_empty(edges, n_pts, rows)
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
        _store_edge(pts[k], pts[(k + 1) % n_pts], gx, gy, gz, focal, cx, cy, edges[k])


@njit(**_JIT)
def _fully_inside(edges, n_edges, u, v):
    """Whether the pixel centred at ``(u, v)`` lies entirely inside every edge."""
    for e in range(n_edges):
        if edges[e, 0] * u + edges[e, 1] * v + edges[e, 2] < edges[e, 3] + edges[e, 4]:
            return False
    return True


@njit(**_JIT)
def _span(edges, n_edges, v, threshold, width):
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


@njit(**_JIT)
def _edge_coverage(edge, u, v):
    d = edge[0] * u + edge[1] * v + edge[2]
    return _halfplane_coverage(d, edge[3], edge[4], edge[5], edge[6])


@njit(**_JIT)
def _quad_coverage(edges, u, v):
    """Fraction of the pixel centred at ``(u, v)`` covered by a quad: product of its two
    bands, each ``F1 + F2 - 1``."""
    band_a = _edge_coverage(edges[0], u, v) + _edge_coverage(edges[2], u, v) - 1.0
    if band_a <= 0.0:
        return 0.0
    band_b = _edge_coverage(edges[1], u, v) + _edge_coverage(edges[3], u, v) - 1.0
    if band_b <= 0.0:
        return 0.0
    return band_a * band_b


@njit(**_JIT)
def _paint_quad_pixels(edges, v, i_start, i_end, paint):
    """Max-combine a quad's coverage of columns ``[i_start, i_end)`` of row ``v`` into
    ``paint``."""
    for i in range(i_start, i_end):
        c = _quad_coverage(edges, i + 0.5, v)
        if c > paint[i]:
            paint[i] = c


@njit(**_JIT)
def _ring_pixels(i_start, i_end, gx0, gy0, gz0, dxu, dxv, dyu, dyv, dzu, dzv, k_out, k_in, paint):
    """The per-pixel part of :func:`_ring_row` for columns ``[i_start, i_end)``."""
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


@njit(**_JIT)
def _ring_row(h, v, s0, s1, hole0, hole1, ring_x, ring_y, r_in, r_out, paint):
    """Ring coverage of the pixels ``s0 <= i < s1`` of row centre ``v`` (skipping the hole
    ``hole0 <= i < hole1``), max-combined into ``paint``. ``h``: pixel-to-ground homography
    (scaled so ``gz > 0`` below the horizon).

    The ring edges are the conics ``q = (gx - cx gz)^2 + (gy - cy gz)^2 - r^2 gz^2 = 0``; the
    signed distance is taken to first order, ``-q / |grad q|`` (px, positive inside)."""
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
    _ring_pixels(s0, hole0, gx0, gy0, gz0, dxu, dxv, dyu, dyv, dzu, dzv, k_out, k_in, paint)
    _ring_pixels(hole1, s1, gx0, gy0, gz0, dxu, dxv, dyu, dyv, dzu, dzv, k_out, k_in, paint)


@njit(**_JIT)
def _ball_shade(ball, u, v, cx, cy, focal, lit, shadow):
    """``(coverage, grey)`` of the ball at pixel centre ``(u, v)``.

    ``ball``: centre ``c`` in camera coordinates, ``|c|^2 - r^2``, the world up axis in camera
    coordinates, ``c . up`` and ``1 / r``. With the pixel ray ``e = (u - cx, v - cy, f)`` the
    silhouette is the conic ``q = (e.c)^2 - (|c|^2 - r^2) |e|^2 = 0`` (``q > 0`` inside).
    Grey: half-Lambert lighting from straight above, ``shadow + (lit - shadow) (1 + n_z) / 2``,
    at the surface point hit by the ray (or nearest to it, for rim pixels the centre misses)."""
    ex = u - cx
    ey = v - cy
    ez = focal
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
        up = (nx * up_x + ny * up_y + nz * up_z) / (math.sqrt(nx * nx + ny * ny + nz * nz)
                                                     + 1e-300)
    return coverage, shadow + (lit - shadow) * (0.5 + 0.5 * up)


@njit(**_JIT)
def _angular_extent(a, z, r, focal, centre, size):
    """Pixel interval ``[lo, hi)`` covered by a sphere seen at lateral offset ``a`` and depth
    ``z`` (one image axis), radius ``r``; the whole axis when it is too close to tell."""
    rho = math.sqrt(a * a + z * z)
    if rho <= r * 1.0001:
        return 0, size
    alpha = math.atan2(a, z)
    beta = math.asin(r / rho)
    if alpha - beta <= -1.5 or alpha + beta >= 1.5:
        return 0, size
    lo = centre + focal * math.tan(alpha - beta)
    hi = centre + focal * math.tan(alpha + beta)
    lo = min(max(lo, -1.0), size + 1.0)
    hi = min(max(hi, -1.0), size + 1.0)
    return max(math.floor(lo), 0), min(math.ceil(hi), size)


@njit(**_JIT)
def _to_camera(rot, cam, x, y, z, out):
    dx = x - cam[0]
    dy = y - cam[1]
    dz = z - cam[2]
    out[0] = rot[0, 0] * dx + rot[0, 1] * dy + rot[0, 2] * dz
    out[1] = rot[1, 0] * dx + rot[1, 1] * dy + rot[1, 2] * dz
    out[2] = rot[2, 0] * dx + rot[2, 1] * dy + rot[2, 2] * dz


@njit(**_JIT)
def _setup_camera(n, pose, pan, tilt, ball_xy, has_ball, params, paint_quads, carpet,
                  ring_polygons, posts, bars, width, height,
                  quad_edges, quad_rows, ring_edges, ring_rows, homography, ball_info,
                  ball_box, object_order, first_row, visible_paint, visible_count, scratch_rot,
                  scratch_cam, scratch_pts, scratch_clip, scratch_keys):
    """Per-camera precomputation (see the module docstring) for camera ``n``."""
    focal = params[P_FOCAL]
    cx = params[P_CX]
    cy = params[P_CY]
    cam_h = params[P_CAM_H]
    yaw = pose[n, 2] + pan[n]
    cyaw = math.cos(yaw)
    syaw = math.sin(yaw)
    ct = math.cos(tilt[n])
    st = math.sin(tilt[n])
    # rows: the camera's right, down and forward axes in world coordinates (camera.py)
    rot = scratch_rot[n]
    rot[0, 0] = syaw
    rot[0, 1] = -cyaw
    rot[0, 2] = 0.0
    rot[1, 0] = -cyaw * st
    rot[1, 1] = -syaw * st
    rot[1, 2] = -ct
    rot[2, 0] = cyaw * ct
    rot[2, 1] = syaw * ct
    rot[2, 2] = -st
    cam = scratch_cam[n]
    cam[0] = pose[n, 0]
    cam[1] = pose[n, 1]
    cam[2] = cam_h

    n_paint = paint_quads.shape[0]
    n_posts = posts.shape[0]
    n_bars = bars.shape[0]
    pts = scratch_pts[n]
    clip = scratch_clip[n]
    # painted quads, then the carpet
    for q in range(n_paint + 1):
        src = paint_quads[q] if q < n_paint else carpet
        for k in range(4):
            _to_camera(rot, cam, src[k, 0], src[k, 1], 0.0, pts[k])
        _polygon_edges_and_rows(pts, 4, focal, cx, cy, width, height, quad_edges[n, q],
                                quad_rows[n, q], clip)

    # Posts: silhouette quad through the two vertical generators tangent to the sight lines.
    base = n_paint + 1
    for p in range(n_posts):
        px, py, pr, ph = posts[p, 0], posts[p, 1], posts[p, 2], posts[p, 3]
        dx = cam[0] - px
        dy = cam[1] - py
        dist = math.sqrt(dx * dx + dy * dy)
        if dist <= pr * 1.001:  # camera inside the post: not drawn
            _store_empty(quad_edges[n, base + p], 4, quad_rows[n, base + p])
            continue
        ux, uy = dx / dist, dy / dist
        cos_b = pr / dist
        sin_b = math.sqrt(1.0 - cos_b * cos_b)
        # tangent points: centre + r * (unit towards camera rotated by +-beta)
        t1x = px + pr * (ux * cos_b - uy * sin_b)
        t1y = py + pr * (uy * cos_b + ux * sin_b)
        t2x = px + pr * (ux * cos_b + uy * sin_b)
        t2y = py + pr * (uy * cos_b - ux * sin_b)
        # The true bottom (top) outline is the near arc of the base (top) circle, which
        # bulges towards the camera by the sagitta r (1 - cos b) beyond the chord T1 T2. A
        # straight edge moved 2/3 of the way out covers the same area (parabolic segment).
        shift = pr * (1.0 - cos_b) * (2.0 / 3.0)
        sx, sy = shift * ux, shift * uy
        _to_camera(rot, cam, t1x + sx, t1y + sy, 0.0, pts[0])
        _to_camera(rot, cam, t2x + sx, t2y + sy, 0.0, pts[1])
        _to_camera(rot, cam, t2x + sx, t2y + sy, ph, pts[2])
        _to_camera(rot, cam, t1x + sx, t1y + sy, ph, pts[3])
        edges = quad_edges[n, base + p]
        _polygon_edges_and_rows(pts, 4, focal, cx, cy, width, height, edges,
                                quad_rows[n, base + p], clip)
        # The sides are the exact tangent generators (the shifted corners are not on them).
        ix = 0.25 * (pts[0, 0] + pts[1, 0] + pts[2, 0] + pts[3, 0])
        iy = 0.25 * (pts[0, 1] + pts[1, 1] + pts[2, 1] + pts[3, 1])
        iz = 0.25 * (pts[0, 2] + pts[1, 2] + pts[2, 2] + pts[3, 2])
        _to_camera(rot, cam, t2x, t2y, 0.0, pts[5])
        _to_camera(rot, cam, t2x, t2y, ph, pts[6])
        _store_edge(pts[5], pts[6], ix, iy, iz, focal, cx, cy, edges[1])
        _to_camera(rot, cam, t1x, t1y, ph, pts[5])
        _to_camera(rot, cam, t1x, t1y, 0.0, pts[6])
        _store_edge(pts[5], pts[6], ix, iy, iz, focal, cx, cy, edges[3])

    # Crossbars: the same in the vertical x-z plane (their axis runs along y).
    base = n_paint + 1 + n_posts
    for b in range(n_bars):
        bx, y0, y1, bz, br = bars[b, 0], bars[b, 1], bars[b, 2], bars[b, 3], bars[b, 4]
        dx = cam[0] - bx
        dz = cam[2] - bz
        dist = math.sqrt(dx * dx + dz * dz)
        if dist <= br * 1.001:  # camera inside the crossbar: not drawn
            _store_empty(quad_edges[n, base + b], 4, quad_rows[n, base + b])
            continue
        ux, uz = dx / dist, dz / dist
        cos_b = br / dist
        sin_b = math.sqrt(1.0 - cos_b * cos_b)
        t1x = bx + br * (ux * cos_b - uz * sin_b)
        t1z = bz + br * (uz * cos_b + ux * sin_b)
        t2x = bx + br * (ux * cos_b + uz * sin_b)
        t2z = bz + br * (uz * cos_b - ux * sin_b)
        _to_camera(rot, cam, t1x, y0, t1z, pts[0])
        _to_camera(rot, cam, t2x, y0, t2z, pts[1])
        _to_camera(rot, cam, t2x, y1, t2z, pts[2])
        _to_camera(rot, cam, t1x, y1, t1z, pts[3])
        _polygon_edges_and_rows(pts, 4, focal, cx, cy, width, height, quad_edges[n, base + b],
                                quad_rows[n, base + b], clip)

    # Centre circle: outer polygon bounds the rows and columns to shade, inner polygon marks
    # pixels certainly inside the hole.
    n_sides = ring_polygons.shape[1]
    for o in range(2):
        for k in range(n_sides):
            _to_camera(rot, cam, params[P_RING_X] + ring_polygons[o, k, 0],
                       params[P_RING_Y] + ring_polygons[o, k, 1], 0.0, pts[k])
        _polygon_edges_and_rows(pts, n_sides, focal, cx, cy, width, height, ring_edges[n, o],
                                ring_rows[n, o], clip)
    # Pixel -> ground homography: ground point (gx, gy) / gz of the ray through (u, v),
    # with gz = -(ray's world z) > 0 below the horizon.
    for r in range(3):
        if r < 2:
            g0 = cam_h * rot[0, r] - cam[r] * rot[0, 2]
            g1 = cam_h * rot[1, r] - cam[r] * rot[1, 2]
            g2 = cam_h * rot[2, r] - cam[r] * rot[2, 2]
        else:
            g0 = -rot[0, 2]
            g1 = -rot[1, 2]
            g2 = -rot[2, 2]
        homography[n, r, 0] = g0 / focal
        homography[n, r, 1] = g1 / focal
        homography[n, r, 2] = g2 - (g0 * cx + g1 * cy) / focal

    # Ball
    ball_r = params[P_BALL_R]
    _to_camera(rot, cam, ball_xy[n, 0], ball_xy[n, 1], ball_r, pts[0])
    c0, c1, c2 = pts[0, 0], pts[0, 1], pts[0, 2]
    ball_info[n, 0] = c0
    ball_info[n, 1] = c1
    ball_info[n, 2] = c2
    ball_info[n, 3] = c0 * c0 + c1 * c1 + c2 * c2 - ball_r * ball_r
    ball_info[n, 4] = rot[0, 2]
    ball_info[n, 5] = rot[1, 2]
    ball_info[n, 6] = rot[2, 2]
    ball_info[n, 7] = c0 * rot[0, 2] + c1 * rot[1, 2] + c2 * rot[2, 2]  # c . up
    ball_info[n, 8] = 1.0 / ball_r
    if has_ball and c2 + ball_r > Z_NEAR and ball_info[n, 3] > 0.0:
        i0, i1 = _angular_extent(c0, c2, ball_r, focal, cx, width)
        j0, j1 = _angular_extent(c1, c2, ball_r, focal, cy, height)
    else:
        i0, i1, j0, j1 = 0, 0, 0, 0
    if i1 <= i0 or j1 <= j0:
        i0, i1, j0, j1 = 0, 0, 0, 0
    ball_box[n, 0] = i0
    ball_box[n, 1] = i1
    ball_box[n, 2] = j0
    ball_box[n, 3] = j1

    # Objects far to near (painter's order): posts, crossbars, ball.
    n_objects = n_posts + n_bars + 1
    keys = scratch_keys[n]
    for p in range(n_posts):
        dx = posts[p, 0] - cam[0]
        dy = posts[p, 1] - cam[1]
        keys[p] = dx * dx + dy * dy
    for b in range(n_bars):
        dx = bars[b, 0] - cam[0]
        dy = min(max(cam[1], bars[b, 1]), bars[b, 2]) - cam[1]
        dz = bars[b, 3] - cam[2]
        keys[n_posts + b] = dx * dx + dy * dy + dz * dz
    keys[n_objects - 1] = c0 * c0 + c1 * c1 + c2 * c2
    for k in range(n_objects):
        object_order[n, k] = k
    for k in range(1, n_objects):  # insertion sort, descending distance
        m = k
        while m > 0 and keys[object_order[n, m - 1]] < keys[object_order[n, m]]:
            tmp = object_order[n, m - 1]
            object_order[n, m - 1] = object_order[n, m]
            object_order[n, m] = tmp
            m -= 1

    n_visible = 0
    for q in range(n_paint):
        if quad_rows[n, q, 1] > quad_rows[n, q, 0]:
            visible_paint[n, n_visible] = q
            n_visible += 1
    visible_count[n] = n_visible

    first = height
    for q in range(n_paint, n_paint + 1 + n_posts + n_bars):
        if quad_rows[n, q, 1] > quad_rows[n, q, 0]:
            first = min(first, quad_rows[n, q, 0])
    if ball_box[n, 3] > ball_box[n, 2]:
        first = min(first, ball_box[n, 2])
    first_row[n] = first


@njit(**_JIT)
def _render_rows(n, row0, row_step, out, params, n_paint, n_posts, n_bars,
                 quad_edges, quad_rows, ring_edges, ring_rows, homography, ball_info,
                 ball_box, object_order, first_row, visible_paint, visible_count, value, paint):
    """Rows ``row0, row0 + row_step, ...`` of image ``n``. ``value`` (W,) float32 scratch;
    ``paint`` (W,) float32 scratch that is all zero on entry and on exit."""
    height = out.shape[1]
    width = out.shape[2]
    grass = params[P_GRASS]
    background = params[P_BACKGROUND]
    line_minus_grass = params[P_LINE] - grass
    post = params[P_POST]
    carpet = n_paint
    n_objects = n_posts + n_bars + 1
    focal = params[P_FOCAL]
    cx = params[P_CX]
    cy = params[P_CY]
    bg_u8 = np.uint8(int(background + 0.5))
    for j in range(row0, height, row_step):
        if j < first_row[n]:
            out[n, j, :] = bg_u8
            continue
        v = j + 0.5
        # --- ground: background, carpet, its anti-aliased border
        if quad_rows[n, carpet, 0] <= j < quad_rows[n, carpet, 1]:
            edges = quad_edges[n, carpet]
            if _fully_inside(edges, 4, 0.5, v) and _fully_inside(edges, 4, width - 0.5, v):
                # Both end pixels fully on the carpet, so the whole row is (convexity).
                value[:] = grass
                o0, o1 = 0, 0
            else:
                o0, o1 = _span(edges, 4, v, -1.0, width)
                i0, i1 = _span(edges, 4, v, 1.0, width)
                value[:o0] = background
                value[o1:] = background
                if i1 > i0:
                    value[i0:i1] = grass
                else:
                    i0 = o1
                    i1 = o1
                # partly covered pixels: [o0, i0) and [i1, o1)
                for i in range(o0, i0):
                    c = _quad_coverage(edges, i + 0.5, v)
                    value[i] = background + c * (grass - background)
                for i in range(i1, o1):
                    c = _quad_coverage(edges, i + 0.5, v)
                    value[i] = background + c * (grass - background)
        else:
            value[:] = background
        # --- paint: lines, marks, centre circle (coverages combine with max)
        touched_lo = width
        touched_hi = 0
        for vq in range(visible_count[n]):
            q = visible_paint[n, vq]
            if quad_rows[n, q, 0] <= j < quad_rows[n, q, 1]:
                edges = quad_edges[n, q]
                s0, s1 = _span(edges, 4, v, -1.0, width)
                i0, i1 = s1, s1
                if s1 - s0 > 4:
                    # pixels fully inside the quad: coverage 1 without per-pixel work
                    i0, i1 = _span(edges, 4, v, 1.0, width)
                    if i1 > i0:
                        paint[i0:i1] = 1.0
                    else:
                        i0, i1 = s1, s1
                _paint_quad_pixels(edges, v, s0, i0, paint)
                _paint_quad_pixels(edges, v, i1, s1, paint)
                if s1 > s0:
                    touched_lo = min(touched_lo, s0)
                    touched_hi = max(touched_hi, s1)
        if ring_rows[n, 0, 0] <= j < ring_rows[n, 0, 1]:
            s0, s1 = _span(ring_edges[n, 0], ring_edges.shape[2], v, -1.0, width)
            # The hole polygon has its own row range (empty when it is off-image while the
            # ring is not): outside it no pixel of this row is certainly in the hole.
            h0, h1 = 0, 0
            if ring_rows[n, 1, 0] <= j < ring_rows[n, 1, 1]:
                h0, h1 = _span(ring_edges[n, 1], ring_edges.shape[2], v, 1.0, width)
            _ring_row(homography[n], v, s0, s1, h0, h1, params[P_RING_X], params[P_RING_Y],
                      params[P_RING_IN], params[P_RING_OUT], paint)
            if s1 > s0:
                touched_lo = min(touched_lo, s0)
                touched_hi = max(touched_hi, s1)
        for i in range(touched_lo, touched_hi):
            value[i] += paint[i] * line_minus_grass
            paint[i] = 0.0
        # --- posts, crossbars, ball: far to near, coverage as alpha
        for k in range(n_objects):
            o = object_order[n, k]
            if o < n_posts + n_bars:
                q = n_paint + 1 + o
                if quad_rows[n, q, 0] <= j < quad_rows[n, q, 1]:
                    edges = quad_edges[n, q]
                    s0, s1 = _span(edges, 4, v, -1.0, width)
                    i0, i1 = s1, s1
                    if s1 - s0 > 4:
                        i0, i1 = _span(edges, 4, v, 1.0, width)
                        if i1 > i0:
                            value[i0:i1] = post
                        else:
                            i0, i1 = s1, s1
                    for i in range(s0, i0):
                        a = _quad_coverage(edges, i + 0.5, v)
                        value[i] += a * (post - value[i])
                    for i in range(i1, s1):
                        a = _quad_coverage(edges, i + 0.5, v)
                        value[i] += a * (post - value[i])
            elif ball_box[n, 2] <= j < ball_box[n, 3]:
                for i in range(ball_box[n, 0], ball_box[n, 1]):
                    a, grey = _ball_shade(ball_info[n], i + 0.5, v, cx, cy, focal,
                                          params[P_BALL_LIT], params[P_BALL_SHADOW])
                    if a > 0.0:
                        value[i] += a * (grey - value[i])
        for i in range(width):
            out[n, j, i] = np.uint8(min(max(value[i] + np.float32(0.5), np.float32(0.0)),
                                        np.float32(255.0)))


@njit(**_JIT)
def _allocate(n_cams, n_paint, n_posts, n_bars, n_ring_sides):
    """Per-call work arrays of the setup pass. Uninitialised on purpose (speed): for each
    camera the setup writes every entry that the row pass reads, so an image never depends
    on what the memory held before (``garbage`` of the kernels tests exactly that)."""
    n_quads = n_paint + 1 + n_posts + n_bars
    return (
        np.empty((n_cams, n_quads, 4, EDGE_PARAMS)),  # quad_edges
        np.empty((n_cams, n_quads, 2), dtype=np.int64),  # quad_rows
        np.empty((n_cams, 2, n_ring_sides, EDGE_PARAMS)),  # ring_edges
        np.empty((n_cams, 2, 2), dtype=np.int64),  # ring_rows
        np.empty((n_cams, 3, 3)),  # homography
        np.empty((n_cams, 9)),  # ball_info
        np.empty((n_cams, 4), dtype=np.int64),  # ball_box
        np.empty((n_cams, n_posts + n_bars + 1), dtype=np.int64),  # object_order
        np.empty(n_cams, dtype=np.int64),  # first_row
        np.empty((n_cams, n_paint), dtype=np.int64),  # visible_paint
        np.empty(n_cams, dtype=np.int64),  # visible_count
        np.empty((n_cams, 3, 3)),  # scratch_rot
        np.empty((n_cams, 3)),  # scratch_cam
        np.empty((n_cams, max(8, n_ring_sides), 3)),  # scratch_pts
        np.empty((n_cams, 2, n_ring_sides + 8, 3)),  # scratch_clip
        np.empty((n_cams, n_posts + n_bars + 1)),  # scratch_keys
    )


@njit(**_JIT)
def _xorshift(x):
    x ^= x << np.uint64(13)
    x ^= x >> np.uint64(7)
    x ^= x << np.uint64(17)
    return x


#: Kinds of garbage of :func:`_fill_garbage`: random mixed values; an edge that takes every
#: pixel with row ranges over every row (stale data that *looks* valid is what turns a
#: missing write into wrong pixels); NaN and -1 everywhere.
GARBAGE_KINDS = 3
#: One edge (EDGE_PARAMS,) whose half-plane contains the whole image.
_ACCEPT_ALL_EDGE = (0.0, 0.0, 1e30, 0.5, 0.5, 1.0, 0.5, 0.0)


@njit(**_JIT)
def _garbage_floats(arr, seed):
    """Fill the C-contiguous float array ``arr`` with garbage of kind ``seed % GARBAGE_KINDS``
    drawn from ``seed``."""
    flat = arr.reshape(arr.size)
    kind = seed % GARBAGE_KINDS
    x = np.uint64(seed) | np.uint64(1)
    for i in range(flat.size):
        if kind == 1:
            flat[i] = _ACCEPT_ALL_EDGE[i % EDGE_PARAMS]
            continue
        if kind == 2:
            flat[i] = np.nan
            continue
        x = _xorshift(x)
        small = (np.int64(x >> np.uint64(40)) % 2001 - 1000) * 0.01  # -10 .. 10
        pick = np.int64(x & np.uint64(3))
        if pick == 0:
            flat[i] = np.nan
        elif pick == 1:
            flat[i] = 1e300 if x & np.uint64(32) else -1e300
        elif pick == 2:
            flat[i] = small * 1e4
        else:
            flat[i] = small


@njit(**_JIT)
def _garbage_ints(arr, seed):
    """Fill the C-contiguous int64 array ``arr`` with garbage of kind ``seed % GARBAGE_KINDS``
    (huge, negative, plausible row, column and object indices) drawn from ``seed``."""
    flat = arr.reshape(arr.size)
    kind = seed % GARBAGE_KINDS
    x = np.uint64(seed) | np.uint64(1)
    for i in range(flat.size):
        if kind == 1:
            flat[i] = 0 if i % 2 == 0 else 1 << 20  # row ranges [0, 2^20): every row
            continue
        if kind == 2:
            flat[i] = -1
            continue
        x = _xorshift(x)
        pick = np.int64(x & np.uint64(3))
        if pick == 0:
            flat[i] = np.int64(x >> np.uint64(1))
        elif pick == 1:
            flat[i] = -1 - np.int64(x >> np.uint64(50))
        else:
            flat[i] = np.int64(x >> np.uint64(40)) % 300


@njit(**_JIT)
def _fill_garbage(work, value, seed):
    """Test hook: overwrite every work buffer of :func:`_allocate` and the row scratch
    ``value`` with garbage of kind ``seed % GARBAGE_KINDS``, as if the memory held anything
    at all (including another camera's data)."""
    k = GARBAGE_KINDS  # seed + m k: the same kind, different values per buffer
    _garbage_floats(work[0], seed + k)
    _garbage_ints(work[1], seed + 2 * k)
    _garbage_floats(work[2], seed + 3 * k)
    _garbage_ints(work[3], seed + 4 * k)
    _garbage_floats(work[4], seed + 5 * k)
    _garbage_floats(work[5], seed + 6 * k)
    _garbage_ints(work[6], seed + 7 * k)
    _garbage_ints(work[7], seed + 8 * k)
    _garbage_ints(work[8], seed + 9 * k)
    _garbage_ints(work[9], seed + 10 * k)
    _garbage_ints(work[10], seed + 11 * k)
    _garbage_floats(work[11], seed + 12 * k)
    _garbage_floats(work[12], seed + 13 * k)
    _garbage_floats(work[13], seed + 14 * k)
    _garbage_floats(work[14], seed + 15 * k)
    _garbage_floats(work[15], seed + 16 * k)
    _garbage_floats(value, seed + 17 * k)


@njit(cache=True, fastmath=True, nogil=True, parallel=True)
def render_kernel(pose, pan, tilt, ball_xy, has_ball, params, paint_quads, carpet,
                  ring_polygons, posts, bars, row_blocks, out, garbage):
    """Render ``len(pose)`` cameras into ``out`` (N, H, W) uint8, on all numba threads.
    Each camera's rows are split into ``row_blocks`` interleaved sets of work. ``garbage``:
    0, or a seed to fill the work memory with garbage first (:func:`_fill_garbage`, for
    the tests; the images must not change)."""
    n_cams = pose.shape[0]
    width = out.shape[2]
    n_paint = paint_quads.shape[0]
    n_posts = posts.shape[0]
    n_bars = bars.shape[0]
    work = _allocate(n_cams, n_paint, n_posts, n_bars, ring_polygons.shape[1])
    if garbage != 0:
        _fill_garbage(work, np.empty(1, dtype=np.float32), garbage)
    for n in prange(n_cams):
        _setup_camera(n, pose, pan, tilt, ball_xy, has_ball, params, paint_quads, carpet,
                      ring_polygons, posts, bars, out.shape[2], out.shape[1], *work)
    for item in prange(n_cams * row_blocks):
        n = item // row_blocks
        value = np.empty(width, dtype=np.float32)
        if garbage != 0:
            _garbage_floats(value, garbage + GARBAGE_KINDS * item)
        paint = np.zeros(width, dtype=np.float32)
        _render_rows(n, item - n * row_blocks, row_blocks, out, params, n_paint, n_posts,
                     n_bars, *work[:11], value, paint)


@njit(cache=True, fastmath=True, nogil=True)
def render_kernel_serial(pose, pan, tilt, ball_xy, has_ball, params, paint_quads, carpet,
                         ring_polygons, posts, bars, out, garbage):
    """:func:`render_kernel` on the calling thread only: no thread hand-off, which matters
    for single frames (and on machines whose cores are busy with other work)."""
    n_cams = pose.shape[0]
    width = out.shape[2]
    n_paint = paint_quads.shape[0]
    n_posts = posts.shape[0]
    n_bars = bars.shape[0]
    work = _allocate(n_cams, n_paint, n_posts, n_bars, ring_polygons.shape[1])
    value = np.empty(width, dtype=np.float32)
    if garbage != 0:
        _fill_garbage(work, value, garbage)
    paint = np.zeros(width, dtype=np.float32)
    for n in range(n_cams):
        _setup_camera(n, pose, pan, tilt, ball_xy, has_ball, params, paint_quads, carpet,
                      ring_polygons, posts, bars, out.shape[2], out.shape[1], *work)
        _render_rows(n, 0, 1, out, params, n_paint, n_posts, n_bars, *work[:11], value, paint)
