"""One moment of an episode: the camera image beside the top view (``env.render()``,
``activevision render``), and the best-viewpoint search (Algorithm 1, ``activevision
viewpoints``): every candidate footprint shaded by the entropy its landmarks leave, the
winner in red, candidates hiding the ball hatched."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.patches import Polygon

from activevision.figures.canvas import new_figure, save_figure
from activevision.figures.topview import draw_field, draw_landmarks, draw_robot, draw_topview
from activevision.geometry import CameraConfig, FieldSpec, LandmarkSet


def camera_beside(image: np.ndarray, pan: float, tilt: float) -> tuple[Figure, Axes]:
    """A figure with the camera image (grayscale (H, W) uint8, titled with the head angles,
    rad) on the left, and the empty axes beside it for a top view."""
    fig = new_figure(figsize=(9, 3.4))
    ax_img, ax_top = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.45]})
    ax_img.imshow(image, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
    ax_img.set_title(
        f"camera: pan {np.degrees(pan):+.0f}°, tilt {np.degrees(tilt):.0f}°", fontsize=9
    )
    ax_img.set_xticks([])
    ax_img.set_yticks([])
    return fig, ax_top


def view_figure(
    spec: FieldSpec,
    landmarks: LandmarkSet,
    cam: CameraConfig,
    image: np.ndarray,
    pose: Sequence[float] | np.ndarray,
    pan: float,
    tilt: float,
    ball: Sequence[float] | np.ndarray | None,
    goal: tuple[float, float] | None = None,
    visible_ids: Sequence[int] | np.ndarray = (),
    title: str | None = None,
    robots: np.ndarray | None = None,
    robot_radius: float = 0.12,
) -> Figure:
    """Camera image (grayscale, (H, W) uint8) beside the top view (other ``robots`` as
    grey discs: :func:`~activevision.figures.topview.draw_topview`), as a figure."""
    fig, ax_top = camera_beside(image, pan, tilt)
    draw_topview(
        ax_top,
        spec,
        landmarks,
        cam,
        pose,
        pan,
        tilt,
        ball,
        goal,
        visible_ids,
        title,
        robots,
        robot_radius,
    )
    fig.tight_layout()
    return fig


@dataclass(frozen=True)
class ViewpointSearch:
    """What the best-viewpoint search of one belief found, ready to draw."""

    field: FieldSpec
    landmarks: LandmarkSet
    pose: np.ndarray  #: (3,) the pose searched from (the belief's mean)
    ball: np.ndarray  #: (2,)
    footprints: np.ndarray  #: (V, P, 2) ground polygon of every candidate, grid order
    entropies: np.ndarray  #: (V,) entropy each candidate's landmarks leave
    shows_ball: np.ndarray  #: (V,) bool
    best: int | None  #: the goal candidate; None when no viewpoint shows the ball
    pan: float = float("nan")  #: rad, of the goal
    tilt: float = float("nan")  #: rad, of the goal
    entropy: float = float("nan")  #: of the goal
    landmark_ids: Sequence[int] = ()  #: landmarks the goal view shows


def _title(search: ViewpointSearch) -> str:
    status = (
        f"best: pan {np.degrees(search.pan):+.0f}°, tilt {np.degrees(search.tilt):.0f}°, "
        f"H = {search.entropy:.2f}"
        if search.best is not None
        else "no viewpoint shows the ball"
    )
    return f"{len(search.footprints)} candidate viewpoints (hatched: ball not in view); {status}"


def _fit_footprints(ax: Axes, footprints: np.ndarray, margin: float = 0.1) -> None:
    """Widen the field's limits to every footprint: views from near the carpet's edge look
    beyond it, and were cut off there."""
    corners = footprints.reshape(-1, 2)
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    ax.set_xlim(min(x0, corners[:, 0].min() - margin), max(x1, corners[:, 0].max() + margin))
    ax.set_ylim(min(y0, corners[:, 1].min() - margin), max(y1, corners[:, 1].max() + margin))


def plot_viewpoint_search(search: ViewpointSearch, out_png: str | os.PathLike[str]) -> None:
    """Top view with every candidate footprint shaded by its entropy, written as PNG."""
    entropies = np.asarray(search.entropies).reshape(-1)
    shows_ball = np.asarray(search.shows_ball).reshape(-1)
    fig = new_figure(figsize=(8, 5.6))
    ax = fig.subplots()
    draw_field(ax, search.field)
    cmap = matplotlib.colormaps["viridis"]
    lo, hi = entropies.min(), entropies.max()
    norm = Normalize(lo, hi if hi > lo else lo + 1)
    # Low-entropy (better) candidates on top, so the interesting ones stay visible.
    for k in np.argsort(-entropies):
        ax.add_patch(
            Polygon(
                search.footprints[k],
                closed=True,
                fc=cmap(norm(entropies[k])),
                ec="k",
                lw=0.3,
                alpha=0.35,
                hatch=None if shows_ball[k] else "//",
                zorder=2,
            )
        )
    if search.best is not None:
        best = search.footprints[search.best]
        ax.add_patch(Polygon(best, closed=True, fill=False, ec="red", lw=2.5, zorder=6))
        draw_landmarks(ax, search.landmarks, search.landmark_ids)
    draw_robot(ax, search.pose, search.ball, search.field.ball_radius)
    _fit_footprints(ax, search.footprints)
    sm = ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=ax, fraction=0.03, pad=0.01, label="entropy ½ ln|2πeΣ| after update")
    ax.set_title(_title(search), fontsize=10)
    fig.tight_layout()
    save_figure(fig, out_png, dpi=120)
