"""Keyword arguments of ``gymnasium.make("ActiveVision-v0", **kwargs)`` as stored in a
training run's JSON config, checked and turned into an :class:`EnvConfig`."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from activevision.envs.config import EnvConfig

#: Keywords the env takes besides EnvConfig's fields (JSON-representable ones only).
ENV_ONLY_KWARGS = frozenset({"render_mode", "max_episode_steps"})


def env_config_from_kwargs(env_kwargs: Mapping[str, Any]) -> EnvConfig:
    """The EnvConfig that ``env_kwargs`` describe; ValueError naming an unknown keyword or a
    bad value (the same checks as the env's own)."""
    fields = {f.name for f in dataclasses.fields(EnvConfig)}
    unknown = sorted(set(env_kwargs) - fields - ENV_ONLY_KWARGS)
    if unknown:
        raise ValueError(
            f"unknown ActiveVision-v0 keyword(s) {unknown}; EnvConfig fields are"
            f" {sorted(fields)}, plus {sorted(ENV_ONLY_KWARGS)}"
        )
    steps = env_kwargs.get("max_episode_steps", 20)
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise ValueError(f"max_episode_steps must be a positive integer, got {steps!r}")
    mode = env_kwargs.get("render_mode")
    if mode not in (None, "rgb_array"):
        raise ValueError(f"render_mode must be 'rgb_array' or None, got {mode!r}")
    return EnvConfig(**{k: v for k, v in env_kwargs.items() if k in fields})
