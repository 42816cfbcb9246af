"""``activevision match``: the tiny real command, its four outputs, and bad input."""

import csv
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from activevision.cli import build_parser, main
from activevision.runtime import CameraMismatchWarning

#: the tiny real command's options: 2 matches of 9 ticks, two quick strategies
TINY_OPTIONS = {"--matches": ("2",), "--ticks": ("9",), "--methods": ("ball_track", "random")}


def tiny(*argv: str) -> list[str]:
    """``match`` with :data:`TINY_OPTIONS` and ``argv``, where an option ``argv`` gives
    takes the place of TINY's (the command refuses one given twice)."""
    given = {word for word in argv if word.startswith("--")}
    kept = [
        w
        for option, values in TINY_OPTIONS.items()
        if option not in given
        for w in (option, *values)
    ]
    return ["match", *kept, *argv]


TINY = tiny()


def test_tiny_match_writes_table_csv_and_figures(tmp_path, capsys):
    out = tmp_path / "m"
    assert main(tiny("--out", str(out))) == 0
    printed = capsys.readouterr().out
    assert "ball_track" in printed and "Pareto front" in printed
    assert "(2.88 s of play)" in printed  # 9 ticks of 0.32 s: not "0.0 min"
    with (out / "match.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [r["method"] for r in rows] == ["ball_track", "random"]
    assert float(rows[0]["position_rmse_low"]) <= float(rows[0]["position_rmse"])
    for name in ("match_pareto.png", "match_error.png"):
        assert Image.open(out / name).size[0] > 400
    gif = Image.open(out / "match_clip.gif")
    assert gif.n_frames == 10  # the start and 9 ticks


def test_the_same_seed_writes_the_same_bytes(tmp_path, capsys):
    """Two runs of one command: every output file is byte-identical (no wall-clock column)."""
    argv = tiny("--ticks", "3", "--baseline", "random")
    for name in ("a", "b"):
        assert main([*argv, "--out", str(tmp_path / name)]) == 0
    written = sorted(p.name for p in (tmp_path / "a").iterdir())
    assert {"match.csv", "match_paired.csv", "match_clip.gif"} <= set(written)
    for name in written:
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name


def test_one_match_says_it_has_no_intervals(tmp_path, capsys):
    assert main(tiny("--matches", "1", "--ticks", "3", "--out", str(tmp_path / "m"))) == 0
    printed = capsys.readouterr().out
    assert "one match gives no 95% intervals" in printed and "[nan,nan]" in printed
    assert (tmp_path / "m" / "match_pareto.png").stat().st_size > 0


def test_a_match_of_one_tick_says_tick(tmp_path, capsys):
    assert main(tiny("--ticks", "1", "--out", str(tmp_path / "m"))) == 0
    assert "2 matches of 1 tick (0.32 s of play)" in capsys.readouterr().out  # not "1 ticks"


def test_a_continuous_match(tmp_path, capsys):
    out = tmp_path / "m"
    assert main(tiny("--action-type", "continuous", "--out", str(out))) == 0
    assert "continuous head moves of up to 3 deg per axis" in capsys.readouterr().out
    with (out / "match.csv").open() as f:
        assert [r["method"] for r in csv.DictReader(f)] == ["ball_track", "random"]


def test_a_match_with_walking_robots_draws_them_in_the_clip(tmp_path, capsys):
    out, plain = tmp_path / "m", tmp_path / "plain"
    argv = tiny("--methods", "ball_track", "--ticks", "3")
    assert main([*argv, "--robots", "4", "--robot-speed", "0.3", "--out", str(out)]) == 0
    assert "4 other robots walking at 0.3 m/s" in capsys.readouterr().out
    assert main([*argv, "--out", str(plain)]) == 0
    # the same matches without robots: the clip's first frame differs by the four discs
    with_robots = np.asarray(Image.open(out / "match_clip.gif").convert("RGB"), dtype=int)
    without = np.asarray(Image.open(plain / "match_clip.gif").convert("RGB"), dtype=int)
    assert (np.abs(with_robots - without).sum(axis=2) > 60).sum() > 4 * 20


def test_a_sparser_detector_localises_worse(tmp_path, capsys):
    argv = tiny("--methods", "nubots_6point", "--matches", "4", "--ticks", "60")
    rmse = {}
    for name, extra in (("default", []), ("sparse", ["--detection", "0.5", "0.1", "0.3"])):
        assert main([*argv, *extra, "--out", str(tmp_path / name)]) == 0
        with (tmp_path / name / "match.csv").open() as f:
            rmse[name] = float(next(csv.DictReader(f))["position_rmse"])
    assert "detector 0.5/0.1/0.3" in capsys.readouterr().out
    assert rmse["sparse"] > rmse["default"]


def test_paired_differences_from_a_baseline(tmp_path, capsys):
    out = tmp_path / "m"
    assert main(tiny("--baseline", "ball_track", "--out", str(out))) == 0
    printed = capsys.readouterr().out
    assert "paired differences from ball_track" in printed
    with (out / "match.csv").open() as f:
        rows = {r["method"]: r for r in csv.DictReader(f)}
    with (out / "match_paired.csv").open() as f:
        (paired,) = list(csv.DictReader(f))
    assert (paired["method"], paired["baseline"]) == ("random", "ball_track")
    gap = float(rows["random"]["position_rmse"]) - float(rows["ball_track"]["position_rmse"])
    assert float(paired["position_rmse_diff"]) == pytest.approx(gap)
    # without --baseline the file is neither written nor in the way
    plain = tmp_path / "plain"
    assert main(tiny("--out", str(plain))) == 0
    assert not (plain / "match_paired.csv").exists()


def test_entropy_track_at_several_margins(tmp_path):
    out = tmp_path / "m"
    argv = tiny("--methods", "entropy_track", "ball_track", "--track-margin", "0", "20")
    assert main([*argv, "--baseline", "ball_track", "--out", str(out)]) == 0
    with (out / "match_paired.csv").open() as f:
        methods = [r["method"] for r in csv.DictReader(f)]
    assert methods == ["entropy_track[0deg]", "entropy_track[20deg]"]


def test_several_models_play_side_by_side(tmp_path, capsys):
    """Two copies of the shipped policy play as two onnx_policy results, named after their
    folders, on the same matches: the same results, every paired difference zero."""
    from activevision.runtime import pretrained_policy_path

    shipped = pretrained_policy_path()
    models = []
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        for suffix in (".onnx", ".json"):
            target = tmp_path / name / f"policy{suffix}"
            target.write_bytes(shipped.with_suffix(suffix).read_bytes())
        models.append(str(tmp_path / name / "policy.onnx"))
    out = tmp_path / "m"
    argv = tiny("--methods", "onnx_policy", "--model", *models)
    assert main([*argv, "--baseline", "onnx_policy[a]", "--out", str(out)]) == 0
    assert "2 methods" in capsys.readouterr().out
    with (out / "match_paired.csv").open() as f:
        (paired,) = list(csv.DictReader(f))
    assert paired["method"] == "onnx_policy[b]"
    assert float(paired["position_rmse_diff"]) == 0.0 == float(paired["head_travel_diff"])


def test_match_csv_records_the_model_each_onnx_policy_row_played(tmp_path, capsys):
    """``match --model runs/X/policy.onnx`` wrote nothing of which model played: its rows
    record the file as given and its SHA-256 (empty in the other rows); without
    ``--model`` (the shipped policy) match.csv has no such columns, as before. So do the
    rows of match_paired.csv (``--baseline``), the baseline's model too."""
    import hashlib

    from activevision.runtime import pretrained_policy_path

    shipped = pretrained_policy_path()
    (tmp_path / "x").mkdir()
    for suffix in (".onnx", ".json"):
        target = tmp_path / "x" / f"policy{suffix}"
        target.write_bytes(shipped.with_suffix(suffix).read_bytes())
    model = tmp_path / "x" / "policy.onnx"
    argv = [*TINY[:3], "--ticks", "3", "--methods", "onnx_policy", "ball_track"]
    paired = ["--baseline", "ball_track"]
    assert main([*argv, *paired, "--model", str(model), "--out", str(tmp_path / "m")]) == 0
    assert main([*argv, *paired, "--out", str(tmp_path / "shipped")]) == 0
    with (tmp_path / "m" / "match.csv").open() as f:
        rows = list(csv.DictReader(f))
    digest = hashlib.sha256(model.read_bytes()).hexdigest()
    assert [(r["method"], r["model"], r["model_sha256"]) for r in rows] == [
        ("onnx_policy", str(model), digest),
        ("ball_track", "", ""),
    ]
    with (tmp_path / "m" / "match_paired.csv").open() as f:
        (row,) = list(csv.DictReader(f))
    assert list(row)[-4:] == ["model", "model_sha256", "baseline_model", "baseline_model_sha256"]
    assert list(row.values())[-4:] == [str(model), digest, "", ""]
    for name in ("match_paired.csv", "match.csv"):  # header: match.csv's, below
        with (tmp_path / "shipped" / name).open() as f:
            header = next(csv.reader(f))
        assert not any("model" in column for column in header), name
    # the model as the baseline: the row's none, the baseline's the model
    out = tmp_path / "b"
    argv = [*argv, "--model", str(model), "--baseline", "onnx_policy", "--out", str(out)]
    assert main(argv) == 0
    with (out / "match_paired.csv").open() as f:
        (row,) = list(csv.DictReader(f))
    assert row["method"] == "ball_track"
    assert list(row.values())[-4:] == ["", "", str(model), digest]
    # the same results otherwise: the shipped policy's bytes are the copy's
    with (tmp_path / "shipped" / "match.csv").open() as f:
        assert [{k: r[k] for k in header} for r in rows] == list(csv.DictReader(f))


def test_existing_outputs_need_overwrite(tmp_path, capsys, one_clear_line):
    out = tmp_path / "m"
    assert main(tiny("--out", str(out))) == 0
    capsys.readouterr()
    assert main(tiny("--out", str(out))) == 2
    one_clear_line("match.csv", "--overwrite")
    assert main(tiny("--out", str(out), "--overwrite")) == 0


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["match", "--methods", "nope"], "nope"),
        (["match", "--matches", "0"], "--matches"),
        (["match", "--step-deg", "90"], "--step-deg"),
        (["match", "--walk", "home"], "--walk"),
        (["match", "--action-type", "diagonal"], "--action-type"),
        (["match", "--robots", "9"], "--robots"),
        (["match", "--robots", "two"], "--robots"),
        (["match", "--robot-speed", "-0.1"], "--robot-speed"),
        (["match", "--detection", "0.9", "0.5"], "--detection"),
        (["match", "--detection", "0.9", "0.5", "1.5"], "--detection"),
        (["match", "--detection", "0.5", "0.9", "0.1", "--matches", "1"], "far"),
        (["match", "--model", "missing.onnx", "--matches", "1"], "missing.onnx"),
        (["match", "--methods", "random", "--clip-method", "ball_track"], "--clip-method"),
        (["match", "--methods", "random", "--baseline", "ball_track"], "--baseline"),
        (["match", "--methods", "random", "--baseline", "random"], "--baseline"),
        # an empty name (a shell variable left unset) was the default, unsaid
        (["match", "--methods", "random", "--clip-method", ""], "--clip-method"),
        (["match", "--methods", "random", "--clip-method", " "], "--clip-method"),
        (["match", "--methods", "random", "--baseline", ""], "--baseline"),
        (["match", "--track-margin", "30"], "--track-margin"),
        (["match", "--methods", "random", "--track-margin", "5"], "--track-margin"),
        (["match", "--methods", "random", "--model", "README.md"], "--model"),
        (["match", "--methods", "random", "--weights", "best"], "--weights"),
    ],
)
def test_bad_input_is_one_clear_line(tmp_path, argv, needle, one_clear_line):
    assert main([*argv, "--out", str(tmp_path / "m")]) == 2
    one_clear_line(needle)


def test_refuses_a_training_run(trained, one_clear_line):
    assert main(tiny("--out", str(Path(trained)))) == 2
    one_clear_line("training run")


def test_a_match_trained_ddqn_run_plays_and_exports(tmp_path, tiny_train, capsys, monkeypatch):
    """--preset match_ddqn trains the package's DDQN on ActiveVisionMatch-v0; the run plays
    as ``learned`` (PyTorch, batched) and, exported, as ``onnx_policy`` (HeadController).
    Trained with a weaker detector, it plays in that world unless --detection says otherwise,
    and match.csv records the detector for the report."""
    run = tmp_path / "match_run"
    argv = [*tiny_train, "--out", str(run), "--set", "eval_interval=30", "--set", "eval_episodes=2"]
    argv += ["--set", "match.detection.far=0.2"]
    argv[argv.index("quickstart_ddqn")] = "match_ddqn"
    assert main(argv) == 0
    # validated on matches, as the match student is (a match has no success rate)
    with (run / "evaluations.csv").open() as f:
        reader = csv.DictReader(f)
        assert len(list(reader)) == 2 and "position_rmse" in (reader.fieldnames or ())
    assert (run / "plots" / "validation_position_rmse.png").exists()
    assert not (run / "plots" / "success_rate.png").exists()
    out = tmp_path / "m"
    capsys.readouterr()
    assert main(tiny("--out", str(out), "--run", str(run), "--methods", "learned")) == 0
    assert f"detector 0.95/0.2/0.05 (the one {run} was trained with)" in capsys.readouterr().out
    with (out / "match.csv").open() as f:
        row = next(csv.DictReader(f))
    detector = (row["detect_near"], row["detect_far"], row["false_detections"])
    assert detector == ("0.95", "0.2", "0.05")
    # the figures' titles name the run by its folder ("the one match_run was trained with"),
    # not by the path given: the same bytes from another directory
    monkeypatch.chdir(tmp_path)
    relative = tiny("--out", "m_relative", "--run", "match_run", "--methods", "learned")
    assert main(relative) == 0
    for name in ("match.csv", "match_pareto.png", "match_error.png"):
        assert (out / name).read_bytes() == (tmp_path / "m_relative" / name).read_bytes(), name
    capsys.readouterr()
    played = tiny("--out", str(out), "--run", str(run), "--methods", "learned", "--overwrite")
    assert main([*played, "--detection", "0.95", "0.5", "0.05"]) == 0
    printed = capsys.readouterr().out
    note = f"note: {run} was trained with detector 0.95/0.2/0.05; these matches use 0.95/0.5/0.05"
    assert note in printed
    assert ", detector" not in printed  # the default world, as asked
    assert main(["export", str(run), "-o", str(tmp_path / "policy.onnx")]) == 0
    onnx = ["--methods", "onnx_policy", "--model", str(tmp_path / "policy.onnx")]
    assert main(tiny("--out", str(out), "--overwrite", *onnx)) == 0
    with (out / "match.csv").open() as f:
        assert [r["method"] for r in csv.DictReader(f)] == ["onnx_policy"]
    # its actions are 3-degree moves: a 6-degree discrete match would play them as 6-degree
    capsys.readouterr()
    assert main(tiny("--out", str(tmp_path / "m6"), "--step-deg", "6", *onnx)) == 2
    err = capsys.readouterr().err.strip()
    assert "3-degree 8way moves; play it with --step-deg 3" in err and "\n" not in err
    assert not (tmp_path / "m6").exists()


MIRROR = """
from activevision.experiments.match_methods import BallTrack


class Mirror(BallTrack):
    name = "mirror"  # ball_track under another name: the same matches, move for move


def not_a_strategy(config):
    return object()


class NoConfig:  # takes no config: not NAME(config)
    def reset(self, n, rng):
        pass


"""


def test_your_own_strategy_plays_beside_the_built_in_ones(tmp_path, capsys):
    """--strategy FILE.py:NAME plays the user's class on the same seeds: a copy of
    ball_track differs from it by exactly nothing, match by match; the README's example
    file plays too, in the discrete and the continuous match."""
    mine = tmp_path / "mine.py"
    mine.write_text(MIRROR)
    out = tmp_path / "m"
    example = Path(__file__).parents[2] / "examples" / "uncertainty_glance.py"
    argv = tiny("--out", str(out), "--baseline", "ball_track")
    strategies = ["--strategy", f"{mine}:Mirror", f"{example}:UncertaintyGlance"]
    assert main([*argv, *strategies]) == 0
    with (out / "match_paired.csv").open() as f:
        paired = {r["method"]: r for r in csv.DictReader(f)}
    assert set(paired) == {"random", "mirror", "uncertainty_glance"}
    mirror = paired["mirror"]
    for metric in ("position_rmse", "ball_in_view", "head_travel"):
        assert float(mirror[f"{metric}_diff"]) == 0.0
    for metric in ("position_rmse", "head_travel"):  # unbounded: nothing limits the spread
        assert float(mirror[f"{metric}_diff_low"]) == float(mirror[f"{metric}_diff_high"]) == 0.0
    # a share: no difference in any match, by the rule of every other metric
    assert float(mirror["ball_in_view_diff_high"]) == float(mirror["ball_in_view_diff_low"]) == 0
    continuous = [*argv, "--overwrite", "--action-type", "continuous", *strategies]
    assert main(continuous) == 0


@pytest.mark.parametrize(
    ("spec", "needle"),
    [
        ("mine.py", "FILE.py:NAME"),
        ("missing.py:Mirror", "no such file"),
        ("mine.py:Nothing", "defines no class or function Nothing"),
        ("mine.py:NoConfig", "NoConfig(config) failed"),
        ("mine.py:not_a_strategy", "no reset or act method"),
        ("no_such_module_xyz:Thing", "cannot import it"),
        ("folder_xyz/:Mirror", "folder_xyz/ is no FILE.py (nor a MODULE name)"),  # a folder
        ("folder_xyz:Mirror", "folder_xyz defines no class or function Mirror"),  # a package
        ("mine.txt:Mirror", "mine.txt is no FILE.py"),
        ("broken.py:Mirror", "broken.py:2: "),
        # the same spec twice played once, the repeat dropped silently
        ("mine.py:Mirror mine.py:Mirror", "names the strategy mine.py:Mirror twice"),
        ("mine.py:Mirror", None),
    ],
)
def test_a_bad_strategy_is_one_clear_line(tmp_path, monkeypatch, spec, needle, one_clear_line):
    (tmp_path / "mine.py").write_text(MIRROR)
    (tmp_path / "broken.py").write_text("class Mirror:\n    def act(self\n")
    (tmp_path / "folder_xyz").mkdir()
    (tmp_path / "mine.txt").write_text(MIRROR)
    monkeypatch.chdir(tmp_path)
    # a MODULE is looked for in the current directory too: this test's, for this test only
    monkeypatch.setattr(sys, "path", list(sys.path))
    monkeypatch.delitem(sys.modules, "folder_xyz", raising=False)
    argv = tiny("--out", str(tmp_path / "m"), "--strategy", *spec.split())
    if needle is None:
        assert main(argv) == 0
        return
    assert main(argv) == 2
    one_clear_line(needle)


def test_a_strategy_imports_its_own_modules_under_the_script_too(tmp_path, monkeypatch):
    """A team's strategy file imports the modules beside it, as ``python FILE.py`` would
    run it, and a MODULE:NAME in the current directory is found under the
    ``activevision`` script (whose sys.path has its bin folder, not the current
    directory) as under ``python -m activevision``: both were "No module named ..."."""
    team = tmp_path / "team"
    team.mkdir()
    (team / "team_helpers.py").write_text("NAME = 'ours'\n")
    (team / "ours.py").write_text(
        "from team_helpers import NAME\n"
        "from activevision.experiments.match_methods import BallTrack\n\n\n"
        "class Ours(BallTrack):\n    name = NAME\n"
    )
    (tmp_path / "here_strategy.py").write_text(MIRROR)
    monkeypatch.chdir(tmp_path)
    # the script's sys.path: no current directory in it
    script_path = [p for p in sys.path if p not in ("", str(tmp_path), str(team))]
    monkeypatch.setattr(sys, "path", script_path)
    for name in ("team_helpers", "here_strategy"):
        monkeypatch.delitem(sys.modules, name, raising=False)
    argv = tiny("--methods", "ball_track", "--ticks", "2", "--strategy")
    assert main([*argv, "team/ours.py:Ours", "--out", "a"]) == 0
    assert main([*argv, "here_strategy:Mirror", "--out", "b"]) == 0
    with (tmp_path / "a" / "match.csv").open() as f:
        assert [r["method"] for r in csv.DictReader(f)] == ["ball_track", "ours"]
    with (tmp_path / "b" / "match.csv").open() as f:
        assert [r["method"] for r in csv.DictReader(f)] == ["ball_track", "mirror"]


WIDE = """
import numpy as np


class Wide:
    name = "wide"

    def __init__(self, config):
        pass

    def reset(self, n, rng):
        self.n = n

    def act(self, obs, info):
        return np.zeros((self.n, 7))  # seven numbers a match: not an action
"""


def test_a_strategy_acting_wrongly_is_named_on_one_line(tmp_path, one_clear_line):
    (tmp_path / "wide.py").write_text(WIDE)
    argv = tiny("--out", str(tmp_path / "m"), "--strategy", f"{tmp_path / 'wide.py'}:Wide")
    assert main(argv) == 2
    one_clear_line("strategy wide, tick 0: invalid action", "shape (2,)")


RAISING = """
import numpy as np


class Late:
    def __init__(self, config):
        self.ticks = 0

    def reset(self, n, rng):
        self.n = n

    def act(self, obs, info):
        self.ticks += 1
        if self.ticks > 4:  # after the trial ticks
            return np.zeros(self.n, dtype=np.int64)[self.n]
        return np.zeros(self.n, dtype=np.int64)


class BadReset(Late):
    def reset(self, n, rng):
        raise RuntimeError("no reset today")


def broken_factory(config):
    return config.nothing


class BadInit(Late):
    def __init__(self, config):
        len(5)  # a TypeError of the user's own, not a wrong signature


class TwoLines(Late):
    def reset(self, n, rng):
        raise RuntimeError("first line\\nsecond line")
"""


def _line(source: str, text: str) -> str:
    """``"line N"``: where ``text`` stands in ``source``."""
    return f"line {source[: source.index(text)].count(chr(10)) + 1}"


@pytest.mark.parametrize(
    ("source", "name", "needles"),
    [
        (
            RAISING,
            "Late",
            ["strategy Late, tick 4: act raised IndexError", _line(RAISING, "[self.n]") + ", in"],
        ),
        (RAISING, "BadReset", ["strategy BadReset: reset raised RuntimeError: no reset today"]),
        (
            RAISING,
            "broken_factory",
            ["broken_factory(config) raised AttributeError", _line(RAISING, "config.nothing")],
        ),
        ("1 / 0\n", "Any", ["importing", "raised ZeroDivisionError", "line 1, in <module>"]),
        ("int('x')\n", "Any", ["importing", "raised ValueError: invalid literal", "line 1"]),
        (RAISING, "BadInit", ["BadInit(config) raised TypeError", _line(RAISING, "len(5)")]),
        (RAISING, "TwoLines", ["reset raised RuntimeError: first line second line"]),
    ],
)
def test_a_strategy_that_raises_is_named_on_one_line_with_its_line(
    tmp_path, source, name, needles, one_clear_line
):
    """An exception from the user's own code (at import, in NAME(config), reset or act,
    also after the trial ticks) ends in one line: what raised, at which tick, and the line
    of their file, not a traceback through the package."""
    (tmp_path / "raising.py").write_text(source)
    argv = tiny("--ticks", "8", "--out", str(tmp_path / "m"))
    argv += ["--strategy", f"{tmp_path / 'raising.py'}:{name}"]
    assert main(argv) == 2
    one_clear_line(*needles, "raising.py")


def test_two_strategies_of_one_name_are_refused(tmp_path, one_clear_line):
    (tmp_path / "a.py").write_text(MIRROR)
    (tmp_path / "b.py").write_text(MIRROR)
    specs = [f"{tmp_path / 'a.py'}:Mirror", f"{tmp_path / 'b.py'}:Mirror"]
    assert main(tiny("--out", str(tmp_path / "m"), "--strategy", *specs)) == 2
    one_clear_line("two strategies are named mirror")


@pytest.mark.parametrize("label", ["two\nlines", "tab\there", "bell\a"])
def test_a_strategy_label_of_more_than_one_printable_line_is_refused(
    tmp_path, label, one_clear_line
):
    """A name attribute with a newline was played and written: it split the printed table's
    row and report.md's Markdown row in two."""
    source = MIRROR.replace('name = "mirror"', f"name = {label!r}")
    assert repr(label) in source
    (tmp_path / "mine.py").write_text(source)
    out = tmp_path / "m"
    argv = tiny("--out", str(out), "--strategy", f"{tmp_path / 'mine.py'}:Mirror")
    assert main(argv) == 2
    one_clear_line(f"its label {label!r} is not one line of printable text")
    assert not out.exists()


@pytest.mark.parametrize("label", ["learned", "oracle_ball", "onnx_policy[mine]"])
def test_a_strategy_labelled_as_a_built_in_one_is_refused(tmp_path, label, one_clear_line):
    """As ``evaluate --strategy`` refuses a built-in method's label: a row named
    ``learned`` or ``oracle_ball`` is read as the built-in's (report.md said "learned: the
    training run `match --run` named" of the user's own class), played beside it or not."""
    source = MIRROR.replace('name = "mirror"', f"name = {label!r}")
    assert label in source
    (tmp_path / "mine.py").write_text(source)
    out = tmp_path / "m"
    argv = tiny("--out", str(out), "--strategy", f"{tmp_path / 'mine.py'}:Mirror")
    assert main(argv) == 2
    one_clear_line(f"its label {label!r} is a built-in strategy's")
    assert not out.exists()


def test_the_ball_can_bounce_off_our_robot(tmp_path, capsys):
    from activevision.cli.match import _match_config

    argv = tiny("--methods", "ball_track", "--ball-bounces-off-us", "--out", str(tmp_path))
    assert main(argv) == 0
    assert "the ball bouncing off our robot" in capsys.readouterr().out
    args = build_parser().parse_args(argv)
    assert _match_config(args).ball.bounces_off_own_robot
    assert not _match_config(build_parser().parse_args(TINY)).ball.bounces_off_own_robot


def test_the_figures_titles_name_a_walk_to_the_ball(tmp_path, capsys, monkeypatch):
    """The figures travel without the console's first line: their titles name what differs
    from the default world, the walk too (``--walk ball`` changes ball in view most)."""
    import activevision.figures.match as figures

    titles = []
    for name in ("plot_pareto", "plot_error_over_time"):
        draw = getattr(figures, name)

        def recorded(*args, draw=draw, **kwargs):
            titles.append(args[3])  # both take (data, ..., path, title)
            return draw(*args, **kwargs)

        monkeypatch.setattr(figures, name, recorded)
    argv = tiny("--methods", "ball_track", "--ticks", "3")
    assert main([*argv, "--walk", "ball", "--out", str(tmp_path / "ball")]) == 0
    assert len(titles) == 2 and all("walking to the ball" in t for t in titles), titles
    titles.clear()
    assert main([*argv, "--out", str(tmp_path / "waypoints")]) == 0
    assert len(titles) == 2 and not any("walking" in t for t in titles), titles


def test_help_says_95_percent_once(capsys):
    # argparse %-formats a description only where it holds "%(prog)": "95%%" printed as is
    assert main(["match", "--help"]) == 0
    printed = " ".join(capsys.readouterr().out.split())
    assert "with 95% intervals; writes match.csv" in printed
    assert "%%" not in printed


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux's /proc")
def test_an_out_that_cannot_be_made_is_refused_before_any_match(monkeypatch, one_clear_line):
    import activevision.experiments.match as experiment

    played = []
    monkeypatch.setattr(experiment, "compare_matches", lambda *a, **k: played.append(a))
    # /proc exists and is a folder, but no folder can be made in it (not even by root)
    assert main(tiny("--out", "/proc/activevision-no-such/m")) == 2
    one_clear_line("--out /proc/activevision-no-such/m", "cannot create")
    assert played == []


def test_a_strategy_failing_in_its_trial_leaves_no_folder(tmp_path, one_clear_line):
    (tmp_path / "wide.py").write_text(WIDE)
    out = tmp_path / "new" / "m"  # the output folder is made before the matches are played
    argv = tiny("--out", str(out), "--strategy", f"{tmp_path / 'wide.py'}:Wide")
    assert main(argv) == 2
    one_clear_line("strategy wide, tick 0: invalid action")
    assert not (tmp_path / "new").exists()


def test_ticks_beyond_memory_are_one_clear_line(tmp_path, one_clear_line):
    # 10**15 ticks of per-tick scores: more than any address space, refused at once
    argv = tiny("--methods", "random", "--ticks", str(10**15), "--out", str(tmp_path / "m"))
    assert main(argv) == 2
    one_clear_line(f"--ticks {10**15} x --matches 2: out of memory")
    assert not (tmp_path / "m").exists()


EXITING = """
import sys

import numpy as np

if "exit_at_import" in sys.modules:
    sys.exit("leaving at import")


class AtInit:
    def __init__(self, config):
        sys.exit()


class AtReset:
    def __init__(self, config):
        pass

    def reset(self, n, rng):
        sys.exit(3)

    def act(self, obs, info):
        return np.zeros(1, dtype=int)


class AtAct(AtReset):
    def reset(self, n, rng):
        self.n = n

    def act(self, obs, info):
        sys.exit(0)
"""


@pytest.mark.parametrize(
    ("name", "needle"),
    [
        ("AtInit", "AtInit(config) raised SystemExit (exiting.py"),
        ("AtReset", "reset raised SystemExit: 3"),
        ("AtAct", "strategy AtAct, tick 0: act raised SystemExit: 0"),
        ("import", "importing"),
    ],
)
def test_a_strategy_calling_sys_exit_is_one_line_not_a_silent_exit_0(
    tmp_path, monkeypatch, name, needle, one_clear_line
):
    """sys.exit() in a user's strategy ended the command with its code (0: success) and
    no outputs, or no message at all."""
    import sys
    import types

    (tmp_path / "exiting.py").write_text(EXITING)
    if name == "import":  # a module the file looks for makes it exit as it is imported
        monkeypatch.setitem(sys.modules, "exit_at_import", types.ModuleType("exit_at_import"))
    argv = tiny("--out", str(tmp_path / "m"))
    argv += ["--strategy", f"{tmp_path / 'exiting.py'}:{'AtAct' if name == 'import' else name}"]
    assert main(argv) == 2
    one_clear_line(needle, "SystemExit", "exiting.py")
    assert not (tmp_path / "m").exists()


def test_a_run_trained_for_another_camera_plays_in_its_camera(tmp_path, tiny_train, capsys):
    """A match run trained for the robot's camera (README: ``--set match.camera.*``) plays
    matches seen through that camera, as it plays its detector: its 160 x 90 network was a
    traceback in the default camera's 160 x 120 matches ("mat1 and mat2 shapes cannot be
    multiplied"), and a wider field of view played silently through the paper's. Its
    exported policy played by onnx_policy in matches of another camera is warned about."""
    run = tmp_path / "wide"
    camera = ["match.camera.width=160", "match.camera.height=90", "match.camera.hfov=1.2217"]
    argv = [*tiny_train, "--out", str(run)]
    argv[argv.index("quickstart_ddqn")] = "match_ddqn"
    for setting in camera:
        argv += ["--set", setting]
    assert main(argv) == 0
    capsys.readouterr()
    out = tmp_path / "m"
    assert main(tiny("--out", str(out), "--run", str(run), "--methods", "learned")) == 0
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err
    assert f"camera 160x90 px, hfov 70 deg (the one {run} was trained with)" in captured.out
    with (out / "match.csv").open() as f:  # and match.csv records it, for report.md
        (row,) = csv.DictReader(f)
    assert (row["camera_px"], float(row["hfov_deg"])) == ("160x90", pytest.approx(70, abs=0.01))
    assert main(["export", str(run), "-o", str(tmp_path / "policy.onnx")]) == 0
    capsys.readouterr()
    onnx = ["--methods", "onnx_policy", "--model", str(tmp_path / "policy.onnx")]
    with pytest.warns(CameraMismatchWarning) as warned:
        assert main(tiny("--out", str(tmp_path / "m2"), *onnx)) == 0
    differs = [str(w.message) for w in warned if "camera differs" in str(w.message)]
    assert len(differs) == 1 and "hfov: robot 58.0 deg, trained 70.0 deg" in differs[0]


def test_a_match_run_of_another_camera_plays_episodes_through_it(tmp_path, tiny_train, capsys):
    """evaluate, episode and robustness play a match-trained run (match_ddqn) on episodes
    seen through the camera it was trained for: a 160 x 90 network was a traceback in the
    episodes' 160 x 120 image ("mat1 and mat2 shapes cannot be multiplied")."""
    run = tmp_path / "wide"
    argv = [*tiny_train, "--out", str(run), "--set", "match.camera.width=160"]
    argv += ["--set", "match.camera.height=90", "--set", "match.step_deg=6"]
    argv[argv.index("quickstart_ddqn")] = "match_ddqn"
    assert main(argv) == 0
    played = ["--run", str(run), "--episodes", "2"]
    assert main(["evaluate", *played, "--methods", "learned", "--out", str(tmp_path / "e")]) == 0
    robust = ["robustness", *played, "--perturbations", "clean", "--out", str(tmp_path / "r")]
    assert main(robust) == 0
    assert main(["episode", "--run", str(run), "--out", str(tmp_path / "ep.png")]) == 0
    assert "Traceback" not in capsys.readouterr().err
    from activevision.cli.args import env_config_of_run

    env = env_config_of_run(run)
    assert (env.camera.width, env.camera.height, env.step_deg) == (160, 90, 6.0)


def test_a_match_run_of_a_neck_that_barely_tilts_plays_episodes(tmp_path):
    """A match run of a camera whose tilt limits leave out the episodes' default start tilt
    (5-25 degrees) starts its episodes within its limits: its EnvConfig was refused
    ("start_tilt_range_deg: must lie within the camera's tilt limits"), and with it
    evaluate, compare, episode and robustness of the run."""
    from activevision.cli.args import env_config_of_run
    from activevision.training import apply_overrides, preset
    from activevision.training.config import save_config

    run = tmp_path / "neck"
    run.mkdir()
    limits = ["match.camera.tilt_min=0.5", "match.camera.tilt_max=0.9"]
    save_config(apply_overrides(preset("match_ddqn"), limits), run / "config.json")
    env = env_config_of_run(run)
    assert (env.camera.tilt_min, env.camera.tilt_max) == (0.5, 0.9)
    low, high = env.start_tilt_range_deg
    assert (low, high) == pytest.approx((np.degrees(0.5), np.degrees(0.9)))


def test_set_changes_the_matches_world_and_says_so(tmp_path, capsys):
    """``--set`` reaches every MatchConfig field no option sets: a faster tick and a wider
    camera (the command named no camera, and the tick only through --run), recorded in the
    CSV's columns; a field no column records goes to its ``settings`` column, which a
    default world's file has none of, and the report names it."""
    from activevision.experiments.match_world import world_differences

    out = tmp_path / "m"
    argv = tiny("--out", str(out), "--set", "tick_seconds=0.16", "--set", "camera.hfov=1.2")
    assert main([*argv, "--set", "match.tracker.gate=9"]) == 0
    printed = capsys.readouterr().out
    assert "per 0.16 s" in printed and "(1.44 s of play)" in printed
    assert "--set tick_seconds=0.16 camera.hfov=1.2 match.tracker.gate=9" in printed
    with (out / "match.csv").open() as f:
        row = next(csv.DictReader(f))
    assert float(row["tick_s"]) == 0.16
    assert float(row["hfov_deg"]) == pytest.approx(68.755, abs=1e-3)
    assert row["settings"] == "tracker.gate=9.0"
    assert world_differences(row)[-1] == "--set tracker.gate=9.0"
    assert main(tiny("--out", str(tmp_path / "plain"))) == 0
    with (tmp_path / "plain" / "match.csv").open() as f:
        assert "settings" not in next(csv.DictReader(f))
    # a detector set so, with no run: it named "the one None was trained with"
    argv = tiny("--out", str(tmp_path / "noise"), "--set", "detection.ball_noise=0.1")
    capsys.readouterr()
    assert main(argv) == 0
    printed = capsys.readouterr().out.splitlines()[0]
    assert "None" not in printed and "ball noise 0.1 of its range" in printed


@pytest.mark.parametrize(
    ("setting", "needle"),
    [
        ("ticks=5", "give it with --ticks"),
        ("match.step_deg=6", "give it with --step-deg"),
        ("detection.far=0.2", "give it with --detection"),
        ("walk.target=ball", "give it with --walk"),
        ("reward.kind=error", "scores no reward"),  # the command reads none
        ("observation=image+head", "observation"),
        ("nope=1", "has no field 'nope'"),
        ("camera.nope=1", "camera has no field 'nope'"),
        ("tick_seconds.x=1", "tick_seconds is a value"),
        ("tick_seconds=0", "tick_seconds"),  # the config's own range
        ("tick_seconds", "key=value"),
    ],
)
def test_a_bad_set_is_one_clear_line(tmp_path, setting, needle, one_clear_line):
    assert main(tiny("--out", str(tmp_path / "m"), "--set", setting)) == 2
    one_clear_line("--set", needle)
    assert not (tmp_path / "m").exists()


def test_set_camera_beside_a_run_is_refused(trained, tmp_path, one_clear_line):
    argv = tiny("--methods", "learned", "--run", str(trained), "--out", str(tmp_path / "m"))
    assert main([*argv, "--set", "camera.hfov=1.2"]) == 2
    one_clear_line("--set camera", "trained for")


def test_kidnapped_matches_report_what_followed(tmp_path, capsys):
    """--kidnap-ticks kidnaps our robot in every match; the console and match.csv say how
    many kidnaps left it lost, how often the lost detector fired, how often and how soon
    the error was back under 0.5 m; a world without kidnaps writes none of those columns."""
    out = tmp_path / "m"
    argv = ["match", "--matches", "3", "--ticks", "60", "--methods", "ball_track", "random"]
    assert main([*argv, "--kidnap-ticks", "10", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "kidnapped in tick 10, carried 1-2 m, turned up to 0.8 rad" in printed
    assert "lost alarm" in printed and "back < 0.5 m" in printed
    with (out / "match.csv").open() as f:
        rows = list(csv.DictReader(f))
    for row in rows:
        assert row["kidnaps"] == "3" and row["kidnap_ticks"] == "10"
        lost = int(row["kidnaps_lost"])
        assert 1 <= lost <= 3
        low, high = float(row["kidnap_recovered_low"]), float(row["kidnap_recovered_high"])
        assert 0 <= low <= float(row["kidnap_recovered"]) <= high <= 1
    assert main(tiny("--out", str(tmp_path / "plain"))) == 0
    with (tmp_path / "plain" / "match.csv").open() as f:
        assert not any(key.startswith("kidnap") for key in next(csv.DictReader(f)))


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--kidnap-ticks", "40"], "past the match's 9 ticks"),
        (["--kidnap-ticks", "0"], "--kidnap-ticks"),
        (["--kidnap", "-1"], "--kidnap"),
        (["--set", "kidnap.turn=0.5"], "give --kidnap or --kidnap-ticks"),
        (["--set", "kidnap.rate=1"], "give it with --kidnap"),
        (["--kidnap", "1", "--set", "kidnap.distance=[3,1]"], "ordered"),
    ],
)
def test_a_bad_kidnap_is_one_clear_line(tmp_path, argv, needle, one_clear_line):
    assert main(tiny("--out", str(tmp_path / "m"), *argv)) == 2
    one_clear_line(needle)
