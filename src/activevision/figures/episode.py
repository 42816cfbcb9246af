"""The paper's qualitative figure: episodes of two methods from the same start, step by
step (camera image over the top view: robot red circle, goal view red, current view blue,
visible landmarks coloured by type), and an animated GIF of one episode.

Fed with :class:`EpisodeTrace` records (``activevision.experiments.episode_figure``
traces them)."""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure

from activevision.figures.canvas import (
    check_fps,
    figure_to_rgb,
    new_figure,
    save_figure,
    save_gif,
)
from activevision.figures.scene import view_figure
from activevision.figures.topview import draw_topview, landmark_key
from activevision.geometry import CameraConfig, FieldSpec, LandmarkSet
from activevision.text import counted


@dataclass(frozen=True)
class Snapshot:
    """What one step of an episode looked like."""

    image: np.ndarray
    pan: float
    tilt: float
    observed: np.ndarray  #: visible landmark ids
    reward: float
    step: int


@dataclass(frozen=True)
class EpisodeTrace:
    """One episode of one policy, step by step, with the world it was played in."""

    policy: str
    pose: np.ndarray
    ball: np.ndarray
    goal: tuple[float, float]
    desired: np.ndarray
    snapshots: list[Snapshot]
    success: bool
    ball_lost: bool
    field: FieldSpec
    camera: CameraConfig
    landmarks: LandmarkSet
    #: the other robots (R, 4) ``(x, y, height, grey)`` (height 0: an empty slot), drawn as
    #: grey discs of ``robot_radius`` in the top views
    robots: np.ndarray | None = None
    robot_radius: float = 0.12


def _has_robots(trace: EpisodeTrace) -> bool:
    return trace.robots is not None and bool((trace.robots[:, 2] > 0).any())


def _pick(snapshots: list[Snapshot], columns: int) -> list[Snapshot]:
    idx = np.unique(np.linspace(0, len(snapshots) - 1, min(columns, len(snapshots))).round())
    return [snapshots[int(i)] for i in idx]


def _outcome(trace: EpisodeTrace) -> str:
    """The row's label: the steps counted from the trace (an episode of another time limit
    than 20 said "no success in 20 steps"; one step was "1 steps")."""
    steps = len(trace.snapshots) - 1
    steps_text = counted(steps, "step")
    if trace.success:
        return f"success in {steps_text}"
    return "ball lost" if trace.ball_lost else f"no success in {steps_text}"


#: the suptitle's top this far below the figure's top edge, in inches: at matplotlib's
#: default (2% of the height) a figure of 3 or more traces put it over the first row's titles,
#: as tight_layout reserves only its height and a pad
_SUPTITLE_INCHES = 0.16


def plot_episodes(
    traces: list[EpisodeTrace], out_png: str | os.PathLike[str], columns: int = 6
) -> None:
    """For each trace a strip of ``columns`` steps: camera image above the top view."""
    save_figure(episodes_figure(traces, columns), out_png, dpi=100)


def episodes_figure(traces: list[EpisodeTrace], columns: int = 6) -> Figure:
    """:func:`plot_episodes`'s figure, not yet written."""
    height = 4.1 * len(traces)
    fig = new_figure(figsize=(2.6 * columns, height))
    axes = fig.subplots(
        2 * len(traces),
        columns,
        gridspec_kw={"height_ratios": [0.75, 1] * len(traces)},
        squeeze=False,
    )
    for r, trace in enumerate(traces):
        shots = _pick(trace.snapshots, columns)
        for c in range(columns):
            ax_img, ax_top = axes[2 * r, c], axes[2 * r + 1, c]
            if c >= len(shots):
                ax_img.axis("off")
                ax_top.axis("off")
                continue
            s = shots[c]
            ax_img.imshow(s.image, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
            ax_img.set_xticks([])
            ax_img.set_yticks([])
            label = f"{trace.policy}: step {s.step}" + (f", r={s.reward:+.0f}" if s.step else "")
            ax_img.set_title(label, fontsize=8)
            draw_topview(
                ax_top,
                trace.field,
                trace.landmarks,
                trace.camera,
                trace.pose,
                s.pan,
                s.tilt,
                trace.ball,
                trace.goal,
                s.observed,
                robots=trace.robots,
                robot_radius=trace.robot_radius,
            )
        axes[2 * r, 0].set_ylabel(_outcome(trace), fontsize=8)
    fig.suptitle(
        "red: robot and goal view, blue: current view; landmarks in view coloured by"
        f" type ({landmark_key()})"
        + ("; grey discs: other robots" if any(_has_robots(t) for t in traces) else ""),
        fontsize=9,
        y=1 - _SUPTITLE_INCHES / height,
    )
    fig.tight_layout()
    return fig


def animate_episode(trace: EpisodeTrace, out_gif: str | os.PathLike[str], fps: int = 3) -> None:
    """An animated GIF: camera image beside the top view, one frame per step. ValueError
    for a trace without snapshots (it was an IndexError after the loop)."""
    if not trace.snapshots:
        raise ValueError("animate_episode: the trace has no snapshots to draw")
    check_fps(fps)  # before drawing every frame
    frames = []
    for s in trace.snapshots:
        fig = view_figure(
            trace.field,
            trace.landmarks,
            trace.camera,
            s.image,
            trace.pose,
            s.pan,
            s.tilt,
            trace.ball,
            trace.goal,
            s.observed,
            title=f"{trace.policy}, step {s.step}",
            robots=trace.robots,
            robot_radius=trace.robot_radius,
        )
        frames.append(figure_to_rgb(fig))
    frames += [frames[-1]] * 2  # linger on the outcome
    save_gif(frames, out_gif, fps)
