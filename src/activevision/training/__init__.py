"""Training runs: configuration, the DDQN + prioritised-replay loop, checkpoints, metrics, plots.

Modules: ``config`` (TrainConfig), ``trainer`` (the loop), ``build`` (what a config builds),
``state`` (checkpoint state and I/O over ``checkpoint``), ``policy_files`` (``load_policy``),
``loggers`` (CSV and TensorBoard), ``aux_targets`` (the auxiliary head's target),
``dagger`` (imitation of the oracle, ``algo="dagger"``), ``match_dagger`` (of the match
planner), ``sb3_learners`` (SAC, TD3, PPO), ``runs`` (``train``, ``resume``: a run's
trainer, whichever ``algo``), ``environment``, ``metrics``, ``validation``, ``plots``.

Typical use::

    from activevision.training import TrainConfig, load_policy, plot_run, preset, resume, train

    config = TrainConfig().replace(**{"env.frame_stack": 1, "run.total_timesteps": 30_000})
    train(config, "runs/paper")                 # DDQN: or Trainer(config, "runs/paper").train()
    train(preset("dagger_head"), "runs/head")   # any algo; resume("runs/head") continues it
    policy = load_policy("runs/paper")          # QNetwork, eval mode
    plot_run("runs/paper")                      # training.png and one PNG per curve
"""

import importlib
from typing import TYPE_CHECKING, Any

# Lazy exports (PEP 562): ``activevision.training.config`` and its presets stay importable
# without loading torch (the CLI builds its help from them); the rest loads on first use.
_EXPORTS = {
    "CheckpointError": "checkpoint",
    "CsvLogger": "loggers",
    "Logger": "loggers",
    "TensorBoardLogger": "loggers",
    "TrainerState": "state",
    "TrainConfig": "config",
    "apply_overrides": "config",
    "load_config": "config",
    "preset": "presets",
    "save_config": "config",
    "plot_run": "plots",
    "Trainer": "trainer",
    "DaggerTrainer": "dagger",
    "reopen_run": "runs",
    "goal_offset": "aux_targets",
    "load_policy": "policy_files",
    "make_env": "environment",
    "resume": "runs",
    "start_run": "runs",
    "train": "runs",
}

if TYPE_CHECKING:
    from activevision.training.aux_targets import goal_offset
    from activevision.training.checkpoint import CheckpointError
    from activevision.training.config import (
        TrainConfig,
        apply_overrides,
        load_config,
        save_config,
    )
    from activevision.training.dagger import DaggerTrainer
    from activevision.training.environment import make_env
    from activevision.training.loggers import CsvLogger, Logger, TensorBoardLogger
    from activevision.training.plots import plot_run
    from activevision.training.policy_files import load_policy
    from activevision.training.presets import preset
    from activevision.training.runs import reopen_run, resume, start_run, train
    from activevision.training.state import TrainerState
    from activevision.training.trainer import Trainer


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)


__all__ = [
    "CheckpointError",
    "CsvLogger",
    "DaggerTrainer",
    "Logger",
    "TensorBoardLogger",
    "TrainConfig",
    "Trainer",
    "TrainerState",
    "apply_overrides",
    "goal_offset",
    "load_config",
    "load_policy",
    "make_env",
    "plot_run",
    "preset",
    "reopen_run",
    "resume",
    "save_config",
    "start_run",
    "train",
]
