"""The training environment: how a run makes it, and what the trainer needs of it."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from activevision.training.aux_targets import is_active_vision
from activevision.training.config import MATCH_ENV_ID, TrainConfig

#: builds a run's environment (the trainer calls it for training and for validation)
EnvFactory = Callable[[], gym.Env]


def make_env(config: TrainConfig) -> gym.Env:
    """``gymnasium.make(config.env_id)``; activevision's own envs get their config
    (``config.env``, or ``config.match`` for the match env)."""
    kwargs: dict[str, Any] = {}
    if is_active_vision(config.env_id):
        kwargs = {"config": config.env}
    elif config.env_id.removeprefix("activevision:") == MATCH_ENV_ID:
        kwargs = {"config": config.match}
    try:
        return gym.make(config.env_id, **kwargs)
    except gym.error.Error as error:  # e.g. NameNotFound: one clear line, not a traceback
        raise ValueError(f"env_id {config.env_id!r}: {error}") from None


def check_env_id(config: TrainConfig) -> None:
    """ValueError naming ``config.env_id`` where Gymnasium registers no such env, before a
    run is set up (``make_env`` would say so only once the run's folder, notes and warnings
    were written). A ``module:`` prefix is imported first, as ``gymnasium.make`` does."""
    module, _, name = config.env_id.rpartition(":")
    try:
        if module:
            importlib.import_module(module)
        gym.spec(name)
    except (gym.error.Error, ImportError) as error:
        raise ValueError(f"env_id {config.env_id!r}: {error}") from None


def discrete_actions(env: gym.Env) -> int:
    """The number of actions of ``env``; ValueError unless its action space is Discrete."""
    if not isinstance(env.action_space, gym.spaces.Discrete):
        raise ValueError(f"need a Discrete action space, got {env.action_space}")
    return int(env.action_space.n)


def chw_shape(space: gym.Space[Any]) -> tuple[int, int, int]:
    """The (stack, H, W) shape of a uint8 image observation space of shape (H, W) or
    (stack, H, W); ValueError for any other space."""
    if not isinstance(space, gym.spaces.Box) or space.dtype != np.uint8:
        raise ValueError(f"need a uint8 Box observation space, got {space}")
    if len(space.shape) == 2:
        return (1, space.shape[0], space.shape[1])
    if len(space.shape) == 3:
        return (space.shape[0], space.shape[1], space.shape[2])
    raise ValueError(f"observations must be (H, W) or (stack, H, W), got {space.shape}")


__all__ = ["EnvFactory", "chw_shape", "discrete_actions", "make_env"]
