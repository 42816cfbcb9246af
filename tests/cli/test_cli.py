"""The command line as a user runs it: pictures, the main job end to end, clear errors."""

import argparse
import json
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from activevision.cli import main


def test_render_and_viewpoints_write_pictures(tmp_path):
    assert main(["render", "--seed", "3", "--out", str(tmp_path / "view.png")]) == 0
    assert main(["viewpoints", "--seed", "3", "--out", str(tmp_path / "vp.png")]) == 0
    assert (tmp_path / "view.png").stat().st_size > 20_000
    assert (tmp_path / "vp.png").stat().st_size > 20_000
    # in the format the suffix names (a .pdf used to hold a PNG)
    assert main(["render", "--seed", "3", "--out", str(tmp_path / "view.pdf")]) == 0
    assert main(["viewpoints", "--seed", "3", "--out", str(tmp_path / "vp.SVG")]) == 0
    assert main(["demo", "--out", str(tmp_path / "demo.jpg")]) == 0
    assert (tmp_path / "view.pdf").read_bytes().startswith(b"%PDF")
    assert b"<svg" in (tmp_path / "vp.SVG").read_bytes()[:1000]
    assert (tmp_path / "demo.jpg").read_bytes().startswith(b"\xff\xd8\xff")  # JPEG
    assert (tmp_path / "view.png").read_bytes().startswith(b"\x89PNG")


def test_python_dash_m_runs_the_command():
    """``python -m activevision`` is the ``activevision`` command: its exit codes and its one
    line on bad input."""
    command = [sys.executable, "-m", "activevision"]
    done = subprocess.run([*command, "--help"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("usage: activevision ")
    done = subprocess.run([*command, "evaluate", "--episodes", "0"], capture_output=True, text=True)
    assert done.returncode == 2
    assert len(done.stderr.strip().splitlines()) == 1 and "--episodes" in done.stderr


def test_quickstart_trains_evaluates_and_reports(tmp_path, capsys):
    out = tmp_path / "run"
    options = ["quickstart", "--out", str(out), "--episodes", "6"]
    options += ["--matches", "2", "--match-ticks", "6"]
    argv = [*options, "--steps", "600"]
    assert main(argv) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last.startswith("main job: learned ") and "scan" in last and "random" in last
    assert "goal reached" in last and str(out / "report.md") in last
    for name in (
        "config.json",
        "metrics.csv",
        "plots/training.png",
        "evaluation/evaluation.json",
        "compare/compare.csv",
        "compare/compare.png",
        "episode.png",
        "episode.gif",
        "match/match.csv",
        "match/match_pareto.png",
        "report.md",
    ):
        assert (out / name).exists(), name
    methods = {
        row["method"]
        for row in json.loads((out / "evaluation/evaluation.json").read_text())["methods"]
    }
    assert {"learned", "random", "oracle", "entropy_jump", "scan"} <= methods
    report = (out / "report.md").read_text()
    assert "compare/compare.png" in report and "| learned |" in report
    assert "match/match_pareto.png" in report and "| entropy_greedy |" in report
    # the comparison and the episode record that this run's final weights played
    assert "`learned` plays this run's final weights.\n\n![comparison]" in report
    assert "`learned` and `random` from the start of seed 0; `learned` plays this run's" in report
    # Running it again finds the finished run and only redoes evaluation and figures.
    assert main(argv) == 0
    # ... but another quickstart's (other steps or seed) is not resumed into this run
    capsys.readouterr()
    for other in (["--steps", "900"], ["--steps", "600", "--seed", "1"]):
        assert main([*options, *other]) == 2
        assert "holds another training run than this quickstart's" in capsys.readouterr().err
    # The trained run exports to ONNX for the robot runtime.
    assert main(["export", str(out), "-o", str(tmp_path / "policy.onnx")]) == 0
    assert (tmp_path / "policy.json").exists()
    # The preset validates a quarter into its run, and so does one of 600 steps (its
    # interval scaled to 150): it kept best weights.
    assert json.loads((out / "config.json").read_text())["run"]["eval_interval"] == 150
    best = ["evaluate", "--run", str(out), "--methods", "learned", "--weights", "best"]
    assert main([*best, "--episodes", "2", "--out", str(tmp_path / "best")]) == 0


def test_bad_input_is_one_clear_line(tmp_path, capsys):
    assert main(["train", "--preset", "nope", "--out", str(tmp_path / "x")]) == 2
    assert "unknown 'nope'" in capsys.readouterr().err
    assert main(["train", "--resume", str(tmp_path / "missing")]) == 2
    assert "error" in capsys.readouterr().err
    assert main(["evaluate", "--methods", "learned"]) == 2
    assert "--run" in capsys.readouterr().err
    assert main(["render"]) == 2  # argparse: --out is required
    assert "--out" in capsys.readouterr().err


def test_a_run_shorter_than_its_validation_interval_says_so(tmp_path):
    # --preset quickstart --steps 3000 kept the preset's interval (10,000 steps): the run
    # never validated and wrote no best_policy.safetensors, and said nothing
    base = ["train", "--steps", "100", "--set", "num_threads=1", "--set", "tensorboard=false"]
    base += ["--set", "learning_starts=50"]  # the paper's 1,000 would never update: a warning
    base += ["--set", "target_update_interval=25"]  # the paper's 10,000 would never sync: a warning
    expected = (
        "run.eval_interval (500) is past the run's 100 steps: it never validates (no"
        " evaluations.csv rows, no best_policy.safetensors)"
    )
    with pytest.warns(UserWarning) as caught:
        assert main([*base, "--set", "eval_interval=500", "--out", str(tmp_path / "a")]) == 0
    assert [str(w.message) for w in caught] == [expected]
    assert not (tmp_path / "a" / "best_policy.safetensors").exists()
    validated = [*base, "--set", "eval_interval=100", "--set", "eval_episodes=1"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main([*validated, "--out", str(tmp_path / "b")]) == 0
    assert not [w for w in caught if "eval_interval" in str(w.message)]
    assert (tmp_path / "b" / "best_policy.safetensors").exists()


def test_a_preset_run_for_other_steps_keeps_its_intervals_as_shares(tmp_path, capsys):
    """``--preset paper --steps 60`` kept the 3,000-step checkpoint interval of its 30,000
    steps (``quickstart --steps 3000`` its 10,000-step validation): it checkpointed only at
    the end. The interval is scaled with the run, and the line says so."""
    from activevision.training.checkpoint import checkpoint_name

    base = ["train", "--steps", "60", "--set", "epoch_steps=30", "--set", "learning_starts=20"]
    base += ["--set", "batch_size=8", "--set", "buffer_size=500", "--set", "tensorboard=false"]
    assert main([*base, "--out", str(tmp_path / "a")]) == 0
    assert (
        "--steps 60: preset paper's run.checkpoint_interval 3000 -> 30 (the same shares of the"
        " run as of its 30000 steps; --set them to choose)"
    ) in capsys.readouterr().out.splitlines()
    assert (
        json.loads((tmp_path / "a" / "config.json").read_text())["run"]["checkpoint_interval"] == 30
    )
    written = sorted(p.name for p in (tmp_path / "a" / "checkpoints").iterdir())
    assert written == sorted([checkpoint_name(30), checkpoint_name(60)])
    # the user's own interval is kept, and nothing said
    assert main([*base, "--set", "checkpoint_interval=60", "--out", str(tmp_path / "b")]) == 0
    assert "--steps 60:" not in capsys.readouterr().out
    assert (
        json.loads((tmp_path / "b" / "config.json").read_text())["run"]["checkpoint_interval"] == 60
    )


def test_train_help_names_every_preset(capsys):
    from activevision.training.presets import PRESET_NAMES

    assert main(["train", "--help"]) == 0
    help_text = " ".join(capsys.readouterr().out.split())
    assert all(name in help_text for name in PRESET_NAMES)


def test_one_episode_says_its_means_have_no_intervals(tmp_path, capsys):
    argv = ["evaluate", "--episodes", "1", "--methods", "scan", "--out", str(tmp_path / "e")]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "one episode: the means' 95% intervals need 2 or more" in printed
    assert "nan" in printed
    written = json.loads((tmp_path / "e" / "evaluation.json").read_text())
    assert (written["episodes"], written["weights"]) == (1, "final")  # for the report


def _strict_json(text: str) -> object:
    """JSON as strict readers (jq, JavaScript) take it: no NaN or Infinity."""

    def refuse(token: str) -> None:
        raise ValueError(f"not strict JSON: {token}")

    return json.loads(text, parse_constant=refuse)


def test_an_evaluation_json_is_strict_json_its_missing_values_null(trained, tmp_path):
    """One episode has no interval: evaluation.json held bare NaN, which jq refuses; it
    writes null, and the report reads it as before (nan in its tables)."""
    run = tmp_path / "run"
    shutil.copytree(trained, run)
    argv = ["evaluate", "--run", str(run), "--episodes", "1", "--methods", "scan"]
    assert main([*argv, "--overwrite"]) == 0
    written = _strict_json((run / "evaluation" / "evaluation.json").read_text())
    assert isinstance(written, dict)
    row = written["methods"][0]
    assert row["success_rate_low"] is None and row["success_rate"] is not None
    assert main(["report", str(run), "--overwrite"]) == 0
    assert "[nan, nan]" in (run / "report.md").read_text()


def test_one_episode_names_the_shares_that_keep_their_intervals(tmp_path, capsys):
    """It said "rates keep theirs" above a success_rate of "1.000 [nan, nan]": the shares
    of episodes keep their Wilson intervals, the success rate (a mean) has none."""
    argv = ["evaluate", "--episodes", "1", "--methods", "oracle", "--out", str(tmp_path / "e")]
    assert main(argv) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("one episode"))
    assert "rates keep" not in line
    assert "(success, regret_within, oscillating) keep their Wilson intervals" in line


def test_an_evaluation_is_the_same_bytes_its_latency_apart(trained, tmp_path, capsys):
    """evaluation.json held the learned policy's measured latency (wall clock), so the same
    seed wrote other bytes each time; the latency has a file of its own."""
    out = tmp_path / "e"
    argv = ["evaluate", "--run", str(trained), "--methods", "learned", "scan", "--episodes", "2"]
    argv += ["--out", str(out)]
    assert main(argv) == 0
    first = {name: (out / name).read_bytes() for name in ("evaluation.json", "evaluation.csv")}
    latency = json.loads((out / "latency.json").read_text())
    assert latency["p99_ms"] >= latency["p50_ms"] > 0 and latency["batch"] == 1
    assert main([*argv, "--overwrite"]) == 0
    assert {name: (out / name).read_bytes() for name in first} == first
    assert "latency" not in json.loads(first["evaluation.json"])
    # an evaluation with no learned policy measures none: an earlier one's is not left
    assert (
        main(["evaluate", "--methods", "scan", "--episodes", "2", "--out", str(out), "--overwrite"])
        == 0
    )
    assert not (out / "latency.json").exists()
    assert "wrote" in capsys.readouterr().out


def test_the_picture_commands_help_says_what_they_draw_and_where(capsys):
    """``episode``, ``demo`` and ``plot --help`` had no description, and no picture command
    said what --out and --seed are (nor that a GIF is written beside the figure, nor the
    record of what played beside both, which ``report`` reads)."""
    from activevision.experiments.provenance import record_path

    for command in ("render", "viewpoints", "episode", "demo", "plot"):
        assert main([command, "--help"]) == 0
        text = capsys.readouterr().out
        description = text.split("\n\n")[1]
        assert not description.startswith(("options:", "positional")), command
        for option in ("--seed", "--out"):
            line = next((row for row in text.splitlines() if row.strip().startswith(option)), "")
            assert command == "plot" or line.split(maxsplit=2)[2:], (command, option)
    for command in ("episode", "demo"):
        assert main([command, "--help"]) == 0
        text = " ".join(capsys.readouterr().out.split())
        assert "GIF is written beside it" in text and "a record of what played" in text
        assert f"+ .json: {record_path('episode.png').name})" in text


def test_every_command_says_what_it_does_in_its_help():
    """``train``, ``evaluate``, ``compare``, ``report``, ``export`` and ``quickstart --help``
    went from the usage line straight to the options."""
    from activevision.cli import build_parser

    (commands,) = [a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)]
    missing = [name for name, parser in commands.choices.items() if not parser.description]
    assert missing == []


def test_demo_names_the_policy_it_shows(tmp_path, monkeypatch):
    """The demo's rows are named after the policy: "shipped", or an exported policy's run
    (every ONNX policy was labelled "onnx")."""
    import shutil

    import activevision.figures.episode as episode_figures
    from activevision.runtime import pretrained_policy_path

    shown: list[list[str]] = []

    def plot(traces, out):
        shown.append([t.policy for t in traces])
        Path(out).write_bytes(b"")  # the record beside it (episode.png.json) takes its digest

    monkeypatch.setattr(episode_figures, "plot_episodes", plot)
    monkeypatch.setattr(episode_figures, "animate_episode", lambda trace, out: out.write_bytes(b""))
    assert main(["demo", "--out", str(tmp_path / "a.png")]) == 0
    run = tmp_path / "my_run"
    run.mkdir()
    for name in ("policy.onnx", "policy.json"):
        shutil.copy(pretrained_policy_path().with_name(name), run / name)
    assert (
        main(["demo", "--policy", str(run / "policy.onnx"), "--out", str(tmp_path / "b.png")]) == 0
    )
    assert shown == [["shipped", "random"], ["my_run", "random"]]


def test_demo_of_a_run_folder_names_its_rows_after_the_run(tmp_path, monkeypatch):
    """``demo --policy .`` in the run folder (as ``--policy RUN`` names the folder that holds
    policy.onnx) drew rows named "": the name came from the path given, not the model read."""
    import shutil

    import activevision.figures.episode as episode_figures
    from activevision.runtime import pretrained_policy_path

    shown: list[list[str]] = []

    def plot(traces, out):
        shown.append([t.policy for t in traces])
        Path(out).write_bytes(b"")

    monkeypatch.setattr(episode_figures, "plot_episodes", plot)
    monkeypatch.setattr(episode_figures, "animate_episode", lambda trace, out: out.write_bytes(b""))
    run = tmp_path / "my_run"
    run.mkdir()
    for name in ("policy.onnx", "policy.json"):
        shutil.copy(pretrained_policy_path().with_name(name), run / name)
    monkeypatch.chdir(run)
    assert main(["demo", "--policy", ".", "--out", "a.png"]) == 0
    assert main(["demo", "--policy", str(run), "--out", "b.png"]) == 0
    assert shown == [["my_run", "random"], ["my_run", "random"]]


def test_demo_of_a_run_folder_records_the_policy_onnx_it_played(tmp_path, monkeypatch):
    """``demo --policy RUN`` (the folder that holds policy.onnx, as HeadController takes it)
    was '[Errno 21] Is a directory': the record hashed the path given, not the model read."""
    import hashlib
    import shutil

    import activevision.figures.episode as episode_figures
    from activevision.experiments.provenance import record_path
    from activevision.runtime import pretrained_policy_path

    monkeypatch.setattr(episode_figures, "plot_episodes", lambda t, out: Path(out).write_bytes(b""))
    monkeypatch.setattr(episode_figures, "animate_episode", lambda trace, out: out.write_bytes(b""))
    run = tmp_path / "my_run"
    run.mkdir()
    for name in ("policy.onnx", "policy.json"):
        shutil.copy(pretrained_policy_path().with_name(name), run / name)
    out = tmp_path / "ep.png"
    assert main(["demo", "--policy", str(run), "--out", str(out)]) == 0
    record = json.loads(record_path(out).read_text())
    played = hashlib.sha256((run / "policy.onnx").read_bytes()).hexdigest()
    assert (record["model"], record["model_sha256"]) == (str(run), played)


def test_the_steps_where_every_method_solves_are_listed_one_space_apart(tmp_path, capsys):
    """The line read "(median): oracle 5,  entropy_jump 1": two spaces after each comma."""
    out = str(tmp_path / "e")
    argv = ["evaluate", "--episodes", "2", "--methods", "oracle", "entropy_jump", "--out", out]
    assert main(argv) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("steps to"))
    assert ",  " not in line
    assert line.endswith("(median): oracle 8.5, entropy_jump 1")


def test_training_on_a_busy_machine_says_one_thread_is_faster_there(tmp_path, monkeypatch):
    """On 2 cores at load 6-7 the default thread per core trained 4x slower than one thread
    (docs/benchmarks.md), unsaid; a run that sets its threads is not told."""
    import os

    monkeypatch.setattr(os, "getloadavg", lambda: (6.5, 6.0, 5.0))
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    base = ["train", "--steps", "30", "--set", "tensorboard=false", "--set", "epoch_steps=30"]
    base += ["--set", "learning_starts=10"]
    with pytest.warns(UserWarning, match=r"busy \(load 6.5 on 2 cores\).*num_threads=1"):
        assert main([*base, "--out", str(tmp_path / "a")]) == 0
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main([*base, "--set", "num_threads=1", "--out", str(tmp_path / "b")]) == 0
    assert not [w for w in caught if "busy" in str(w.message)]


def test_a_run_that_ends_before_its_first_update_says_so(tmp_path):
    """``--preset paper --steps 600`` kept the paper's 1,000 steps of random play before the
    first update: the run never updated its network, and said nothing."""
    base = ["train", "--steps", "60", "--set", "num_threads=1", "--set", "tensorboard=false"]
    with pytest.warns(UserWarning, match=r"learning_starts \(1000\) is not before the run's end"):
        assert main([*base, "--out", str(tmp_path / "a")]) == 0
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main([*base, "--set", "learning_starts=30", "--out", str(tmp_path / "b")]) == 0
    assert not [w for w in caught if "learning_starts" in str(w.message)]


def test_a_run_that_never_syncs_its_target_network_says_so(tmp_path, monkeypatch):
    """``--preset paper --steps 5000`` kept the paper's 10,000-step target_update_interval:
    its DDQN learned against its random initial target network throughout, unsaid."""
    from activevision.agents.ddqn import DDQNLearner

    synced: list[str] = []
    sync = DDQNLearner.sync_target
    monkeypatch.setattr(
        DDQNLearner, "sync_target", lambda self: synced.append(run) or sync(self), raising=True
    )
    base = ["train", "--steps", "60", "--set", "num_threads=1", "--set", "tensorboard=false"]
    base += ["--set", "learning_starts=20", "--set", "batch_size=8", "--set", "epoch_steps=30"]
    expected = (
        "learner.target_update_interval (10000) first syncs the target network at step 10000,"
        " not before the run's end (60 steps): it is never updated (--set"
        " target_update_interval=N for a shorter one)"
    )
    run = "a"
    with pytest.warns(UserWarning) as caught:
        assert main([*base, "--out", str(tmp_path / run)]) == 0
    assert [str(w.message) for w in caught] == [expected]
    assert synced == []  # as said
    run = "b"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        synced_often = [*base, "--set", "target_update_interval=25"]
        assert main([*synced_often, "--out", str(tmp_path / run)]) == 0
    assert not [w for w in caught if "target_update_interval" in str(w.message)]
    assert synced == ["b", "b"]  # steps 25 and 50


def _train_warnings(argv, tmp_path, monkeypatch):
    """The warnings ``train ARGV`` gives before it trains (training and its figures left
    out: each test here is about the run's settings), and the config it would train."""
    import activevision.training

    trained = []
    monkeypatch.setattr(activevision.training, "train", lambda config, run: trained.append(config))
    monkeypatch.setattr(activevision.training, "plot_run", lambda run: run)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(["train", *argv, "--out", str(tmp_path / "run")]) == 0  # nothing written
    return [str(w.message) for w in caught], trained[0]


def test_a_run_whose_validations_outplay_its_training_says_so(tmp_path, monkeypatch):
    """``--preset data8x --steps 400`` scaled the preset's interval to 13 steps (the same
    share of the run, rightly), and validated 200 episodes 30 times: 6,000 episodes in a
    run of 400 steps, unsaid. The line names the fields to set; the presets at their own
    lengths, the paper's and quickstart's runs say nothing of it."""
    said, config = _train_warnings(["--preset", "data8x", "--steps", "400"], tmp_path, monkeypatch)
    assert (config.run.eval_interval, config.run.eval_episodes) == (13, 200)  # 400 // 13 = 30
    expected = (
        "run.eval_interval (13) and run.eval_episodes (200): 30 validations play 6000 episodes,"
        " more than the run's 400 steps, and take most of its time (--set eval_interval=N for"
        " fewer validations, eval_episodes=N for fewer episodes each)"
    )
    assert expected in said
    # 4 validations of 25 episodes are as many episodes as steps, not more; of 26 they are
    for episodes, warned in ((25, False), (26, True)):
        argv = ["--steps", "100", "--set", "eval_interval=25", "--set", f"eval_episodes={episodes}"]
        said, _ = _train_warnings(argv, tmp_path, monkeypatch)
        assert any("validations play" in line for line in said) == warned, said
    from activevision.training.presets import PRESET_NAMES

    for name in PRESET_NAMES:  # quickstart, data8x... at their own lengths
        said, _ = _train_warnings(["--preset", name], tmp_path, monkeypatch)
        assert not [line for line in said if "validations play" in line], name
    said, _ = _train_warnings(["--preset", "quickstart", "--steps", "3000"], tmp_path, monkeypatch)
    assert not [line for line in said if "validations play" in line]


@pytest.mark.parametrize(
    ("starts", "interval", "total", "first"),
    [(40, 30, 60, 60), (40, 30, 61, None), (0, 60, 60, 60), (0, 60, 59, 60), (58, 1, 60, None)],
)
def test_the_target_sync_warning_is_where_the_first_sync_is_not_before_the_end(
    starts, interval, total, first
):
    """The first sync is the first multiple of the interval after learning_starts
    (``training.trainer``): hand-counted here."""
    from activevision.cli.train import _warn_never_synced
    from activevision.training import preset

    config = preset("paper").replace(
        learning_starts=starts, target_update_interval=interval, total_timesteps=total
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _warn_never_synced(config)
    said = [str(w.message) for w in caught]
    assert said == ([] if first is None else [said[0]])
    if first is not None:
        assert f"first syncs the target network at step {first}," in said[0]
    # only DDQN has a target network of its own to sync (SB3's learners take no interval)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _warn_never_synced(preset("quickstart").replace(total_timesteps=total))
    assert caught == []


@pytest.mark.parametrize(
    ("env_id", "said"),
    [
        ("Nope-v0", "Environment `Nope` doesn't exist"),
        ("no_such_module:Nope-v0", "No module named 'no_such_module'"),
    ],
)
def test_an_env_that_is_not_there_is_the_only_line(tmp_path, capsys, env_id, said):
    """``--set env_id=Nope-v0 --steps 30`` printed the preset's interval note and the
    learning_starts warning before its error: the env is checked first, and nothing is
    written."""
    argv = ["train", "--set", f"env_id={env_id}", "--steps", "30", "--out", str(tmp_path / "x")]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(argv) == 2
    captured = capsys.readouterr()
    assert not caught and not captured.out.strip()
    (line,) = captured.err.strip().splitlines()
    assert f"env_id '{env_id}'" in line and said in line
    assert not (tmp_path / "x").exists()
