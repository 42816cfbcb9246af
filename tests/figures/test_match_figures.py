"""The match figures (``activevision.figures.match``) refuse what they cannot draw with one
line naming it, not an error from deep in Python, numpy or matplotlib."""

from __future__ import annotations

import numpy as np
import pytest

from activevision.figures.match import plot_error_over_time, plot_pareto

POINT = {"ball_in_view": (0.5, 0.4, 0.6), "position_rmse": (0.1, 0.05, 0.15)}


def test_plot_pareto_names_what_it_cannot_draw(tmp_path):
    png = tmp_path / "pareto.png"
    with pytest.raises(ValueError, match="plot_pareto: no points to draw"):
        plot_pareto({}, [], png, "t")  # was "max() arg is an empty sequence"
    with pytest.raises(ValueError, match="the front's zz has no point"):
        plot_pareto({"a": POINT}, ["a", "zz"], png, "t")  # was KeyError: 'zz'
    assert not png.exists()


def test_plot_pareto_without_a_front_zooms_on_every_method(monkeypatch):
    # no front and no references: the zoom's limits were the max() of nothing
    drawn = []
    monkeypatch.setattr(
        "activevision.figures.match.save_figure", lambda fig, path, dpi: drawn.append(fig)
    )
    plot_pareto({"a": POINT, "b": {**POINT, "ball_in_view": (0.3, 0.2, 0.4)}}, [], "x", "t")
    zoom = drawn[0].axes[1]
    assert zoom.get_title() == "zoomed on every method"
    low, high = zoom.get_xlim()
    assert low < 20 and high > 60  # every whisker of both methods, in percent


@pytest.mark.parametrize(
    ("curves", "message"),
    [
        ({}, "no curves to draw"),  # a blank figure
        ({"a": np.zeros(10)}, r"a's errors expect .*got shape \(10,\)"),  # numpy's AxisError
        ({"a": np.zeros((0, 3))}, r"got shape \(0, 3\)"),  # a blank figure
    ],
)
def test_plot_error_over_time_names_what_it_cannot_draw(tmp_path, curves, message):
    with pytest.raises(ValueError, match=message):
        plot_error_over_time(curves, 0.1, tmp_path / "error.png", "t")
    assert not (tmp_path / "error.png").exists()


@pytest.mark.parametrize("tick_seconds", [0, -0.32, float("nan"), float("inf"), "0.32", None, True])
def test_plot_error_over_time_names_a_bad_tick_length(tmp_path, tick_seconds):
    # 0 drew every tick at time 0, a negative one ran time backwards
    with pytest.raises(ValueError, match="tick_seconds expects a positive number"):
        plot_error_over_time({"a": np.zeros((3, 2))}, tick_seconds, tmp_path / "e.png", "t")
    assert not (tmp_path / "e.png").exists()


def test_plot_error_over_time_takes_nested_lists(tmp_path):
    # a list of lists was "'list' object has no attribute 'mean'"
    plot_error_over_time({"a": [[0.1, 0.2], [0.3, 0.1]]}, 0.1, tmp_path / "error.png", "t")
    assert (tmp_path / "error.png").stat().st_size > 5_000


@pytest.mark.parametrize(
    ("matches", "title", "bands"),
    [
        ({"a": 1, "b": 1}, "t; one match: no 95% bands", 0),
        ({"a": 2, "b": 1}, "t; bands: 95% intervals, none over one match", 1),
        ({"a": 2, "b": 3}, "t; bands: 95% intervals", 2),
    ],
)
def test_plot_error_over_time_claims_bands_only_where_it_draws_them(
    monkeypatch, matches, title, bands
):
    # one match's curve was titled "bands: 95% intervals" with no band drawn
    drawn = []
    monkeypatch.setattr(
        "activevision.figures.match.save_figure", lambda fig, path, dpi: drawn.append(fig)
    )
    curves = {name: np.full((4, m), 0.2) + np.arange(m) * 0.1 for name, m in matches.items()}
    plot_error_over_time(curves, 0.1, "x", "t")
    ax = drawn[0].axes[0]
    assert ax.get_title() == title
    assert len(ax.collections) == bands


def _legends_fit(fig) -> bool:
    """Whether every legend lies within what holds it: a panel's within the panel, the
    figure's within the figure (at the dpi it is saved at)."""
    fig.set_dpi(120)
    fig.draw_without_rendering()
    held = [(legend, fig.bbox) for legend in fig.legends]
    held += [(ax.get_legend(), ax.get_window_extent()) for ax in fig.axes if ax.get_legend()]

    def within(b, box):
        return (
            box.x0 - 1 <= b.x0 and b.x1 <= box.x1 + 1 and box.y0 - 1 <= b.y0 <= b.y1 <= box.y1 + 1
        )

    return bool(held) and all(within(legend.get_window_extent(), box) for legend, box in held)


@pytest.mark.parametrize(
    "names",
    [
        # ran off the panel and the figure's bottom
        [f"strategy_with_a_forty_character_name_{i:03d}" for i in range(30)],
        ["a", "strategy_with_a_very_long_name_" * 20],  # ran off the left edge
    ],
)
def test_plot_pareto_keeps_the_legend_of_long_names_inside_the_figure(monkeypatch, names):
    drawn = []
    monkeypatch.setattr(
        "activevision.figures.match.save_figure", lambda fig, path, dpi: drawn.append(fig)
    )
    points = {
        name: {**POINT, "ball_in_view": (0.2 + 0.02 * i, 0.15 + 0.02 * i, 0.25 + 0.02 * i)}
        for i, name in enumerate(names)
    }
    plot_pareto(points, names[:2], "x", "t")
    assert _legends_fit(drawn[0])
    plot_pareto({"a": POINT, "b": {**POINT, "ball_in_view": (0.3, 0.2, 0.4)}}, ["a"], "x", "t")
    assert _legends_fit(drawn[1])


@pytest.mark.parametrize("count", [2, 11])
def test_plot_pareto_s_legend_lies_outside_the_panels(monkeypatch, count):
    """The legend sat inside the left panel wherever it fitted there, over the whiskers of
    the default command's eleven strategies; now it lies below both panels, on none."""
    drawn = []
    monkeypatch.setattr(
        "activevision.figures.match.save_figure", lambda fig, path, dpi: drawn.append(fig)
    )
    points = {
        f"strategy_{i}": {
            "ball_in_view": (0.2 + 0.02 * i, 0.15 + 0.02 * i, 0.25 + 0.02 * i),
            "position_rmse": (0.07 + 0.001 * i, 0.065 + 0.001 * i, 0.075 + 0.001 * i),
        }
        for i in range(count)
    }
    plot_pareto(points, [f"strategy_{count - 1}"], "x", "t", references=["strategy_0"])
    fig = drawn[0]
    assert _legends_fit(fig)
    assert not any(ax.get_legend() for ax in fig.axes) and len(fig.legends) == 1
    legend = fig.legends[0].get_window_extent()
    for ax in fig.axes:
        assert not legend.overlaps(ax.get_window_extent())
    assert len(fig.legends[0].get_texts()) == count


def test_plot_pareto_of_no_ball_in_view_starts_its_axis_at_0(monkeypatch):
    """Every strategy at 0% ball in view (a camera that never sees it): the axis ran to
    -1% in the zoom and -0.4% in the whole, a share that cannot be; now both start at 0,
    and the points on that edge are drawn whole (clipped beyond it, not at it)."""
    drawn = []
    monkeypatch.setattr(
        "activevision.figures.match.save_figure", lambda fig, path, dpi: drawn.append(fig)
    )
    points = {
        f"m{i}": {
            "ball_in_view": (0.0, 0.0, 0.071),
            "position_rmse": (0.1 + 0.01 * i, 0.09 + 0.01 * i, 0.11 + 0.01 * i),
        }
        for i in range(3)
    }
    plot_pareto(points, ["m0"], "x", "t")
    fig = drawn[0]
    fig.draw_without_rendering()
    for ax in fig.axes:
        assert ax.get_xlim()[0] == 0.0 and ax.get_ylim()[0] >= 0.0
        marker = next(line for line in ax.lines if line.get_marker() == "o")  # m0's, at 0
        clip = marker.get_clip_box()  # matplotlib keeps a rectangle as the clip box
        assert clip.x0 < ax.get_window_extent().x0  # reaches beyond the edge at 0
    # points away from 0 keep the axes as they were
    plot_pareto({"a": POINT}, ["a"], "x", "t")
    assert drawn[1].axes[0].get_xlim()[0] > 30


def test_plot_pareto_of_one_match_says_it_has_no_whiskers(monkeypatch):
    # one match has no interval (NaN ends): the whiskers were missing without a word
    drawn = []
    monkeypatch.setattr(
        "activevision.figures.match.save_figure", lambda fig, path, dpi: drawn.append(fig)
    )
    single = {"ball_in_view": (0.5, np.nan, np.nan), "position_rmse": (0.1, np.nan, np.nan)}
    plot_pareto({"a": single}, ["a"], "x", "1 match x 19.2 s")
    plot_pareto({"a": POINT}, ["a"], "x", "2 matches x 19.2 s")
    titles = [fig.axes[0].get_title() for fig in drawn]
    assert titles == ["1 match x 19.2 s\none match: no 95% whiskers", "2 matches x 19.2 s"]


def test_a_long_title_of_the_match_figures_stays_inside_them(monkeypatch):
    # the world of moving robots and a detector ran past both edges of the figure ("2 " and
    # "bands: 95% intervals" cut off)
    drawn = []
    monkeypatch.setattr(
        "activevision.figures.match.save_figure", lambda fig, path, dpi: drawn.append(fig)
    )
    title = (
        "2 matches x 9.6 s, seed 0, discrete head 3 deg/tick, 3 other robots walking at"
        " 0.2 m/s, detector 0.9/0.4/0.1"
    )
    plot_pareto({"a": POINT}, ["a"], "x", title)
    plot_error_over_time({"a": np.full((30, 2), 0.1)}, 0.32, "x", title)
    for fig in drawn:
        renderer = fig.canvas.get_renderer()
        fig.draw(renderer)
        box, text = fig.bbox, fig.axes[0].title.get_window_extent(renderer)
        assert box.x0 <= text.x0 and text.x1 <= box.x1


def test_the_default_command_s_eleven_strategies_get_eleven_hues_where_they_can(monkeypatch):
    """Beyond ten methods tab20's colours came in its order, dark and light of one hue side
    by side: the default command's eleven strategies were five pairs of near-twins (the
    error figure's lines have no marker to tell them apart). The first ten now take its ten
    hues, the rest their light shades."""
    from matplotlib import colormaps

    drawn = []
    monkeypatch.setattr(
        "activevision.figures.match.save_figure", lambda fig, path, dpi: drawn.append(fig)
    )
    curves = {f"m{i}": np.full((3, 2), 0.05 + 0.01 * i) for i in range(11)}
    plot_error_over_time(curves, 0.32, "x", "t")
    tab20 = [tuple(c) for c in colormaps["tab20"].colors]
    shades = [tab20.index(tuple(line.get_color()[:3])) for line in drawn[0].axes[0].lines]
    assert len({i // 2 for i in shades[:10]}) == 10  # ten hues, one each
    assert len(set(shades)) == 11
    # ten or fewer: matplotlib's default ten, as before
    plot_error_over_time({"a": np.zeros((3, 2)), "b": np.ones((3, 2))}, 0.32, "x", "t")
    tab10 = [tuple(c) for c in colormaps["tab10"].colors]
    assert [tuple(line.get_color()[:3]) for line in drawn[1].axes[0].lines] == tab10[:2]


def test_an_error_curve_of_one_tick_is_drawn(monkeypatch):
    # a line through one point draws nothing: --ticks 1 gave an empty figure with a legend
    drawn = []
    monkeypatch.setattr(
        "activevision.figures.match.save_figure", lambda fig, path, dpi: drawn.append(fig)
    )
    plot_error_over_time({"a": np.full((1, 2), 0.06)}, 0.32, "x", "t")
    plot_error_over_time({"a": np.full((5, 2), 0.06)}, 0.32, "x", "t")
    one, many = (fig.axes[0].lines[0] for fig in drawn)
    assert one.get_marker() not in (None, "", "None") and one.get_xdata().tolist() == [0.32]
    assert many.get_marker() in (None, "", "None")  # a curve: a line, as before


def test_plot_pareto_s_legend_rows_are_as_full_as_each_other(monkeypatch):
    # 11 strategies in the 9 columns that fitted: two columns of two, then seven of one
    drawn = []
    monkeypatch.setattr(
        "activevision.figures.match.save_figure", lambda fig, path, dpi: drawn.append(fig)
    )
    names = [
        "ball_track",
        "bhuman_cycle",
        "bitbots_search",
        "nubots_6point",
        "entropy_greedy",
        "entropy_track (front)",
        "glance_track (front)",
        "onnx_policy",
        "random",
        "oracle_ball (privileged)",
        "oracle_entropy (privileged)",
    ]
    plot_pareto({name: POINT for name in names}, [], "x", "t")
    columns = drawn[0].legends[0]._ncols
    rows = -(-len(names) // columns)
    assert rows > 1 and columns == -(-len(names) // rows)  # 6 + 5, not 9 + 2
