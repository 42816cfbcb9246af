"""Seed x grid sweeps of training runs on Ray Tune, with per-epoch aggregation over seeds.

Each trial is one training run, of the trainer its config's ``algo`` names
(:func:`~activevision.training.runs.start_run`), in a fixed directory
``out_dir/trials/<name>`` (e.g. ``seed=3,learning_rate=0.001``); a finished trial gets the
figures of a ``train`` run (``plots/training.png``, :func:`~activevision.training.plot_run`).
The trainable trains one ``checkpoint_interval`` at a time and then reports each epoch of it
to Tune, with a Tune checkpoint that records that directory (not the trainer's checkpoint
files, which hold the replay buffer and would be copied on every report). When a trial's
worker dies, Tune restarts it (up to ``max_failures`` times) and the trainable resumes from
the run directory's newest trainer checkpoint
(:func:`~activevision.training.runs.reopen_run`), which also drops ``metrics.csv`` rows
written after that checkpoint, so every epoch appears exactly once.
Re-running a sweep into the same ``out_dir`` likewise continues (or just re-reads) its trials;
a trial that had finished keeps its run time and session count.

On a multi-node cluster ``out_dir`` must be a shared filesystem mounted at the same path on
every node (NFS, etc.): trials write their run directories there, a restarted trial may land on
another node, and the driver aggregates the trials' ``metrics.csv`` from there.

Outputs in ``out_dir``: ``trials.csv`` (one row per trial: status, restarts, epochs, its own
run time), ``sweep.csv`` (per grid point and epoch: mean, std, min, max over seeds of
:data:`METRICS`) and ``sweep.png`` (success rate vs step, mean +- std per grid point; a sweep
of match runs: reward per match).
"""

from __future__ import annotations

import json
import logging
import math
import os
import tempfile
import time
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from activevision.training.config import (
    TrainConfig,
    config_path,
    field_paths,
    load_config,
    override_value,
    parse_value,
    with_values,
)

if TYPE_CHECKING:
    from ray.tune.experiment import Trial

#: Epoch metrics aggregated over seeds.
METRICS = ("success_rate", "episode_reward", "success_duration", "ball_loss_duration")
#: Trainable testing hook (param ``crash_after_epoch``): marker file of the injected crash.
CRASH_MARKER = ".scaleout_crashed"
#: Per-trial bookkeeping the trainable keeps in its run directory.
STATE_FILE = "scaleout.json"


#: The start of the warning :func:`sweep` gives when trials did not finish.
UNFINISHED_WARNING = "sweep trials did not finish"


class TrialsFailedError(RuntimeError):
    """Trials of a sweep did not finish (their errors: trials.csv's ``error`` column)."""


# ---------------------------------------------------------------------- trial points
def trial_name(seed: int, point: Mapping[str, Any]) -> str:
    """Directory name of a trial: ``seed=0`` then ``,key=value`` per grid key (sorted); a
    value typed as a JSON string (``device="cpu"``) is named by its plain text (``cpu``).
    A ``/`` in a value (a path) is written ``%2F`` (and ``%`` ``%25``), so that every trial
    is one folder of the sweep's, never one nested in another or outside it."""
    name = ",".join([f"seed={seed}", *(f"{k}={_plain(point[k])}" for k in sorted(point))])
    return name.replace("%", "%25").replace("/", "%2F")


def _plain(value: Any) -> str:
    """A grid value as text, without the quotes of a JSON string (``"cpu"`` -> ``cpu``)
    unless the text means something else unquoted (``"null"``, ``"1"`` keep them)."""
    if not isinstance(value, str):
        return str(value)
    unquoted = parse_value(value)
    if isinstance(unquoted, str) and unquoted != value and parse_value(unquoted) == unquoted:
        return unquoted
    return value


def _plain_point(point: Mapping[str, Any]) -> dict[str, Any]:
    """A grid point's values as trials.csv, sweep.csv and sweep.png show them: a JSON string
    by its plain text, as in the trial's folder name (:func:`_plain`); numbers as they are."""
    return {k: _plain(v) if isinstance(v, str) else v for k, v in point.items()}


def grid_points(grid: Mapping[str, Sequence[Any]]) -> list[dict[str, Any]]:
    """Every combination of the grid's values (one empty point for an empty grid)."""
    points: list[dict[str, Any]] = [{}]
    for key in sorted(grid):
        values = list(grid[key])
        if not values:
            raise ValueError(f"grid key {key!r} has no values")
        points = [{**p, key: v} for p in points for v in values]
    return points


def trial_config(base: TrainConfig, seed: int, point: Mapping[str, Any]) -> TrainConfig:
    """``base`` with ``seed`` and the grid point applied (string values are parsed like
    ``--set key=value``, other values used as is); validated. The point's keys are set
    together, as one ``--set`` list's: a grid over ``algo`` with keys only some algo reads
    is checked against each trial's algo, whatever the keys' order."""
    return with_values(base, {"seed": int(seed), **_point_values(point)})


def _point_values(point: Mapping[str, Any]) -> dict[str, Any]:
    """A grid point's values, its text values parsed as ``--set``'s."""
    return {k: override_value(k, v) if isinstance(v, str) else v for k, v in point.items()}


def checked_grid(
    items: Sequence[tuple[str, Sequence[Any]]], overrides: Mapping[str, Any]
) -> dict[str, list[Any]]:
    """The grid of ``--grid KEY=V1,V2`` ``items``; ValueError where two of them set one
    config value (``--grid learning_rate=1e-3 --grid learning_rate=2e-3`` swept only the
    last: put the values in one) or one of them sets a value ``overrides`` (``--set``) sets
    too (every trial replaced the --set value). Keys are compared by the path they name
    (``learning_rate`` is ``learner.learning_rate``); unknown ones are left to the config's
    own check."""
    paths = field_paths()
    owner: dict[str, str] = {}  # each named path -> the --grid key that set it
    grid: dict[str, list[Any]] = {}
    for key, values in items:
        path = config_path(key, paths)
        if path in owner:
            raise ValueError(
                f"--grid {owner[path]} and --grid {key} both set {path}: give its values in"
                " one --grid, separated by commas"
            )
        owner[path] = key
        grid[key] = list(values)
    for key in overrides:
        path = config_path(key, paths)
        if path in owner:
            raise ValueError(
                f"--set {key.strip()} and --grid {owner[path]} both set {path}: each trial"
                " takes the grid's value; drop one of them"
            )
    return grid


#: The settings that decide which other keys a run reads (``training.config``'s unread-key
#: checks): a ``--set`` key is checked against each of their grid values.
DECIDING_KEYS = (
    "algo",
    "env_id",
    "dagger.match_teacher",
    "dagger.act_by",
    "env.observation",
    "env.action_type",
    "match.action_type",
    "env.prior_error_range",
    "env.success_mode",
    "run.eval_interval",
)


def checked_base(
    config: TrainConfig, overrides: Mapping[str, Any], grid: Mapping[str, Sequence[Any]] | None
) -> TrainConfig:
    """``config`` with ``overrides`` (a ``--set`` list's values) applied: the sweep's base
    config. Every key must be read by the trials' runs; where the grid varies a setting of
    :data:`DECIDING_KEYS`, by each of them (``--set sb3.tau=0.01 --grid algo=sac,td3``
    holds, though the preset's algo never reads ``sb3.*``; ``--set
    dagger.glance_track_margin_deg=10 --grid dagger.match_teacher=entropy_track`` does not).
    Where it does, the base takes the first grid point's deciding values: each trial sets
    its own."""
    paths = field_paths()
    deciding = {k: v for k, v in (grid or {}).items() if paths.get(k.strip()) in DECIDING_KEYS}
    if not deciding:
        return with_values(config, overrides)
    bases = [with_values(config, {**overrides, **_point_values(p)}) for p in grid_points(deciding)]
    return bases[0]


# ---------------------------------------------------------------------- the trainable
def _read_state(run_dir: Path) -> dict[str, Any]:
    try:
        state: dict[str, Any] = json.loads((run_dir / STATE_FILE).read_text())
        return state
    except (OSError, json.JSONDecodeError):
        return {"elapsed_s": 0.0, "sessions": 0}


def _last_metrics_row(run_dir: Path) -> dict[str, float]:
    rows = _metrics_rows(run_dir)
    return {k: float(v) for k, v in rows[-1].items()} if rows else {}


def train_trial(params: dict[str, Any]) -> None:
    """Tune function trainable: train (or resume) one trial, reporting every epoch.

    ``params["trial"]``: ``config`` (a TrainConfig dict), ``run_dir`` (absolute path), and the
    testing hook ``crash_after_epoch`` (int or None): exit the worker process once, right after
    reporting that epoch, leaving :data:`CRASH_MARKER` in the run directory.
    """
    started = time.perf_counter()  # the trial's own run time includes its imports
    from ray import tune

    from activevision.io import write_json
    from activevision.training import plot_run
    from activevision.training.checkpoint import list_checkpoints
    from activevision.training.runs import reopen_run, start_run

    if params.get("quiet"):  # not a log line per report: "Checkpoint successfully created"
        logging.getLogger("ray.train").setLevel(logging.WARNING)
    params = params["trial"]
    config = TrainConfig.from_dict(params["config"])
    run_dir = Path(params["run_dir"])
    restored = tune.get_checkpoint()
    if restored is not None:  # the Tune checkpoint only records where the run lives
        with restored.as_directory() as d:
            run_dir = Path(json.loads((Path(d) / "trial.json").read_text())["run_dir"])
    state = _read_state(run_dir)
    prior_sessions = int(state.get("sessions", 0))
    prior_s = float(state.get("elapsed_s", 0.0))
    resumed = bool(list_checkpoints(run_dir))
    trainer = reopen_run(run_dir) if resumed else start_run(config, run_dir)
    crash_after = params.get("crash_after_epoch")

    def report(row: Mapping[str, float], trained: bool = True) -> None:
        # a trial finished in an earlier sweep keeps its run time and sessions: re-reading
        # it is no training
        if trained:
            state["sessions"] = prior_sessions + 1
            state["elapsed_s"] = prior_s + time.perf_counter() - started
            write_json(run_dir / STATE_FILE, state)
        metrics = {
            **row,
            "trial_elapsed_s": state["elapsed_s"],
            "resumed": float(resumed),
            "sessions": float(state["sessions"]),
        }
        with tempfile.TemporaryDirectory() as d:
            (Path(d) / "trial.json").write_text(
                json.dumps({"run_dir": str(run_dir), "step": trainer.step})
            )
            tune.report(metrics, checkpoint=tune.Checkpoint.from_directory(d))

    try:
        reported = False
        # train() checkpoints when it returns, so train a checkpoint interval per call
        # (an epoch when checkpoints are only taken at the end), then report its epochs
        chunk = config.run.checkpoint_interval or config.run.epoch_steps
        while trainer.step < config.run.total_timesteps:
            for row in trainer.train(steps=chunk):
                report(row)
                reported = True
                marker = run_dir / CRASH_MARKER
                if crash_after is not None and row["epoch"] >= crash_after and not marker.exists():
                    marker.write_text(f"crashed after epoch {int(row['epoch'])}\n")
                    os._exit(1)  # the testing hook: a worker dying mid-run
        if not reported:  # finished in an earlier sweep: report its final epoch once
            report(_last_metrics_row(run_dir), trained=False)
    finally:
        trainer.close()
    if reported or not (run_dir / "plots" / "training.png").exists():
        plot_run(run_dir)  # the figures `activevision train` draws, in the trial's plots/


# ---------------------------------------------------------------------- the sweep
def sweep(
    base_config: TrainConfig,
    seeds: Iterable[int],
    grid: Mapping[str, Sequence[Any]] | None,
    out_dir: str | Path,
    address: str | None = None,
    num_cpus: int | None = None,
    max_failures: int = 2,
    *,
    cpus_per_trial: float = 1.0,
    gpus_per_trial: float | None = None,
    verbose: int = 0,
    progress: Callable[[Mapping[str, Any]], None] | None = None,
    crash_after_epoch: int | None = None,
) -> list[dict[str, Any]]:
    """One Ray Tune trial per (seed x grid point); returns the aggregated ``sweep.csv`` rows.

    Args:
        base_config: configuration of every trial before its seed and grid point.
        seeds: training seeds; grid: config key -> values (their product is swept).
        out_dir: trial run directories, Tune's results, trials.csv, sweep.csv, sweep.png.
        address: None starts a local Ray instance with ``num_cpus`` CPUs (default: all);
            ``"auto"`` or ``"ray://head:10001"`` joins a running cluster.
        max_failures: restarts of a failed trial (each resumes from its checkpoint).
        cpus_per_trial: CPUs per trial; a config with ``num_threads=0`` gets that many
            torch threads. gpus_per_trial: default 1 when the cluster has GPUs, else 0.
        verbose: Tune's console verbosity: 0 (default) no status tables, nor Ray's log of
            each report's checkpoint and each failed trial's traceback (its error is in
            trials.csv and the closing warning); Ray and Tune still print about ten lines
            (Ray's start, Tune's configuration box and closing hints, a failed trial's error
            file); 1 Tune's status tables, 2 also every result.
        progress: called in the driver as each trial ends, with ``name``, ``status``
            (``TERMINATED`` or ``ERROR``), ``ended`` (trials ended so far) and ``trials``.
        crash_after_epoch: testing hook, see :func:`train_trial`.
    """
    from activevision.io import write_csv
    from activevision.scaleout.ray_session import ray_session

    out_dir = Path(out_dir).resolve()
    trials = _trial_specs(base_config, seeds, grid, out_dir, cpus_per_trial, crash_after_epoch)
    statuses: dict[str, dict[str, Any]] = {t["name"]: {"restarts": 0} for t in trials}
    # quiet: no INFO lines of Ray's start ("Started a local Ray instance") or of Tune's
    # bookkeeping ("Wrote the latest version of all result files"), and no worker's output:
    # a trial's error reaches trials.csv through Tune, and an idle worker that Ray's shutdown
    # stops with SIGTERM may print a traceback ("Exception ignored in: ... SystemExit: 1")
    quiet_logs: dict[str, Any] = (
        {"logging_level": logging.WARNING, "log_to_driver": False} if verbose == 0 else {}
    )
    with ray_session(address, num_cpus, **quiet_logs) as ray:
        if gpus_per_trial is None:
            gpus_per_trial = 1.0 if ray.cluster_resources().get("GPU", 0) > 0 else 0.0
        resources = {"cpu": cpus_per_trial, "gpu": gpus_per_trial}
        _fit(trials, statuses, out_dir, resources, max_failures, verbose, progress)

    trial_rows = [_trial_row(t, statuses[t["name"]]) for t in trials]
    write_csv(out_dir / "trials.csv", trial_rows)
    failed = [
        r["name"] + (f" ({r['error']})" if r["error"] else "")
        for r in trial_rows
        if r["status"] != "TERMINATED"
    ]
    if failed:
        warnings.warn(
            f"{UNFINISHED_WARNING} (trials.csv): {'; '.join(failed)}",
            RuntimeWarning,
            stacklevel=2,
        )
    rows = aggregate(trials, out_dir)
    if rows:
        write_csv(out_dir / "sweep.csv", rows)
        plot_sweep(rows, out_dir / "sweep.png")
    else:
        # no trial logged an epoch: sweep.csv was written empty (0 bytes, no header), beside
        # an earlier sweep's figure, which read as this one's
        for name in ("sweep.csv", "sweep.png"):
            (out_dir / name).unlink(missing_ok=True)
    return rows


def _check_no_older_name(trials_dir: Path, seed: int, point: Mapping[str, Any], name: str) -> None:
    """ValueError when the trial is in ``trials_dir`` under the name sweeps gave it before
    2026-12-04 (a quoted grid value with its quotes, ``device="cpu"``): a rerun would start
    it over in ``name`` instead of resuming it."""
    older = ",".join([f"seed={seed}", *(f"{k}={point[k]}" for k in sorted(point))])
    if older != name and "/" not in older and (trials_dir / older).is_dir():
        raise ValueError(
            f"{trials_dir / older} holds this trial under its older folder name: rename it to"
            f" {name} to resume it"
        )


def _trial_specs(
    base_config: TrainConfig,
    seeds: Iterable[int],
    grid: Mapping[str, Sequence[Any]] | None,
    out_dir: Path,
    cpus_per_trial: float,
    crash_after_epoch: int | None,
) -> list[dict[str, Any]]:
    """One plain-data trial description per (grid point, seed), in sweep order."""
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("a sweep needs at least one seed")
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"duplicate seeds: {seeds}")
    if {"seed", "run.seed"} & set(grid or {}):
        raise ValueError("the grid may not hold the seed: give the seeds with --seeds")
    if out_dir.exists() and not out_dir.is_dir():
        raise ValueError(f"{out_dir} is a file, not a directory: choose another --out")
    trials: list[dict[str, Any]] = []
    for point in grid_points(grid or {}):
        for seed in seeds:
            config = trial_config(base_config, seed, point)
            if config.run.num_threads == 0:
                config = config.replace(**{"run.num_threads": max(1, math.floor(cpus_per_trial))})
            name = trial_name(seed, point)
            same = [t["name"] for t in trials if t["config"] == config.to_dict()]
            if same:
                raise ValueError(f"grid points {same[0]} and {name} are the same configuration")
            check_trial_dir(out_dir / "trials" / name, config)
            _check_no_older_name(out_dir / "trials", seed, point, name)
            trials.append(
                {
                    "name": name,
                    "seed": seed,
                    "point": point,
                    "config": config.to_dict(),
                    "run_dir": str(out_dir / "trials" / name),
                    "crash_after_epoch": crash_after_epoch,
                }
            )
    return trials


def check_trial_dir(run_dir: Path, config: TrainConfig) -> None:
    """ValueError when ``run_dir`` holds a trial of another configuration: a sweep rerun
    into its folder resumes its trials as they were configured (a changed setting or budget
    would be ignored, or never reached)."""
    if not (run_dir / "config.json").is_file():
        return
    saved = _leaves(load_config(run_dir / "config.json").to_dict())
    wanted = _leaves(config.to_dict())
    differ = sorted(k for k in saved.keys() | wanted.keys() if saved.get(k) != wanted.get(k))
    if differ:
        shown = ", ".join(f"{k} {saved.get(k)!r} -> {wanted.get(k)!r}" for k in differ[:3])
        raise ValueError(
            f"{run_dir} holds this trial trained with another configuration ({shown}"
            f"{', ...' if len(differ) > 3 else ''}): a rerun only resumes its trials; choose"
            " another --out"
        )


def _leaves(tree: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """A nested config dict as ``{"learner.gamma": 0.99, ...}``."""
    out: dict[str, Any] = {}
    for key, value in tree.items():
        if isinstance(value, Mapping):
            out |= _leaves(value, f"{prefix}{key}.")
        else:
            out[f"{prefix}{key}"] = value
    return out


def _fit(
    trials: list[dict[str, Any]],
    statuses: dict[str, dict[str, Any]],
    out_dir: Path,
    resources: dict[str, float],
    max_failures: int,
    verbose: int,
    progress: Callable[[Mapping[str, Any]], None] | None,
) -> None:
    """Run every trial as a Ray Tune grid; record each one's final status and restarts."""
    from ray import tune

    def ended(trial: Trial, status: str) -> None:
        name = trial.config["trial"]["name"]
        statuses[name]["status"] = status
        if progress is not None:
            done = sum("status" in s for s in statuses.values())
            progress({"name": name, "status": status, "ended": done, "trials": len(trials)})

    class _Recorder(tune.Callback):
        """Final status and restart count of every trial (runs in the driver)."""

        def on_trial_recover(
            self, iteration: int, trials: list[Trial], trial: Trial, **info: Any
        ) -> None:
            statuses[trial.config["trial"]["name"]]["restarts"] += 1

        def on_trial_complete(
            self, iteration: int, trials: list[Trial], trial: Trial, **info: Any
        ) -> None:
            ended(trial, "TERMINATED")

        def on_trial_error(
            self, iteration: int, trials: list[Trial], trial: Trial, **info: Any
        ) -> None:
            ended(trial, "ERROR")

    trainable = tune.with_resources(train_trial, resources)
    tuner = tune.Tuner(
        trainable,
        param_space={"trial": tune.grid_search(trials), "quiet": verbose == 0},
        tune_config=tune.TuneConfig(num_samples=1, trial_dirname_creator=_tune_dirname),
        run_config=tune.RunConfig(
            name="tune",
            storage_path=str(out_dir / "ray_results"),
            failure_config=tune.FailureConfig(max_failures=max_failures),
            checkpoint_config=tune.CheckpointConfig(num_to_keep=1),
            callbacks=[_Recorder()],
            verbose=verbose,
        ),
    )
    # Ctrl-C: a KeyboardInterrupt (one line, exit code 130; a rerun resumes the trials from
    # their own checkpoints), not Tune's graceful stop that returns as if the sweep had ended
    # and advises Tuner.restore. Quiet: no traceback of a failed trial (its error is one line
    # in trials.csv and the closing warning; Ray keeps the traceback in its error.txt).
    settings = {"TUNE_DISABLE_SIGINT_HANDLER": "1"}
    if verbose == 0:  # nor Tune's advice to keep more checkpoints: we keep one on purpose
        quiet = {
            "TUNE_PRINT_ALL_TRIAL_ERRORS": "0",
            "TUNE_WARN_EXCESSIVE_EXPERIMENT_CHECKPOINT_SYNC_THRESHOLD_S": "0",
            # Tune's console output that honours verbose=0: its newer one prints the
            # experiment's configuration box and where its results and TensorBoard logs lie
            "RAY_AIR_NEW_OUTPUT": "0",
        }
        # (Tune reads these from the environment only; a user's own setting wins)
        settings |= {k: v for k, v in quiet.items() if k not in os.environ}
    with _environ(settings):
        results = tuner.fit()
    for i in range(len(results)):
        result = results[i]
        if result.error is not None and result.config:
            statuses[result.config["trial"]["name"]]["error"] = _error_line(result.error)


@contextmanager
def _environ(settings: Mapping[str, str]) -> Iterator[None]:
    """Environment variables set for the duration of the block, then as they were."""
    saved = {k: os.environ.get(k) for k in settings}
    os.environ.update(settings)
    try:
        yield
    finally:
        for key, value in saved.items():
            if value is None:
                del os.environ[key]
            else:
                os.environ[key] = value


def _error_line(error: BaseException) -> str:
    """A failed trial's error on one line: the trainer's own exception, not Ray's wrapper
    (whose text holds the worker's traceback)."""
    cause = getattr(error, "cause", None)
    if isinstance(cause, BaseException):
        error = cause
    text = " ".join(str(error).split())
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def _tune_dirname(trial: Any) -> str:
    """Tune's own directory of a trial: its id (our run directory carries the name)."""
    return f"trial_{trial.trial_id}"


def _metrics_rows(run_dir: Path) -> list[dict[str, str]]:
    """A trial's ``metrics.csv`` rows (none before its first epoch), read as the rest of the
    package reads its CSVs (csv.DictReader counted a cut row: ``0.12`` of ``0.1234`` went
    into the statistics as that epoch's value, missing cells were a TypeError): a last line
    without its end of line, a row a trial that failed for good was killed writing, is
    left out with a warning (the sweep still tables its trials and says which failed); a
    row of more or fewer cells before it is a ValueError naming the file."""
    from activevision.io import read_csv, read_csv_text

    path = run_dir / "metrics.csv"
    if not path.exists():
        return []
    if read_csv_text(path, live=True)[1]:
        warnings.warn(
            f"{path}: its last line has no end of line (the trial was stopped writing it):"
            " read without it",
            stacklevel=2,
        )
    return read_csv(path, ("epoch", "step", *METRICS), live=True)


def _trial_row(trial: Mapping[str, Any], status: Mapping[str, Any]) -> dict[str, Any]:
    run_dir = Path(trial["run_dir"])
    state = _read_state(run_dir)
    return {
        "name": trial["name"],
        "seed": trial["seed"],
        **_plain_point(trial["point"]),
        "status": status.get("status", "UNKNOWN"),
        "restarts": status["restarts"],
        "sessions": state.get("sessions", 0),
        "epochs": len(_metrics_rows(run_dir)),
        "elapsed_s": round(float(state.get("elapsed_s", 0.0)), 3),
        "crashed": (run_dir / CRASH_MARKER).exists(),
        "run_dir": str(run_dir),
        "error": status.get("error", ""),
    }


def check_trials_finished(out_dir: str | Path) -> None:
    """:class:`TrialsFailedError` saying how many trials of the sweep in ``out_dir`` did
    not finish and where their errors are, when any did not (read from its trials.csv)."""
    from activevision.io import read_csv

    path = Path(out_dir) / "trials.csv"
    rows = read_csv(path, ("name", "status", "error"))
    failed = [r for r in rows if r["status"] != "TERMINATED"]
    if failed:
        first = failed[0]["name"] + (f" ({failed[0]['error']})" if failed[0].get("error") else "")
        raise TrialsFailedError(
            f"{len(failed)} of {len(rows)} trials failed, the first {first}: their errors are"
            f" in the error column of {path}"
        )


def _stats(values: Sequence[float]) -> tuple[float, float, float, float]:
    """mean, std (sample, 0 for one value), min, max of the finite values (NaN if none)."""
    import numpy as np

    x = np.asarray([v for v in values if math.isfinite(v)], float)
    if len(x) == 0:
        return (math.nan,) * 4
    std = float(x.std(ddof=1)) if len(x) > 1 else 0.0
    return float(x.mean()), std, float(x.min()), float(x.max())


def aggregate(trials: Sequence[Mapping[str, Any]], out_dir: str | Path) -> list[dict[str, Any]]:
    """Per (grid point, epoch) statistics over seeds of :data:`METRICS`, read from every
    trial's ``metrics.csv``; columns: grid keys, epoch, step, seeds, ``<metric>_mean``,
    ``_std``, ``_min``, ``_max``. Epochs only some seeds reached use those seeds (``seeds``
    counts them); a seed's NaN (an epoch in which no episode ended) is left out of that
    metric's statistics. ``step`` is
    the mean of the seeds' steps at the epoch's end (DAgger plays whole rounds, so its seeds
    end an epoch at different steps; the first trial's step made it depend on their order)."""
    del out_dir  # the trials carry absolute run directories
    groups: dict[tuple, dict[int, list[dict[str, str]]]] = {}
    keys: dict[tuple, dict[str, Any]] = {}
    for trial in trials:
        point_key = tuple(sorted((k, repr(v)) for k, v in trial["point"].items()))
        keys[point_key] = _plain_point(trial["point"])
        by_epoch = groups.setdefault(point_key, {})
        for metrics_row in _metrics_rows(Path(trial["run_dir"])):
            by_epoch.setdefault(int(float(metrics_row["epoch"])), []).append(metrics_row)
    rows = []
    for point_key, by_epoch in groups.items():
        for epoch in sorted(by_epoch):
            sel = by_epoch[epoch]
            row: dict[str, Any] = {
                **keys[point_key],
                "epoch": epoch,
                "step": round(sum(float(r["step"]) for r in sel) / len(sel)),
                "seeds": len(sel),
            }
            for m in METRICS:
                mean, std, lo, hi = _stats([float(r[m]) for r in sel])
                row.update({f"{m}_mean": mean, f"{m}_std": std, f"{m}_min": lo, f"{m}_max": hi})
            rows.append(row)
    return rows


def plot_sweep(rows: Sequence[Mapping[str, Any]], out_png: str | Path) -> None:
    """Success rate vs step, one mean curve with a +-std band per grid point (drawn by
    :func:`activevision.figures.sweep.plot_sweep_curves`); a sweep of match runs, which
    have no success (every ``success_rate_mean`` NaN: an empty figure), draws the reward
    per match instead."""
    from activevision.figures.sweep import plot_sweep_curves

    skip = {"epoch", "step", "seeds"} | {f"{m}_{s}" for m in METRICS for s in STATS}
    curves: dict[str, list[Mapping[str, Any]]] = {}
    for r in rows:
        label = ", ".join(f"{k}={v}" for k, v in r.items() if k not in skip) or "base config"
        curves.setdefault(label, []).append(r)
    success = any(math.isfinite(float(r["success_rate_mean"])) for r in rows)
    plot_sweep_curves(curves, out_png, "success_rate" if success else "episode_reward")


STATS = ("mean", "std", "min", "max")
