"""A run directory's trainer, whichever algorithm its config names, and the library's
``train`` / ``resume``.

``algo`` "ddqn": a :class:`~activevision.training.trainer.Trainer`; "dagger": a
:class:`~activevision.training.dagger.DaggerTrainer` (a
:class:`~activevision.training.match_dagger.MatchDaggerTrainer` on the match env); "sac",
"td3", "ppo": an :class:`~activevision.training.sb3_learners.Sb3Trainer`. Only DDQN trains
on an environment of the caller's (``env_factory``, ``aux_target``); the others build
their own batched simulations.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from activevision.training.aux_targets import AuxTarget
from activevision.training.config import TrainConfig, load_config
from activevision.training.dagger import DaggerTrainer
from activevision.training.environment import EnvFactory
from activevision.training.loggers import Logger
from activevision.training.match_dagger import MatchDaggerTrainer
from activevision.training.state import CONFIG_FILE
from activevision.training.trainer import Trainer

if TYPE_CHECKING:
    from typing import TypeAlias

    from activevision.training.sb3_learners import Sb3Trainer

    AnyTrainer: TypeAlias = Trainer | DaggerTrainer | MatchDaggerTrainer | Sb3Trainer


def _trainer_class(config: TrainConfig) -> type[DaggerTrainer | MatchDaggerTrainer | Sb3Trainer]:
    if config.match_student:
        return MatchDaggerTrainer
    if config.algo == "dagger":
        return DaggerTrainer
    from activevision.training.sb3_learners import Sb3Trainer  # SB3 loads only here

    return Sb3Trainer


def _check_ddqn_only(
    config: TrainConfig, env_factory: EnvFactory | None, aux_target: AuxTarget | None
) -> None:
    if config.algo != "ddqn" and (env_factory is not None or aux_target is not None):
        raise ValueError(
            f"algo={config.algo!r} builds its own environments: no env_factory or aux_target"
        )


def start_run(
    config: TrainConfig,
    run_dir: str | os.PathLike[str],
    env_factory: EnvFactory | None = None,
    *,
    aux_target: AuxTarget | None = None,
    loggers: Sequence[Logger] | None = None,
) -> AnyTrainer:
    """A new run of ``config`` in ``run_dir`` (which must not hold one already)."""
    _check_ddqn_only(config, env_factory, aux_target)
    if config.algo == "ddqn":
        return Trainer(config, run_dir, env_factory, aux_target=aux_target, loggers=loggers)
    return _trainer_class(config)(config, run_dir, loggers=loggers)


def reopen_run(
    run_dir: str | os.PathLike[str],
    env_factory: EnvFactory | None = None,
    *,
    aux_target: AuxTarget | None = None,
    loggers: Sequence[Logger] | None = None,
) -> AnyTrainer:
    """The trainer of ``run_dir`` rebuilt from its newest checkpoint (verified first)."""
    config = load_config(Path(run_dir) / CONFIG_FILE)
    _check_ddqn_only(config, env_factory, aux_target)
    if config.algo == "ddqn":
        return Trainer.resume(run_dir, env_factory, aux_target=aux_target, loggers=loggers)
    return _trainer_class(config).resume(run_dir, loggers=loggers)


def train(
    config: TrainConfig,
    run_dir: str | os.PathLike[str],
    env_factory: EnvFactory | None = None,
    *,
    aux_target: AuxTarget | None = None,
    loggers: Sequence[Logger] | None = None,
) -> list[dict[str, float]]:
    """Train a fresh run to ``config.run.total_timesteps``; returns its ``metrics.csv`` rows."""
    trainer = start_run(config, run_dir, env_factory, aux_target=aux_target, loggers=loggers)
    try:
        return trainer.train()
    finally:
        trainer.close()


def resume(
    run_dir: str | os.PathLike[str],
    env_factory: EnvFactory | None = None,
    steps: int | None = None,
    *,
    aux_target: AuxTarget | None = None,
    loggers: Sequence[Logger] | None = None,
) -> list[dict[str, float]]:
    """Continue an interrupted run from its newest checkpoint (to the end by default, or
    ``steps`` more); returns this call's ``metrics.csv`` rows."""
    trainer = reopen_run(run_dir, env_factory, aux_target=aux_target, loggers=loggers)
    try:
        return trainer.train(steps)
    finally:
        trainer.close()


__all__ = ["reopen_run", "resume", "start_run", "train"]
