"""The static scene of one field as flat arrays: what the renderers draw.

Everything the camera can see is one of four primitives:

* **ground quads** — painted lines (each a ``line_width`` wide rectangle whose ends are
  extended by half a line width, so corners and T-junctions close like painted ones), the
  penalty marks, a short centre mark crossing the halfway line, and the carpet;
* **the centre-circle ring** — the ground between radii ``R - w/2`` and ``R + w/2``;
* **goal cylinders** — vertical posts (diameter ``post_diameter``, from the ground up to
  the top of the crossbar, ``goal_height + post_diameter``) and the horizontal crossbars
  joining the post axes, whose lower edge is at ``goal_height``;
* **the ball** — a sphere of radius ``ball_radius`` resting on the ground.

Quad corners are listed so that edges ``(0, 1)`` and ``(2, 3)`` are opposite, as are
``(1, 2)`` and ``(3, 0)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from activevision.geometry.field import FieldSpec
from activevision.geometry.landmarks import painted_lines


def _line_quad(a: np.ndarray, b: np.ndarray, width: float) -> np.ndarray:
    """Corners (4, 2) of the painted rectangle around the centre line ``a``-``b``."""
    along = (b - a) / np.linalg.norm(b - a)
    normal = np.array([-along[1], along[0]])
    a = a - along * width / 2
    b = b + along * width / 2
    half = normal * width / 2
    return np.array([a + half, b + half, b - half, a - half])


def _line_expand(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """How the corners (4, 2) of :func:`_line_quad` move per metre of line width."""
    along = (b - a) / np.linalg.norm(b - a)
    normal = np.array([-along[1], along[0]])
    return 0.5 * np.array([normal - along, along + normal, along - normal, -along - normal])


def _square_quad(centre: tuple[float, float], side: float) -> np.ndarray:
    x, y = centre
    h = side / 2
    return np.array([[x - h, y - h], [x + h, y - h], [x + h, y + h], [x - h, y + h]])


#: Sides of the polygons bounding the centre-circle ring.
RING_POLYGON_SIDES = 16


def _regular_polygon(radius: float, sides: int = RING_POLYGON_SIDES) -> np.ndarray:
    """Regular polygon (sides, 2) with circumradius ``radius``, counter-clockwise."""
    angles = (np.arange(sides) + 0.5) * (2 * np.pi / sides)
    return radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)


@dataclass(frozen=True)
class SceneArrays:
    """The static scene of one field (all float64, metres)."""

    paint_quads: np.ndarray  #: (Q, 4, 2) painted lines, penalty marks, centre mark
    #: (Q, 4, 2) how each corner moves per metre of extra line width (0 for the marks)
    paint_expand: np.ndarray
    carpet_quad: np.ndarray  #: (4, 2) the green carpet (field plus border strip)
    ring: np.ndarray  #: (4,) centre x, centre y, inner radius, outer radius
    ring_polygons: np.ndarray  #: (2, S, 2) polygons around the outer and inside the inner edge
    posts: np.ndarray  #: (P, 4) axis x, axis y, radius, height
    crossbars: np.ndarray  #: (B, 5) axis x, y start, y end, axis height z, radius
    ball_radius: float


def build_scene(spec: FieldSpec) -> SceneArrays:
    """The renderable scene of ``spec``."""
    w = spec.line_width
    lines = painted_lines(spec)
    quads = [_line_quad(seg[0], seg[1], w) for seg in lines]
    expand = [_line_expand(seg[0], seg[1]) for seg in lines]
    hl = spec.half_length
    for s in (1.0, -1.0):
        quads.append(
            _square_quad((s * (hl - spec.penalty_mark_distance), 0.0), spec.penalty_mark_size)
        )
        expand.append(np.zeros((4, 2)))
    # Centre mark: a short line across the halfway line, as long as a penalty mark is wide.
    half_mark = spec.penalty_mark_size / 2
    mark_ends = np.array([-half_mark + w / 2, 0.0]), np.array([half_mark - w / 2, 0.0])
    quads.append(_line_quad(*mark_ends, w))
    expand.append(_line_expand(*mark_ends))
    bx, by = spec.carpet_half_extent
    carpet = np.array([[-bx, -by], [bx, -by], [bx, by], [-bx, by]], dtype=np.float64)

    radius = spec.centre_circle_diameter / 2
    r_in, r_out = radius - w / 2, radius + w / 2
    # The outer polygon contains the ring; the inner one lies inside its hole.
    polygons = np.stack(
        [
            _regular_polygon(r_out / math.cos(math.pi / RING_POLYGON_SIDES)),
            _regular_polygon(r_in),
        ]
    )

    post_y = (spec.goal_width + spec.post_diameter) / 2
    post_r = spec.post_diameter / 2
    post_height = spec.goal_height + spec.post_diameter
    posts, bars = [], []
    for s in (1.0, -1.0):
        for sy in (1.0, -1.0):
            posts.append((s * hl, sy * post_y, post_r, post_height))
        bars.append((s * hl, -post_y, post_y, spec.goal_height + post_r, post_r))
    return SceneArrays(
        paint_quads=np.ascontiguousarray(np.asarray(quads, dtype=np.float64)),
        paint_expand=np.ascontiguousarray(np.asarray(expand, dtype=np.float64)),
        carpet_quad=carpet,
        ring=np.array([0.0, 0.0, r_in, r_out]),
        ring_polygons=np.ascontiguousarray(polygons),
        posts=np.asarray(posts, dtype=np.float64),
        crossbars=np.asarray(bars, dtype=np.float64),
        ball_radius=float(spec.ball_radius),
    )
