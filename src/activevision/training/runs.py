"""A run directory's trainer, whichever algorithm its ``config.json`` names."""

from __future__ import annotations

import os
from pathlib import Path

from activevision.training.config import load_config
from activevision.training.dagger import DaggerTrainer
from activevision.training.state import CONFIG_FILE
from activevision.training.trainer import Trainer


def reopen_run(run_dir: str | os.PathLike[str]) -> Trainer | DaggerTrainer:
    """The trainer of ``run_dir`` rebuilt from its newest checkpoint (``algo`` "ddqn": a
    :class:`Trainer`; "dagger": a :class:`DaggerTrainer`)."""
    config = load_config(Path(run_dir) / CONFIG_FILE)
    if config.algo == "dagger":
        return DaggerTrainer.resume(run_dir)
    return Trainer.resume(run_dir)
