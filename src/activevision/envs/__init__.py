"""The ActiveVision Gymnasium environments (registered as ``ActiveVision-v0`` by
``import activevision``, see :mod:`activevision.registration`).

The env classes load on first use (PEP 562), so ``activevision.envs.config`` (read by the
training presets and the CLI's help) stays as light as the geometry it builds on."""

import importlib
from typing import TYPE_CHECKING, Any

from activevision.registration import ENV_ID, register_envs

register_envs()

_EXPORTS = {
    "ActiveVisionEnv": "active_vision",
    "ActiveVisionVectorEnv": "vector",
    "EnvConfig": "config",
}

if TYPE_CHECKING:
    from activevision.envs.active_vision import ActiveVisionEnv
    from activevision.envs.config import EnvConfig
    from activevision.envs.vector import ActiveVisionVectorEnv


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)


__all__ = ["ENV_ID", "ActiveVisionEnv", "ActiveVisionVectorEnv", "EnvConfig"]
