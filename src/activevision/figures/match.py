"""The match comparison's figures (``activevision match``): the Pareto front of position
error against ball in view, the error over time, and an animated top view of one match with
the belief's ellipse. Plain arrays in; the caller gathers them from the env."""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Collection, Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Ellipse, Polygon, Rectangle

from activevision.figures.canvas import (
    figure_to_rgb,
    fit_legend,
    new_figure,
    save_figure,
    save_gif,
)
from activevision.figures.scene import camera_beside
from activevision.figures.topview import draw_field
from activevision.geometry import CameraConfig, FieldSpec

__all__ = [
    "clip_frames",
    "draw_match_tick",
    "match_view",
    "plot_error_over_time",
    "plot_pareto",
    "save_gif",
]

#: dots per inch of the Pareto figure
PARETO_DPI = 120

#: how far (a share of the panel) a point on an edge at 0 is drawn beyond it, whole
EDGE_SPILL = 0.02

#: a method's point and whiskers: (mean, low, high) of each axis
Point = Mapping[str, tuple[float, float, float]]


def plot_pareto(
    points: Mapping[str, Point],
    front: Sequence[str],
    path: str | os.PathLike[str],
    title: str,
    references: Collection[str] = (),
) -> None:
    """Position RMSE (y, lower is better) against the share of ticks with the ball in view
    (x, higher is better), with 95% whiskers; the Pareto front joined by a line, privileged
    ``references`` drawn as crosses. Beside it the same, zoomed on the front and the
    references (where the strategies that matter lie close together; on every point where
    there are neither). ValueError where there is no point, or ``front`` names a method
    that has none (a KeyError, and no front was "max() arg is an empty sequence")."""
    if not points:
        raise ValueError("plot_pareto: no points to draw")
    unknown = [name for name in front if name not in points]
    if unknown:
        raise ValueError(f"plot_pareto: the front's {', '.join(unknown)} has no point")
    # at the dpi it is saved at: whether the legend fits is judged on the layout saved
    fig = new_figure(figsize=(12.0, 5.0), layout="constrained", dpi=PARETO_DPI)
    whole, zoom = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    # tab20 for many strategies: the default cycle repeats its colours after ten
    colours = _colours(len(points))
    on_front = sorted(
        (100 * points[n]["ball_in_view"][0], points[n]["position_rmse"][0]) for n in front
    )
    markers: dict[Axes, list[Any]] = {whole: [], zoom: []}
    for ax in (whole, zoom):
        for colour, (name, p) in zip(colours, points.items(), strict=True):
            bx, by = p["ball_in_view"], p["position_rmse"]
            drawn = ax.errorbar(
                100 * bx[0],
                by[0],
                xerr=[[100 * (bx[0] - bx[1])], [100 * (bx[2] - bx[0])]],
                yerr=[[by[0] - by[1]], [by[2] - by[0]]],
                fmt="x" if name in references else "o" if name in front else "s",
                color=colour,
                ms=7,
                capsize=3,
                label=name
                + (" (front)" if name in front else " (privileged)" if name in references else ""),
            )
            markers[ax].extend(drawn.get_children())
        if len(on_front) > 1:
            ax.plot(*zip(*on_front, strict=True), color="grey", lw=1, ls="--", zorder=0)
        ax.set_xlabel("ball in view (% of ticks)  ->  better")
        ax.set_ylabel("position RMSE (m)  <-  better")
        ax.grid(alpha=0.3)
    near = [points[n] for n in (*front, *references) if n in points]
    zoom.set_title(
        "zoomed on the front and the references" if near else "zoomed on every method",
        fontsize=9,
    )
    near = near or list(points.values())
    xs = [100 * v for p in near for v in p["ball_in_view"]]
    ys = [v for p in near for v in p["position_rmse"]]
    pad_x, pad_y = max(1.0, 0.1 * (max(xs) - min(xs))), max(1e-3, 0.1 * (max(ys) - min(ys)))
    zoom.set_xlim(min(xs) - pad_x, max(xs) + pad_x)
    zoom.set_ylim(min(ys) - pad_y, max(ys) + pad_y)
    for ax in (whole, zoom):
        _within_what_can_be(ax, markers[ax])
    # one match has no interval (NaN ends): its whiskers are missing, and the title says so
    # (on a line of its own: a title of the world beside it ran past the figure's edge)
    ends = [v for p in points.values() for k in ("ball_in_view", "position_rmse") for v in p[k][1:]]
    whole.set_title(
        title + ("\none match: no 95% whiskers" if all(np.isnan(ends)) else ""),
        fontsize=9,
        wrap=True,  # a long world (robots, detector) ran past the figure's edges
    )
    _legend_below(fig, whole)
    save_figure(fig, path, dpi=PARETO_DPI)


def _within_what_can_be(ax: Axes, markers: list[Any]) -> None:
    """``ax``'s limits cut to what the axes can take, ball in view within 0-100% and a
    position RMSE at least 0 (every point at 0% ball in view ran the axis to -1%, of a share
    that cannot be below 0). A point on an edge at 0 is drawn whole, not cut in half by it:
    the points' ``markers`` (each an errorbar's artists) are clipped to the panel widened by
    :data:`EDGE_SPILL` beyond such an edge (nothing else can lie there)."""
    left, right = ax.get_xlim()
    ax.set_xlim(max(left, 0.0), min(right, 100.0))
    bottom, top = ax.get_ylim()
    ax.set_ylim(max(bottom, 0.0), top)
    spill_x = EDGE_SPILL if ax.get_xlim()[0] == 0.0 else 0.0
    spill_y = EDGE_SPILL if ax.get_ylim()[0] == 0.0 else 0.0
    if not spill_x and not spill_y:
        return
    box = Rectangle(
        (-spill_x, -spill_y), 1 + spill_x, 1 + spill_y, transform=ax.transAxes, visible=False
    )
    for artist in markers:
        artist.set_clip_path(box)


def _legend_below(fig: Figure, ax: Axes) -> None:
    """``ax``'s legend below the panels, outside them, in as many columns as fit the
    figure's width (long or many method names ran past the figure's edges; inside the
    panel, with many strategies, it hid their whiskers)."""
    handles, labels = ax.get_legend_handles_labels()
    style: dict[str, Any] = {"loc": "outside lower center", "fontsize": 7, "frameon": False}
    columns, labels = fit_legend(fig, handles, labels, len(labels), **style)
    # rows as full as each other: 11 strategies in 9 columns filled two columns of two
    # and a row of seven; in 6 they are rows of 6 and 5 (no wider than what fits)
    rows = math.ceil(len(labels) / columns)
    fig.legend(handles, labels, ncol=math.ceil(len(labels) / rows), **style)


def _colours(n: int) -> list[tuple[float, float, float, float]]:
    """``n`` distinct colours: matplotlib's default ten, tab20 beyond, its ten hues first
    and their light shades after them (in tab20's order the default command's eleven
    strategies came in pairs of one hue: ball_track and bhuman_cycle both blue,
    entropy_greedy and entropy_track both green)."""
    if n <= 10:
        return [colormaps["tab10"](i) for i in range(n)]
    cmap = colormaps["tab20"]
    order = [*range(0, 20, 2), *range(1, 20, 2)]
    return [cmap(order[i % 20]) for i in range(n)]


def plot_error_over_time(
    curves: Mapping[str, np.ndarray],
    tick_seconds: float,
    path: str | os.PathLike[str],
    title: str,
) -> None:
    """Mean position error over matches at each tick (``curves``: method -> (ticks, M)),
    with a 95% band where M > 1 (the title says which). ValueError where there is no curve
    or one is not a (ticks, M) array (a blank figure, numpy's AxisError of a (ticks,)
    array), or ``tick_seconds`` is not a positive number."""
    if not curves:
        raise ValueError("plot_error_over_time: no curves to draw")
    if isinstance(tick_seconds, bool) or not (
        isinstance(tick_seconds, numbers.Real) and 0 < tick_seconds < math.inf
    ):
        # 0 drew every tick at time 0, a negative time ran backwards
        raise ValueError(
            f"plot_error_over_time: tick_seconds expects a positive number, got {tick_seconds!r}"
        )
    for name, errors in curves.items():
        shape = np.shape(errors)
        if len(shape) != 2 or 0 in shape:
            raise ValueError(
                f"plot_error_over_time: {name}'s errors expect an array of (ticks, matches),"
                f" got shape {shape}"
            )
    fig = new_figure(figsize=(7.5, 4.0), layout="constrained")
    ax = fig.add_subplot()
    # the default cycle's ten colours would repeat beyond ten methods
    for (name, errors), colour in zip(curves.items(), _colours(len(curves)), strict=True):
        errors = np.asarray(errors, dtype=float)
        t = np.arange(1, len(errors) + 1) * tick_seconds
        mean = errors.mean(axis=1)
        # one tick is one point, which a line alone does not draw
        ax.plot(t, mean, lw=1.2, label=name, color=colour, marker="o" if len(t) == 1 else None)
        if errors.shape[1] > 1:  # one match has no interval
            half = 1.96 * errors.std(axis=1, ddof=1) / math.sqrt(errors.shape[1])
            ax.fill_between(t, mean - half, mean + half, alpha=0.2, color=colour)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("position error (m), mean over matches")
    ax.set_title(f"{title}; {_bands_note(curves)}", fontsize=9, wrap=True)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    save_figure(fig, path, dpi=110)


def _bands_note(curves: Mapping[str, np.ndarray]) -> str:
    """What the error figure's bands are: 95% intervals, drawn for curves of two matches or
    more (the title claimed bands over a single match's curve, which has none)."""
    singles = sum(np.shape(errors)[1] == 1 for errors in curves.values())
    if singles == len(curves):
        return "one match: no 95% bands"
    if singles:
        return "bands: 95% intervals, none over one match"
    return "bands: 95% intervals"


def draw_match_tick(
    ax: Axes,
    field: FieldSpec,
    camera: CameraConfig,
    pose: np.ndarray,
    mean: np.ndarray,
    cov: np.ndarray,
    pan: float,
    ball: np.ndarray,
    ball_in_view: bool,
    robots: np.ndarray | None = None,
    robot_radius: float = 0.12,
    trail: np.ndarray | None = None,
) -> None:
    """One tick of a match from above on ``ax``: the true robot (red; its path so far,
    ``trail`` (T, 2+), when given) with its camera's view wedge, the belief's mean and
    2-sigma ellipse (blue), the ball (orange, hollow when out of view), the other robots
    (grey discs of ``robot_radius``; ``robots`` (R, 4) rows ``x, y, height, grey``, height 0
    an empty slot)."""
    draw_field(ax, field)
    x, y, th = pose
    yaw = th + pan
    reach = 8.0  # the view wedge, drawn long enough to reach a far ball
    half = camera.hfov / 2
    wedge = [
        (x, y),
        (x + reach * math.cos(yaw + half), y + reach * math.sin(yaw + half)),
        (x + reach * math.cos(yaw - half), y + reach * math.sin(yaw - half)),
    ]
    ax.add_patch(Polygon(wedge, closed=True, color="yellow", alpha=0.25, zorder=2))
    for rx, ry, height, _ in [] if robots is None else robots:
        if height > 0:
            ax.add_patch(Circle((rx, ry), robot_radius, color="0.35", zorder=4))
    if trail is not None:
        ax.plot(trail[:, 0], trail[:, 1], color="red", lw=0.8, alpha=0.6, zorder=3)
    ax.plot(x, y, "o", color="red", ms=7, zorder=4)
    ax.plot([x, x + 0.3 * math.cos(th)], [y, y + 0.3 * math.sin(th)], color="red", lw=2, zorder=4)
    values, vectors = np.linalg.eigh(cov[:2, :2])
    angle = math.degrees(math.atan2(vectors[1, 1], vectors[0, 1]))
    width, height = 4 * np.sqrt(np.maximum(values[::-1], 0))  # 2 sigma each side
    ax.add_patch(
        Ellipse(
            tuple(mean[:2]), width, height, angle=angle, fill=False, ec="blue", lw=1.5, zorder=5
        )
    )
    ax.plot(*mean[:2], "x", color="blue", ms=7, zorder=5)
    ax.plot(*ball, "o", ms=6, zorder=6, mfc="orange" if ball_in_view else "none", mec="darkorange")


def clip_frames(
    pose: np.ndarray,
    mean: np.ndarray,
    cov: np.ndarray,
    head: np.ndarray,
    ball: np.ndarray,
    ball_in_view: np.ndarray,
    field: FieldSpec,
    camera: CameraConfig,
    title: str,
    tick_seconds: float,
    every: int = 3,
    robots: np.ndarray | None = None,
    robot_radius: float = 0.12,
) -> list[np.ndarray]:
    """RGB frames of one match from above (:func:`draw_match_tick`, with the robot's path so
    far), every ``every``-th tick of ``pose`` (T, 3), ``mean`` (T, 3), ``cov`` (T, 3, 3),
    ``head`` (T, 2), ``ball`` (T, 2), ``ball_in_view`` (T,) and ``robots`` (T, R, 4)."""
    frames = []
    fig = new_figure(figsize=(6.4, 4.6), layout="constrained")
    for t in range(0, len(pose), every):
        fig.clear()
        ax = fig.add_subplot()
        draw_match_tick(
            ax,
            field,
            camera,
            pose[t],
            mean[t],
            cov[t],
            head[t, 0],
            ball[t],
            bool(ball_in_view[t]),
            None if robots is None else robots[t],
            robot_radius,
            trail=pose[: t + 1],
        )
        error = math.hypot(*(mean[t, :2] - pose[t, :2]))
        ax.set_title(f"{title}   t = {t * tick_seconds:5.1f} s   error {error:.2f} m", fontsize=9)
        frames.append(figure_to_rgb(fig))
    return frames


def match_view(
    image: np.ndarray,
    field: FieldSpec,
    camera: CameraConfig,
    info: Mapping[str, np.ndarray],
    title: str,
    robot_radius: float = 0.12,
) -> Figure:
    """The camera image (grayscale (H, W) uint8) beside the top view of one match tick
    (:func:`draw_match_tick`), from one robot's match info (``pose``, ``belief_mean``,
    ``belief_cov``, ``head``, ``ball``, ``ball_in_view``, ``robots``): ``env.render()``."""
    pan, tilt = info["head"]
    fig, ax_top = camera_beside(image, pan, tilt)
    draw_match_tick(
        ax_top,
        field,
        camera,
        info["pose"],
        info["belief_mean"],
        info["belief_cov"],
        float(pan),
        info["ball"],
        bool(info["ball_in_view"]),
        info["robots"],
        robot_radius,
    )
    ax_top.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig
