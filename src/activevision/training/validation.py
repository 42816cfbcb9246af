"""Greedy validation during training (Stable-Baselines3's ``EvalCallback``).

Every ``eval_interval`` steps the trainer plays ``eval_episodes`` fixed-seed episodes with the
greedy policy (no exploration) on an environment of its own, logs their mean to
``evaluations.csv`` and keeps the weights that scored best in ``best_policy.safetensors``.
DQN's greedy policy changes with every update, so the last weights of a run are not always
its best ones; choosing by validation episodes that differ from the test episodes keeps the
test score honest.

The validation episodes are those of ``activevision evaluate --seed eval_seed`` (seeds from
:func:`activevision.envs.seeding.episode_seed`); the test figures of the README and docs/
use seed 0.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from activevision.envs.match.config import MatchConfig
from activevision.envs.match.scores import MatchScores
from activevision.training.config import TrainConfig
from activevision.training.metrics import episode_record, nan_mean

#: columns of ``evaluations.csv``
EVALUATION_FIELDS = ("step", "episodes", "success_rate", "success", "episode_reward", "best")
#: columns of a match run's ``evaluations.csv`` (a match has no success; best by reward)
MATCH_EVALUATION_FIELDS = (
    "step",
    "episodes",
    "position_rmse",
    "ball_in_view",
    "episode_reward",
    "best",
)


def evaluation_fields(config: TrainConfig) -> tuple[str, ...]:
    """The ``evaluations.csv`` columns of a run of ``config``: a match run's (DDQN or the
    match student), or the episodes'."""
    return MATCH_EVALUATION_FIELDS if config.on_match else EVALUATION_FIELDS


def validation_score(config: TrainConfig) -> str:
    """The column that picks a run's best weights: a match run's mean reward (a match has
    no success: a DDQN run on the match kept its first validation's weights, all scoring a
    success rate of 0), else the success rate."""
    return "episode_reward" if config.on_match else "success_rate"


def greedy_episodes(
    q_values: Callable[[np.ndarray], np.ndarray],
    env: Any,
    seeds: list[int],
    obs_shape: tuple[int, ...],
    max_steps: int = 10_000,
    match: MatchConfig | None = None,
) -> list[dict[str, float]]:
    """Play one greedy episode from each seed; one ``episodes.csv``-style record each, or
    with ``match`` (the config of ``env``, ActiveVisionMatch-v0) one match's total
    ``reward`` and the metrics of :mod:`activevision.envs.match.scores`.

    ``max_steps`` guards against environments without a time limit.
    """
    records = []
    for number, seed in enumerate(seeds):
        obs, info = env.reset(seed=int(seed))
        scores = None if match is None else MatchScores(match.ticks, 1, match.tick_seconds)
        reward_sum, length = 0.0, 0
        while length < max_steps:
            action = int(np.argmax(q_values(np.asarray(obs, np.uint8).reshape(obs_shape))))
            obs, reward, terminated, truncated, info = env.step(action)
            reward_sum += float(reward)
            length += 1
            if scores is not None:
                scores.add(info, np.array([float(reward)]))
            if terminated or truncated:
                break
        if scores is None:
            records.append(episode_record(number, length, reward_sum, length, info))
        else:
            per_match = {name: float(value[0]) for name, value in scores.per_match().items()}
            records.append({"reward": reward_sum, **per_match})
    return records


def summarise_validation(
    step: int,
    records: Sequence[Mapping[str, float]],
    best_before: float,
    fields: Sequence[str] = EVALUATION_FIELDS,
    score: str = "success_rate",
) -> dict[str, float]:
    """The ``evaluations.csv`` row (``fields``) of one validation: the records' mean of each
    field (``episode_reward``: of their ``reward``); ``best`` is 1 if its ``score`` beat
    ``best_before``."""
    row: dict[str, float] = {"step": step, "episodes": len(records)}
    for name in fields:
        if name not in ("step", "episodes", "best"):
            key = "reward" if name == "episode_reward" else name
            row[name] = nan_mean([r[key] for r in records])
    row["best"] = int(row[score] > best_before)
    return row
