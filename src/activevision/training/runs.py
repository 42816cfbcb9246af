"""A run directory's trainer, whichever algorithm its ``config.json`` names."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

from activevision.training.config import MATCH_ENV_ID, SB3_ALGORITHMS, load_config
from activevision.training.dagger import DaggerTrainer
from activevision.training.match_dagger import MatchDaggerTrainer
from activevision.training.state import CONFIG_FILE
from activevision.training.trainer import Trainer

if TYPE_CHECKING:
    from activevision.training.sb3_learners import Sb3Trainer


def reopen_run(
    run_dir: str | os.PathLike[str],
) -> Trainer | DaggerTrainer | MatchDaggerTrainer | Sb3Trainer:
    """The trainer of ``run_dir`` rebuilt from its newest checkpoint (``algo`` "ddqn": a
    :class:`Trainer`; "dagger": a :class:`DaggerTrainer` (a :class:`MatchDaggerTrainer`
    on the match env); "sac", "td3", "ppo": an
    :class:`~activevision.training.sb3_learners.Sb3Trainer`)."""
    config = load_config(Path(run_dir) / CONFIG_FILE)
    if config.algo == "dagger" and config.env_id == MATCH_ENV_ID:
        return MatchDaggerTrainer.resume(run_dir)
    if config.algo == "dagger":
        return DaggerTrainer.resume(run_dir)
    if config.algo in SB3_ALGORITHMS:
        from activevision.training.sb3_learners import Sb3Trainer  # SB3 loads only here

        return Sb3Trainer.resume(run_dir)
    return Trainer.resume(run_dir)
