"""The terminal progress bar of a training run (tqdm; only on a terminal, if enabled): every
learner's (DDQN's steps, DAgger's rounds, Stable-Baselines3's callback steps)."""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from typing import Any

from activevision.training.config import SB3_ALGORITHMS, TrainConfig


def progress_bar(config: TrainConfig, start: int, end: int) -> Any:
    """A tqdm bar from step ``start`` to ``end``; disabled unless ``run.progress_bar`` is set
    and stderr is a terminal."""
    from tqdm.auto import tqdm

    enabled = config.run.progress_bar and sys.stderr.isatty()
    return tqdm(total=end, initial=start, disable=not enabled, unit="step", dynamic_ncols=True)


def advance(bar: Any, step: int) -> None:
    """Move ``bar`` on to ``step``, at most to its end: DAgger's whole rounds and PPO's whole
    rollouts pass the run's last step."""
    shown = min(step, bar.total)
    if shown > bar.n:
        bar.update(shown - bar.n)


def postfix(row: Mapping[str, float], algo: str = "ddqn") -> dict[str, str]:
    """The bar's summary of an epoch row: ``epsilon`` is DDQN's exploration rate ("eps"),
    DAgger's teacher share ("teacher"), and an SB3 learner's unused 0 (left out); a match
    has no success (left out)."""
    shown = {
        "success": f"{row['success_rate']:.2f}",
        "reward": f"{row['episode_reward']:.2f}",
        "loss": f"{row['loss']:.4f}",
        "eps": f"{row['epsilon']:.2f}",
        "sps": f"{row['steps_per_s']:.0f}",
    }
    if math.isnan(row["success_rate"]):
        del shown["success"]
    if algo == "dagger":
        shown["teacher"] = shown.pop("eps")
        shown["sps"] = shown.pop("sps")  # keep the rate last
    elif algo in SB3_ALGORITHMS:
        del shown["eps"]
    return shown


__all__ = ["advance", "postfix", "progress_bar"]
