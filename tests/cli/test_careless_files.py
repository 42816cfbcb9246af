"""A careless user's files: a config with a key written twice, the wrong file passed where
a policy goes, a run named twice, a file where a run's folder goes, results copied between
runs, a run started over beside an earlier attempt's outputs, a log read while written."""

from __future__ import annotations

import csv
import hashlib
import json
import shutil
import warnings
from pathlib import Path

import pytest

from activevision.cli import main


@pytest.fixture
def run(trained, tmp_path) -> Path:
    """A private copy of the tiny run, free to be tampered with."""
    return Path(shutil.copytree(trained, tmp_path / "run"))


def test_a_config_with_a_key_written_twice_is_refused(tmp_path, tiny_train, one_clear_line):
    """The last value was trained, the first dropped unsaid (``--set`` values alike)."""
    config = tmp_path / "dup.json"
    config.write_text('{"seed": 1, "run": {"total_timesteps": 60}, "seed": 2}')
    assert main(["train", "--config", str(config), "--out", str(tmp_path / "r")]) == 2
    one_clear_line(str(config), "duplicate key 'seed'")
    assert not (tmp_path / "r").exists()
    camera = 'env.camera={"hfov": 1.0, "hfov": 1.2}'
    assert main([*tiny_train, "--set", camera, "--out", str(tmp_path / "r")]) == 2
    one_clear_line("env.camera", "duplicate key 'hfov'")


def test_demo_of_a_file_that_is_no_policy_says_so(tmp_path, one_clear_line):
    """It named a missing ``f.json``, a file the user never meant."""
    table = tmp_path / "f.csv"
    table.write_text("a,b\n")
    assert main(["demo", "--policy", str(table), "--out", str(tmp_path / "d.png")]) == 2
    line = one_clear_line(f"{table} is not a policy file")
    assert "f.json" not in line


def test_a_run_named_twice_is_said_to_be_named_twice(run, tmp_path, monkeypatch, one_clear_line):
    """``--runs r r`` said "rename one directory"."""
    monkeypatch.chdir(run.parent)
    out = ["--episodes", "1", "--out", str(tmp_path / "ev")]
    assert main(["evaluate", "--runs", "run", "./run/", *out]) == 2
    line = one_clear_line("--runs names the run run twice")
    assert "rename" not in line
    assert main(["compare", "--runs", str(run), f"{run}/", "--errors", "0", *out]) == 2
    one_clear_line(f"--runs names the run {run} twice")
    assert not (tmp_path / "ev").exists()


def test_the_run_of_run_named_again_in_runs_is_refused(run, tmp_path, monkeypatch, one_clear_line):
    """``evaluate --run R --runs R`` scored the run twice, as learned and as learned:R, on
    the same episodes (and ``compare`` drew both lines); the paths are compared as the
    folders they name."""
    monkeypatch.chdir(run.parent)
    out = ["--episodes", "1", "--out", str(tmp_path / "ev")]
    argv = ["evaluate", "--run", "run", "--runs", f"{run}/", "--methods", "learned", *out]
    assert main(argv) == 2
    one_clear_line(f"--runs {run} is --run run, whose policy plays as method learned already")
    compare = ["compare", "--run", str(run), "--runs", "./run", "--errors", "0", *out]
    assert main(compare) == 2
    one_clear_line(f"--runs run is --run {run}")
    assert not (tmp_path / "ev").exists()
    # where --run only sets the env (learned is not among --methods) it plays once: taken
    argv = ["evaluate", "--run", "run", "--runs", "run", "--methods", "random", *out]
    assert main(argv) == 0
    with (tmp_path / "ev" / "evaluation.csv").open() as f:
        assert [r["method"] for r in csv.DictReader(f)] == ["random", "learned:run"]


def test_a_model_named_twice_is_refused(tmp_path, monkeypatch, one_clear_line):
    """``match --model a/policy.onnx ./a/policy.onnx`` played one policy twice (as
    onnx_policy[a-1] and onnx_policy[a-2]); the same path twice was dropped silently."""
    from activevision.runtime import pretrained_policy_path

    (tmp_path / "a").mkdir()
    for suffix in (".onnx", ".json"):
        shipped = pretrained_policy_path().with_suffix(suffix)
        (tmp_path / "a" / f"policy{suffix}").write_bytes(shipped.read_bytes())
    monkeypatch.chdir(tmp_path)
    argv = ["match", "--methods", "onnx_policy", "--matches", "1", "--ticks", "1", "--model"]
    out = ["--out", str(tmp_path / "m")]
    assert main([*argv, "a/policy.onnx", str(tmp_path / "a" / "policy.onnx"), *out]) == 2
    one_clear_line(f"--model names the policy a/policy.onnx and {tmp_path}/a/policy.onnx twice")
    assert main([*argv, "a/policy.onnx", "a/policy.onnx", *out]) == 2
    one_clear_line("--model names the policy a/policy.onnx twice: give each once")
    assert not (tmp_path / "m").exists()


#: what keeps each command below short where it is not refused (it was not, before):
#: a paper run of 2 steps, a sweep of one seed, one match of one tick, one episode
_SHORT = {
    "train": [("--steps", "2")],
    "sweep": [("--seeds", "0"), ("--set", "total_timesteps=2")],
    "match": [("--matches", "1"), ("--ticks", "1"), ("--methods", "random")],
    "compare": [("--episodes", "1"), ("--methods", "random")],
}


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        (
            ["train", "--set", "learning_rate=1e-3", "--set", "learner.learning_rate=2e-3"],
            "overrides learning_rate=1e-3 and learner.learning_rate=2e-3 both set"
            " learner.learning_rate: give it once",
        ),
        (
            ["train", "--set", "step_deg=4", "--set", "step_deg=5"],
            "override 'step_deg' (env.step_deg) is given twice (step_deg=4, then step_deg=5)",
        ),
        (
            ["sweep", "--set", "learning_rate=1e-3", "--set", "learner.learning_rate=2e-3"],
            "both set learner.learning_rate",
        ),
        (
            ["sweep", "--grid", "learning_rate=1e-3", "--grid", "learner.learning_rate=2e-3"],
            "--grid learning_rate and --grid learner.learning_rate both set",
        ),
        (
            ["match", "--set", "camera.hfov=1.2", "--set", "match.camera.hfov=1.0"],
            "--set: overrides camera.hfov=1.2 and match.camera.hfov=1.0 both set camera.hfov",
        ),
        # an option that keeps one value: argparse kept the last
        (
            ["train", "--steps", "5", "--steps", "6"],
            "argument --steps: given twice (--steps 5, then --steps 6): give it once",
        ),
        (["train", "--seed", "1", "--seed", "1"], "argument --seed: given twice"),
        (["train", "--overwrite", "--overwrite"], "argument --overwrite: given twice"),
        (
            ["evaluate", "--runs", "a", "b", "--runs", "c"],
            "argument --runs: given twice (--runs a b, then --runs c)",
        ),
        (["match", "--ticks", "3", "--ticks", "4"], "argument --ticks: given twice"),
        (["compare", "--errors", "0", "--errors", "1"], "argument --errors: given twice"),
    ],
)
def test_a_value_given_twice_is_refused_naming_it(tmp_path, argv, named, one_clear_line):
    """The last of two values was taken silently: ``train --set X=1 --set X=2`` (or two
    spellings of X), ``--steps 5 --steps 6``, ``--runs A --runs B`` (B alone scored)."""
    taken = {word for word in argv if word.startswith("--")} - {"--set"}  # --set: repeatable
    short = [w for pair in _SHORT.get(argv[0], []) if pair[0] not in taken for w in pair]
    assert main([*argv, *short, "--out", str(tmp_path / "out")]) == 2
    one_clear_line(named)
    assert not (tmp_path / "out").exists()


_EXAMPLES = Path(__file__).parents[2] / "examples"


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        (
            ["evaluate", "--methods", "random", "scan", "random", "--episodes", "1"],
            "argument --methods: names the method random twice: give each method once",
        ),
        (
            ["compare", "--methods", "random", "random", "--episodes", "1", "--errors", "0"],
            "argument --methods: names the method random twice: give each method once",
        ),
        (
            ["match", "--methods", "random", "random", "--matches", "1", "--ticks", "1"],
            "argument --methods: names the method random twice: give each method once",
        ),
        (
            ["match", "--methods", "entropy_track", "--track-margin", "5", "5.0"]
            + ["--matches", "1", "--ticks", "1"],
            "argument --track-margin: names the margin 5 twice: give each margin once",
        ),
        (
            ["evaluate", "--methods", "random", "--episodes", "1", "--strategy"]
            + [f"{_EXAMPLES / 'centre_ball.py'}:CentreBall"] * 2,
            "argument --strategy: names the strategy ",
        ),
        (
            ["match", "--methods", "random", "--matches", "1", "--ticks", "1", "--strategy"]
            + [f"{_EXAMPLES / 'uncertainty_glance.py'}:UncertaintyGlance"] * 2,
            "argument --strategy: names the strategy ",
        ),
        (
            ["episode", "--policies", "random", "random", "--seed", "1"],
            "argument --policies: names the policy random twice: give each policy once",
        ),
        # a row or a kidnap named twice was played once, the repeat dropped silently
        (
            ["robustness", "--method", "random", "--episodes", "1"]
            + ["--perturbations", "robots-1", "robots-1"],
            "argument --perturbations: names the perturbation robots-1 twice: give each"
            " perturbation once",
        ),
        (
            ["match", "--methods", "random", "--matches", "1", "--ticks", "9"]
            + ["--kidnap-ticks", "5", "5"],
            "argument --kidnap-ticks: names the tick 5 twice: give each tick once",
        ),
        # the list itself is still given once
        (
            ["evaluate", "--methods", "random", "--methods", "scan"],
            "argument --methods: given twice (--methods random, then --methods scan)",
        ),
    ],
)
def test_a_method_named_twice_is_refused_naming_it(tmp_path, argv, named, one_clear_line):
    """``evaluate --methods random scan random`` scored random once, the repeat dropped
    silently (so did compare's and match's --methods, --strategy, match's --track-margin 5
    5.0 and --kidnap-ticks 5 5, robustness --perturbations and episode's --policies, which
    drew one episode where two were asked for); as a run or model named twice, it is
    refused, naming it."""
    out = tmp_path / ("ep.png" if argv[0] == "episode" else "out")
    assert main([*argv, "--out", str(out)]) == 2
    one_clear_line(named)
    assert not out.exists()


def test_a_parsed_command_keeps_only_its_own_values():
    """The parser's note of the options given (to refuse one given twice) is not left in
    the namespace the command reads."""
    from activevision.cli import build_parser

    args = build_parser().parse_args(["train", "--steps", "5", "--out", "r", "--overwrite"])
    assert not [name for name in vars(args) if name.startswith("_")]
    assert (args.steps, args.overwrite) == (5, True)


@pytest.mark.parametrize("folder", ["tensorboard", "checkpoints"])
def test_a_file_where_a_run_writes_a_folder_is_named_before_training(
    tmp_path, tiny_train, folder, one_clear_line
):
    """``--overwrite`` went on and ended on ``[Errno 17] File exists`` once the config and
    logs were written (a run that then asked for --overwrite again). --overwrite replaces
    files by files, as every command's does: the file is named, and kept."""
    out = tmp_path / "out"
    out.mkdir()
    (out / folder).write_text("mine")
    argv = [*tiny_train[:-4], "--set", "tensorboard=true", "--out", str(out), "--overwrite"]
    assert main(argv) == 2
    one_clear_line(f"{out / folder} is a file, not a directory")
    assert [p.name for p in out.iterdir()] == [folder]
    assert (out / folder).read_text() == "mine"


def test_report_refuses_results_of_another_run_or_of_no_run(run, trained, tmp_path, capsys):
    evaluate = ["evaluate", "--methods", "learned", "random", "--episodes", "1"]
    assert main([*evaluate, "--run", str(run)]) == 0
    evaluation = run / "evaluation" / "evaluation.json"
    data = json.loads(evaluation.read_text())
    weights = run / "policy.safetensors"
    assert data["run"] == {
        "config_sha256": hashlib.sha256((run / "config.json").read_bytes()).hexdigest(),
        "weights_sha256": hashlib.sha256(weights.read_bytes()).hexdigest(),
    }
    assert main(["report", str(run)]) == 0
    capsys.readouterr()
    # another run's weights (as another run's evaluation copied in records them)
    evaluation.write_text(json.dumps({**data, "run": {**data["run"], "weights_sha256": "0" * 64}}))
    assert main(["report", str(run), "--overwrite"]) == 2
    assert "scored another run's weights" in capsys.readouterr().err
    # an evaluate without --run: the paper's env, no learned policy of this run
    assert (
        main(
            [
                "evaluate",
                "--methods",
                "random",
                "--episodes",
                "1",
                "--out",
                str(run / "evaluation"),
                "--overwrite",
            ]
        )
        == 0
    )
    capsys.readouterr()
    assert main(["report", str(run), "--overwrite"]) == 2
    assert "written by an evaluate without --run" in capsys.readouterr().err
    # a file from before the record is read as before
    data.pop("run")
    evaluation.write_text(json.dumps(data))
    assert main(["report", str(run), "--overwrite"]) == 0


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _report(run: Path) -> tuple[list[str], str]:
    """``report RUN --overwrite``'s warnings and page."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(["report", str(run), "--overwrite"]) == 0
    return [str(w.message) for w in caught], (run / "report.md").read_text()


def test_report_leaves_out_matches_and_robustness_of_another_run_or_replaced_weights(run, capsys):
    """``match --run`` and ``robustness --run`` recorded nothing of the run they scored, and
    ``report`` showed whatever lay in RUN/match/ and RUN/robustness/ as the run's: another
    run's results copied in, or this run's from before its weights were replaced. Each now
    records the run's digests in its last columns; ``report`` leaves a stale one out with
    one warning line naming it and how to write it again, and still writes the page."""
    match_csv, robustness_csv = run / "match" / "match.csv", run / "robustness" / "robustness.csv"
    matches = ["match", "--matches", "2", "--ticks", "9", "--methods", "ball_track", "learned"]
    paired = ["--baseline", "ball_track"]  # match_paired.csv records the run as match.csv does
    assert main([*matches, *paired, "--run", str(run), "--out", str(run / "match")]) == 0
    suite = ["robustness", "--episodes", "2", "--perturbations", "gain-dark-mild"]
    assert main([*suite, "--run", str(run)]) == 0
    weights = run / "policy.safetensors"
    recorded = {
        "run_config_sha256": _sha256(run / "config.json"),
        "run_weights_sha256": _sha256(weights),
        "run_weights": "final",
    }
    for table in (match_csv, match_csv.with_name("match_paired.csv"), robustness_csv):
        with table.open(newline="") as f:
            reader = csv.DictReader(f)
            rows = list(reader)
        assert list(reader.fieldnames or ())[-3:] == list(recorded), table
        assert [{key: row[key] for key in recorded} for row in rows] == [recorded] * len(rows)

    warned, page = _report(run)
    assert warned == []
    assert "## Head control through whole matches" in page and "## Robustness" in page
    # this run's weights replaced since (trained on, retrained): both left out, the page kept
    original = weights.read_bytes()
    weights.write_bytes(original + b" ")
    warned, page = _report(run)
    assert len(warned) == 2, warned
    for line, table, again in zip(
        warned, (match_csv, robustness_csv), ("match", "robustness"), strict=True
    ):
        assert line.startswith(f"left {table} out of the report: it scored another run's weights")
        assert f"activevision {again} --run {run} --out {table.parent} --overwrite" in line
    assert "## Head control" not in page and "## Robustness" not in page
    assert "match/match_pareto.png" not in page and "## Configuration" in page
    # another run's matches (its config's digest) copied in: left out too
    weights.write_bytes(original)
    text = match_csv.read_text().replace(recorded["run_config_sha256"], "0" * 64)
    match_csv.write_text(text)
    warned, page = _report(run)
    assert len(warned) == 1 and f"left {match_csv} out" in warned[0]
    assert "scored another run's config.json," in warned[0]
    assert "## Head control" not in page and "## Robustness" in page
    # matches without --run (the quickstart's: the handwritten strategies, no weights of
    # the run) record no run, and are reported
    assert main([*matches[:-1], "--out", str(run / "match"), "--overwrite"]) == 0
    with match_csv.open(newline="") as f:
        assert not set(recorded) & set(next(csv.reader(f)))
    warned, page = _report(run)
    assert warned == [] and "## Head control through whole matches" in page


def test_plot_of_a_run_writing_its_last_row_leaves_that_row_out_and_says_so(run, capsys):
    """A row cut inside its last cell has all its cells: ``0.12`` of ``0.1234`` was drawn
    as a value. A run still training may be writing it: drawn without it, with a note."""
    metrics = run / "metrics.csv"
    whole = metrics.read_bytes()
    assert whole.endswith(b"\r\n")
    last = whole[:-2].rsplit(b"\n", 1)[1]
    metrics.write_bytes(whole + last[: len(last) // 2])
    with pytest.warns(UserWarning, match=r"metrics\.csv: its last line has no end of line"):
        assert main(["plot", str(run)]) == 0


def test_a_folder_where_a_file_goes_is_named_as_a_folder(tmp_path, monkeypatch, one_clear_line):
    """``--strategy dir.py:NAME`` and ``match --model FOLDER`` said "no such file"."""
    monkeypatch.chdir(tmp_path)
    Path("mine.py").mkdir()
    argv = ["evaluate", "--methods", "random", "--episodes", "1", "--out", "ev"]
    assert main([*argv, "--strategy", "mine.py:Mirror"]) == 2
    one_clear_line("mine.py is a directory, not a file")
    Path("export").mkdir()
    assert main(["match", "--methods", "onnx_policy", "--model", "export", "--out", "m"]) == 2
    one_clear_line("--model export is a directory", "export/policy.onnx")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["export", "mine.py"]


@pytest.mark.parametrize(
    "argv",
    [
        ["report", "{run}/config.json"],
        ["plot", "{run}/metrics.csv"],
        ["export", "{run}/policy.safetensors"],
        ["train", "--resume", "{run}/config.json"],
        ["evaluate", "--run", "{run}/config.json", "--methods", "random"],
        ["match", "--run", "{run}/config.json"],
    ],
    ids=" ".join,
)
def test_a_run_named_by_one_of_its_files_names_the_run(trained, argv, one_clear_line):
    """It said "RUN/config.json: not a training run (no config.json)"."""
    assert main([a.format(run=trained) for a in argv]) == 2
    line = one_clear_line(f"a file of the training run {trained}, not a run: name the run's")
    assert "no config.json" not in line


def test_overwrite_of_a_run_with_checkpoints_says_why_it_is_kept(
    run, tiny_train, digests, one_clear_line
):
    """``--out RUN --overwrite`` over a trained run said only "continue it with --resume",
    as if --overwrite had not been read."""
    before = digests(run)
    assert main([*tiny_train, "--out", str(run), "--overwrite"]) == 2
    one_clear_line("--resume", "--overwrite starts over only a run stopped before its first")
    assert digests(run) == before


def test_compare_resumes_no_levels_another_run_played(run, tmp_path, capsys):
    """compare.csv was resumed whatever run played it: ``compare --run A --out C``
    stopped, then ``--run B --out C`` kept A's levels as B's (checked: episodes and seed)."""
    from activevision.io import read_csv, write_csv

    out = tmp_path / "c"
    argv = ["compare", "--methods", "random", "--episodes", "1", "--out", str(out)]
    assert main([*argv, "--errors", "0"]) == 0  # no run
    assert main([*argv, "--errors", "0,0.5", "--run", str(run)]) == 2
    assert "holds levels played by a compare without --run" in capsys.readouterr().err
    assert main([*argv, "--errors", "0", "--run", str(run), "--overwrite"]) == 0
    rows = read_csv(out / "compare.csv")
    digest = hashlib.sha256((run / "policy.safetensors").read_bytes()).hexdigest()
    assert [row["run_sha256"] for row in rows] == [digest]
    write_csv(out / "compare.csv", [{**rows[0], "run_sha256": "0" * 64}])  # another run's
    assert main([*argv, "--errors", "0,0.5", "--run", str(run)]) == 2
    assert "holds levels played by another run's weights" in capsys.readouterr().err
    # a CSV from before the column resumes as before, in its own layout
    write_csv(out / "compare.csv", [{k: v for k, v in rows[0].items() if k != "run_sha256"}])
    assert main([*argv, "--errors", "0,0.5", "--run", str(run)]) == 0
    rows = read_csv(out / "compare.csv")
    assert len(rows) == 2 and "run_sha256" not in rows[1]


def test_report_leaves_out_figures_and_a_suite_that_played_no_policy_of_the_run(run):
    """``report`` showed RUN/compare/compare.png, RUN/episode.png and RUN/robustness/ as the
    run's whatever played them: a compare without --run, ``demo`` (the shipped policy) or
    an episode without --run, ``robustness --shipped``. ``compare.csv`` records the weights'
    digest, ``episode`` and ``demo`` a record beside the figure (episode.png.json), and
    robustness.csv the method; report leaves out what is not this run's, with one warning
    line each, and still writes the page."""
    figure = run / "episode.png"
    compare = ["compare", "--methods", "random", "--errors", "0", "--episodes", "1"]
    assert main([*compare, "--run", str(run)]) == 0
    assert main(["episode", "--run", str(run), "--out", str(figure)]) == 0
    record = json.loads((run / "episode.png.json").read_text())
    assert record["command"] == "episode" and record["policies"] == ["learned", "random"]
    assert record["run"] == {
        "config_sha256": _sha256(run / "config.json"),
        "weights_sha256": _sha256(run / "policy.safetensors"),
    }
    assert record["files"] == {p.name: _sha256(p) for p in (figure, run / "episode.gif")}
    suite = ["robustness", "--episodes", "2", "--perturbations", "gain-dark-mild"]
    assert main([*suite, "--run", str(run)]) == 0

    warned, page = _report(run)
    assert warned == []
    for heading in ("## Success vs localisation error", "## One episode", "## Robustness"):
        assert heading in page
    assert "`learned` plays this run's final weights." in page
    assert "`learned` and `random` from the start of seed 0; `learned` plays" in page
    # what played no policy of this run, written over the run's own
    assert main([*compare, "--out", str(run / "compare"), "--overwrite"]) == 0
    assert main(["demo", "--out", str(figure), "--overwrite"]) == 0
    shipped = ["robustness", "--shipped", "--episodes", "2", "--perturbations", "gain-dark-mild"]
    assert main([*shipped, "--out", str(run / "robustness"), "--overwrite"]) == 0
    warned, page = _report(run)
    assert [line.split(" out of the report: ")[0] for line in warned] == [
        f"left {path}"
        for path in (run / "compare" / "compare.png", figure, run / "robustness/robustness.csv")
    ]
    assert "it played no run (a compare without --run)" in warned[0]
    assert "it played the shipped policy (demo), not this run's policy" in warned[1]
    assert f"activevision episode --run {run} --out {figure} --overwrite" in warned[1]
    assert "it scored `shipped` (robustness --shipped), not this run's learned policy" in warned[2]
    for heading in ("## Success vs localisation error", "## One episode", "## Robustness"):
        assert heading not in page
    assert "## Configuration" in page


def test_an_episode_drawn_again_in_another_format_keeps_each_figures_record(run):
    """``episode --out RUN/episode.svg --overwrite`` wrote its record to RUN/episode.json,
    over episode.png's, and report then left episode.png out as "replaced since". Each
    figure has its own record (episode.png.json, episode.svg.json); the same start draws the
    same GIF, so episode.png is still the run's."""
    png, svg = run / "episode.png", run / "episode.svg"
    assert main(["episode", "--run", str(run), "--out", str(png)]) == 0
    assert main(["episode", "--run", str(run), "--out", str(svg), "--overwrite"]) == 0
    for figure in (png, svg):
        record = json.loads((run / f"{figure.name}.json").read_text())
        assert record["files"] == {p.name: _sha256(p) for p in (figure, run / "episode.gif")}
    assert not (run / "episode.json").exists()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(["report", str(run), "--overwrite"]) == 0
    assert [str(w.message) for w in caught] == []
    assert "## One episode" in (run / "report.md").read_text()


def test_a_figure_whose_gif_is_another_figures_is_refused_naming_it(run, tmp_path, capsys):
    """``episode --out RUN/episode.svg`` beside RUN/episode.png draws RUN/episode.gif, the
    GIF episode.png.json records: the refusal said only that episode.gif exists, and with
    --overwrite from another start it replaced episode.png's GIF, unsaid; report then left
    episode.png out ("episode.gif is not the one episode.png.json records"). The refusal
    names the figure whose GIF it is and a name of its own; --overwrite replaces it and
    warns that episode.png no longer goes with it. The default names are unchanged."""
    png, svg, gif = run / "episode.png", run / "episode.svg", run / "episode.gif"
    episode = ["episode", "--run", str(run), "--seed", "1"]
    assert main(["episode", "--run", str(run), "--out", str(png)]) == 0
    drawn = gif.read_bytes()
    capsys.readouterr()
    assert main([*episode, "--out", str(svg)]) == 2
    assert capsys.readouterr().err == (
        f"activevision episode: error: {gif} is the GIF of {png} (episode.png.json records it):"
        f" name another figure (--out {run / 'episode-2.svg'} draws episode-2.gif), or pass"
        " --overwrite to replace it (from another start, episode.png then no longer goes with"
        " it: report leaves it out)\n"
    )
    assert not svg.exists() and gif.read_bytes() == drawn
    # the name it offers draws a GIF of its own: episode.png is still the run's
    assert main([*episode, "--out", str(run / "episode-2.svg")]) == 0
    assert (run / "episode-2.gif").read_bytes() != drawn  # another start
    assert _report(run)[0] == []
    # --overwrite replaces the GIF, and says what became of episode.png
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main([*episode, "--out", str(svg), "--overwrite"]) == 0
    assert [str(w.message) for w in caught] == [
        f"{gif} is no longer the GIF episode.png.json records: draw {png} again (--out {png}"
        " --overwrite) or remove it (report leaves it out)"
    ]
    warned, _ = _report(run)
    assert len(warned) == 1 and "episode.gif is not the one episode.png.json records" in warned[0]
    # demo the same: its record (the shipped policy's) owns demo.gif
    demo = tmp_path / "demo.png"
    assert main(["demo", "--out", str(demo)]) == 0
    capsys.readouterr()
    assert main(["demo", "--seed", "1", "--out", str(demo.with_suffix(".pdf"))]) == 2
    assert f"{tmp_path / 'demo.gif'} is the GIF of {demo}" in capsys.readouterr().err


def test_a_figure_of_no_format_beside_a_gifs_figure_is_refused_for_its_format(tmp_path, capsys):
    """``demo --out demo.txt`` beside demo.png (whose record holds demo.gif) was refused for
    the GIF, offering ``--out demo-2.txt``, a name refused in turn for its format; with
    --overwrite, the format. The format is said first, as for any figure."""
    from activevision.experiments.provenance import record_path

    png, gif = tmp_path / "demo.png", tmp_path / "demo.gif"
    png.write_bytes(b"png")
    gif.write_bytes(b"gif")
    record_path(png).write_text(json.dumps({"files": {"demo.png": "0", "demo.gif": "1"}}))
    for overwrite in ([], ["--overwrite"]):
        assert main(["demo", "--out", str(tmp_path / "demo.txt"), *overwrite]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"activevision demo: error: --out {tmp_path / 'demo.txt'}: a figure")
        assert err.count("\n") == 1 and "demo-2" not in err
    assert gif.read_bytes() == b"gif"


def test_a_comparison_records_which_weights_played_for_report(run, tmp_path):
    """compare.csv recorded only the digest of the weights that played (run_sha256): a
    comparison of best weights the run replaced since was to be written again without
    ``--weights best``, and best weights that were the final ones read as final. It records
    which (run_weights), only where a run played: a compare without --run keeps its bytes."""
    from activevision.io import read_csv

    shutil.copyfile(run / "policy.safetensors", run / "best_policy.safetensors")
    out = run / "compare"
    argv = ["compare", "--methods", "learned", "--episodes", "1", "--errors", "0"]
    assert main([*argv, "--run", str(run), "--weights", "best", "--out", str(out)]) == 0
    digest = _sha256(run / "best_policy.safetensors")
    [row] = read_csv(out / "compare.csv")
    assert list(row)[-2:] == ["run_sha256", "run_weights"]
    assert (row["run_sha256"], row["run_weights"]) == (digest, "best")
    warned, page = _report(run)
    assert warned == [] and "`learned` plays this run's best validated weights." in page
    (run / "best_policy.safetensors").write_bytes(b"validated again")
    warned, page = _report(run)
    assert "## Success vs localisation error" not in page
    assert len(warned) == 1 and "it played another run's weights" in warned[0]
    assert warned[0].endswith(
        f"activevision compare --run {run} --weights best --out {out} --overwrite"
    )
    argv[2] = "random"  # no run: no learned
    assert main([*argv, "--out", str(tmp_path / "c")]) == 0  # no run: no run_weights
    assert list(read_csv(tmp_path / "c" / "compare.csv")[0])[-1] == "run_sha256"


def test_a_comparison_without_learned_does_not_say_learned_plays(run):
    """``compare --run R --methods random scan`` records the run (its env, its weights'
    digest), and report said "`learned` plays this run's final weights." of a figure with
    no learned curve."""
    out = run / "compare"
    argv = ["compare", "--run", str(run), "--methods", "random", "--episodes", "1"]
    assert main([*argv, "--errors", "0", "--out", str(out)]) == 0
    warned, page = _report(run)
    assert warned == [] and "## Success vs localisation error" in page
    assert "`learned` plays" not in page


def test_a_comparison_of_the_final_weights_is_not_resumed_as_the_best(
    run, tmp_path, one_clear_line
):
    """Where best_policy.safetensors is a copy of policy.safetensors (one digest), ``compare
    --run R --weights best`` resumed the levels ``--weights final`` played: its rows named
    both, and report read the CSV it wrote as damaged. Refused, as other weights are."""
    shutil.copyfile(run / "policy.safetensors", run / "best_policy.safetensors")
    out = tmp_path / "c"
    argv = ["compare", "--run", str(run), "--methods", "random", "--episodes", "1"]
    assert main([*argv, "--errors", "0", "--out", str(out)]) == 0
    before = (out / "compare.csv").read_bytes()
    resumed = ["--errors", "0,1", "--weights", "best", "--out", str(out)]
    assert main([*argv, *resumed]) == 2
    one_clear_line(
        "holds levels played by the run's final weights, not its best: resume with --weights"
        " final, or pass --overwrite"
    )
    assert (out / "compare.csv").read_bytes() == before


def test_report_tells_a_policy_exported_before_the_run_was_trained_on(run):
    """``demo --policy RUN/policy.onnx --out RUN/episode.png`` was reported as the run's
    policy whenever RUN/policy.onnx was the file it played, though exported before the run
    trained on: ``export`` records in policy.json the weights it read (which, and their
    SHA-256), and report leaves out a demo of an export of weights the run has replaced."""
    assert main(["export", str(run)]) == 0
    meta = json.loads((run / "policy.json").read_text())
    weights = meta["training_weights"], meta["training_weights_sha256"]
    assert weights == ("final", _sha256(run / "policy.safetensors"))
    figure = run / "episode.png"
    assert main(["demo", "--policy", str(run / "policy.onnx"), "--out", str(figure)]) == 0
    warned, page = _report(run)
    assert warned == [] and "is this run's policy.onnx, exported from its final weights." in page
    # trained on (a run exported mid-training, then resumed): its next weights
    from activevision.training.checkpoint import load_tensors, save_tensors

    tensors, metadata = load_tensors(run / "policy.safetensors")
    trained_on = {name: tensor + 0.01 for name, tensor in tensors.items()}
    save_tensors(run / "policy.safetensors", trained_on, metadata | {"step": 100})
    warned, page = _report(run)
    assert "## One episode" not in page
    assert len(warned) == 1 and warned[0].startswith(
        f"left {figure} out of the report: it played this run's policy.onnx, exported from"
        " another run's weights, or this run's before they were replaced (trained on"
    )
