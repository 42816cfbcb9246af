"""Auxiliary targets: what the network's auxiliary head regresses (``learner.aux_goal_weight``).

An auxiliary target is a function of an environment's ``info`` dict (from ``reset`` or
``step``) returning a float vector: the target of the observation returned with that info.
The trainer stores it beside the observation in the replay buffer, and the learner adds the
head's mean squared error, weighted by ``aux_goal_weight``, to the TD loss (an auxiliary
task, Jaderberg et al. 2017). The policy itself acts on the image only.

:func:`goal_offset` is ActiveVision-v0's: the goal viewpoint's (pan, tilt) offset from the
head. Another environment's trainer needs a function of its own (``Trainer(...,
aux_target=f)``); :func:`resolve_aux_target` picks the default or says what is missing.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from activevision.registration import ENV_ID
from activevision.training.config import TrainConfig

#: an auxiliary target: info dict -> float vector (its length is the auxiliary head's)
AuxTarget = Callable[[dict[str, Any]], np.ndarray]

GOAL_OFFSET_DIM = 2


def goal_offset(info: dict[str, Any]) -> np.ndarray:
    """(pan, tilt) from the head to the goal viewpoint, rad: ActiveVision-v0's target."""
    try:
        offset = np.asarray(info["goal_viewpoint"], np.float32) - np.asarray(info["head"])
    except KeyError as error:
        raise ValueError(
            "aux_goal_weight needs an environment whose info holds 'goal_viewpoint' and 'head'"
            f" (as ActiveVision-v0's does); missing {error}"
        ) from error
    target: np.ndarray = offset.astype(np.float32).reshape(GOAL_OFFSET_DIM)
    return target


def is_active_vision(env_id: str) -> bool:
    """Whether ``env_id`` names activevision's own environment (with or without the
    ``activevision:`` module prefix)."""
    return env_id.removeprefix("activevision:") == ENV_ID


def resolve_aux_target(config: TrainConfig, aux_target: AuxTarget | None) -> AuxTarget | None:
    """The auxiliary target a run uses: None without ``aux_goal_weight`` (a given function
    is then unused), else ``aux_target``, else :func:`goal_offset` for ActiveVision-v0.

    Raises ValueError for another environment without a function.
    """
    if not config.learner.aux_goal_weight:
        return None
    if aux_target is not None:
        return aux_target
    if is_active_vision(config.env_id):
        return goal_offset
    raise ValueError(
        f"{no_default_aux_target(config)}: pass Trainer(..., aux_target=f) with f(info) ->"
        " float vector, or set aux_goal_weight=0"
    )


def no_default_aux_target(config: TrainConfig) -> str:
    """Why ``config``'s ``learner.aux_goal_weight`` has no auxiliary target to regress
    without a function of the caller's ("" when it has one, or is 0): the command line's
    refusal (it cannot pass a function), and the start of the library's."""
    weight = config.learner.aux_goal_weight
    if not weight or is_active_vision(config.env_id):
        return ""
    return (
        f"learner.aux_goal_weight={weight} adds a head regressing the goal view's offset from"
        f" the head, which only {ENV_ID}'s episodes have (goal_offset); env_id"
        f" {config.env_id!r} has none"
    )


def aux_vector(aux_target: AuxTarget, info: dict[str, Any]) -> np.ndarray:
    """``aux_target(info)`` as a flat float32 vector; ValueError if it is not finite."""
    values = np.asarray(aux_target(info), dtype=np.float32).reshape(-1)
    if not np.all(np.isfinite(values)):
        raise ValueError(f"the auxiliary target gave non-finite values {values}")
    return values


def aux_dim(aux_target: AuxTarget | None, env: gym.Env, seed: int) -> int:
    """The length of ``aux_target``'s vectors (0 for None), from the info of one
    ``env.reset(seed=seed)``. Training does not notice: every episode starts with a reset to
    a seed of its own."""
    if aux_target is None:
        return 0
    _, info = env.reset(seed=seed)
    return len(aux_vector(aux_target, info))


__all__ = [
    "GOAL_OFFSET_DIM",
    "AuxTarget",
    "aux_dim",
    "aux_vector",
    "goal_offset",
    "is_active_vision",
    "no_default_aux_target",
    "resolve_aux_target",
]
