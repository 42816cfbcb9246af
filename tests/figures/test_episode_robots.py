"""The episode figure (``activevision episode``, ``demo``, ``env.render()``) of a world with
other robots draws them in the top view: the camera image showed a robot the top view left
out, with the landmarks it hid unmarked and nothing to say why."""

from __future__ import annotations

import numpy as np
from matplotlib.patches import Circle

from activevision.envs import EnvConfig
from activevision.envs.robots import RobotsConfig
from activevision.experiments.episode_figure import trace_episode
from activevision.experiments.policies import RandomPolicy
from activevision.figures.canvas import new_figure
from activevision.figures.episode import plot_episodes
from activevision.figures.topview import draw_topview


def _grey_discs(ax) -> list[tuple[float, float, float]]:
    return [
        (*p.center, p.radius)
        for p in ax.patches
        if isinstance(p, Circle) and np.allclose(p.get_facecolor()[:3], 0.35)
    ]


def _top_view(trace, **robots):
    """The axes of ``trace``'s top view drawn at its start pose."""
    ax = new_figure().subplots()
    draw_topview(
        ax,
        trace.field,
        trace.landmarks,
        trace.camera,
        trace.pose,
        0.0,
        0.3,
        trace.ball,
        robots=trace.robots,
        **robots,
    )
    return ax


def test_the_trace_keeps_its_robots_and_the_top_view_draws_them(tmp_path):
    config = EnvConfig(robots=RobotsConfig(count=(3, 3), radius=0.15))
    trace = trace_episode(RandomPolicy(config), 0, config)
    placed = trace.robots[trace.robots[:, 2] > 0]
    assert len(placed) == 3 and trace.robot_radius == 0.15
    ax = _top_view(trace, robot_radius=trace.robot_radius)
    assert sorted(_grey_discs(ax)) == sorted((x, y, 0.15) for x, y, _, _ in placed)
    plot_episodes([trace], tmp_path / "episode.png")  # the figure takes the trace
    assert (tmp_path / "episode.png").read_bytes().startswith(b"\x89PNG")


def test_an_empty_field_draws_no_robot():
    trace = trace_episode(RandomPolicy(EnvConfig()), 0)
    assert _grey_discs(_top_view(trace)) == []
