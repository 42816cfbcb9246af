"""Same seed, same bytes, wherever it runs: what a command writes names a training run or a
model by its folder's name, never by the path it was given (relative to the current
directory, ``.``, or absolute), so the same command from another directory writes the same
files."""

from __future__ import annotations

import shutil
from pathlib import Path

from activevision.cli import main
from activevision.experiments.match import model_labels


def test_report_and_plot_of_dot_equal_those_of_the_runs_path(trained, tmp_path, monkeypatch):
    """``report .`` and ``plot .`` inside the run titled it with an empty name."""
    here, there = tmp_path / "a" / "tiny", tmp_path / "b" / "tiny"
    for copy in (here, there):
        shutil.copytree(trained, copy)
    assert main(["report", str(there)]) == 0
    assert main(["plot", str(there)]) == 0
    monkeypatch.chdir(here)
    assert main(["report", "."]) == 0
    assert main(["plot", "."]) == 0
    for name in ("report.md", "plots/training.png"):
        assert (here / name).read_bytes() == (there / name).read_bytes(), name


def test_robustness_figure_names_the_run_not_its_path(trained, tmp_path, monkeypatch):
    """The figure's title held ``--run`` as given: ``tiny`` here, an absolute path there."""
    argv = ["robustness", "--episodes", "2", "--perturbations", "gain-dark-mild"]
    assert main([*argv, "--run", str(trained), "--out", str(tmp_path / "absolute")]) == 0
    monkeypatch.chdir(trained.parent)
    assert main([*argv, "--run", trained.name, "--out", str(tmp_path / "relative")]) == 0
    for name in ("robustness.csv", "robustness.png"):
        relative = (tmp_path / "relative" / name).read_bytes()
        assert relative == (tmp_path / "absolute" / name).read_bytes(), name


def test_evaluate_runs_names_a_run_by_its_folder(trained, tmp_path, monkeypatch):
    """``--runs .`` played as ``learned:`` (an empty name), the same run by path as
    ``learned:tiny``."""
    argv = ["evaluate", "--run", str(trained), "--methods", "random", "--episodes", "1"]
    assert main([*argv, "--runs", str(trained), "--out", str(tmp_path / "absolute")]) == 0
    monkeypatch.chdir(trained)
    assert main([*argv, "--runs", ".", "--out", str(tmp_path / "dot")]) == 0
    for name in ("evaluation.csv", "episodes.csv", "evaluation.json"):
        dot = (tmp_path / "dot" / name).read_bytes()
        assert dot == (tmp_path / "absolute" / name).read_bytes(), name
    assert b"learned:tiny" in dot


def test_a_models_label_is_its_folders_name_however_given(tmp_path, monkeypatch):
    """``--model policy.onnx`` in the run's folder played as ``onnx_policy[policy]``, the same
    file given by its full path as ``onnx_policy[RUN]`` (match.csv's method column)."""
    monkeypatch.chdir(tmp_path)
    Path("first").mkdir()
    monkeypatch.chdir(tmp_path / "first")
    models = [Path("policy.onnx"), tmp_path / "second" / "policy.onnx", Path("other.onnx")]
    assert model_labels(models) == [
        "onnx_policy[first]",
        "onnx_policy[second]",
        "onnx_policy[other]",
    ]
