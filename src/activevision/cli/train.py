"""``activevision train``, ``plot`` and ``sweep``."""

from __future__ import annotations

import argparse
import contextlib
import shutil
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from activevision.cli.args import (
    add_overwrite,
    choice_list,
    grid_item,
    int_in,
    not_a_run,
    path,
    positive_float,
    positive_int,
    seed,
    seed_list,
)
from activevision.cli.outputs import OutputError, check_run_directory, is_training_run


def _preset_names() -> tuple[str, ...]:
    from activevision.training.presets import PRESET_NAMES

    return PRESET_NAMES


def _preset_help() -> dict[str, str]:
    from activevision.training.presets import PRESET_HELP

    return PRESET_HELP


def cmd_train(args: argparse.Namespace) -> None:
    """Train (or resume) a DDQN + PER, DAgger or Stable-Baselines3 run."""
    from activevision.training import plot_run

    # before training: the figures drawn after it failed on "[Errno 17] File exists"
    # (a resume names a checkpoints file itself, once no checkpoint is found)
    if args.resume is not None:
        _check_run_folders(args.resume, ("plots",))
    else:
        _check_run_folders(args.out, ("plots", "checkpoints"))
    run_dir = _resume(args) if args.resume is not None else _train_fresh(args)
    if run_dir is not None:
        print(f"figures: {plot_run(run_dir)}")


def _resume(args: argparse.Namespace) -> Path | None:
    from activevision.training import load_config, reopen_run
    from activevision.training.checkpoint import (
        CHECKPOINTS_DIR,
        CheckpointError,
        list_checkpoints,
    )

    names = ("config", "preset", "seed", "set", "out", "algo")
    given = [f"--{n}" for n in names if _given(args, n)]
    # --overwrite was ignored: a resume replaces nothing, and a run with a checkpoint is never
    # started again over its files
    given += ["--overwrite"] if args.overwrite else []
    if given:
        raise ValueError(
            f"--resume continues a run with its own config.json; {', '.join(given)} cannot be"
            " combined with it (start a new run with --out instead)"
        )
    if not (args.resume / "config.json").is_file():
        raise ValueError(not_a_run(args.resume, "--resume"))
    tensorboard = False
    with contextlib.suppress(ValueError, OSError):  # an unreadable config: reopen_run says so
        tensorboard = load_config(args.resume / "config.json").run.tensorboard
    if tensorboard:
        _check_run_folders(args.resume, ("tensorboard",))
    try:
        trainer = reopen_run(args.resume)
    except CheckpointError as error:
        folder = args.resume / CHECKPOINTS_DIR
        if folder.exists() and not folder.is_dir():
            raise CheckpointError(
                f"{folder} is not a directory: it holds the run's checkpoints"
            ) from None
        checkpoints = list_checkpoints(args.resume)
        if checkpoints:
            older = _older_whole_checkpoint(checkpoints)
            if older is None:
                raise
            # the run keeps two checkpoints for this, but the line named only the broken one
            raise CheckpointError(
                f"{error}; its older checkpoint {older.name} is whole: move"
                f" {checkpoints[-1]} out of the run to resume from that one"
            ) from None
        # stopped before its first checkpoint (a kill -9, a crash): said "no checkpoint in
        # RUN/checkpoints", without what to do
        raise ValueError(
            f"--resume {args.resume}: the run stopped before its first checkpoint, so there is"
            f" nothing to continue; start it again with --out {args.resume} --overwrite"
        ) from None
    try:
        total = trainer.config.run.total_timesteps
        if trainer.step >= total:
            if args.steps is not None:
                raise ValueError(
                    f"{args.resume} is finished ({trainer.step} of {total} steps); --steps"
                    " cannot extend it (its schedules end at total_timesteps): train a new run"
                    " with a larger --steps"
                )
            print(f"{args.resume} is finished ({total} steps); nothing to train")
        else:
            _warn_busy_machine(trainer.config.run.num_threads, resuming=True)
            trainer.train(args.steps)
    finally:
        trainer.close()
    run_dir: Path = args.resume
    return run_dir


def _older_whole_checkpoint(checkpoints: list[Path]) -> Path | None:
    """The run's older checkpoint where the newest one fails its verification (a file
    corrupt, missing or added) and the older one passes it; else None."""
    from activevision.training.checkpoint import CheckpointError, verify_checkpoint

    def whole(checkpoint: Path) -> bool:
        try:
            verify_checkpoint(checkpoint)
        except CheckpointError:
            return False
        return True

    # a whole newest one: the error is another (an edited config.json, its state)
    if len(checkpoints) < 2 or whole(checkpoints[-1]) or not whole(checkpoints[-2]):
        return None
    return checkpoints[-2]


def _interrupted(args: argparse.Namespace) -> str:
    """What an interrupted ``train`` can do next: resume from its last checkpoint, or start
    over when it had written none."""
    from activevision.training.checkpoint import list_checkpoints

    run = args.resume or args.out
    if run is None or not is_training_run(run):
        return ""
    checkpoints = list_checkpoints(run)
    if checkpoints:
        return (
            f"; `activevision train --resume {run}` continues from its last checkpoint"
            f" ({checkpoints[-1].name})"
        )
    return f" before its first checkpoint; start it again with --out {run} --overwrite"


def _given(args: argparse.Namespace, name: str) -> bool:
    return getattr(args, name) not in (None, [])


def _train_fresh(args: argparse.Namespace) -> Path:
    from activevision.training import apply_overrides, load_config, preset, train
    from activevision.training.checkpoint import list_checkpoints
    from activevision.training.environment import check_env_id

    if args.out is None:
        raise ValueError("--out runs/NAME is required (or --resume runs/NAME)")
    if args.config is not None and args.preset is not None:
        raise ValueError("--config and --preset cannot be combined (the file is the config)")
    if list_checkpoints(args.out):
        # --overwrite said nothing of why it did not start the run over
        over = (
            " (--overwrite starts over only a run stopped before its first checkpoint: to"
            " start this one over, remove it first)"
            if args.overwrite
            else ""
        )
        raise OutputError(
            f"{args.out} already holds a run; continue it with --resume {args.out}{over}"
        )
    if is_training_run(args.out) and not args.overwrite:
        raise OutputError(
            f"{args.out} already holds a run that has no checkpoint yet; pass --overwrite to"
            " start it over"
        )
    check_run_directory(args.out, overwrite=args.overwrite)
    base = load_config(args.config) if args.config else preset(args.preset or "paper")
    overrides = list(args.set or [])
    _refuse_set_beside(
        overrides,
        {
            "run.total_timesteps": "--steps" if args.steps is not None else "",
            "seed": "--seed" if args.seed is not None else "",
            "algo": "--algo" if args.algo is not None else "",
        },
    )
    if args.steps is not None:
        overrides.append(f"total_timesteps={args.steps}")
    if args.seed is not None:
        overrides.append(f"seed={args.seed}")
    if args.algo is not None:
        overrides.append(f"algo={args.algo}")
    run_dir: Path = args.out
    config = apply_overrides(base, overrides)
    check_env_id(config)  # before any note or warning: one line for an env that is not there
    if args.config is None and args.steps is not None:
        config = _scale_preset_intervals(args.preset or "paper", base, config, args.set or [])
    _refuse_aux_without_target(config)
    if config.run.tensorboard:
        _check_run_folders(run_dir, ("tensorboard",))
    _warn_never_validated(config)
    _warn_validation_dominates(config)
    _warn_never_updated(config)
    _warn_never_synced(config)
    _warn_busy_machine(config.run.num_threads)
    new_folder = not run_dir.exists()
    try:
        train(config, run_dir)
    except Exception:
        if new_folder and _nothing_trained(run_dir):
            shutil.rmtree(run_dir, ignore_errors=True)  # e.g. no start found: try again freely
        raise
    return run_dir


def _scale_preset_intervals(name: str, base: Any, config: Any, sets: list[str]) -> Any:
    """``config`` (preset ``name``, ``base``, with ``--steps`` and ``sets``) with the preset's
    validation and checkpoint intervals as the same shares of the ``--steps`` run, where
    ``--set`` does not name them (``presets.scaled_intervals``), said in one line:
    ``--preset quickstart --steps 3000`` kept the 10,000-step interval and never
    validated."""
    from activevision.training.config import config_path, field_paths, parse_overrides
    from activevision.training.presets import scaled_intervals

    paths = field_paths()
    given = {config_path(key, paths) for key in parse_overrides(sets)}
    changes = scaled_intervals(base, config, keep=given)
    if not changes:
        return config
    told = ", ".join(
        f"{path} {getattr(base.run, path.removeprefix('run.'))} -> {value}"
        for path, value in changes.items()
    )
    print(
        f"--steps {config.run.total_timesteps}: preset {name}'s {told} (the same shares of the"
        f" run as of its {base.run.total_timesteps} steps; --set them to choose)",
        flush=True,
    )
    return config.replace(**changes)


def _refuse_aux_without_target(config: Any) -> None:
    """ValueError where ``learner.aux_goal_weight`` is set for an env without a goal view
    (``--preset match_ddqn --set aux_goal_weight=1``): the trainer's own error told a
    command-line user to pass a Python function."""
    from activevision.training.aux_targets import no_default_aux_target

    why = no_default_aux_target(config)
    if why:
        raise ValueError(f"{why}: leave it at 0 on this env")


def _warn_never_validated(config: Any) -> None:
    """Warn where ``run.eval_interval`` is past the run's end: ``--preset quickstart --steps
    3000`` kept the preset's interval (10,000, a quarter of its 40,000 steps), so it never
    validated and wrote no best_policy.safetensors, unsaid."""
    run = config.run
    if 0 < run.total_timesteps < run.eval_interval:
        warnings.warn(
            f"run.eval_interval ({run.eval_interval}) is past the run's {run.total_timesteps}"
            " steps: it never validates (no evaluations.csv rows, no best_policy.safetensors)",
            stacklevel=2,
        )


def _warn_validation_dominates(config: Any) -> None:
    """Warn where the run's validations would play more episodes than the run trains steps
    (each episode is many steps, each validation on the weights of one moment): ``--preset
    data8x --steps 400`` scaled the preset's interval to 13 steps, and its 30 validations
    of 200 episodes took most of the run's time, the first ones on weights not yet updated.
    A preset at its own length plays far fewer (``data8x``: 6,000 episodes in 240,000
    steps; ``quickstart``: 400 in 40,000; ``paper`` does not validate)."""
    run = config.run
    if not 0 < run.eval_interval <= run.total_timesteps:
        return  # no validation (or none before the run's end: _warn_never_validated)
    validations = run.total_timesteps // run.eval_interval
    episodes = validations * run.eval_episodes
    if episodes > run.total_timesteps:
        warnings.warn(
            f"run.eval_interval ({run.eval_interval}) and run.eval_episodes"
            f" ({run.eval_episodes}): {validations} validations play {episodes} episodes, more"
            f" than the run's {run.total_timesteps} steps, and take most of its time (--set"
            " eval_interval=N for fewer validations, eval_episodes=N for fewer episodes each)",
            stacklevel=2,
        )


def _warn_never_updated(config: Any) -> None:
    """Warn where ``learner.learning_starts`` is past the run's end (DDQN, SAC, TD3):
    ``--preset paper --steps 600`` kept the preset's 1,000 steps of random play before the
    first update, so it never updated its network, unsaid."""
    starts, total = config.learner.learning_starts, config.run.total_timesteps
    if config.algo in ("ddqn", "sac", "td3") and 0 < total <= starts:
        warnings.warn(
            f"learner.learning_starts ({starts}) is not before the run's end ({total} steps):"
            " it never updates its network (--set learning_starts=N to start sooner)",
            stacklevel=2,
        )


def _warn_never_synced(config: Any) -> None:
    """Warn where DDQN's target network would never be synced before the run's end: the
    first sync is the first multiple of ``learner.target_update_interval`` after
    ``learning_starts`` (``training.trainer``), and ``--preset paper --steps 5000`` kept the
    paper's 10,000, so the run learned against its random initial target throughout,
    unsaid. (A run that never updates at all has :func:`_warn_never_updated`'s line.)"""
    learner, total = config.learner, config.run.total_timesteps
    interval, starts = learner.target_update_interval, learner.learning_starts
    first = (starts // interval + 1) * interval
    if config.algo == "ddqn" and starts < total <= first:
        warnings.warn(
            f"learner.target_update_interval ({interval}) first syncs the target network at"
            f" step {first}, not before the run's end ({total} steps): it is never updated"
            " (--set target_update_interval=N for a shorter one)",
            stacklevel=2,
        )


def _warn_busy_machine(num_threads: int, *, resuming: bool = False) -> None:
    """Warn where the run's threads would wait on cores other processes keep busy."""
    from activevision.training.cpu import busy_machine_note

    note = busy_machine_note(num_threads, resuming=resuming)
    if note is not None:
        warnings.warn(note, stacklevel=2)


def _refuse_set_beside(overrides: list[str], options: Mapping[str, str]) -> None:
    """ValueError where a ``--set`` key sets the field (full path -> option) that an option
    given sets too: the option's value was taken and the ``--set`` one dropped silently
    (``--set total_timesteps=5000 --steps 100`` trained 100 steps)."""
    from activevision.training.config import config_path, field_paths, parse_overrides

    paths = field_paths()
    for key in parse_overrides(overrides):
        path = config_path(key, paths)
        if options.get(path):
            raise ValueError(
                f"--set {key}=... and {options[path]} both set {path}: give it with"
                f" {options[path]} alone"
            )


def _nothing_trained(run_dir: Path) -> bool:
    """A run that failed before its first checkpoint and before it logged anything (no
    episode ended): its folder holds only the config and empty logs. One that played and
    failed later, even within its first epoch, keeps its logs to show what happened."""
    from activevision.training.checkpoint import list_checkpoints
    from activevision.training.loggers import EPISODES_CSV, EVALUATIONS_CSV, METRICS_CSV

    def logged(name: str) -> bool:
        log = run_dir / name
        return log.is_file() and len(log.read_bytes().splitlines()) > 1

    csvs = (METRICS_CSV, EPISODES_CSV, EVALUATIONS_CSV)
    return not list_checkpoints(run_dir) and not any(logged(n) for n in csvs)


def cmd_plot(args: argparse.Namespace) -> None:
    from activevision.training import plot_run

    if args.run.is_file():  # "RUN/metrics.csv is not a training run (no config.json...)"
        raise ValueError(not_a_run(args.run, ""))
    if not is_training_run(args.run):
        # name what is missing: a run's config.json alone read "no config.json and metrics.csv"
        missing = [n for n in ("config.json", "metrics.csv") if not (args.run / n).is_file()]
        raise ValueError(f"{args.run} is not a training run (no {' and no '.join(missing)})")
    for log in ("metrics.csv", "episodes.csv"):  # episodes.csv: a bare "[Errno 2] ..."
        if not (args.run / log).is_file():
            raise ValueError(f"{args.run} has no {log} (its training log): nothing to plot")
    _check_run_folders(args.run, ("plots",))
    print(f"wrote {plot_run(args.run)}")


#: the folders of a run that train writes, and what each holds
_RUN_FOLDERS = {
    "plots": "the run's figures are drawn there",
    "checkpoints": "the run's checkpoints are written there",
    "tensorboard": "the run's TensorBoard events are written there (run.tensorboard is true)",
}


def _check_run_folders(run_dir: Path | None, names: Sequence[str]) -> None:
    """OutputError where one of ``names`` in ``run_dir``, a folder train writes, is a file:
    ``[Errno 17] File exists`` once the run had written its config and logs (``plots``:
    once it had trained), with or without ``--overwrite``, which replaces files by files
    (as every command's: a file where a folder goes is never removed)."""
    for name in names:
        folder = None if run_dir is None else run_dir / name
        if folder is not None and folder.exists() and not folder.is_dir():
            raise OutputError(f"{folder} is a file, not a directory: {_RUN_FOLDERS[name]}")


def cmd_sweep(args: argparse.Namespace) -> None:
    """Run a Ray Tune sweep; print a line per trial that ends and where the outputs went.
    Trials that failed end it with an error (exit code 2) after the outputs of the others."""
    from activevision.scaleout.sweep import (
        UNFINISHED_WARNING,
        check_trials_finished,
        checked_base,
        checked_grid,
        sweep,
    )
    from activevision.training import load_config, preset
    from activevision.training.config import parse_overrides

    def ended(trial: Mapping[str, Any]) -> None:
        status = "finished" if trial["status"] == "TERMINATED" else "failed"
        print(f"trial {trial['ended']}/{trial['trials']} {status}: {trial['name']}", flush=True)

    config = load_config(args.config) if args.config else preset(args.preset or "paper")
    overrides = parse_overrides(args.set or [])
    # each trial's seed is one of --seeds: a --set seed was dropped
    _refuse_set_beside(list(args.set or []), {"seed": "--seeds"})
    grid = checked_grid(args.grid or [], overrides)
    config = checked_base(config, overrides, grid)
    _refuse_aux_without_target(config)
    with warnings.catch_warnings():
        # the command ends with one error line on failed trials (check_trials_finished)
        warnings.filterwarnings("ignore", message=UNFINISHED_WARNING)
        rows = sweep(
            config,
            args.seeds,
            grid,
            args.out,
            address=args.address,
            num_cpus=args.num_cpus,
            max_failures=args.max_failures,
            cpus_per_trial=args.cpus_per_trial,
            verbose=1 if args.verbose else 0,
            progress=ended,
        )
    print(f"{len(rows)} aggregated rows")
    print(f"wrote {args.out}/trials.csv" + (", sweep.csv and sweep.png" if rows else ""))
    check_trials_finished(args.out)


def _sweep_interrupted(args: argparse.Namespace) -> str:
    """What an interrupted ``sweep`` can do next: its trials resume from their checkpoints."""
    return f"; the same command again resumes its trials in {args.out}"


def _add_config_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--config", type=path, help="TrainConfig JSON file (instead of --preset)")
    p.add_argument(
        "--preset",
        type=choice_list(_preset_names),
        help="a named config (default: paper): "
        + "; ".join(f"{name}: {text}" for name, text in _preset_help().items()),
    )
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="override a config value: learner.learning_rate=1e-3, env.step_deg=4, or a unique"
        " field name (learning_rate=1e-3); values are JSON",
    )


def add_parsers(sub: Any) -> None:
    text = "train a head controller (DDQN + PER, DAgger, SAC/TD3/PPO)"
    p = sub.add_parser(
        "train",
        help=text,
        description=text + " from a preset, a config file and --set changes; writes"
        " config.json, the logs, the weights, checkpoints/ and plots/ in --out (--resume RUN"
        " goes on from its last checkpoint)",
    )
    p.set_defaults(func=cmd_train, interrupted=_interrupted)
    _add_config_arguments(p)
    p.add_argument(
        "--algo",
        choices=("ddqn", "dagger", "sac", "td3", "ppo"),
        help="ddqn: the paper's DDQN + PER; dagger: imitate the oracle; sac, td3, ppo:"
        " Stable-Baselines3's, for continuous moves (--set env.action_type=continuous; PPO"
        " also discrete) (default: the config's)",
    )
    p.add_argument(
        "--steps",
        type=positive_int,
        help="total environment steps; with --resume: at most this many more",
    )
    p.add_argument("--seed", type=seed)
    p.add_argument("--out", type=path, help="run directory, e.g. runs/NAME")
    p.add_argument("--resume", type=path, metavar="RUN", help="continue runs/NAME")
    add_overwrite(p)

    text = "draw a run's training figures"
    p = sub.add_parser("plot", help=text, description=text + ": RUN/plots/*.png, redrawn")
    p.set_defaults(func=cmd_plot)
    p.add_argument("run", type=path, help="a training run's folder")

    text = "seed x grid sweep of training runs on Ray Tune (pip install activevision[ray])"
    p = sub.add_parser("sweep", help=text, description=text)
    p.set_defaults(func=cmd_sweep, interrupted=_sweep_interrupted)
    p.add_argument(
        "--seeds", type=seed_list, default="0..4", help="0..9 (inclusive) or 0,1,2 (default 0..4)"
    )
    p.add_argument(
        "--grid",
        action="append",
        type=grid_item,
        metavar="KEY=V1,V2",
        help="sweep a config key (repeatable)",
    )
    _add_config_arguments(p)
    p.add_argument("--out", type=path, required=True, help="sweep directory, e.g. runs/SWEEP")
    p.add_argument("--address", help="join a Ray cluster: auto | ray://HEAD:10001")
    p.add_argument("--num-cpus", type=positive_int, help="CPUs of the local Ray instance")
    p.add_argument("--cpus-per-trial", type=positive_float, default=1.0)
    p.add_argument(
        "--max-failures",
        type=int_in(0, 100),
        default=2,
        help="restarts of a failed trial (default 2)",
    )
    p.add_argument(
        "--verbose",
        action="store_true",
        help="print Ray Tune's status tables and Ray's log of each trial (default: a line per"
        " trial that ends)",
    )
