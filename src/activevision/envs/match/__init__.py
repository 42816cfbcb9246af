"""``ActiveVisionMatch-v0``: head control through a whole match, the robot walking and the
ball moving, with the UKF tracking the pose every tick (registered by ``import
activevision``). The classes load on first use, as in :mod:`activevision.envs`."""

import importlib
from typing import TYPE_CHECKING, Any

_EXPORTS = {
    "ActiveVisionMatchEnv": "env",
    "ActiveVisionMatchVectorEnv": "vector",
    "MatchBatch": "simulation",
    "MatchConfig": "config",
}

if TYPE_CHECKING:
    from activevision.envs.match.config import MatchConfig
    from activevision.envs.match.env import ActiveVisionMatchEnv
    from activevision.envs.match.simulation import MatchBatch
    from activevision.envs.match.vector import ActiveVisionMatchVectorEnv


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)


__all__ = ["ActiveVisionMatchEnv", "ActiveVisionMatchVectorEnv", "MatchBatch", "MatchConfig"]
