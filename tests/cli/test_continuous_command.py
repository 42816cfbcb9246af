"""Continuous head control from the command line: ``train --algo sac|td3|ppo|dagger`` with
continuous moves, ``--resume``, ``export``, and a discrete and a continuous policy scored on
the same episodes by ``evaluate`` and ``compare --runs``."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from activevision.cli import main

#: a tiny run's sizes, whatever its moves
SMALL = [
    "--set",
    "epoch_steps=40",
    "--set",
    "checkpoint_interval=40",
    "--set",
    "tensorboard=false",
    "--set",
    "num_threads=1",
    "--set",
    "batch_size=8",
]
TINY = ["--set", "env.action_type=continuous", *SMALL]
#: what each learner reads on top (a key its algo never reads is refused)
SB3_TINY = {
    algo: [*TINY, "--set", "sb3.num_envs=2", *own]
    for algo, own in {
        "sac": ("--set", "replay.buffer_size=500", "--set", "learning_starts=20"),
        "td3": ("--set", "replay.buffer_size=500", "--set", "learning_starts=20"),
        "ppo": ("--set", "sb3.n_steps=20"),
    }.items()
}
DAGGER_SMALL = [*SMALL, "--set", "dagger.num_envs=8", "--set", "dagger.updates_per_rollout=1"]
DAGGER_TINY = ["--set", "env.action_type=continuous", *DAGGER_SMALL]


@pytest.fixture(scope="module")
def continuous_run(tmp_path_factory):
    """A tiny continuous DAgger run on the paper's image (the discrete ``trained`` run's)."""
    run = tmp_path_factory.mktemp("runs") / "cont"
    args = ["train", "--algo", "dagger", "--set", "env.action_history=0", *DAGGER_TINY]
    assert main([*args, "--steps", "80", "--out", str(run)]) == 0
    return run


@pytest.mark.parametrize("algo", ["sac", "td3", "ppo"])
def test_sb3_learners_train_resume_and_export(algo, tmp_path, capsys):
    run = tmp_path / algo
    base = ["train", "--algo", algo, *SB3_TINY[algo], "--set", "env.observation=image+head"]
    assert main([*base, "--steps", "80", "--out", str(run)]) == 0
    config = json.loads((run / "config.json").read_text())
    assert config["algo"] == algo and config["env"]["action_type"] == "continuous"
    with (run / "metrics.csv").open() as f:
        assert next(int(r["step"]) for r in csv.DictReader(f)) == 40
    # --resume reopens it from its newest checkpoint (tests/training: resuming mid-run)
    assert main(["train", "--resume", str(run)]) == 0
    assert "is finished" in capsys.readouterr().out
    assert main(["export", str(run)]) == 0
    meta = json.loads((run / "policy.json").read_text())
    assert meta["action_type"] == "continuous" and meta["vector_keys"] == ["head"]
    assert "wrote" in capsys.readouterr().out


def test_evaluate_and_compare_score_discrete_and_continuous_side_by_side(
    trained, continuous_run, tmp_path
):
    out = tmp_path / "eval"
    args = ["evaluate", "--run", str(trained), "--runs", str(continuous_run)]
    assert main([*args, "--methods", "learned", "scan", "--episodes", "6", "--out", str(out)]) == 0
    with (out / "evaluation.csv").open() as f:
        rows = {r["method"]: r for r in csv.DictReader(f)}
    assert set(rows) == {"learned", "scan", "learned:cont"}
    with (out / "episodes.csv").open() as f:
        travel = [(r["method"], float(r["head_travel"])) for r in csv.DictReader(f)]
    # the continuous policy moves by any amount up to 10 degrees on each axis, not in the
    # discrete policies' 3-degree steps
    assert any(1e-3 < t % 3 < 3 - 1e-3 for m, t in travel if m == "learned:cont")
    compare_out = tmp_path / "cmp"
    args = ["compare", "--runs", str(continuous_run), "--methods", "scan", "--errors", "0"]
    assert main([*args, "--episodes", "4", "--out", str(compare_out)]) == 0
    with (compare_out / "compare.csv").open() as f:
        methods = [r["method"] for r in csv.DictReader(f)]
    assert methods == ["scan", "learned:cont"]


def test_runs_observing_what_the_env_does_not_give_are_refused(trained, tmp_path, one_clear_line):
    run = tmp_path / "head"
    args = ["train", "--algo", "dagger", "--set", "env.observation=image+head", *DAGGER_TINY]
    assert main([*args, "--set", "env.action_history=0", "--steps", "40", "--out", str(run)]) == 0
    evaluate = ["evaluate", "--run", str(trained), "--runs", str(run), "--episodes", "2"]
    assert main([*evaluate, "--out", str(tmp_path / "e")]) == 2
    one_clear_line("--runs", "trained on observation 'image+head' (head) against 'image'")


def test_runs_remembering_moves_the_env_does_not_give_are_named(tmp_path, one_clear_line):
    """Two runs of one observation that differ in the moves they remember: the refusal
    names what the comparison's env lacks (it read "observes 'image+head' ..., which the
    comparison's env ('image+head') does not give", the same observation twice)."""
    runs = {}
    for history in (0, 1):
        runs[history] = run = tmp_path / f"history{history}"
        args = ["train", "--algo", "dagger", "--set", "env.observation=image+head", *DAGGER_SMALL]
        args += ["--set", "env.action_type=discrete", "--set", f"env.action_history={history}"]
        args += ["--steps", "40", "--out", str(run)]
        assert main(args) == 0
    evaluate = ["evaluate", "--run", str(runs[0]), "--runs", str(runs[1]), "--episodes", "2"]
    assert main([*evaluate, "--out", str(tmp_path / "e")]) == 2
    one_clear_line(
        "'image+head' (head, actions) against 'image+head': no actions (action_history 1:"
        " the moves it remembers)"
    )


@pytest.mark.parametrize(
    ("setting", "named"),
    [("env.step_deg=4", "'env.step_deg'"), ("action_set=4way", "'action_set' (env.action_set)")],
)
def test_the_discrete_moves_settings_are_refused_on_a_continuous_run(
    tmp_path, setting, named, one_clear_line
):
    """``--set env.step_deg=4`` on a run of continuous moves was stored in config.json and
    never read (its moves are scaled by env.max_move_deg); a discrete run takes it."""
    args = ["train", "--algo", "dagger", "--set", "env.action_history=0", *DAGGER_SMALL]
    args += ["--set", setting, "--steps", "40"]
    continuous = [*args, "--set", "env.action_type=continuous"]
    assert main([*continuous, "--out", str(tmp_path / "c")]) == 2
    one_clear_line(f"{named} is never read by this run: only discrete moves read it")
    assert not (tmp_path / "c").exists()
    assert main([*args, "--out", str(tmp_path / "d")]) == 0
    config = json.loads((tmp_path / "d" / "config.json").read_text())["env"]
    assert (config["step_deg"], config["action_set"]) != (3.0, "8way")


@pytest.mark.parametrize(
    ("preset", "setting", "why"),
    [
        (
            "match_dagger_continuous",
            "match.step_deg=5",
            "only discrete moves read it (the step of the 8-way moves)",
        ),
        ("match_dagger", "match.max_move_deg=[5,5]", "only continuous moves are scaled by it"),
    ],
)
def test_the_match_moves_of_the_other_kind_are_refused(
    tmp_path, preset, setting, why, one_clear_line
):
    """``train --preset match_dagger_continuous --set match.step_deg=5`` trained a student
    whose moves were still of up to 3 degrees, and stored the 5 unread in config.json (so
    did match.max_move_deg on a discrete match run): refused before the run's folder."""
    out = tmp_path / "run"
    args = ["train", "--preset", preset, "--set", setting, "--steps", "40", "--out", str(out)]
    assert main(args) == 2
    field = setting.partition("=")[0]
    one_clear_line(f"'{field}' is never read by this run: {why}")
    assert not out.exists()


def _carrying_unread_moves(continuous_run: Path, tmp_path: Path) -> Path:
    """A continuous run trained from ``continuous_run``'s config with env.step_deg 6 and
    action_set 4way carried in its config file (a continuous run never reads them)."""
    values = json.loads((continuous_run / "config.json").read_text())
    values["env"] |= {"step_deg": 6.0, "action_set": "4way"}
    carried = tmp_path / "carried.json"
    carried.write_text(json.dumps(values))
    run = tmp_path / "carried"
    assert main(["train", "--config", str(carried), "--out", str(run)]) == 0
    return run


def test_the_baselines_beside_a_continuous_run_make_the_papers_moves(
    continuous_run, trained, tmp_path
):
    """Beside ``--run`` of continuous moves, the other methods make the paper's discrete
    moves (3 degrees, 8 ways). They made the run's env.step_deg and action_set, which a
    continuous run never reads: a config file carrying others (6 degrees, 4 ways) trained
    the same kind of policy, yet made scan, random and the oracle move otherwise, and a
    discrete run of the paper's moves was refused beside it."""
    run = _carrying_unread_moves(continuous_run, tmp_path)
    assert json.loads((run / "config.json").read_text())["env"]["step_deg"] == 6.0
    episodes = {}
    for name, scored in (("paper", continuous_run), ("carried", run)):
        out = tmp_path / f"eval_{name}"
        args = ["evaluate", "--run", str(scored), "--methods", "scan", "random", "oracle"]
        assert main([*args, "--episodes", "4", "--out", str(out)]) == 0
        episodes[name] = (out / "episodes.csv").read_bytes()
    # the same episodes, moves and scores as beside the run of the paper's (default) values
    assert episodes["carried"] == episodes["paper"]
    # a discrete run of the paper's moves plays beside it (was: "moves of 3 deg, 8way,
    # against 6 deg, 4way")
    args = ["evaluate", "--run", str(run), "--runs", str(trained), "--methods", "scan"]
    assert main([*args, "--episodes", "2", "--out", str(tmp_path / "beside")]) == 0


def test_the_envs_of_runs_make_their_own_discrete_moves_or_the_papers(tmp_path):
    """``env_config_of_run``: a discrete run's moves are its own (the episodes' or the
    match's step), a continuous run's the paper's (3 degrees, 8 ways), whatever step its
    config carries unread."""
    import dataclasses

    from activevision.cli.args import env_config_of_run
    from activevision.training import preset
    from activevision.training.config import save_config

    cases = {
        "discrete": (preset("paper"), "env", (6.0, "4way")),
        "continuous": (preset("dagger_image_continuous"), "env", (3.0, "8way")),
        "match_discrete": (preset("match_dagger"), "match", (6.0, "8way")),
        "match_continuous": (preset("match_dagger_continuous"), "match", (3.0, "8way")),
    }
    for name, (config, section, moves) in cases.items():
        world = getattr(config, section)
        carried = {"step_deg": 6.0} | ({"action_set": "4way"} if section == "env" else {})
        config = dataclasses.replace(config, **{section: world.replace(**carried)})
        (tmp_path / name).mkdir()
        save_config(config, tmp_path / name / "config.json")
        env = env_config_of_run(tmp_path / name)
        assert (env.action_type, env.step_deg, env.action_set) == ("discrete", *moves), name


def test_bench_continuous_beside_a_continuous_run_makes_the_papers_moves(
    continuous_run, trained, tmp_path
):
    """``bench/continuous.py --runs CONT DISC``: the first run's env made the discrete moves
    of its config's env.step_deg and action_set, which a continuous run never reads (as
    evaluate's did): a continuous run carrying 6 degrees, 4 ways moved the oracle otherwise
    and refused a discrete run of the paper's moves beside it; it takes the paper's, as
    ``env_config_of_run`` gives every command."""
    import subprocess
    import sys

    run = _carrying_unread_moves(continuous_run, tmp_path)
    bench = Path(__file__).parents[2] / "bench" / "continuous.py"
    done = subprocess.run(
        [sys.executable, str(bench), "--runs", str(run), str(trained), "--episodes", "1"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    assert "was trained on" not in done.stderr
