"""The robustness suite: its table of perturbations and its scoring loop."""

import csv
import dataclasses
import json
import shutil

import numpy as np
import pytest

from activevision.envs import EnvConfig
from activevision.envs.robots import RobotsConfig
from activevision.experiments.policies import OnnxPolicy, OraclePolicy, with_world
from activevision.experiments.robustness import (
    CLEAN,
    PAPER_CLEAN,
    PERTURBATIONS,
    ROBUST_APPEARANCE,
    ROBUST_ROBOTS,
    format_row,
    format_table,
    neutral_config,
    perturbation_names,
    perturbations,
    score_perturbations,
    within,
    worst_drops,
)
from activevision.figures.robustness import plot_robustness
from activevision.rendering.appearance import FACTORS, AppearanceConfig
from activevision.runtime import PolicyFileError, pretrained_policy_path
from activevision.typecheck import config_to_dict

RANDOMISED = EnvConfig(appearance=AppearanceConfig.randomised(), robots=RobotsConfig(count=(0, 4)))
BY_NAME = {p.name: p for p in PERTURBATIONS}


def changed_fields(a, b, prefix=""):
    """Dotted paths of the (nested) dataclass fields where ``a`` and ``b`` differ."""
    out = set()
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if dataclasses.is_dataclass(x) and type(x) is type(y):
            out |= changed_fields(x, y, f"{prefix}{f.name}.")
        elif x != y:
            out.add(prefix + f.name)
    return out


def test_names_are_unique_and_cover_every_kind():
    names = perturbation_names()
    assert len(names) == len(set(names))
    assert names[0] == CLEAN
    for expected in (
        "gain-dark-mild",
        "gain-bright-strong",
        "defocus-strong",
        "robots-4",
        "mount-tilt+4deg",
        "mount-height+5cm",
        "mount-fov+10%",
        "all-mild",
        "all-mild+robots-4",
        PAPER_CLEAN,
    ):
        assert expected in names
    appearance = {f.name for f in dataclasses.fields(AppearanceConfig)}
    assert appearance - set(FACTORS) == {"neutral_share"}  # a share of episodes, not a factor
    # every drawn appearance factor is perturbed (the stripe width only with the stripes)
    played = {p.factor for p in PERTURBATIONS}
    assert set(FACTORS) - played == {"stripe_width"}


@pytest.mark.parametrize("clean", [EnvConfig(), RANDOMISED], ids=["clean-trained", "randomised"])
def test_each_row_changes_its_factor_alone(clean):
    neutral = neutral_config(clean)
    if clean == EnvConfig():
        assert neutral == clean  # a clean-trained policy: rows differ from clean itself
    for p in PERTURBATIONS:
        config = p.config(clean)
        changed = changed_fields(neutral, config)
        if p.name == CLEAN:
            assert config == clean
        elif p.name == PAPER_CLEAN:
            assert changed == set()
        elif p.factor == "all":
            continue  # test_all_mild_sets_every_mild_level_at_once
        elif p.factor == "robots":
            assert changed == {"robots.count"}
            assert config.robots.count == (int(p.value), int(p.value))
        elif p.factor == "stripes":
            assert changed == {"appearance.stripes", "appearance.stripe_width"}
        else:
            assert changed == {f"appearance.{p.factor}"}, p.name
            assert getattr(config.appearance, p.factor) == (p.value, p.value)  # exact level


@pytest.mark.parametrize("clean", [EnvConfig(), RANDOMISED], ids=["clean-trained", "randomised"])
def test_all_mild_sets_every_mild_level_at_once(clean):
    # written out by hand, not from the level table: the first direction of each factor
    mild = {
        "gain": 0.75,
        "offset": -15.0,
        "gamma": 1.3,
        "vignetting": 0.3,
        "read_noise": 4.0,
        "shot_noise": 0.4,
        "defocus": 0.8,
        "motion_blur": 0.3,
        "stripes": 8.0,
        "grain": 6.0,
        "line_width": -0.01,
        "line_wear": 0.35,
        "clutter": 40.0,
    }
    for name, robots in (("all-mild", 0), ("all-mild+robots-4", 4)):
        config = BY_NAME[name].config(clean)
        changed = changed_fields(neutral_config(clean), config)
        expected = {f"appearance.{f}" for f in mild} | {"appearance.stripe_width"}
        assert changed == expected | ({"robots.count"} if robots else set()), name
        for factor, value in mild.items():
            assert getattr(config.appearance, factor) == (value, value), (name, factor)
        assert config.appearance.stripe_width == (0.75, 0.75)
        assert config.robots.count == (robots, robots)
        # the mount is left as modelled: it has no mild level
        assert config.appearance.mount_tilt_deg == (0.0, 0.0)
    assert BY_NAME["all-mild+robots-4"].setting == "all factors mild, robots=4"
    assert BY_NAME["all-mild"].setting == "all factors mild"


def test_mild_levels_lie_inside_the_robust_ranges_and_strong_ones_beyond():
    robust = EnvConfig(appearance=ROBUST_APPEARANCE, robots=RobotsConfig(count=ROBUST_ROBOTS))
    for p in PERTURBATIONS:
        inside = within(p.config(EnvConfig()), robust)
        if p.level in ("mild", "trained", "neutral") or p.factor == "robots":
            assert inside, p.name
        else:
            assert p.level == "strong" and not inside, p.name
    # a clean-trained policy saw none of them
    assert not any(
        within(p.config(EnvConfig()), EnvConfig()) for p in PERTURBATIONS if p.factor != "none"
    )


def test_robust_ranges_are_the_robust_presets():
    from activevision.training.presets import preset

    env = preset("dagger_robust").env
    assert env.appearance == ROBUST_APPEARANCE
    assert env.robots.count == ROBUST_ROBOTS


def test_selection_always_starts_with_clean_and_paper_clean_only_when_randomised():
    assert PAPER_CLEAN not in [p.name for p in perturbations(EnvConfig())]
    assert [p.name for p in perturbations(RANDOMISED)][:2] == [CLEAN, PAPER_CLEAN]
    chosen = perturbations(EnvConfig(), ["robots-2", "gain-dark-mild"])
    assert [p.name for p in chosen] == [CLEAN, "gain-dark-mild", "robots-2"]  # table order
    with pytest.raises(ValueError, match="'nope'"):
        perturbations(EnvConfig(), ["nope"])


class Watcher:
    """Stays put; remembers each episode's start and the brightness of its first image."""

    name = "watcher"

    def __init__(self):
        self.starts, self.brightness = [], []

    def reset(self, info, rng):
        self.starts.append((info["pose"].copy(), info["ball"].copy(), info["head"].copy()))
        self.brightness.append(None)

    def act(self, obs, info):
        if self.brightness[-1] is None:
            self.brightness[-1] = float(np.mean(obs))
        return 0


def test_appearance_rows_play_the_clean_starts_in_another_light():
    rows = perturbations(EnvConfig(), ["gain-dark-strong", "gain-bright-strong"])
    watcher = Watcher()
    scored = score_perturbations(watcher, EnvConfig(), rows, episodes=3, seed=5)
    assert [r["name"] for r in scored] == [CLEAN, "gain-dark-strong", "gain-bright-strong"]
    clean, dark, bright = (watcher.starts[i : i + 3] for i in (0, 3, 6))
    for a, b, c in zip(clean, dark, bright, strict=True):
        for x, y, z in zip(a, b, c, strict=True):
            np.testing.assert_array_equal(x, y)
            np.testing.assert_array_equal(x, z)
    light = np.array(watcher.brightness).reshape(3, 3)  # row x episode
    assert (light[1] < 0.7 * light[0]).all()  # gain 0.45
    assert (light[2] > light[0]).all()  # gain 1.8


def test_oracle_reaches_every_goal_whatever_the_look(tmp_path):
    clean = EnvConfig()
    rows = perturbations(clean, ["defocus-strong", "read-noise-strong", "clutter-strong"])
    progress = []
    scored = score_perturbations(OraclePolicy(clean), clean, rows, 4, 0, progress.append)
    assert progress == scored
    for row in scored:
        assert row["n"] == 4 and row["seed"] == 0
        assert row["goal_reached"] == 1.0
        assert row["goal_reached_drop_pts"] == 0.0 and row["success_rate_drop_pts"] == 0.0
        assert 0.0 <= row["goal_reached_low"] < 1.0 == row["goal_reached_high"]  # Wilson
        assert row["in_training_range"] is None  # the oracle was never trained
    assert "no drop" in worst_drops(scored)
    # told it was trained, the rows say whether they lie within its training ranges
    told = score_perturbations(OraclePolicy(clean), clean, rows[:2], 1, 0, trained=True)
    assert [r["in_training_range"] for r in told] == [True, False]
    table = format_table(scored)
    assert all(row["name"] in table for row in scored)
    # the figure, also from the CSV's text values
    path = tmp_path / "rows.csv"
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(scored[0]))
        writer.writeheader()
        writer.writerows(scored)
    with path.open() as f:
        plot_robustness(list(csv.DictReader(f)), tmp_path / "r.png", title="oracle")
    assert (tmp_path / "r.png").read_bytes().startswith(b"\x89PNG")


def test_drops_are_points_below_clean():
    rows = [
        {"name": CLEAN, "success_rate_drop_pts": 0.0, "goal_reached_drop_pts": 0.0},
        {"name": "a", "success_rate_drop_pts": 12.5, "goal_reached_drop_pts": -3.0},
        {"name": "b", "success_rate_drop_pts": 2.0, "goal_reached_drop_pts": 40.0},
    ]
    assert worst_drops(rows) == (
        "worst change vs clean: success rate -12.5 pts (a), goal reached -40.0 pts (b)"
    )


def test_the_clean_row_comes_first():
    with pytest.raises(ValueError, match="clean"):
        score_perturbations(OraclePolicy(), EnvConfig(), [BY_NAME["robots-1"]], 1, 0)


def exported_copy(directory, **world_changes):
    """A copy of the shipped policy whose policy.json's world has ``world_changes``
    (record -> {field: value}) applied."""
    model = directory / "policy.onnx"
    shutil.copy(pretrained_policy_path(), model)
    values = json.loads(pretrained_policy_path().with_suffix(".json").read_text())
    for record, changes in world_changes.items():
        values["world"][record].update(changes)
    model.with_suffix(".json").write_text(json.dumps(values))
    return model


def test_an_exported_policy_is_scored_against_its_training_world(tmp_path):
    neutral = config_to_dict(AppearanceConfig())
    policy = OnnxPolicy(exported_copy(tmp_path, robots={"count": [0, 4]}, appearance=neutral))
    assert policy.env_config().robots.count == (0, 0)  # evaluate: the paper's clean world
    clean = policy.env_config(trained_world=True)
    assert clean == policy.env_config().replace(robots=RobotsConfig(count=(0, 4)))
    rows = perturbations(clean)
    assert [p.name for p in rows][:2] == [CLEAN, PAPER_CLEAN]  # randomised: both clean rows
    assert clean.robots.count == (0, 4) == BY_NAME[CLEAN].config(clean).robots.count
    inside = {p.name for p in rows if within(p.config(clean), clean)}
    assert inside == {CLEAN, PAPER_CLEAN, "robots-1", "robots-2", "robots-3", "robots-4"}


def test_the_shipped_policy_is_scored_in_its_randomised_world():
    policy = OnnxPolicy(pretrained_policy_path())
    clean = policy.env_config(trained_world=True)
    assert clean.appearance.enabled and clean.robots.count == (0, 4)
    assert not policy.env_config().appearance.enabled  # evaluate plays the paper's world
    assert [p.name for p in perturbations(clean)][:2] == [CLEAN, PAPER_CLEAN]


def test_a_world_this_version_cannot_play_is_a_policy_file_error():
    with pytest.raises(PolicyFileError, match=r"p\.json: 'world' records \['weather'\]"):
        with_world(EnvConfig(), {"weather": {"rain": [0, 1]}}, source="p.json")
    with pytest.raises(PolicyFileError, match=r"'world' does not fit.*'world' appearance.*fog"):
        with_world(EnvConfig(), {"appearance": {"fog": [0, 1]}})
    with pytest.raises(PolicyFileError, match=r"'world' does not fit.*count"):
        with_world(EnvConfig(), {"robots": {"count": [3, 1]}})
    partial = with_world(RANDOMISED, {"robots": {"count": [1, 2]}})  # missing: the defaults
    assert partial.robots == RobotsConfig(count=(1, 2))
    assert partial.appearance == RANDOMISED.appearance  # a record not given is kept


def test_a_blind_method_gets_only_the_rows_that_change_more_than_the_image():
    from activevision.experiments.policies import ScanPolicy
    from activevision.experiments.robustness import sees_image

    assert not sees_image(ScanPolicy()) and not sees_image(OraclePolicy())
    image_only = {p.name for p in PERTURBATIONS if p.image_only}
    assert {"gain-dark-mild", "mount-tilt+4deg", "all-mild"} <= image_only
    assert not image_only & {CLEAN, PAPER_CLEAN, "robots-1", "all-mild+robots-4"}
    rows = [p.name for p in perturbations(RANDOMISED, blind="scan")]
    assert rows == [
        CLEAN,
        PAPER_CLEAN,
        "robots-1",
        "robots-2",
        "robots-3",
        "robots-4",
        "all-mild+robots-4",
    ]
    with pytest.raises(ValueError, match="grain-mild: changes only the camera image, which scan"):
        perturbations(EnvConfig(), ["robots-2", "grain-mild"], blind="scan")
    assert len(perturbations(EnvConfig(), blind=None)) == len(PERTURBATIONS) - 1


def test_the_figure_says_what_each_panel_and_the_clean_line_measure():
    # "success rate" read as the share of episodes solved (that is goal reached), and the
    # dashed "clean" line as the paper's clean world (for a randomised policy it is its
    # randomised training world)
    from activevision.figures.robustness import CLEAN_LABEL, PANELS

    labels = dict(PANELS)
    assert "landmarks" in labels["success_rate"] and "normal" in labels["success_rate"]
    assert "episodes" in labels["goal_reached"] and "Wilson" in labels["goal_reached"]
    assert "training world" in CLEAN_LABEL


def test_a_small_figure_has_no_empty_band_under_its_title(tmp_path):
    # tight_layout leaves room for a suptitle itself: the rect reserved 0.4 inches more, an
    # empty band as tall as the title between it and the panels
    import matplotlib.image

    clean = {"name": "clean", "factor": "none", "level": "trained", "setting": "as trained"}
    for metric in ("success_rate", "goal_reached"):
        clean |= {metric: 0.8, f"{metric}_low": 0.7, f"{metric}_high": 0.9}
    dark = clean | {"name": "gain-dark-mild", "factor": "gain", "level": "mild"}
    rows = [clean | {"in_training_range": True}, dark | {"in_training_range": True}]
    plot_robustness(rows, tmp_path / "r.png", title="a title")
    ink = matplotlib.image.imread(tmp_path / "r.png")[..., :3].min(axis=(1, 2)) < 0.9
    gaps = np.diff(np.flatnonzero(ink))  # between pixel rows with anything drawn
    # the first gap below the title's text: under 0.4 inches (48 pixel rows at 120 dpi; the
    # band made it 0.7)
    assert gaps[np.argmax(gaps > 1)] < 48


def test_the_figure_of_no_rows_is_refused(tmp_path):
    # it drew two empty panels under the legend
    with pytest.raises(ValueError, match="plot_robustness: no rows to draw"):
        plot_robustness([], tmp_path / "r.png")
    assert not (tmp_path / "r.png").exists()


def test_the_legend_names_only_the_kinds_of_bar_drawn(tmp_path, monkeypatch):
    # a --perturbations of two gain rows listed "other robots", "camera mounted off the
    # model" and the hatching of rows outside the training ranges, none of them drawn
    import activevision.figures.robustness as figure

    drawn = {}
    monkeypatch.setattr(figure, "save_figure", lambda fig, path, dpi: drawn.update(fig=fig))
    clean = {"name": "clean", "factor": "none", "level": "trained", "setting": "as trained"}
    for metric in ("success_rate", "goal_reached"):
        clean |= {metric: 0.8, f"{metric}_low": 0.7, f"{metric}_high": 0.9}
    strong = clean | {"name": "gain-dark-strong", "factor": "gain", "level": "strong"}
    rows = [clean | {"in_training_range": True}, strong | {"in_training_range": True}]
    figure.plot_robustness(rows, tmp_path / "r.png")
    (legend,) = drawn["fig"].legends
    labels = [t.get_text() for t in legend.get_texts()]
    assert labels == ["strong (beyond the robust training ranges)", figure.CLEAN_LABEL]
    robots = clean | {"name": "robots-2", "factor": "robots", "level": "strong"}
    mild = clean | {"name": "gain-dark-mild", "factor": "gain", "level": "mild"}
    rows += [robots | {"in_training_range": False}, mild | {"in_training_range": True}]
    figure.plot_robustness(rows, tmp_path / "r.png")
    labels = [t.get_text() for t in drawn["fig"].legends[0].get_texts()]
    assert labels == [
        "mild (inside the robust training ranges)",
        "strong (beyond them)",
        "other robots",
        "outside this policy's training ranges",
        figure.CLEAN_LABEL,
    ]


def test_the_bars_are_labelled_as_the_table_prints_them(tmp_path, monkeypatch):
    # the labels were rounded to whole points, half to even: 72.5% read "72" beside a table
    # that says 72.5
    import activevision.figures.robustness as figure

    drawn = {}
    monkeypatch.setattr(figure, "save_figure", lambda fig, path, dpi: drawn.update(fig=fig))
    clean = {"name": "clean", "factor": "none", "level": "trained", "setting": "as trained"}
    clean |= {"in_training_range": True, "success_rate_drop_pts": 0.0}
    clean |= {"goal_reached_drop_pts": 0.0}
    for metric, value in (("success_rate", 0.725), ("goal_reached", 0.125)):
        clean |= {metric: value, f"{metric}_low": value - 0.05, f"{metric}_high": value + 0.05}
    figure.plot_robustness([clean], tmp_path / "r.png")
    labels = [[t.get_text() for t in ax.texts] for ax in drawn["fig"].axes]
    assert labels == [["72.5"], ["12.5"]]
    cells = format_row(clean).split()
    assert "72.5" in cells and "12.5" in cells


def test_the_panels_axis_labels_do_not_run_into_each_other(tmp_path, monkeypatch):
    # a blind method's rows (`robustness --method scan`): the long name of
    # all-mild+robots-4 narrowed both panels, and the success-rate panel's two-line label ran
    # 33 px into the goal-reached panel's ("...at the end goal reached: ...")
    import activevision.figures.robustness as figure

    drawn = {}
    monkeypatch.setattr(figure, "save_figure", lambda fig, path, dpi: drawn.update(fig=fig))
    clean = {"name": "clean", "factor": "none", "level": "trained", "setting": "the env as it is"}
    clean["in_training_range"] = ""  # untrained, as the CSV of a blind method says
    for metric in ("success_rate", "goal_reached"):
        clean |= {metric: 0.73, f"{metric}_low": 0.57, f"{metric}_high": 0.89}
    rows = [clean]
    rows += [
        clean | {"name": f"robots-{k}", "factor": "robots", "level": str(k)} for k in range(1, 5)
    ]
    rows.append(
        clean
        | {
            "name": "all-mild+robots-4",
            "factor": "all",
            "level": "mild",
            "setting": "all factors mild, robots=4",
        }
    )
    figure.plot_robustness(rows, tmp_path / "r.png", title="scan: 6 rows")
    fig = drawn["fig"]
    renderer = fig.canvas.get_renderer()
    left, right = (ax.xaxis.label.get_window_extent(renderer) for ax in fig.axes[:2])
    assert left.x1 + 10 < right.x0, (left, right)  # 10 px apart at least
    for ax in fig.axes[:2]:  # and each label stays inside the figure
        box = ax.xaxis.label.get_window_extent(renderer)
        assert fig.bbox.x0 <= box.x0 and box.x1 <= fig.bbox.x1
