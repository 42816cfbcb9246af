"""The setup pass of the renderer: per camera, every shape's image edge lines and the range
of image rows it touches (its polygon clipped to the view frustum and projected; shapes out
of view get no rows and edges no pixel touches), the pixel -> ground homography of the ring,
the ball's parameters and box, and the painter's order of posts, crossbars and ball (see
:mod:`activevision.rendering.kernels`)."""

from __future__ import annotations

import math

import numpy as np

from activevision.geometry.jit import cached_njit
from activevision.geometry.kernels import camera_rotation
from activevision.rendering.appearance import LOOK
from activevision.rendering.kernels.bundles import (
    JIT,
    JIT_PART,
    Z_NEAR,
    Cameras,
    Looks,
    Optics,
    Params,
    RenderWork,
    Scene,
    SetupScratch,
)
from activevision.rendering.kernels.edges import polygon_edges_and_rows, store_edge, store_empty

MOUNT_HEIGHT = LOOK["mount_height"]
MOUNT_TILT = LOOK["mount_tilt"]
MOUNT_FOV = LOOK["mount_fov"]
LINE_WIDTH = LOOK["line_width"]


@cached_njit(**JIT)
def setup_camera(
    n: int,
    scene: Scene,
    params: Params,
    cams: Cameras,
    looks: Looks,
    work: RenderWork,
    scratch: SetupScratch,
) -> None:
    """Per-camera precomputation (see :mod:`activevision.rendering.kernels`) for camera
    ``n`` of ``cams``, into slice ``n`` of every :class:`RenderWork` array (and of the
    :class:`SetupScratch`).

    One function, its sections written out: handing the work or scene bundle (arrays) to
    helpers would count references to every array of it on each call."""
    # Bundle fields into locals once: reading an array field counts a reference to it, and
    # those counts (atomic) add up to several percent of a frame.
    pose, pan, tilt, ball_xy, has_ball = cams
    paint_quads, carpet, polygons, posts, bars, paint_expand = scene
    look_rows, _, cylinders, _, looks_on = looks
    cam_h = params.cam_h
    focal = params.focal
    head_tilt = tilt[n]
    widen = 0.0
    if looks_on:
        # the camera mount as built, not as the robot's model has it (image only)
        look = look_rows[n]
        cam_h += look[MOUNT_HEIGHT]
        head_tilt += look[MOUNT_TILT]
        focal = params.cx / math.tan((1.0 + look[MOUNT_FOV]) * math.atan(params.cx / focal))
        widen = look[LINE_WIDTH]
    rot = scratch.rot[n]
    camera_rotation(pose[n, 2] + pan[n], head_tilt, rot)
    cam = scratch.cam[n]
    cam[0] = pose[n, 0]
    cam[1] = pose[n, 1]
    cam[2] = cam_h
    pts = scratch.pts[n]
    clip = scratch.clip[n]
    optics = Optics(focal, params.cx, params.cy, params.width, params.height)
    quad_edges = work.quad_edges[n]
    quad_rows = work.quad_rows[n]
    object_grey = work.object_grey[n]
    n_paint = paint_quads.shape[0]
    n_posts = posts.shape[0]
    n_bars = bars.shape[0]
    n_cyl = cylinders.shape[1]

    # painted quads, then the carpet
    for q in range(n_paint + 1):
        src = paint_quads[q] if q < n_paint else carpet
        for k in range(4):
            x, y = src[k, 0], src[k, 1]
            if widen != 0.0 and q < n_paint:
                x += widen * paint_expand[q, k, 0]
                y += widen * paint_expand[q, k, 1]
            _to_camera(rot, cam, x, y, 0.0, pts[k])
        polygon_edges_and_rows(pts, 4, optics, quad_edges[q], quad_rows[q], clip)

    # Posts, crossbars and other robots' cylinders: the silhouette quad of each, none when
    # the camera is inside it. (Written out here: helpers taking the camera's arrays cost ~5%
    # of the setup.)
    for o in range(n_posts + n_bars + n_cyl):
        edges = quad_edges[n_paint + 1 + o]
        rows = quad_rows[n_paint + 1 + o]
        object_grey[o] = params.post
        if o < n_posts or o >= n_posts + n_bars:
            # a post or cylinder: the quad through the two vertical generators tangent to the
            # sight lines, from z0 to z1
            if o < n_posts:
                px, py, pr, z0, z1 = posts[o, 0], posts[o, 1], posts[o, 2], 0.0, posts[o, 3]
            else:
                cyl = cylinders[n, o - n_posts - n_bars]
                px, py, pr, z0, z1 = cyl[0], cyl[1], cyl[2], cyl[3], cyl[4]
                object_grey[o] = cyl[5]
            outside, ux, uy, cos_b, t1x, t1y, t2x, t2y = _tangents(px, py, pr, cam[0], cam[1])
            if not outside or not pr > 0.0:
                store_empty(edges, 4, rows)
                continue
            # The true bottom (top) outline is the near arc of the base (top) circle, which
            # bulges towards the camera by the sagitta r (1 - cos b) beyond the chord T1 T2. A
            # straight edge moved 2/3 of the way out covers the same area (parabolic segment).
            shift = pr * (1.0 - cos_b) * (2.0 / 3.0)
            sx, sy = shift * ux, shift * uy
            _to_camera(rot, cam, t1x + sx, t1y + sy, z0, pts[0])
            _to_camera(rot, cam, t2x + sx, t2y + sy, z0, pts[1])
            _to_camera(rot, cam, t2x + sx, t2y + sy, z1, pts[2])
            _to_camera(rot, cam, t1x + sx, t1y + sy, z1, pts[3])
            polygon_edges_and_rows(pts, 4, optics, edges, rows, clip)
            # The sides are the exact tangent generators (the shifted corners are not on them).
            ix = 0.25 * (pts[0, 0] + pts[1, 0] + pts[2, 0] + pts[3, 0])
            iy = 0.25 * (pts[0, 1] + pts[1, 1] + pts[2, 1] + pts[3, 1])
            iz = 0.25 * (pts[0, 2] + pts[1, 2] + pts[2, 2] + pts[3, 2])
            _to_camera(rot, cam, t2x, t2y, z0, pts[5])
            _to_camera(rot, cam, t2x, t2y, z1, pts[6])
            store_edge(pts[5], pts[6], (ix, iy, iz), optics, edges[1])
            _to_camera(rot, cam, t1x, t1y, z1, pts[5])
            _to_camera(rot, cam, t1x, t1y, z0, pts[6])
            store_edge(pts[5], pts[6], (ix, iy, iz), optics, edges[3])
        else:
            # a crossbar: the same in the vertical x-z plane (its axis runs along y)
            b = o - n_posts
            y0, y1 = bars[b, 1], bars[b, 2]
            outside, _, _, _, t1x, t1z, t2x, t2z = _tangents(
                bars[b, 0], bars[b, 3], bars[b, 4], cam[0], cam[2]
            )
            if not outside:
                store_empty(edges, 4, rows)
                continue
            _to_camera(rot, cam, t1x, y0, t1z, pts[0])
            _to_camera(rot, cam, t2x, y0, t2z, pts[1])
            _to_camera(rot, cam, t2x, y1, t2z, pts[2])
            _to_camera(rot, cam, t1x, y1, t1z, pts[3])
            polygon_edges_and_rows(pts, 4, optics, edges, rows, clip)

    # Centre circle: the outer polygon bounds the rows and columns to shade, the inner one
    # marks pixels certainly inside the hole.
    n_sides = polygons.shape[1]
    ring_edges = work.ring_edges[n]
    ring_rows = work.ring_rows[n]
    for o in range(2):
        for k in range(n_sides):
            x = params.ring_x + polygons[o, k, 0]
            y = params.ring_y + polygons[o, k, 1]
            _to_camera(rot, cam, x, y, 0.0, pts[k])
        polygon_edges_and_rows(pts, n_sides, optics, ring_edges[o], ring_rows[o], clip)
    # Pixel -> ground homography: ground point (gx, gy) / gz of the ray through (u, v),
    # with gz = -(ray's world z) > 0 below the horizon.
    homography = work.homography[n]
    for r in range(3):
        if r < 2:
            g0 = cam_h * rot[0, r] - cam[r] * rot[0, 2]
            g1 = cam_h * rot[1, r] - cam[r] * rot[1, 2]
            g2 = cam_h * rot[2, r] - cam[r] * rot[2, 2]
        else:
            g0 = -rot[0, 2]
            g1 = -rot[1, 2]
            g2 = -rot[2, 2]
        homography[r, 0] = g0 / focal
        homography[r, 1] = g1 / focal
        homography[r, 2] = g2 - (g0 * params.cx + g1 * params.cy) / focal
    # Pixel -> world ray direction, rot^T K^-1, and the camera centre (the hall).
    ray = work.ray[n]
    for r in range(3):
        ray[r, 0] = rot[0, r] / focal
        ray[r, 1] = rot[1, r] / focal
        ray[r, 2] = rot[2, r] - (rot[0, r] * params.cx + rot[1, r] * params.cy) / focal
        ray[r, 3] = cam[r]

    # Ball: the parameters of coverage.ball_shade and its pixel box (empty when there is
    # no ball or it is out of view)
    ball_r = params.ball_r
    _to_camera(rot, cam, ball_xy[n, 0], ball_xy[n, 1], ball_r, pts[0])
    c0, c1, c2 = pts[0, 0], pts[0, 1], pts[0, 2]
    ball_info = work.ball_info[n]
    ball_info[0] = c0
    ball_info[1] = c1
    ball_info[2] = c2
    ball_info[3] = c0 * c0 + c1 * c1 + c2 * c2 - ball_r * ball_r
    ball_info[4] = rot[0, 2]
    ball_info[5] = rot[1, 2]
    ball_info[6] = rot[2, 2]
    ball_info[7] = c0 * rot[0, 2] + c1 * rot[1, 2] + c2 * rot[2, 2]  # c . up
    ball_info[8] = 1.0 / ball_r
    ball_info[9] = focal
    if has_ball and c2 + ball_r > Z_NEAR and ball_info[3] > 0.0:
        i0, i1 = _angular_extent(c0, c2, ball_r, focal, params.cx, params.width)
        j0, j1 = _angular_extent(c1, c2, ball_r, focal, params.cy, params.height)
    else:
        i0, i1, j0, j1 = 0, 0, 0, 0
    if i1 <= i0 or j1 <= j0:
        i0, i1, j0, j1 = 0, 0, 0, 0
    ball_box = work.ball_box[n]
    ball_box[0] = i0
    ball_box[1] = i1
    ball_box[2] = j0
    ball_box[3] = j1

    # Objects far to near (painter's order): posts, crossbars, cylinders, ball.
    n_objects = n_posts + n_bars + n_cyl + 1
    keys = scratch.keys[n]
    order = work.object_order[n]
    for p in range(n_posts):
        dx = posts[p, 0] - cam[0]
        dy = posts[p, 1] - cam[1]
        keys[p] = dx * dx + dy * dy
    for b in range(n_bars):
        dx = bars[b, 0] - cam[0]
        dy = min(max(cam[1], bars[b, 1]), bars[b, 2]) - cam[1]
        dz = bars[b, 3] - cam[2]
        keys[n_posts + b] = dx * dx + dy * dy + dz * dz
    for c in range(n_cyl):
        dx = cylinders[n, c, 0] - cam[0]
        dy = cylinders[n, c, 1] - cam[1]
        keys[n_posts + n_bars + c] = dx * dx + dy * dy
    keys[n_objects - 1] = c0 * c0 + c1 * c1 + c2 * c2
    for k in range(n_objects):
        order[k] = k
    for k in range(1, n_objects):  # insertion sort, descending distance
        m = k
        while m > 0 and keys[order[m - 1]] < keys[order[m]]:
            tmp = order[m - 1]
            order[m - 1] = order[m]
            order[m] = tmp
            m -= 1

    # the paint quads in view, and the first row that shows more than background
    visible_paint = work.visible_paint[n]
    n_visible = 0
    for q in range(n_paint):
        if quad_rows[q, 1] > quad_rows[q, 0]:
            visible_paint[n_visible] = q
            n_visible += 1
    work.visible_count[n] = n_visible
    first = params.height
    for q in range(n_paint, n_paint + 1 + n_posts + n_bars + n_cyl):
        if quad_rows[q, 1] > quad_rows[q, 0]:
            first = min(first, quad_rows[q, 0])
    if ball_box[3] > ball_box[2]:
        first = min(first, ball_box[2])
    work.first_row[n] = first


@cached_njit(**JIT_PART)
def _tangents(
    ca: float, cb: float, r: float, pa: float, pb: float
) -> tuple[bool, float, float, float, float, float, float, float]:
    """The circle of centre ``(ca, cb)`` and radius ``r`` seen from ``(pa, pb)``, in one
    plane: ``(outside, ua, ub, cos_b, t1a, t1b, t2a, t2b)``: whether the viewpoint is outside
    (all else 0 if not), the unit vector from the centre towards it, the cosine of the angle
    at the centre between it and the tangent points, and the two tangent points (the centre
    plus ``r`` times the unit vector turned by ``+-b``)."""
    da = pa - ca
    db = pb - cb
    dist = math.sqrt(da * da + db * db)
    if dist <= r * 1.001:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    ua, ub = da / dist, db / dist
    cos_b = r / dist
    sin_b = math.sqrt(1.0 - cos_b * cos_b)
    t1a = ca + r * (ua * cos_b - ub * sin_b)
    t1b = cb + r * (ub * cos_b + ua * sin_b)
    t2a = ca + r * (ua * cos_b + ub * sin_b)
    t2b = cb + r * (ub * cos_b - ua * sin_b)
    return True, ua, ub, cos_b, t1a, t1b, t2a, t2b


@cached_njit(**JIT)
def _angular_extent(
    a: float, z: float, r: float, focal: float, centre: float, size: int
) -> tuple[int, int]:
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


@cached_njit(**JIT)
def _to_camera(
    rot: np.ndarray, cam: np.ndarray, x: float, y: float, z: float, out: np.ndarray
) -> None:
    """World point ``(x, y, z)`` in the coordinates of the camera at ``cam`` (3,) turned by
    ``rot`` (3, 3), into ``out`` (3,)."""
    dx = x - cam[0]
    dy = y - cam[1]
    dz = z - cam[2]
    out[0] = rot[0, 0] * dx + rot[0, 1] * dy + rot[0, 2] * dz
    out[1] = rot[1, 0] * dx + rot[1, 1] * dy + rot[1, 2] * dz
    out[2] = rot[2, 0] * dx + rot[2, 1] * dy + rot[2, 2] * dz
