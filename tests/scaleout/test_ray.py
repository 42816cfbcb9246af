"""Ray scale-out end to end: a seed sweep, a worker crash survived, distributed compare."""

from __future__ import annotations

import csv
import json
import logging
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ray = pytest.importorskip("ray")
pytest.importorskip("ray.tune")

from activevision.envs import EnvConfig  # noqa: E402
from activevision.experiments.compare import compare, default_methods  # noqa: E402
from activevision.scaleout import compare_ray, sweep  # noqa: E402
from activevision.scaleout.sweep import (  # noqa: E402
    CRASH_MARKER,
    TrialsFailedError,
    check_trials_finished,
)
from activevision.training import apply_overrides, preset  # noqa: E402

TINY = [
    "total_timesteps=600",
    "learning_starts=100",
    "buffer_size=1000",
    "batch_size=8",
    "checkpoint_interval=300",
    "num_threads=1",
    "target_update_interval=100",
    "tensorboard=false",
    "progress_bar=false",
]


@pytest.fixture(scope="module", autouse=True)
def local_ray():
    """One local Ray instance for the module; the scale-out functions join it."""
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
    yield
    ray.shutdown()


def _read(path: Path) -> list[dict[str, str]]:
    with path.open() as f:
        return list(csv.DictReader(f))


def test_sweep_two_seeds_aggregates(tmp_path, capsys):
    config = apply_overrides(preset("paper"), TINY)
    ended = []
    rows = sweep(config, [0, 1], {"learning_rate": [5e-4]}, tmp_path, progress=ended.append)
    # by default Tune prints no status tables (they were ~300 lines a trial), and each
    # trial's end is reported once
    assert len(capsys.readouterr().out.splitlines()) < 20
    assert sorted((e["name"], e["status"], e["trials"]) for e in ended) == [
        ("seed=0,learning_rate=0.0005", "TERMINATED", 2),
        ("seed=1,learning_rate=0.0005", "TERMINATED", 2),
    ]
    assert sorted(e["ended"] for e in ended) == [1, 2]

    trials = _read(tmp_path / "trials.csv")
    assert [t["name"] for t in trials] == [
        "seed=0,learning_rate=0.0005",
        "seed=1,learning_rate=0.0005",
    ]
    assert all(t["status"] == "TERMINATED" and t["epochs"] == "2" for t in trials)
    # each trial has the figures of a `train` run
    assert all((Path(t["run_dir"]) / "plots" / "training.png").stat().st_size > 0 for t in trials)
    on_disk = _read(tmp_path / "sweep.csv")
    assert len(on_disk) == len(rows) == 2
    assert [int(r["epoch"]) for r in on_disk] == [1, 2]
    assert [int(r["step"]) for r in on_disk] == [300, 600]
    for r in on_disk:
        assert r["seeds"] == "2" and float(r["learning_rate"]) == 5e-4
        for m in ("success_rate", "episode_reward", "success_duration", "ball_loss_duration"):
            assert float(r[f"{m}_min"]) <= float(r[f"{m}_mean"]) <= float(r[f"{m}_max"])
            assert float(r[f"{m}_std"]) >= 0
    # the mean is the mean of the two seeds' own metrics.csv rows
    per_seed = [_read(Path(t["run_dir"]) / "metrics.csv") for t in trials]
    mean = (float(per_seed[0][1]["success_rate"]) + float(per_seed[1][1]["success_rate"])) / 2
    assert float(on_disk[1]["success_rate_mean"]) == pytest.approx(mean)
    assert (tmp_path / "sweep.png").stat().st_size > 0


def test_a_dagger_sweep_trains_dagger_trials_and_prints_a_line_a_trial(tmp_path):
    """From the command line (its own Ray instance): each trial trains with the trainer its
    config's algo names (a DAgger preset failed in every trial: the DDQN trainer refused its
    dict observation), and the sweep prints a line per trial and its outputs, not Tune's
    configuration box, where its results lie, or Ray's INFO lines."""
    out = tmp_path / "sweep"
    sets = ["total_timesteps=256", "epoch_steps=128", "checkpoint_interval=128"]
    sets += ["dagger.num_envs=8", "progress_bar=false", "tensorboard=false"]
    command = [sys.executable, "-m", "activevision.cli", "sweep", "--seeds", "0", "--preset"]
    command += ["quickstart", *(a for kv in sets for a in ("--set", kv)), "--out", str(out)]
    done = subprocess.run(
        [*command, "--num-cpus", "1"], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    printed = (done.stdout + done.stderr).splitlines()
    ours = [line for line in printed if "Token authentication" not in line]  # Ray's notice
    assert ours == [
        "trial 1/1 finished: seed=0",
        "2 aggregated rows",
        f"wrote {out}/trials.csv, sweep.csv and sweep.png",
    ]
    run_dir = Path(_read(out / "trials.csv")[0]["run_dir"])
    assert json.loads((run_dir / "config.json").read_text())["algo"] == "dagger"
    assert [int(r["epoch"]) for r in _read(run_dir / "metrics.csv")] == [1, 2]


def test_trial_survives_worker_crash(tmp_path):
    config = apply_overrides(preset("paper"), TINY)
    sweep(config, [3], {}, tmp_path, max_failures=1, verbose=0, crash_after_epoch=1)

    (trial,) = _read(tmp_path / "trials.csv")
    assert trial["status"] == "TERMINATED"
    assert trial["restarts"] == "1" and trial["sessions"] == "2"
    run_dir = Path(trial["run_dir"])
    assert (run_dir / CRASH_MARKER).read_text().startswith("crashed after epoch 1")
    # resumed from the step-300 checkpoint: every epoch logged exactly once, in order
    assert [(r["epoch"], r["step"]) for r in _read(run_dir / "metrics.csv")] == [
        ("1", "300"),
        ("2", "600"),
    ]
    assert [int(r["epoch"]) for r in _read(tmp_path / "sweep.csv")] == [1, 2]
    assert (run_dir / "plots" / "training.png").is_file()

    # a rerun re-reads the finished trial: its run time and sessions stay what they were,
    # and a figure it lacks (a trial of an older sweep) is drawn
    (run_dir / "plots" / "training.png").unlink()
    metrics = (run_dir / "metrics.csv").read_text()
    sweep(config, [3], {}, tmp_path, max_failures=1, verbose=0, crash_after_epoch=1)
    (again,) = _read(tmp_path / "trials.csv")
    assert again["status"] == "TERMINATED"
    assert (again["elapsed_s"], again["sessions"]) == (trial["elapsed_s"], trial["sessions"])
    assert (run_dir / "metrics.csv").read_text() == metrics
    assert (run_dir / "plots" / "training.png").is_file()


def test_compare_ray_equals_local(tmp_path):
    config = EnvConfig()
    names = ["oracle", "entropy_jump", "random", "scan"]
    errors = [0.0, 1.0]
    methods = {k: v for k, v in default_methods(config).items() if k in names}
    local = compare(tmp_path / "local", methods, errors, 6, seed=5, config=config, progress=False)
    order = list(methods)  # the local run's method order
    distributed = compare_ray(tmp_path / "ray", order, errors, 6, seed=5, config=config, chunk=4)

    assert distributed == local
    assert (tmp_path / "ray" / "compare.csv").read_text() == (
        tmp_path / "local" / "compare.csv"
    ).read_text()
    # a finished run is skipped: nothing is recomputed, the CSV stays the same
    again = compare_ray(tmp_path / "ray", order, errors, 6, seed=5, config=config, chunk=4)
    assert again == _read(tmp_path / "ray" / "compare.csv")


@pytest.mark.parametrize("verbose", [False, True])
def test_compare_ray_prints_the_workers_output_only_when_verbose(tmp_path, monkeypatch, verbose):
    """Quiet by default (an idle worker's shutdown traceback reached the driver); with
    ``verbose`` (``compare --ray --verbose``) the workers' warnings and errors are shown."""
    from contextlib import contextmanager

    started = []

    class Started(Exception):
        pass

    @contextmanager
    def recording_session(address, num_cpus, **kwargs):
        started.append(kwargs)
        raise Started
        yield  # a generator, as ray_session is

    # the module (the package's attribute of that name is the function)
    module = sys.modules["activevision.scaleout.ray_session"]
    monkeypatch.setattr(module, "ray_session", recording_session)
    with pytest.raises(Started):
        compare_ray(tmp_path, ["random"], [0.0], 2, verbose=verbose)
    quiet = {} if verbose else {"logging_level": logging.WARNING}
    assert started == [{"log_to_driver": verbose, **quiet}]


def test_compare_ray_prints_no_info_line_of_rays_start(tmp_path):
    """From the command line (its own Ray instance): ``compare --ray`` printed Ray's INFO
    line "Started a local Ray instance", which ``sweep`` hides; now neither does."""
    out = tmp_path / "compare"
    command = [sys.executable, "-m", "activevision.cli", "compare", "--ray", "--num-cpus", "1"]
    command += ["--methods", "random", "--episodes", "2", "--errors", "0", "--out", str(out)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    printed = done.stdout + done.stderr
    assert "Started a local Ray instance" not in printed
    assert "INFO" not in printed, printed
    assert (out / "compare.csv").is_file()


def test_a_failing_trial_is_reported_with_its_error(tmp_path):
    """A grid value the trainer refuses (no machine has CUDA device 99) fails its trial; the
    sweep names the trial and the trainer's own error, and trials.csv keeps it."""
    config = apply_overrides(preset("paper"), TINY)
    grid = {"device": ['"cuda:99"']}
    with pytest.warns(RuntimeWarning, match=r"seed=0,device=cuda:99 \(ValueError: device"):
        sweep(config, [0], grid, tmp_path, max_failures=0, verbose=0)
    (trial,) = _read(tmp_path / "trials.csv")
    assert trial["run_dir"] == str(tmp_path / "trials" / "seed=0,device=cuda:99")  # no quotes
    assert trial["status"] == "ERROR"
    assert trial["error"].startswith("ValueError: device 'cuda:99' requested"), trial["error"]
    # what ends `activevision sweep` with exit code 2 after writing the outputs
    with pytest.raises(
        TrialsFailedError, match=r"^1 of 1 trials failed, the first .*: .* error column of"
    ):
        check_trials_finished(tmp_path)


def test_compare_ray_raises_a_tasks_own_error():
    """A task's error reaches the CLI as itself (one line there), not as Ray's RayTaskError
    carrying the worker's traceback."""
    from activevision.scaleout.compare import _get
    from activevision.training.checkpoint import CheckpointError

    @ray.remote
    def broken() -> None:
        raise CheckpointError("no best_policy.safetensors in RUN")

    with pytest.raises(CheckpointError, match="no best_policy") as caught:
        _get(ray, [broken.remote()])
    assert type(caught.value) is CheckpointError


@pytest.mark.parametrize(
    ("signum", "code", "said"),
    [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "stopped by SIGTERM")],
)
def test_sweep_ctrl_c_or_sigterm_is_one_line_and_its_code(tmp_path, signum, code, said):
    """Ctrl-C (or SIGTERM) ends a sweep as it ends any command (one line, exit code 130 or
    143), not with Tune's graceful stop that returned 0 as if done and advised
    Tuner.restore."""
    out = tmp_path / "sweep"
    sets = [a for kv in TINY for a in ("--set", kv.replace("600", "100000"))]
    command = [sys.executable, "-m", "activevision.cli", "sweep", "--seeds", "0"]
    command += ["--preset", "quickstart_ddqn", *sets, "--out", str(out), "--num-cpus", "1"]
    # Ctrl-C reaches the command as from a terminal, also where the tests run with SIGINT
    # ignored (a background job: the child would inherit it and never stop)
    proc = subprocess.Popen(
        command,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        started = time.monotonic()
        while not (out / "trials" / "seed=0" / "config.json").exists():  # the trial trains
            assert proc.poll() is None and time.monotonic() - started < 120
            time.sleep(0.2)
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == code, err
    assert err.splitlines()[-1] == (
        f"activevision sweep: {said}; the same command again resumes its trials in {out}"
    )
