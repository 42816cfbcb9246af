"""The row pass of the renderer and its entry points (see :mod:`activevision.rendering.kernels`
for the method).

Entry points: :func:`render_kernel` hands row work to the numba threads in interleaved sets
(rows ``b, b + B, b + 2B, ...``) so that sky-only rows do not pile up on one thread;
:func:`render_kernel_serial` renders on the calling thread (single frames). Both take the
:class:`.bundles.Scene`, :class:`.bundles.Params` and :class:`.bundles.Cameras` as plain
tuples of their fields (see :mod:`.bundles`), and ``garbage`` last: 0, or a seed to fill the
work memory with garbage first (:func:`.garbage.fill_garbage`, for the tests; the images
must not change).
"""

from __future__ import annotations

import numpy as np
from numba import prange

from activevision.geometry.jit import cached_njit
from activevision.rendering.appearance import LOOK
from activevision.rendering.kernels.bundles import (
    JIT,
    JIT_PART,
    Cameras,
    Fields,
    Looks,
    Params,
    RenderWork,
    Scene,
    SetupScratch,
    allocate_scratch,
    allocate_work,
)
from activevision.rendering.kernels.camera_setup import setup_camera
from activevision.rendering.kernels.coverage import (
    ball_shade,
    fully_inside,
    paint_quad_pixels,
    quad_coverage,
    ring_row,
    span,
)
from activevision.rendering.kernels.garbage import GARBAGE_KINDS, fill_garbage, garbage_floats
from activevision.rendering.kernels.looks import (
    KNOT,
    KNOT_ROWS,
    illuminate_row,
    texture_row,
    worn_paint,
)
from activevision.rendering.kernels.selects import clamp

STRIPES = LOOK["stripes"]
GRAIN = LOOK["grain"]
CLUTTER = LOOK["clutter"]
WEAR = LOOK["line_wear"]


@cached_njit(**JIT_PART)
def _quad_columns(
    edges: np.ndarray, v: float, width: int, min_width: int
) -> tuple[int, int, int, int]:
    """Columns of row centre ``v`` that a quad touches, ``[s0, s1)``, and those it covers
    entirely, ``[i0, i1)`` (``(s1, s1)`` when none, or when ``[s0, s1)`` is not wider than
    ``min_width``: not worth looking for). Returns ``(s0, s1, i0, i1)``."""
    s0, s1 = span(edges, 4, v, -1.0, width)
    i0, i1 = s1, s1
    if s1 - s0 > min_width:
        i0, i1 = span(edges, 4, v, 1.0, width)
        if i1 <= i0:
            i0, i1 = s1, s1
    return s0, s1, i0, i1


@cached_njit(**JIT_PART)
def _carpet_row(edges: np.ndarray, v: float, params: Params, value: np.ndarray) -> None:
    """``value`` (W,) of a row the carpet's ``edges`` reach: background, the carpet and its
    anti-aliased border."""
    width = value.shape[0]
    grass = params.grass
    background = params.background
    if fully_inside(edges, 4, 0.5, v) and fully_inside(edges, 4, width - 0.5, v):
        # Both end pixels fully on the carpet, so the whole row is (convexity).
        value[:] = grass
        return
    o0, o1, i0, i1 = _quad_columns(edges, v, width, -1)
    value[:o0] = background
    value[o1:] = background
    value[i0:i1] = grass
    # partly covered pixels: [o0, i0) and [i1, o1)
    for i in range(o0, i0):
        c = quad_coverage(edges, i + 0.5, v)
        value[i] = background + c * (grass - background)
    for i in range(i1, o1):
        c = quad_coverage(edges, i + 0.5, v)
        value[i] = background + c * (grass - background)


@cached_njit(**JIT_PART)
def _paint_quad_row(edges: np.ndarray, v: float, paint: np.ndarray) -> tuple[int, int]:
    """Max-combine a painted quad's coverage of row centre ``v`` into ``paint``; returns the
    columns ``[s0, s1)`` it touches."""
    # pixels fully inside a quad wider than 4 px: coverage 1 without per-pixel work
    s0, s1, i0, i1 = _quad_columns(edges, v, paint.shape[0], 4)
    paint[i0:i1] = 1.0
    paint_quad_pixels(edges, v, s0, i0, paint)
    paint_quad_pixels(edges, v, i1, s1, paint)
    return s0, s1


@cached_njit(**JIT_PART)
def _post_quad_row(edges: np.ndarray, v: float, grey: float, value: np.ndarray) -> None:
    """Composite a post's or crossbar's quad of grey ``grey`` over row centre ``v`` of
    ``value``, with its coverage as alpha."""
    s0, s1, i0, i1 = _quad_columns(edges, v, value.shape[0], 4)
    value[i0:i1] = grey
    for i in range(s0, i0):
        a = quad_coverage(edges, i + 0.5, v)
        value[i] += a * (grey - value[i])
    for i in range(i1, s1):
        a = quad_coverage(edges, i + 0.5, v)
        value[i] += a * (grey - value[i])


@cached_njit(**JIT)
def render_rows(
    n: int,
    rows: tuple[int, int],
    out: np.ndarray,
    params: Params,
    work: RenderWork,
    looks: Looks,
    value: np.ndarray,
    paint: np.ndarray,
    knots: np.ndarray,
    texture: np.ndarray,
) -> None:
    """Rows ``row0, row0 + row_step, ...`` (``rows = (row0, row_step)``) of image ``n`` into
    ``out`` (N, H, W). ``value`` (W,) float32 scratch; ``paint`` (W,) float32 scratch that is
    all zero on entry and on exit; ``knots`` (KNOT_ROWS, W // KNOT + 2) float64 and
    ``texture`` (2, W) float32 scratch of the looks' patterns (:func:`.looks.texture_row`).

    The per-row helpers take single arrays and :class:`.bundles.Params` (scalars), never the
    work bundle: every call with a bundle of arrays would count references to all of them,
    once per row. (Nor does this function take the scene: the counts it needs are the work
    arrays' sizes. Every array handed to it is counted on every thread for every camera.)"""
    row0, row_step = rows
    height = out.shape[1]
    width = out.shape[2]
    n_paint = work.visible_paint.shape[1]
    carpet = n_paint
    n_quad_objects = work.object_order.shape[1] - 1  # posts, bars, cylinders (the ball last)
    object_grey = work.object_grey[n]
    quad_edges = work.quad_edges[n]
    quad_rows = work.quad_rows[n]
    ring_edges = work.ring_edges[n]
    ring_rows = work.ring_rows[n]
    homography = work.homography[n]
    ball_info = work.ball_info[n]
    ball_box = work.ball_box[n]
    object_order = work.object_order[n]
    visible_paint = work.visible_paint[n]
    n_visible = work.visible_count[n]
    first_row = work.first_row[n]
    n_sides = ring_edges.shape[1]
    line_minus_grass = params.line - params.grass
    bg_u8 = np.uint8(int(params.background + 0.5))
    looks_on = looks.enabled
    look = looks.rows[n] if looks_on else looks.rows[0]
    noise = looks.noise
    ray = work.ray[n]
    textured = looks_on and (look[STRIPES] != 0.0 or look[GRAIN] != 0.0 or look[CLUTTER] != 0.0)
    worn = looks_on and look[WEAR] > 0.0
    for j in range(row0, height, row_step):
        if j < first_row and not looks_on:
            out[n, j, :] = bg_u8
            continue
        v = j + 0.5
        # --- ground: background, carpet, its anti-aliased border
        if quad_rows[carpet, 0] <= j < quad_rows[carpet, 1]:
            _carpet_row(quad_edges[carpet], v, params, value)
        else:
            value[:] = params.background
        if textured:
            texture_row(v, value, homography, ray, look, params, noise, knots, texture)
        # --- paint: lines, marks, centre circle (coverages combine with max)
        touched_lo = width
        touched_hi = 0
        for vq in range(n_visible):
            q = visible_paint[vq]
            if quad_rows[q, 0] <= j < quad_rows[q, 1]:
                s0, s1 = _paint_quad_row(quad_edges[q], v, paint)
                if s1 > s0:
                    touched_lo = min(touched_lo, s0)
                    touched_hi = max(touched_hi, s1)
        if ring_rows[0, 0] <= j < ring_rows[0, 1]:
            s0, s1 = span(ring_edges[0], n_sides, v, -1.0, width)
            # The hole polygon has its own row range (empty when it is off-image while the
            # ring is not): outside it no pixel of this row is certainly in the hole.
            h0, h1 = 0, 0
            if ring_rows[1, 0] <= j < ring_rows[1, 1]:
                h0, h1 = span(ring_edges[1], n_sides, v, 1.0, width)
            ring_row(homography, v, (s0, s1), (h0, h1), params, paint)
            if s1 > s0:
                touched_lo = min(touched_lo, s0)
                touched_hi = max(touched_hi, s1)
        if worn and touched_hi > touched_lo:
            worn_paint(v, touched_lo, touched_hi, paint, homography, look, noise)
        for i in range(touched_lo, touched_hi):
            value[i] += paint[i] * line_minus_grass
            paint[i] = 0.0
        # --- posts, crossbars, ball: far to near, coverage as alpha
        for k in range(n_quad_objects + 1):
            o = object_order[k]
            if o < n_quad_objects:
                q = n_paint + 1 + o
                if quad_rows[q, 0] <= j < quad_rows[q, 1]:
                    _post_quad_row(quad_edges[q], v, object_grey[o], value)
            elif ball_box[2] <= j < ball_box[3]:
                for i in range(ball_box[0], ball_box[1]):
                    a, grey = ball_shade(ball_info, i + 0.5, v, params)
                    if a > 0.0:
                        value[i] += a * (grey - value[i])
        if looks_on:
            illuminate_row(v, value, look, params)
        for i in range(width):
            out[n, j, i] = np.uint8(
                clamp(value[i] + np.float32(0.5), np.float32(0.0), np.float32(255.0))
            )


@cached_njit(**JIT_PART)
def _check_size(params: Params, out: np.ndarray) -> None:
    """Every kernel takes the image size from ``params``: ``out`` must have it."""
    if out.shape[1] != params.height or out.shape[2] != params.width:
        raise ValueError("render kernels: out does not have the image size of params")


@cached_njit(**JIT_PART)
def _bundles(
    scene: Fields, params: Fields, cameras: Fields, looks: Fields, out: np.ndarray
) -> tuple[Scene, Params, Cameras, Looks, RenderWork, SetupScratch]:
    """An entry point's bundles from the tuples of their fields (size-checked against
    ``out``), and the work memory: ``(scene, params, cameras, looks, work, scratch)``."""
    params = Params(*params)
    _check_size(params, out)
    cams = Cameras(*cameras)
    scene = Scene(*scene)
    looks = Looks(*looks)
    n_cams = cams.pose.shape[0]
    n_cyl = looks.cylinders.shape[1]
    return (
        scene,
        params,
        cams,
        looks,
        allocate_work(n_cams, scene, n_cyl),
        allocate_scratch(n_cams, scene, n_cyl),
    )


@cached_njit(**JIT, parallel=True)
def render_kernel(
    scene: Fields,
    params: Fields,
    cameras: Fields,
    looks: Fields,
    row_blocks: int,
    out: np.ndarray,
    garbage: int,
) -> None:
    """Render the cameras into ``out`` (N, H, W) uint8, on all numba threads. Each camera's
    rows are split into ``row_blocks`` interleaved sets of work."""
    # As _bundles, written out: numba's parfor lowering finds the class of a namedtuple used
    # in a prange body only from the call that made it, so each is made right here.
    scene = Scene(*scene)
    params = Params(*params)
    cams = Cameras(*cameras)
    looks = Looks(*looks)
    _check_size(params, out)
    n_cams = cams.pose.shape[0]
    n_cyl = looks.cylinders.shape[1]
    work = RenderWork(*allocate_work(n_cams, scene, n_cyl))
    scratch = SetupScratch(*allocate_scratch(n_cams, scene, n_cyl))
    width = params.width
    if garbage != 0:
        fill_garbage(work, scratch, np.empty(1, dtype=np.float32), garbage)
    for n in prange(n_cams):
        setup_camera(n, scene, params, cams, looks, work, scratch)
    for item in prange(n_cams * row_blocks):
        n = item // row_blocks
        value = np.empty(width, dtype=np.float32)
        if garbage != 0:
            garbage_floats(value, garbage + GARBAGE_KINDS * item)
        paint = np.zeros(width, dtype=np.float32)
        knots = np.empty((KNOT_ROWS, width // KNOT + 2))
        texture = np.empty((2, width), dtype=np.float32)
        if garbage != 0:
            garbage_floats(knots, garbage + GARBAGE_KINDS * (item + n_cams * row_blocks))
            garbage_floats(texture, garbage + GARBAGE_KINDS * (item + 2 * n_cams * row_blocks))
        render_rows(
            n,
            (item - n * row_blocks, row_blocks),
            out,
            params,
            work,
            looks,
            value,
            paint,
            knots,
            texture,
        )


@cached_njit(**JIT)
def render_kernel_serial(
    scene: Fields, params: Fields, cameras: Fields, looks: Fields, out: np.ndarray, garbage: int
) -> None:
    """:func:`render_kernel` on the calling thread only: no thread hand-off, which matters
    for single frames (and on machines whose cores are busy with other work)."""
    scene, params, cams, looks, work, scratch = _bundles(scene, params, cameras, looks, out)
    width = params.width
    value = np.empty(width, dtype=np.float32)
    if garbage != 0:
        fill_garbage(work, scratch, value, garbage)
    paint = np.zeros(width, dtype=np.float32)
    knots = np.empty((KNOT_ROWS, width // KNOT + 2))
    texture = np.empty((2, width), dtype=np.float32)
    if garbage != 0:
        garbage_floats(knots, garbage + 20 * GARBAGE_KINDS)
        garbage_floats(texture, garbage + 21 * GARBAGE_KINDS)
    for n in range(cams.pose.shape[0]):
        setup_camera(n, scene, params, cams, looks, work, scratch)
        render_rows(n, (0, 1), out, params, work, looks, value, paint, knots, texture)
