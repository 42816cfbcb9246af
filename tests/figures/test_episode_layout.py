"""The episode figure (``activevision episode --policies a b c d``) stays readable with any
number of traces: its colour key over the first row's titles, and its row labels counting
the steps the trace played."""

from __future__ import annotations

import dataclasses

import pytest

from activevision.envs import EnvConfig
from activevision.experiments.episode_figure import trace_episode
from activevision.experiments.policies import RandomPolicy
from activevision.figures.episode import episodes_figure


@pytest.fixture(scope="module")
def trace():
    return trace_episode(RandomPolicy(EnvConfig()), 0)


@pytest.mark.parametrize("rows", [1, 2, 4, 6])
def test_the_colour_key_overlaps_no_title(trace, rows):
    fig = episodes_figure([trace] * rows)
    renderer = fig.canvas.get_renderer()
    fig.draw(renderer)
    key = fig.get_suptitle()
    assert key.startswith("red: robot and goal view")
    key_box = fig._suptitle.get_window_extent(renderer)
    assert key_box.y1 <= fig.bbox.y1  # not cut at the top either
    for ax in fig.axes:
        if ax.get_title():
            assert not key_box.overlaps(ax.title.get_window_extent(renderer)), ax.get_title()


def test_the_row_label_counts_the_trace_s_steps(trace):
    def label(**changes) -> str:
        fig = episodes_figure([dataclasses.replace(trace, **changes)], columns=2)
        return fig.axes[0].get_ylabel()

    assert label(success=True, snapshots=trace.snapshots[:2]) == "success in 1 step"
    assert label(success=True, snapshots=trace.snapshots[:4]) == "success in 3 steps"
    short = trace.snapshots[:11]  # an episode of a 10-step limit
    assert label(success=False, ball_lost=False, snapshots=short) == "no success in 10 steps"
    assert label(success=False, ball_lost=True) == "ball lost"


def test_an_animation_of_no_snapshots_is_refused_before_writing(trace, tmp_path, monkeypatch):
    from activevision.figures.episode import animate_episode

    # it was an IndexError (the last frame lingers on the outcome) after the drawing
    with pytest.raises(ValueError, match="animate_episode: the trace has no snapshots"):
        animate_episode(dataclasses.replace(trace, snapshots=[]), tmp_path / "a.gif")

    # a bad fps is named before the frames are drawn (then save_gif refused it)
    def drawn(*args, **kwargs):
        raise AssertionError("drew a frame")

    monkeypatch.setattr("activevision.figures.episode.view_figure", drawn)
    with pytest.raises(ValueError, match="fps: expects a finite positive number, got 0"):
        animate_episode(trace, tmp_path / "a.gif", fps=0)
    assert list(tmp_path.iterdir()) == []
