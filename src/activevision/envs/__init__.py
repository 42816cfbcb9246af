"""The ActiveVision Gymnasium environments; importing this module registers
``ActiveVision-v0`` (single and native vector entry points)."""

from gymnasium.envs.registration import register, registry

from activevision.envs.active_vision import ActiveVisionEnv
from activevision.envs.config import EnvConfig
from activevision.envs.vector import ActiveVisionVectorEnv

ENV_ID = "ActiveVision-v0"

if ENV_ID not in registry:
    register(
        id=ENV_ID,
        entry_point="activevision.envs.active_vision:ActiveVisionEnv",
        vector_entry_point="activevision.envs.vector:ActiveVisionVectorEnv",
        max_episode_steps=20,
    )

__all__ = ["ENV_ID", "ActiveVisionEnv", "ActiveVisionVectorEnv", "EnvConfig"]
