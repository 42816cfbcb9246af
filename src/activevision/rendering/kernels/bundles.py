"""The typed bundles the renderer's kernels take (numba namedtuples), and their work memory.

A kernel takes a few of these instead of tens of positional arrays and scalars; fields are
read by name (``params.focal``, ``work.quad_rows``), so no call depends on the order of a
tuple. From Python, the entry points (:mod:`.raster`) are handed each bundle as a *plain*
tuple of its fields (``tuple(bundle)``) and rebuild the namedtuple inside: numba's dispatcher
types a plain tuple of arrays and scalars in C, but a namedtuple in Python, which costs about
2.5 us per bundle and call (a single frame takes about 30 us). Inside, a bundle that holds
arrays is reference-counted array by array on every call it is handed to, so the kernels
called per row, edge or pixel take :class:`Params` (scalars only) and single arrays, not
:class:`Scene` or :class:`RenderWork`.
"""

from __future__ import annotations

from typing import Any, Literal, NamedTuple, TypedDict

import numpy as np

from activevision.geometry.camera import CameraConfig
from activevision.geometry.jit import cached_njit
from activevision.rendering.config import RenderConfig
from activevision.rendering.scene import SceneArrays


class JitFlags(TypedDict, total=False):
    """The ``numba.njit`` flags the renderer's kernels use (typed for ``njit(**flags)``);
    :func:`~activevision.geometry.jit.cached_njit` adds the cache where numba can keep one."""

    fastmath: bool
    nogil: bool
    error_model: Literal["python", "numpy"]
    inline: Literal["never", "always"]


#: Flags of every renderer kernel (the entry points add ``parallel``). ``error_model="numpy"``:
#: a float division by zero gives inf or nan instead of a check and a raise in every loop
#: that divides (an exit from the loop keeps it from vectorising); no kernel divides by zero.
JIT: JitFlags = {"fastmath": True, "nogil": True, "error_model": "numpy"}
#: Flags of the parts of one kernel that only it calls: inlined into it by numba (one
#: compiled function instead of several, each linking and optimising its callees again).
JIT_PART: JitFlags = {**JIT, "inline": "always"}
#: Distance (m) from the carpet's edge to the walls of the hall around it.
HALL_MARGIN = 1.5
#: Depth (m) at which polygons are clipped before projection.
Z_NEAR = 1e-3
#: Parameters stored per edge: l0, l1, l2 (unit normal form), hi, lo (trapezoid half-widths),
#: 1 / (2 hi), 1 / (8 hi lo), 1 / l0 (0 when l0 is 0).
EDGE_PARAMS = 8
#: A bundle as the entry points take it from Python: the plain tuple of its fields
#: (``tuple(bundle)``), rebuilt into the namedtuple inside. (To mypy, ``tuple()`` of a
#: namedtuple is a homogeneous tuple; the field types are checked where the bundle is made.)
Fields = tuple[Any, ...]


class Scene(NamedTuple):
    """The static scene every camera sees (world frame, metres)."""

    paint_quads: np.ndarray  #: (Q, 4, 2) painted lines, penalty marks, centre mark
    carpet: np.ndarray  #: (4, 2) the carpet
    ring_polygons: np.ndarray  #: (2, S, 2) around the centre circle, inside its hole
    posts: np.ndarray  #: (P, 4) axis x, axis y, radius, height
    bars: np.ndarray  #: (B, 5) axis x, y start, y end, axis height, radius
    #: (Q, 4, 2) how each paint quad corner moves per metre of extra line width
    paint_expand: np.ndarray


class Params(NamedTuple):
    """The scalars of a render: camera intrinsics and image size, the centre circle and ball,
    the greys. Scalars only, so the kernels called per row or pixel take it whole (a bundle
    holding arrays is reference-counted on every call)."""

    width: int  #: image size (px)
    height: int
    focal: float  #: focal length (px)
    cx: float  #: principal point (px)
    cy: float
    cam_h: float  #: camera height above the ground (m)
    ring_x: float  #: centre circle: centre (m), inner and outer radius
    ring_y: float
    ring_in: float
    ring_out: float
    ball_r: float  #: ball radius (m)
    grass: float  #: greys (0-255)
    line: float
    background: float
    post: float
    ball_lit: float
    ball_shadow: float
    hall_x: float  #: half extents (m) of the hall whose walls stand beyond the carpet
    hall_y: float


class Cameras(NamedTuple):
    """The N cameras of one call."""

    pose: np.ndarray  #: (N, 3) robot poses (x, y, theta)
    pan: np.ndarray  #: (N,) head yaw
    tilt: np.ndarray  #: (N,) head pitch
    ball_xy: np.ndarray  #: (N, 2) ball on the ground
    has_ball: bool  #: whether the ball is drawn at all


class Looks(NamedTuple):
    """Per-camera appearance (:mod:`activevision.rendering.appearance`) and other robots."""

    rows: np.ndarray  #: (N, len(LOOK_FIELDS)) float64 look rows
    tone: np.ndarray  #: (N, 256) uint8 tone curves
    #: (N, C, 6) vertical cylinders x, y, radius, bottom z, top z, grey; radius 0: none
    cylinders: np.ndarray
    noise: np.ndarray  #: (T,) float32 standard normal table (patterns and sensor noise)
    enabled: bool  #: False: the clean render (rows and tone unread)


class RenderWork(NamedTuple):
    """Per-call work memory, one slice per camera (first axis): what the setup pass
    (:func:`.camera_setup.setup_camera`) writes for the row pass
    (:func:`.raster.render_rows`)."""

    quad_edges: np.ndarray  #: (N, Q', 4, EDGE_PARAMS) paint quads, carpet, posts, bars
    quad_rows: np.ndarray  #: (N, Q', 2) image rows [first, end) of each quad
    ring_edges: np.ndarray  #: (N, 2, S, EDGE_PARAMS) outer and hole polygon of the ring
    ring_rows: np.ndarray  #: (N, 2, 2) their rows
    homography: np.ndarray  #: (N, 3, 3) pixel -> ground
    #: (N, 3, 4) pixel -> world ray direction (3, 3), then the camera centre (the hall)
    ray: np.ndarray
    ball_info: np.ndarray  #: (N, 10) see :func:`.coverage.ball_shade`
    ball_box: np.ndarray  #: (N, 4) ball columns [i0, i1), rows [j0, j1)
    object_order: np.ndarray  #: (N, P + B + C + 1) posts, bars, cylinders, ball far to near
    object_grey: np.ndarray  #: (N, P + B + C) grey of each post, bar and cylinder
    first_row: np.ndarray  #: (N,) rows above it show only background
    visible_paint: np.ndarray  #: (N, Q) indices of the paint quads in view
    visible_count: np.ndarray  #: (N,) how many


class SetupScratch(NamedTuple):
    """The setup pass's own per-call scratch, one slice per camera. (Apart from
    :class:`RenderWork` so that the row pass, handed the work per camera on every thread,
    counts references to fewer arrays.)"""

    rot: np.ndarray  #: (N, 3, 3) world -> camera rotation
    cam: np.ndarray  #: (N, 3) camera centre
    pts: np.ndarray  #: (N, max(8, S), 3) polygon in camera coordinates
    clip: np.ndarray  #: (N, 2, S + 8, 3) clipping scratch
    keys: np.ndarray  #: (N, P + B + C + 1) distances for the painter's order


class Optics(NamedTuple):
    """The pinhole camera and image size: what the per-edge kernels of the setup pass need
    of :class:`Params` (few scalars: the setup hands it to a kernel per edge)."""

    focal: float
    cx: float
    cy: float
    width: int
    height: int


def scene_bundles(
    scene: SceneArrays, camera: CameraConfig, config: RenderConfig
) -> tuple[Scene, Params]:
    """The kernels' :class:`Scene` and :class:`Params` of ``scene`` seen by ``camera`` with
    ``config``'s greys (every scalar a float or an int, so one compiled specialisation serves
    every renderer)."""
    ring_x, ring_y, ring_in, ring_out = (float(v) for v in scene.ring)
    arrays = Scene(
        paint_quads=scene.paint_quads,
        carpet=scene.carpet_quad,
        ring_polygons=scene.ring_polygons,
        posts=scene.posts,
        bars=scene.crossbars,
        paint_expand=scene.paint_expand,
    )
    params = Params(
        width=int(camera.width),
        height=int(camera.height),
        focal=float(camera.focal),
        cx=camera.width / 2,
        cy=camera.height / 2,
        cam_h=float(camera.camera_height),
        ring_x=ring_x,
        ring_y=ring_y,
        ring_in=ring_in,
        ring_out=ring_out,
        ball_r=float(scene.ball_radius),
        grass=float(config.grass),
        line=float(config.line),
        background=float(config.background),
        post=float(config.post),
        ball_lit=float(config.ball_lit),
        ball_shadow=float(config.ball_shadow),
        hall_x=float(np.abs(scene.carpet_quad[:, 0]).max()) + HALL_MARGIN,
        hall_y=float(np.abs(scene.carpet_quad[:, 1]).max()) + HALL_MARGIN,
    )
    return arrays, params


@cached_njit(**JIT)
def allocate_work(n_cams: int, scene: Scene, n_cyl: int) -> RenderWork:
    """Per-call :class:`RenderWork` for ``n_cams`` cameras. Uninitialised on purpose (speed):
    for each camera the setup writes every entry that the row pass reads, so an image never
    depends on what the memory held before (:func:`.garbage.fill_garbage` tests exactly
    that)."""
    n_paint = scene.paint_quads.shape[0]
    # carpet after paint, then posts, bars and cylinders
    n_quads = n_paint + 1 + scene.posts.shape[0] + scene.bars.shape[0] + n_cyl
    n_sides = scene.ring_polygons.shape[1]
    return RenderWork(
        np.empty((n_cams, n_quads, 4, EDGE_PARAMS)),
        np.empty((n_cams, n_quads, 2), dtype=np.int64),
        np.empty((n_cams, 2, n_sides, EDGE_PARAMS)),
        np.empty((n_cams, 2, 2), dtype=np.int64),
        np.empty((n_cams, 3, 3)),
        np.empty((n_cams, 3, 4)),
        np.empty((n_cams, 10)),
        np.empty((n_cams, 4), dtype=np.int64),
        np.empty((n_cams, n_quads - n_paint), dtype=np.int64),  # posts, bars, cyls, ball
        np.empty((n_cams, n_quads - n_paint - 1)),
        np.empty(n_cams, dtype=np.int64),
        np.empty((n_cams, n_paint), dtype=np.int64),
        np.empty(n_cams, dtype=np.int64),
    )


@cached_njit(**JIT)
def allocate_scratch(n_cams: int, scene: Scene, n_cyl: int) -> SetupScratch:
    """Per-call :class:`SetupScratch` for ``n_cams`` cameras (uninitialised, as
    :func:`allocate_work`)."""
    n_objects = scene.posts.shape[0] + scene.bars.shape[0] + n_cyl + 1  # the ball last
    n_sides = scene.ring_polygons.shape[1]
    return SetupScratch(
        np.empty((n_cams, 3, 3)),
        np.empty((n_cams, 3)),
        np.empty((n_cams, max(8, n_sides), 3)),
        np.empty((n_cams, 2, n_sides + 8, 3)),
        np.empty((n_cams, n_objects)),
    )
