"""``activevision robustness``: the tiny real command, its outputs, and bad input."""

import csv
import shutil
from pathlib import Path

import pytest

from activevision.cli import main
from activevision.figures.robustness import plot_robustness


def read_rows(path: Path) -> list[dict]:
    with path.open() as f:
        return list(csv.DictReader(f))


TINY = [
    "robustness",
    "--method",
    "oracle",
    "--episodes",
    "4",
    "--perturbations",
    "robots-2",
    "all-mild+robots-4",
]


def test_tiny_run_writes_its_rows_and_figure(tmp_path, capsys):
    out = tmp_path / "r"
    assert main([*TINY, "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    rows = read_rows(out / "robustness.csv")
    # clean first, then the chosen rows in table order, each on 4 episodes of seed 0
    assert [r["name"] for r in rows] == ["clean", "robots-2", "all-mild+robots-4"]
    assert {r["method"] for r in rows} == {"oracle"}
    assert {(r["n"], r["seed"]) for r in rows} == {("4", "0")}
    for column in ("success_rate", "goal_reached"):
        for suffix in ("", "_low", "_high", "_drop_pts"):
            assert all(r[column + suffix] for r in rows)
    by = {r["name"]: r for r in rows}
    # the oracle reads the true goal: it reaches it whoever stands on the field
    for name in ("clean", "robots-2", "all-mild+robots-4"):
        assert float(by[name]["goal_reached"]) == 1.0
        assert float(by[name]["goal_reached_drop_pts"]) == 0.0
    assert by["all-mild+robots-4"]["setting"] == "all factors mild, robots=4"
    assert by["robots-2"]["in_training_range"] == ""  # the oracle was never trained
    assert by["robots-2"]["in_robust_range"] == "True"
    assert (out / "robustness.png").read_bytes().startswith(b"\x89PNG")
    lines = printed.splitlines()
    assert any(line.startswith("all-mild+robots-4") for line in lines)
    assert any(line.startswith("worst change vs clean:") for line in lines)


def test_existing_outputs_need_overwrite(tmp_path, capsys, one_clear_line):
    out = tmp_path / "r"
    out.mkdir()
    (out / "robustness.csv").write_text("my earlier results\n")
    argv = [
        "robustness",
        "--method",
        "oracle",
        "--episodes",
        "1",
        "--perturbations",
        "robots-1",
        "--out",
        str(out),
    ]
    assert main(argv) == 2
    one_clear_line("robustness.csv", "--overwrite")
    assert (out / "robustness.csv").read_text() == "my earlier results\n"
    assert main([*argv, "--overwrite"]) == 0
    assert [r["name"] for r in read_rows(out / "robustness.csv")] == ["clean", "robots-1"]


def test_list_prints_the_table(capsys):
    from activevision.experiments.robustness import perturbation_names

    assert main(["robustness", "--list"]) == 0
    out = capsys.readouterr().out
    names = [line.split()[0] for line in out.splitlines()[2:]]
    assert names == list(perturbation_names())
    assert "no (beyond)" in out
    assert main(["robustness", "--list", "--perturbations", "robots-4", "gamma-mild"]) == 0
    chosen = capsys.readouterr().out.splitlines()[2:]
    assert [line.split()[0] for line in chosen] == ["clean", "gamma-mild", "robots-4"]


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--method", "oracle", "--perturbations", "nope"], "'nope'"),
        (["--method", "oracle", "--perturbations"], "--perturbations"),
        (["--method", "oracle", "--episodes", "0"], "--episodes"),
        (["--method", "oracle", "--seed", "-1"], "'-1'"),
        (["--method", "nope"], "'nope'"),
        (["--method", "learned"], "--run"),
        (["--shipped", "--method", "scan"], "--shipped"),
        (["--shipped", "--run", "runs/x"], "--shipped and --run runs/x name two policies"),
        (["--method", "shipped", "--run", "runs/x"], "--shipped and --run"),
        ([], "--run"),
        # a method that does not see the image would score an image-only row as clean's
        (["--method", "oracle", "--perturbations", "gamma-strong", "robots-1"], "gamma-strong"),
        (["--method", "scan", "--perturbations", "mount-fov+10%", "all-mild"], "does not see"),
    ],
    ids=" ".join,
)
def test_bad_input_is_one_clear_line(tmp_path, capsys, argv, needle, one_clear_line):
    out = tmp_path / "r"
    assert main(["robustness", *argv, "--out", str(out)]) == 2
    one_clear_line(needle)
    assert not out.exists()


def test_a_method_blind_to_the_image_plays_only_the_rows_that_change_its_world(tmp_path, capsys):
    # scan, the oracle and the entropy methods play from the env's state: every appearance
    # and mount row scored them exactly as clean, a column of "no drop" read as robustness
    out = tmp_path / "r"
    assert main(["robustness", "--method", "scan", "--episodes", "1", "--out", str(out)]) == 0
    assert "left out" in capsys.readouterr().out
    names = [r["name"] for r in read_rows(out / "robustness.csv")]
    assert names == ["clean", "robots-1", "robots-2", "robots-3", "robots-4", "all-mild+robots-4"]
    assert main(["robustness", "--list", "--method", "entropy_jump"]) == 0
    listed = [line.split()[0] for line in capsys.readouterr().out.splitlines()[2:]]
    assert listed == names


@pytest.mark.parametrize("method", ["scan", "random", "oracle", "entropy_jump"])
def test_a_method_never_trained_has_no_training_range(method, tmp_path, capsys):
    """--list and the scored table of a built-in baseline say it has no training range (it
    read yes / no, compared with a world the method never learnt in)."""
    assert main(["robustness", "--list", "--method", method]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split()[-2:] == ["training", "range"]
    for line in lines[2:]:
        assert line.endswith("— (untrained)"), line
    assert "the env as it is" in lines[2] and "as trained" not in "".join(lines)
    if method != "scan":
        return
    out = tmp_path / "r"
    argv = ["robustness", "--method", method, "--episodes", "1", "--out", str(out)]
    assert main([*argv, "--perturbations", "robots-1"]) == 0
    table = capsys.readouterr().out.splitlines()
    rows = [line for line in table if line.startswith(("clean ", "robots-1 "))]
    assert len(rows) == 2
    for line in rows:
        assert line[25 + 28 : 25 + 28 + 7].strip() == "—", line  # name, setting, trained
    # the CSV says the same (empty, not True/False), and the figure hatches no bar as
    # "outside the training ranges", its legend naming no training world
    scored = read_rows(out / "robustness.csv")
    assert [r["in_training_range"] for r in scored] == ["", ""]
    assert [r["setting"] for r in scored] == ["the env as it is", "robots=1"]  # not "as trained"
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    labels, hatches = [], []
    real_legend, real_hatch = Figure.legend, Rectangle.set_hatch
    with pytest.MonkeyPatch.context() as mp:

        def legend(fig, *args, **kwargs):
            labels.extend(h.get_label() for h in kwargs["handles"])
            return real_legend(fig, *args, **kwargs)

        def set_hatch(bar, hatch):
            if hatch:
                hatches.append(hatch)
            return real_hatch(bar, hatch)

        mp.setattr(Figure, "legend", legend)
        mp.setattr(Rectangle, "set_hatch", set_hatch)  # the bars (the legend's are Patches)
        plot_robustness(read_rows(out / "robustness.csv"), tmp_path / "again.png")
    assert hatches == []
    assert not any("this policy's training ranges" in label for label in labels), labels
    assert not any("training world" in label for label in labels), labels
    assert "clean: the env's own world (every change is against it)" in labels


def test_a_trained_policy_keeps_its_training_range(capsys):
    assert main(["robustness", "--list", "--shipped", "--perturbations", "robots-4"]) == 0
    lines = capsys.readouterr().out.splitlines()[2:]
    assert [line[25 + 16 + 9 + 28 + 14 :] for line in lines] == ["yes", "yes"]  # the column
    assert "untrained" not in "".join(lines)


@pytest.mark.parametrize("what", ["file", "missing", "empty folder"])
def test_a_run_that_is_no_run_is_named_as_the_run(tmp_path, capsys, what, one_clear_line):
    # The default output lies inside the run (RUN/robustness): a --run that is a file was
    # refused as "RUN is a file, not a directory: choose another --out", an --out nobody typed.
    run = tmp_path / "run"
    if what == "file":
        run.write_text("not a run\n")
    elif what == "empty folder":
        run.mkdir()
    assert main(["robustness", "--run", str(run), "--episodes", "2"]) == 2
    line = one_clear_line(f"--run {run}: not a training run")
    assert "--out" not in line


def test_a_run_is_scored_beside_its_files_never_over_them(
    trained, tmp_path, capsys, digests, one_clear_line
):
    run = Path(shutil.copytree(trained, tmp_path / "run"))
    before = digests(run)
    argv = [
        "robustness",
        "--run",
        str(run),
        "--episodes",
        "2",
        "--perturbations",
        "line-wear-strong",
    ]
    assert main([*argv, "--out", str(run)]) == 2
    one_clear_line("training run", "--out")
    assert main(argv) == 0
    rows = read_rows(run / "robustness" / "robustness.csv")
    assert [(r["method"], r["name"]) for r in rows] == [
        ("learned", "clean"),
        ("learned", "line-wear-strong"),
    ]
    after = digests(run)
    assert {k: after[k] for k in before} == before  # the run's own files untouched
    assert set(after) - set(before) == {"robustness/robustness.csv", "robustness/robustness.png"}


def test_an_exported_policy_is_marked_against_its_training_world(tmp_path, capsys, monkeypatch):
    import json

    from activevision.runtime import pretrained_policy_path

    # the shipped policy, as if it had been trained among 0-4 other robots
    model = tmp_path / "policy" / "policy.onnx"
    model.parent.mkdir()
    shutil.copy(pretrained_policy_path(), model)
    values = json.loads(pretrained_policy_path().with_suffix(".json").read_text())
    values["world"]["robots"]["count"] = [0, 4]
    model.with_suffix(".json").write_text(json.dumps(values))
    monkeypatch.setattr("activevision.runtime.pretrained_policy_path", lambda: model)

    out = tmp_path / "r"
    argv = ["robustness", "--shipped", "--episodes", "1", "--out", str(out), "--perturbations"]
    assert main([*argv, "robots-3", "gain-dark-strong"]) == 0
    rows = {r["name"]: r for r in read_rows(out / "robustness.csv")}
    assert list(rows) == ["clean", "gain-dark-strong", "robots-3"]
    trained = {name: r["in_training_range"] for name, r in rows.items()}
    assert trained == {"clean": "True", "gain-dark-strong": "False", "robots-3": "True"}
    printed = capsys.readouterr().out
    assert any(line.startswith("robots-3") and " yes " in line for line in printed.splitlines())
    # --list for this policy says what its CSV says, row by row, without playing
    assert (
        main(
            ["robustness", "--shipped", "--list", "--perturbations"]
            + ["robots-3", "gain-dark-strong"]
        )
        == 0
    )
    listed = capsys.readouterr().out.replace("no (beyond)", "no").splitlines()[2:]
    assert [line.split()[0] for line in listed] == list(rows)
    for line in listed:
        *_, robust, trained_range = line.split()
        row = rows[line.split()[0]]
        assert (robust == "yes", trained_range == "yes") == (
            row["in_robust_range"] == "True",
            row["in_training_range"] == "True",
        ), line
