"""Greedy validation during training (Stable-Baselines3's ``EvalCallback``).

Every ``eval_interval`` steps the trainer plays ``eval_episodes`` fixed-seed episodes with the
greedy policy (no exploration) on an environment of its own, logs their mean to
``evaluations.csv`` and keeps the weights that scored best in ``best_policy.safetensors``.
DQN's greedy policy changes with every update, so the last weights of a run are not always
its best ones; choosing by validation episodes that differ from the test episodes keeps the
test score honest.

The validation episodes are those of ``activevision evaluate --seed eval_seed`` (seeds from
:func:`activevision.envs.seeding.episode_seed`); the README's test figures use seed 0.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from activevision.training.metrics import episode_record, nan_mean

#: columns of ``evaluations.csv``
EVALUATION_FIELDS = ("step", "episodes", "success_rate", "success", "episode_reward", "best")


def greedy_episodes(
    q_values: Callable[[np.ndarray], np.ndarray],
    env: Any,
    seeds: list[int],
    obs_shape: tuple[int, ...],
    max_steps: int = 10_000,
) -> list[dict[str, float]]:
    """Play one greedy episode from each seed; one ``episodes.csv``-style record each.

    ``max_steps`` guards against environments without a time limit.
    """
    records = []
    for number, seed in enumerate(seeds):
        obs, info = env.reset(seed=int(seed))
        reward_sum, length = 0.0, 0
        while length < max_steps:
            action = int(np.argmax(q_values(np.asarray(obs, np.uint8).reshape(obs_shape))))
            obs, reward, terminated, truncated, info = env.step(action)
            reward_sum += float(reward)
            length += 1
            if terminated or truncated:
                break
        records.append(episode_record(number, length, reward_sum, length, info))
    return records


def summarise_validation(
    step: int, records: Sequence[Mapping[str, float]], best_before: float
) -> dict[str, float]:
    """The ``evaluations.csv`` row of one validation; ``best`` is 1 if it beat ``best_before``."""
    success_rate = nan_mean([r["success_rate"] for r in records])
    return {
        "step": step,
        "episodes": len(records),
        "success_rate": success_rate,
        "success": nan_mean([r["success"] for r in records]),
        "episode_reward": nan_mean([r["reward"] for r in records]),
        "best": int(success_rate > best_before),
    }
