"""Registers activevision's environments with Gymnasium.

``import activevision`` calls :func:`register_envs`, as ale_py and minigrid do, so
``gymnasium.make("activevision:ActiveVision-v0")`` works. Registration names the entry points
as strings: nothing heavy (numba, the renderer, torch) is imported until an env is made.
"""

from __future__ import annotations

ENV_ID = "ActiveVision-v0"
MATCH_ENV_ID = "ActiveVisionMatch-v0"


def register_envs() -> None:
    """Register ``ActiveVision-v0`` and ``ActiveVisionMatch-v0`` (single and native vector
    entry points) once."""
    try:
        from gymnasium.envs.registration import register, registry
    except ImportError:  # the robot runtime needs no Gymnasium
        return
    # Without Gymnasium's passive env checker: the tests run the full ``check_env`` on both
    # envs, and the checker (Gymnasium 1.4) breaks an env for good once its first reset
    # raises (a bad seed or option): every later step fails inside the checker.
    if ENV_ID not in registry:
        register(
            id=ENV_ID,
            entry_point="activevision.envs.active_vision:ActiveVisionEnv",
            vector_entry_point="activevision.envs.vector:ActiveVisionVectorEnv",
            max_episode_steps=20,
            disable_env_checker=True,
        )
    if MATCH_ENV_ID not in registry:
        # no max_episode_steps: the match truncates itself after MatchConfig.ticks
        register(
            id=MATCH_ENV_ID,
            entry_point="activevision.envs.match.env:ActiveVisionMatchEnv",
            vector_entry_point="activevision.envs.match.vector:ActiveVisionMatchVectorEnv",
            disable_env_checker=True,
        )
