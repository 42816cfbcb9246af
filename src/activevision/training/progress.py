"""The terminal progress bar of a training run (tqdm; only on a terminal, if enabled)."""

from __future__ import annotations

import sys
from collections.abc import Mapping
from typing import Any

from activevision.training.config import TrainConfig


def progress_bar(config: TrainConfig, start: int, end: int) -> Any:
    """A tqdm bar from step ``start`` to ``end``; disabled unless ``run.progress_bar`` is set
    and stderr is a terminal."""
    from tqdm.auto import tqdm

    enabled = config.run.progress_bar and sys.stderr.isatty()
    return tqdm(total=end, initial=start, disable=not enabled, unit="step", dynamic_ncols=True)


def postfix(row: Mapping[str, float]) -> dict[str, str]:
    """The bar's summary of an epoch row."""
    return {
        "success": f"{row['success_rate']:.2f}",
        "reward": f"{row['episode_reward']:.2f}",
        "loss": f"{row['loss']:.4f}",
        "eps": f"{row['epsilon']:.2f}",
        "sps": f"{row['steps_per_s']:.0f}",
    }


__all__ = ["postfix", "progress_bar"]
