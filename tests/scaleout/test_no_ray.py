"""Scale-out pieces that need no Ray: the optional import, grid points, aggregation."""

from __future__ import annotations

import csv
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from activevision.experiments.methods import make_policy
from activevision.scaleout import RAY_INSTALL_HINT, aggregate, require_ray
from activevision.scaleout.compare import default_method_names
from activevision.scaleout.sweep import (
    UNFINISHED_WARNING,
    checked_base,
    grid_points,
    plot_sweep,
    trial_config,
    trial_name,
)
from activevision.training import TrainConfig


def test_nothing_imports_ray_eagerly():
    code = (
        "import sys, activevision, activevision.cli, activevision.training,"
        " activevision.experiments.compare, activevision.scaleout;"
        " assert 'ray' not in sys.modules, 'ray imported'"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_missing_ray_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray -> ImportError
    with pytest.raises(ImportError, match=r"pip install activevision\[ray\]"):
        require_ray()
    assert RAY_INSTALL_HINT == "pip install activevision[ray]"


def test_grid_points_and_trial_configs():
    points = grid_points({"learning_rate": [1e-3, 5e-4], "batch_size": ["16"]})
    assert points == [
        {"batch_size": "16", "learning_rate": 1e-3},
        {"batch_size": "16", "learning_rate": 5e-4},
    ]
    config = trial_config(TrainConfig(), 4, points[0])
    assert (config.seed, config.learner.batch_size, config.learner.learning_rate) == (4, 16, 1e-3)
    assert trial_name(4, points[0]) == "seed=4,batch_size=16,learning_rate=0.001"
    # a quoted value names its folder without the quotes, unless unquoted it means another
    # value ("null" is not null, "1" not 1)
    quoted = {"device": '"cuda:0"', "run.name": '"null"', "x": '"1"'}
    assert trial_name(0, quoted) == 'seed=0,device=cuda:0,run.name="null",x="1"'
    # a path is one folder, not nested ones (nor ../ outside the sweep's)
    assert trial_name(0, {"x": '"../a/b"', "y": '"50%"'}) == "seed=0,x=..%2Fa%2Fb,y=50%25"
    assert grid_points({}) == [{}]
    with pytest.raises(ValueError):
        grid_points({"batch_size": []})


@pytest.mark.parametrize(
    ("base", "point", "algo"),
    [
        ("sac_head", {"action_noise": "0.2", "algo": "td3"}, "td3"),
        ("paper", {"act_by": '"goal"', "algo": "dagger"}, "dagger"),
    ],
)
def test_a_grid_point_sets_its_keys_together(base, point, algo):
    """A grid over algo with a key of that algo (sorted before "algo") was refused: the
    point's keys were set one by one, the key checked against the base config's algo."""
    from activevision.training import preset

    config = trial_config(preset(base), 3, point)
    assert (config.algo, config.seed) == (algo, 3)
    with pytest.raises(ValueError, match="never read by an algo='sac' run"):
        trial_config(preset(base), 3, {**point, "algo": "sac"})


def test_a_set_key_is_checked_against_each_grid_algo_and_env():
    """``sweep --preset sac_head --set sb3.action_noise=0.2 --grid algo=td3`` was refused:
    the --set key was checked against the preset's algo (SAC), which no trial runs. It is
    checked against each trial's algo (and env) where the grid varies them."""
    from activevision.training import preset

    sets = {"sb3.tau": 0.01, "env.action_type": "continuous", "replay.buffer_size": 50_000}
    config = checked_base(preset("paper"), sets, {"algo": ["sac", "td3"]})
    trials = [trial_config(config, 0, p) for p in grid_points({"algo": ["sac", "td3"]})]
    assert [(t.algo, t.sb3.tau) for t in trials] == [("sac", 0.01), ("td3", 0.01)]
    config = checked_base(preset("sac_head"), {"sb3.action_noise": 0.2}, {"algo": ["td3"]})
    assert trial_config(config, 0, {"algo": "td3"}).sb3.action_noise == 0.2
    # read by TD3 only: the SAC trial would store it unread
    with pytest.raises(ValueError, match="never read by an algo='sac' run"):
        checked_base(preset("sac_head"), {"sb3.action_noise": 0.2}, {"algo": ["sac", "td3"]})
    # no grid over algo: the base config's algo decides, as --set on train
    with pytest.raises(ValueError, match="never read by an algo='sac' run"):
        checked_base(preset("sac_head"), {"sb3.action_noise": 0.2}, {"learning_rate": ["1e-3"]})
    # a grid over the env: a match key holds where every trial plays the match
    match_grid = {"env_id": ['"ActiveVisionMatch-v0"'], "algo": ['"dagger"']}
    sets = {"match.ticks": 300, "match.observation": "image+head+belief", "act_by": "action"}
    assert checked_base(preset("paper"), sets, match_grid).match.ticks == 300
    with pytest.raises(ValueError, match="sets the match env's config"):
        checked_base(preset("paper"), sets, {"algo": ['"dagger"']})
    # a grid over the DAgger teacher: a teacher's margin holds where every trial's reads it
    margin = {"dagger.glance_track_margin_deg": 10.0}
    teachers = {"dagger.match_teacher": ["glance_track"]}
    assert checked_base(preset("match_dagger"), margin, teachers).dagger.match_teacher == (
        "glance_track"
    )
    with pytest.raises(ValueError, match="only the glance_track teacher reads it"):
        checked_base(
            preset("match_dagger_glance"), margin, {"dagger.match_teacher": ["entropy_track"]}
        )


def test_a_set_key_is_checked_against_each_grid_observation_and_validation():
    """The settings that leave prior-pose, continuous-move and validation keys unread
    decide per grid point too: a --set key holds where every trial reads it."""
    from activevision.training import preset

    prior = {"env.prior_error_range": [0.0, 1.0], "algo": "dagger"}
    poses = {"env.observation": ["image+head+pose", "image+head+pose+proposal"]}
    assert checked_base(preset("paper"), prior, poses).env.prior_error_range == (0.0, 1.0)
    with pytest.raises(ValueError, match="only an observation with a prior pose reads it"):
        checked_base(preset("paper"), prior, {"env.observation": ["image", "image+head+pose"]})
    episodes = {"eval_episodes": 50}
    assert checked_base(preset("paper"), episodes, {"eval_interval": [1000, 3000]})
    with pytest.raises(ValueError, match="this run never validates"):
        checked_base(preset("paper"), episodes, {"eval_interval": [0, 1000]})
    # the match's moves: max_move_deg holds where every trial's are continuous (match_dagger's
    # are discrete), and is refused where one trial's are not
    moves = {"match.max_move_deg": [5.0, 5.0]}
    continuous = {"match.action_type": ["continuous"]}
    assert checked_base(preset("match_dagger"), moves, continuous).match.max_move_deg == (5, 5)
    with pytest.raises(ValueError, match=r"'match\.max_move_deg' is never read by this run"):
        both = {"match.action_type": ["discrete", "continuous"]}
        checked_base(preset("match_dagger"), moves, both)


def _metrics(run_dir: Path, success: list[float], epoch_steps: int = 300) -> None:
    run_dir.mkdir(parents=True)
    with (run_dir / "metrics.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(
            [
                "epoch",
                "step",
                "success_rate",
                "episode_reward",
                "success_duration",
                "ball_loss_duration",
            ]
        )
        for i, s in enumerate(success, 1):
            w.writerow([i, epoch_steps * i, s, 2 * s, 10, "nan"])


def test_aggregate_over_seeds(tmp_path):
    trials = []
    for seed, success in [(0, [0.2, 0.4]), (1, [0.4, 0.8]), (2, [0.6])]:
        run_dir = tmp_path / f"seed={seed}"
        _metrics(run_dir, success)
        trials.append({"seed": seed, "point": {"lr": 1}, "run_dir": str(run_dir)})
    rows = aggregate(trials, tmp_path)
    assert [(r["epoch"], r["step"], r["seeds"]) for r in rows] == [(1, 300, 3), (2, 600, 2)]
    assert rows[0]["success_rate_mean"] == pytest.approx(0.4)
    assert rows[0]["success_rate_std"] == pytest.approx(0.2)
    assert (rows[1]["success_rate_min"], rows[1]["success_rate_max"]) == (0.4, 0.8)
    assert rows[1]["episode_reward_mean"] == pytest.approx(1.2)
    assert rows[0]["lr"] == 1
    assert rows[0]["ball_loss_duration_mean"] != rows[0]["ball_loss_duration_mean"]  # all NaN


@pytest.mark.parametrize(
    ("success", "drawn", "label"),
    [([0.2, 0.4], [0.2, 0.4], "success rate"), (["nan", "nan"], [3.0, 5.0], "reward per match")],
)
def test_sweep_png_draws_the_reward_of_runs_without_a_success(
    tmp_path, monkeypatch, success, drawn, label
):
    # a sweep of match runs (no success: NaN) drew an empty success-rate figure
    import activevision.figures.sweep as figure

    run_dir = tmp_path / "seed=0"
    _metrics(run_dir, [0.2, 0.4])
    rows = aggregate([{"seed": 0, "point": {}, "run_dir": str(run_dir)}], tmp_path)
    for row, value, reward in zip(rows, success, [3.0, 5.0], strict=True):
        row["success_rate_mean"], row["episode_reward_mean"] = float(value), reward
    saved = []
    monkeypatch.setattr(figure, "save_figure", lambda fig, *_, **__: saved.append(fig))
    plot_sweep(rows, tmp_path / "sweep.png")
    (ax,) = saved[0].axes
    assert list(ax.lines[0].get_ydata()) == pytest.approx(drawn)
    assert ax.get_ylabel() == f"{label} (mean ± std over seeds)"


def test_an_epoch_s_step_is_the_mean_of_the_seeds_steps_whatever_their_order(tmp_path):
    """DAgger plays whole rounds, so its seeds end an epoch at different steps: sweep.csv's
    step was the first trial's."""
    trials = []
    for seed, steps in [(0, 320), (1, 300), (2, 310)]:
        run_dir = tmp_path / f"seed={seed}"
        _metrics(run_dir, [0.5, 0.5], epoch_steps=steps)
        trials.append({"seed": seed, "point": {}, "run_dir": str(run_dir)})
    for order in (trials, trials[::-1]):
        assert [r["step"] for r in aggregate(order, tmp_path)] == [310, 620]


def test_a_quoted_grid_value_reads_as_its_folder_name_in_the_tables(tmp_path):
    # the folder was seed=0,device=cpu while sweep.csv (and sweep.png's labels, trials.csv)
    # said "cpu" with its quotes
    run_dir = tmp_path / "seed=0,device=cpu"
    _metrics(run_dir, [0.5])
    point = {"device": '"cpu"', "name": '"null"', "lr": 0.001}
    assert trial_name(0, point) == 'seed=0,device=cpu,lr=0.001,name="null"'
    rows = aggregate([{"seed": 0, "point": point, "run_dir": str(run_dir)}], tmp_path)
    assert (rows[0]["device"], rows[0]["name"], rows[0]["lr"]) == ("cpu", '"null"', 0.001)


def test_method_names_and_policies():
    assert default_method_names(None, None) == [
        "entropy_jump",
        "entropy_steps",
        "oracle",
        "scan",
        "random",
    ]
    # the order given, each once; learned only with a run
    assert default_method_names("runs/x", ["random", "learned", "random"]) == ["random", "learned"]
    assert default_method_names(None, ["random", "learned"]) == ["random"]
    with pytest.raises(ValueError, match="unknown method"):
        make_policy("nope", 0.0, None)
    with pytest.raises(ValueError, match="run directory"):
        make_policy("learned", 0.0, None)


def test_a_sweep_is_refused_before_ray_starts(tmp_path):
    """What a rerun or a grid would get wrong is refused before any trial: a trial folder of
    another configuration (a rerun only resumes its trials: a bigger budget was never
    reached, a changed setting silently ignored), the seed in the grid, two grid points of
    one configuration, an --out that is a file."""
    from activevision.scaleout.sweep import _trial_specs
    from activevision.training import save_config

    base = TrainConfig()
    out = tmp_path / "sweep"

    def specs(grid, seeds=(0,), out_dir=out):
        return _trial_specs(base, seeds, grid, out_dir, 1.0, None)

    trials = specs({"learning_rate": ["1e-3"]})
    run_dir = Path(trials[0]["run_dir"])
    run_dir.mkdir(parents=True)
    save_config(TrainConfig.from_dict(trials[0]["config"]), run_dir / "config.json")
    assert specs({"learning_rate": ["1e-3"]}) == trials  # the same trial: resumed
    changed = base.replace(total_timesteps=base.run.total_timesteps * 2)
    with pytest.raises(ValueError, match=r"total_timesteps .* a rerun only resumes its trials"):
        _trial_specs(changed, (0,), {"learning_rate": ["1e-3"]}, out, 1.0, None)
    with pytest.raises(ValueError, match="with --seeds"):
        specs({"seed": ["1", "2"]})
    with pytest.raises(ValueError, match="are the same configuration"):
        specs({"learning_rate": ["1e-3", "0.001"]}, out_dir=tmp_path / "other")
    (tmp_path / "file").write_text("")
    with pytest.raises(ValueError, match="is a file"):
        specs({}, out_dir=tmp_path / "file")
    # a trial that sweeps before 2026-12-04 kept in a folder named with the quotes: a rerun
    # would start it over, unseen, in the plain-named one
    (out / "trials" / 'seed=0,run.device="cpu"').mkdir(parents=True)
    with pytest.raises(ValueError, match=r"older folder name: rename it to seed=0,run.device=cpu"):
        specs({"run.device": ['"cpu"']})


def test_an_address_nobody_answers_is_one_line_at_once():
    """Ray retries a dead HOST:PORT for minutes (ray://: half a minute), printing its own log
    lines; the check before ray.init names the address instead."""
    import socket
    import time

    from activevision.scaleout.ray_session import check_reachable

    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    started = time.perf_counter()
    for address in (f"127.0.0.1:{port}", f"ray://127.0.0.1:{port}"):
        with pytest.raises(ValueError, match=f"no Ray cluster answers at --address {address} "):
            check_reachable(address, timeout_s=2.0)
    assert time.perf_counter() - started < 5
    check_reachable("auto")  # Ray's own: finds a local cluster or fails at once


def test_a_failed_trial_names_its_error():
    from activevision.scaleout.sweep import _error_line, _trial_row

    class Wrapped(Exception):  # what Tune hands over: Ray's wrapper of the trainer's error
        cause = ValueError("device 'cuda:99' requested\n but this machine has 0")

    assert _error_line(Wrapped("traceback ...")) == (
        "ValueError: device 'cuda:99' requested but this machine has 0"
    )
    trial = {"name": "seed=0", "seed": 0, "point": {}, "run_dir": "/nonexistent"}
    row = _trial_row(trial, {"restarts": 0, "status": "ERROR", "error": "ValueError: x"})
    assert (row["status"], row["error"]) == ("ERROR", "ValueError: x")
    assert _trial_row(trial, {"restarts": 0})["error"] == ""


def test_sweep_command_with_failed_trials_exits_2_after_its_outputs(tmp_path, monkeypatch, capsys):
    """A sweep whose trials failed writes the outputs of the others, then ends with one line
    (how many failed, where their errors are) and exit code 2; by default Tune is quiet
    (--verbose: its tables) and each trial's end is one line."""
    import importlib

    from activevision.cli import main
    from activevision.io import write_csv

    calls = []

    def fake_sweep(config, seeds, grid, out_dir, **kwargs):
        calls.append(kwargs)
        kwargs["progress"]({"name": "seed=0", "status": "TERMINATED", "ended": 1, "trials": 2})
        kwargs["progress"]({"name": "seed=1", "status": "ERROR", "ended": 2, "trials": 2})
        rows = [
            {"name": f"seed={s}", "status": st, "error": e}
            for s, st, e in ((0, "TERMINATED", ""), (1, "ERROR", "ValueError: no start"))
        ]
        write_csv(Path(out_dir) / "trials.csv", rows)
        # the library's warning (as sweep gives it): the command says it once, as its error
        warnings.warn(f"{UNFINISHED_WARNING} (trials.csv): seed=1", RuntimeWarning, stacklevel=2)
        return [{"epoch": 1}]

    # the module (the package's attribute `sweep` is the function)
    sweep_module = importlib.import_module("activevision.scaleout.sweep")
    monkeypatch.setattr(sweep_module, "sweep", fake_sweep)
    out = tmp_path / "s"
    out.mkdir()
    with warnings.catch_warnings(record=True) as warned:
        warnings.simplefilter("always")
        assert main(["sweep", "--seeds", "0,1", "--out", str(out)]) == 2
    assert not warned  # the warning would be a second line beside the error
    captured = capsys.readouterr()
    assert captured.out.splitlines() == [
        "trial 1/2 finished: seed=0",
        "trial 2/2 failed: seed=1",
        "1 aggregated rows",
        f"wrote {out}/trials.csv, sweep.csv and sweep.png",
    ]
    assert captured.err.splitlines() == [
        "activevision sweep: error: 1 of 2 trials failed, the first seed=1 (ValueError: no"
        f" start): their errors are in the error column of {out / 'trials.csv'}"
    ]
    assert calls[0]["verbose"] == 0
    assert main(["sweep", "--seeds", "0,1", "--out", str(out), "--verbose"]) == 2
    assert calls[1]["verbose"] == 1


def test_a_sweep_that_logged_no_epoch_leaves_no_table_or_figure(tmp_path, monkeypatch):
    """Every trial failed before its first epoch (here: a rerun over damaged logs): sweep.csv
    was written empty (0 bytes, no header) beside the earlier sweep's sweep.png."""
    import contextlib
    import importlib
    import types

    sweep_module = importlib.import_module("activevision.scaleout.sweep")
    session = importlib.import_module("activevision.scaleout.ray_session")
    fake_ray = types.SimpleNamespace(cluster_resources=lambda: {"CPU": 1.0})
    monkeypatch.setattr(session, "ray_session", lambda *a, **k: contextlib.nullcontext(fake_ray))

    def every_trial_fails(trials, statuses, *args):
        for trial in trials:
            statuses[trial["name"]].update(status="ERROR", error="RunLogError: damaged")

    monkeypatch.setattr(sweep_module, "_fit", every_trial_fails)
    out = tmp_path / "s"
    out.mkdir()
    (out / "sweep.csv").write_text("epoch,step\n1,30\n")  # an earlier sweep's outputs
    (out / "sweep.png").write_bytes(b"an earlier figure")
    with pytest.warns(RuntimeWarning, match="damaged"):
        rows = sweep_module.sweep(TrainConfig(), [0, 1], None, out)
    assert rows == []
    assert sorted(p.name for p in out.iterdir() if p.is_file()) == ["trials.csv"]
    statuses = [r["status"] for r in csv.DictReader((out / "trials.csv").open())]
    assert statuses == ["ERROR", "ERROR"]


def test_a_failed_ray_init_gives_the_sigterm_handler_back(monkeypatch):
    """ray.init sets its own SIGTERM handler (exit status 1) before it connects: one that
    failed (a cluster it could not join) left it in place of the caller's."""
    import importlib
    import signal
    import types

    session = importlib.import_module("activevision.scaleout.ray_session")

    def init(**kwargs):
        signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(signum))
        raise ConnectionError("could not join the cluster")

    fake = types.SimpleNamespace(is_initialized=lambda: False, init=init, shutdown=lambda: None)
    monkeypatch.setattr(session, "require_ray", lambda: fake)

    def ours(signum, frame):
        raise KeyboardInterrupt

    before = signal.signal(signal.SIGTERM, ours)
    try:
        with pytest.raises(ConnectionError), session.ray_session(address="auto"):
            pass
        assert signal.getsignal(signal.SIGTERM) is ours
    finally:
        signal.signal(signal.SIGTERM, before)


def test_aggregate_leaves_out_a_trial_log_s_cut_last_row_and_refuses_a_short_one(tmp_path):
    """aggregate read each trial's metrics.csv with a bare csv.DictReader: a last row cut
    inside its last cell went into the statistics as that epoch's value (success 0.12 where
    the trial logged 0.1234); one cut after a cell was a TypeError."""
    run_dir = tmp_path / "seed=0"
    _metrics(run_dir, [0.2])
    whole = (run_dir / "metrics.csv").read_bytes()
    trials = [{"seed": 0, "point": {}, "run_dir": str(run_dir)}]
    (run_dir / "metrics.csv").write_bytes(whole + b"2,600,0.12")  # a trial killed writing it
    with pytest.warns(UserWarning, match=r"metrics\.csv: its last line has no end of line"):
        rows = aggregate(trials, tmp_path)
    assert [(r["epoch"], r["success_rate_mean"]) for r in rows] == [(1, 0.2)]
    (run_dir / "metrics.csv").write_bytes(whole + b"2,600,0.1234,0,0,0\r\n")  # written whole
    assert [r["success_rate_mean"] for r in aggregate(trials, tmp_path)] == [0.2, 0.1234]
    (run_dir / "metrics.csv").write_bytes(whole + b"2,600,0.4\r\n")
    with pytest.raises(ValueError, match=r"metrics\.csv line 3 has fewer cells"):
        aggregate(trials, tmp_path)
