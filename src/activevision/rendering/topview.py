"""Top views of the field (matplotlib): robot, ball, camera footprints and landmarks, in the
style of the paper's figures (robot as a red circle, best viewpoint red, current blue)."""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
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


def draw_field(ax, spec: FieldSpec) -> None:
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
    ax, pose, pan, tilt, cam: CameraConfig, colour: str, max_distance=4.0, alpha=0.3, **kwargs
) -> None:
    poly = footprint_polygon(np.asarray(pose)[None], [pan], [tilt], cam, max_distance)[0]
    ax.add_patch(Polygon(poly, closed=True, fc=colour, ec=colour, alpha=alpha, zorder=2, **kwargs))


def draw_landmarks(ax, landmarks: LandmarkSet, ids: Sequence[int], points=None) -> None:
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


def draw_robot(ax, pose, ball=None, ball_radius=0.07) -> None:
    x, y, theta = pose
    ax.add_patch(Circle((x, y), 0.18, fc="none", ec="red", lw=2, zorder=5))
    ax.arrow(x, y, 0.35 * np.cos(theta), 0.35 * np.sin(theta), color="red", width=0.02, zorder=5)
    if ball is not None:
        ax.add_patch(Circle(tuple(ball), max(ball_radius, 0.06), fc="white", ec="black", zorder=5))


def draw_topview(
    ax,
    spec: FieldSpec,
    landmarks: LandmarkSet,
    cam: CameraConfig,
    pose,
    pan,
    tilt,
    ball=None,
    goal=None,
    visible_ids=(),
    title=None,
) -> None:
    """The paper's top view: field, robot, ball, current view (blue), goal view (red)."""
    draw_field(ax, spec)
    if goal is not None:
        draw_footprint(ax, pose, goal[0], goal[1], cam, "red")
    draw_footprint(ax, pose, pan, tilt, cam, "blue")
    draw_landmarks(ax, landmarks, visible_ids)
    draw_robot(ax, pose, ball, spec.ball_radius)
    if title:
        ax.set_title(title, fontsize=9)


def figure_to_rgb(fig) -> np.ndarray:
    fig.canvas.draw()
    rgb = np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()
    plt.close(fig)
    return rgb


def view_figure(
    spec, landmarks, cam, image, pose, pan, tilt, ball, goal=None, visible_ids=(), title=None
):
    """Camera image beside the top view, as a matplotlib figure."""
    fig, (ax_img, ax_top) = plt.subplots(
        1, 2, figsize=(9, 3.4), gridspec_kw={"width_ratios": [1, 1.45]}
    )
    ax_img.imshow(image, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
    ax_img.set_title(
        f"camera: pan {np.degrees(pan):+.0f}°, tilt {np.degrees(tilt):.0f}°", fontsize=9
    )
    ax_img.set_xticks([])
    ax_img.set_yticks([])
    draw_topview(ax_top, spec, landmarks, cam, pose, pan, tilt, ball, goal, visible_ids, title)
    fig.tight_layout()
    return fig


def episode_panel(sim, i: int, image: np.ndarray) -> np.ndarray:
    """RGB array of slot ``i`` of an :class:`~activevision.envs.simulation.EpisodeBatch`:
    the camera image beside the top view with the goal (red) and current (blue) views."""
    cfg = sim.cfg
    fig = view_figure(
        cfg.field,
        sim.landmarks,
        cfg.camera,
        image,
        sim.pose[i],
        sim.pan[i],
        sim.tilt[i],
        sim.ball[i],
        goal=(sim.goal_pan[i], sim.goal_tilt[i]),
        visible_ids=np.flatnonzero(sim.observed[i]),
        title=f"step {sim.step_count[i]}: {int((sim.observed[i] & sim.desired[i]).sum())}/"
        f"{int(sim.desired[i].sum())} goal landmarks in view",
    )
    return figure_to_rgb(fig)


def save_rgb(rgb: np.ndarray, path) -> None:
    """Write an RGB array as PNG atomically."""
    from activevision.io import atomic_path

    with atomic_path(path) as tmp:
        plt.imsave(tmp, rgb, format="png")
