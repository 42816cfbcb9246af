"""The ActiveVision Gymnasium environments (registered as ``ActiveVision-v0`` by
``import activevision``, see :mod:`activevision.registration`)."""

from activevision.envs.active_vision import ActiveVisionEnv
from activevision.envs.config import EnvConfig
from activevision.envs.vector import ActiveVisionVectorEnv
from activevision.registration import ENV_ID, register_envs

register_envs()

__all__ = ["ENV_ID", "ActiveVisionEnv", "ActiveVisionVectorEnv", "EnvConfig"]
