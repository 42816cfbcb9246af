"""Episodes for the paper's qualitative figure: :func:`trace_episode` plays one policy and
records every step; :mod:`activevision.figures.episode` draws the traces (``plot_episodes``,
``animate_episode``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from activevision.envs import ActiveVisionEnv, EnvConfig
from activevision.envs.observations import IMAGE_KEY, Observation
from activevision.experiments.evaluate import time_limit
from activevision.experiments.policies import HeadPolicy, HeadTarget
from activevision.figures.episode import EpisodeTrace, Snapshot


def _snapshot(obs: Observation, info: dict[str, Any], reward: float) -> Snapshot:
    pan, tilt = info["head"]
    image: np.ndarray = obs[IMAGE_KEY] if isinstance(obs, dict) else obs
    return Snapshot(
        image[-1].copy(),
        float(pan),
        float(tilt),
        np.flatnonzero(info["observed_mask"]),
        reward,
        info["step"],
    )


def trace_episode(policy: HeadPolicy, seed: int, config: EnvConfig | None = None) -> EpisodeTrace:
    """One episode of ``policy`` from the start ``seed`` draws, step by step."""
    env = ActiveVisionEnv(config or EnvConfig())
    obs, info = env.reset(seed=seed)
    policy.reset(info, np.random.default_rng([seed, 7]))
    shots = [_snapshot(obs, info, 0.0)]
    for _ in range(time_limit(env)):
        action = policy.act(obs, info)
        if isinstance(action, HeadTarget):
            obs, reward, terminated, _, info = env.jump_head(action.pan, action.tilt)
        else:
            obs, reward, terminated, _, info = env.step(action)
        shots.append(_snapshot(obs, info, reward))
        if terminated:
            break
    return EpisodeTrace(
        policy.name,
        info["pose"],
        info["ball"],
        tuple(info["goal_viewpoint"]),
        np.flatnonzero(info["desired_mask"]),
        shots,
        info["success"],
        info["ball_lost"],
        field=env.config.field,
        camera=env.config.camera,
        landmarks=env.sim.landmarks,
        robots=env.sim.robots[0].copy(),
        robot_radius=env.config.robots.radius,
    )
