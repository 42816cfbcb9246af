"""Top views of the field on a matplotlib ``Axes``: robot, ball, camera footprints and
landmarks, in the style of the paper's figures (robot as a red circle, best viewpoint red,
current blue)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Circle, Polygon, Rectangle

from activevision.geometry import (
    CameraConfig,
    FieldSpec,
    LandmarkSet,
    LandmarkType,
    footprint_polygon,
    painted_lines,
)

#: Landmark colours: the paper's Figure 2 (L red, T blue, lines yellow, boundary purple),
#: and distinct colours for the types it does not show.
LANDMARK_COLOURS = {
    LandmarkType.L_CORNER: "red",
    LandmarkType.T_JUNCTION: "blue",
    LandmarkType.X_CROSSING: "darkorange",
    LandmarkType.PENALTY_MARK: "magenta",
    LandmarkType.GOAL_POST: "black",
    LandmarkType.CENTRE_CIRCLE: "cyan",
    LandmarkType.LINE: "gold",
    LandmarkType.FIELD_BOUNDARY: "purple",
}


#: What each landmark type is called in a figure's colour key.
LANDMARK_NAMES = {
    LandmarkType.L_CORNER: "L",
    LandmarkType.T_JUNCTION: "T",
    LandmarkType.X_CROSSING: "X",
    LandmarkType.PENALTY_MARK: "penalty mark",
    LandmarkType.GOAL_POST: "goal post",
    LandmarkType.CENTRE_CIRCLE: "centre",
    LandmarkType.LINE: "lines",
    LandmarkType.FIELD_BOUNDARY: "boundary",
}


def landmark_key() -> str:
    """The landmark colours as a caption: ``"L red, T blue, ..."``."""
    return ", ".join(f"{LANDMARK_NAMES[t]} {c}" for t, c in LANDMARK_COLOURS.items())


def draw_field(ax: Axes, spec: FieldSpec) -> None:
    """Carpet, painted lines, centre circle, penalty marks and goals."""
    bx, by = spec.carpet_half_extent
    ax.add_patch(Rectangle((-bx, -by), 2 * bx, 2 * by, color="#3a8f3a", zorder=0))
    for (x0, y0), (x1, y1) in painted_lines(spec):
        ax.plot([x0, x1], [y0, y1], color="white", lw=1.2, zorder=1)
    ax.add_patch(
        Circle((0, 0), spec.centre_circle_diameter / 2, fill=False, ec="white", lw=1.2, zorder=1)
    )
    for s in (1, -1):
        ax.plot(s * (spec.half_length - spec.penalty_mark_distance), 0, "w+", ms=5, zorder=1)
        gx = s * spec.half_length
        gy = spec.goal_width / 2 + spec.post_diameter / 2
        ax.plot(
            [gx, gx + s * spec.goal_depth, gx + s * spec.goal_depth, gx],
            [gy, gy, -gy, -gy],
            color="lightgrey",
            lw=1.5,
            zorder=1,
        )
    ax.set_xlim(-bx - 0.1, bx + 0.1)
    ax.set_ylim(-by - 0.1, by + 0.1)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def draw_footprint(
    ax: Axes,
    pose: Sequence[float] | np.ndarray,
    pan: float,
    tilt: float,
    cam: CameraConfig,
    colour: str,
    max_distance: float = 4.0,
    alpha: float = 0.3,
    **kwargs: Any,
) -> None:
    """The ground the camera sees from ``pose`` at ``(pan, tilt)``, cut at ``max_distance``."""
    poly = footprint_polygon(np.asarray(pose)[None], [pan], [tilt], cam, max_distance)[0]
    ax.add_patch(Polygon(poly, closed=True, fc=colour, ec=colour, alpha=alpha, zorder=2, **kwargs))


def draw_landmarks(
    ax: Axes,
    landmarks: LandmarkSet,
    ids: Sequence[int] | np.ndarray,
    points: np.ndarray | None = None,
) -> None:
    """Landmarks ``ids`` coloured by type; segments drawn whole, with their measured point
    (``points``, (K, 2)) marked when given."""
    for k in ids:
        colour = LANDMARK_COLOURS[LandmarkType(landmarks.types[k])]
        (x0, y0), (x1, y1) = landmarks.segments[k]
        if landmarks.is_point[k]:
            ax.plot(x0, y0, "o", color=colour, ms=6, mec="white", mew=0.7, zorder=4)
        else:
            ax.plot([x0, x1], [y0, y1], color=colour, lw=3, alpha=0.85, zorder=3)
            if points is not None:
                ax.plot(*points[k], "o", color=colour, ms=4, mec="black", mew=0.5, zorder=4)


def draw_robot(
    ax: Axes,
    pose: Sequence[float] | np.ndarray,
    ball: Sequence[float] | np.ndarray | None = None,
    ball_radius: float = 0.07,
) -> None:
    """The robot as a red circle with a heading arrow; the ball white when given."""
    x, y, theta = pose
    ax.add_patch(Circle((x, y), 0.18, fc="none", ec="red", lw=2, zorder=5))
    ax.arrow(x, y, 0.35 * np.cos(theta), 0.35 * np.sin(theta), color="red", width=0.02, zorder=5)
    if ball is not None:
        ax.add_patch(Circle(tuple(ball), max(ball_radius, 0.06), fc="white", ec="black", zorder=5))


def draw_topview(
    ax: Axes,
    spec: FieldSpec,
    landmarks: LandmarkSet,
    cam: CameraConfig,
    pose: Sequence[float] | np.ndarray,
    pan: float,
    tilt: float,
    ball: Sequence[float] | np.ndarray | None = None,
    goal: tuple[float, float] | None = None,
    visible_ids: Sequence[int] | np.ndarray = (),
    title: str | None = None,
    robots: np.ndarray | None = None,
    robot_radius: float = 0.12,
) -> None:
    """The paper's top view: field, robot, ball, current view (blue), goal view (red), and
    the other robots (``robots`` (R, 4) ``(x, y, height, grey)``, height 0 an empty slot) as
    grey discs of ``robot_radius``."""
    draw_field(ax, spec)
    if goal is not None:
        draw_footprint(ax, pose, goal[0], goal[1], cam, "red")
    draw_footprint(ax, pose, pan, tilt, cam, "blue")
    draw_landmarks(ax, landmarks, visible_ids)
    for x, y, height, _ in [] if robots is None else robots:
        if height > 0:
            ax.add_patch(Circle((x, y), robot_radius, color="0.35", zorder=4))
    draw_robot(ax, pose, ball, spec.ball_radius)
    if title:
        ax.set_title(title, fontsize=9)
