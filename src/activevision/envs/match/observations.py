"""What the match agent observes (``MatchConfig.observation``).

| key      | shape           | contents                                                      |
|----------|-----------------|---------------------------------------------------------------|
| "image"  | (1, H, W) uint8 | the camera image                                              |
| "head"   | (2,) float32    | head joint angles (pan, tilt), rad                            |
| "pose"   | (4,) float32    | the belief's mean (x m, y m, cos theta, sin theta)            |
| "belief" | (3,) float32    | the belief's std in x, y (m) and theta (rad), capped at 10    |
| "ball"   | (3,) float32    | the ball model: position in the robot frame (m), seconds since |
|          |                 | the ball was last seen (capped at 10)                         |

"image+head" has image and head; "image+head+belief" adds pose, belief and ball: everything
a robot's own localisation and ball model give it.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from activevision.envs.match.config import MatchConfig
from activevision.envs.match.simulation import MatchBatch
from activevision.envs.observations import in_space_order
from activevision.runtime.metadata import (  # every vector is clipped to +-VECTOR_BOUND
    OBSERVATION_VECTOR_KEYS,
    VECTOR_BOUND,
)

IMAGE_KEY = "image"
VECTOR_SIZES = {"head": 2, "pose": 4, "belief": 3, "ball": 3}

Observation = np.ndarray | dict[str, np.ndarray]


def vector_keys(cfg: MatchConfig) -> tuple[str, ...]:
    """The Dict observation's vector keys, in the order networks concatenate them."""
    return OBSERVATION_VECTOR_KEYS[cfg.observation]


def image_space(cfg: MatchConfig) -> spaces.Box:
    return spaces.Box(0, 255, (1, cfg.camera.height, cfg.camera.width), dtype=np.uint8)


def observation_space(cfg: MatchConfig) -> spaces.Box | spaces.Dict:
    """The image Box, or the Dict of the image and the vector keys."""
    image = image_space(cfg)
    if cfg.observation == "image":
        return image
    vectors = {
        key: spaces.Box(-VECTOR_BOUND, VECTOR_BOUND, (VECTOR_SIZES[key],), dtype=np.float32)
        for key in vector_keys(cfg)
    }
    return spaces.Dict({IMAGE_KEY: image, **vectors})


def observe(frames: np.ndarray, sim: MatchBatch) -> Observation:
    """Observations of all N slots: ``frames`` (N, 1, H, W) and the slots' state."""
    keys = vector_keys(sim.cfg)
    if not keys:
        return frames.copy()
    known = {
        "head": sim.head,
        "belief_mean": sim.mean,
        "belief_cov": sim.cov,
        "ball_relative": sim.ball_relative,
        "ball_age": sim.ball_age,
    }
    obs: dict[str, np.ndarray] = {IMAGE_KEY: frames.copy()}
    for key in keys:
        obs[key] = knowledge_vector(key, known, sim.cfg.tick_seconds)
    return in_space_order(obs)


def knowledge_vector(key: str, info: dict[str, np.ndarray], tick_seconds: float) -> np.ndarray:
    """The vector ``key`` (N, size) float32 from what the robot knows, as the env's info
    holds it (``head``, ``belief_mean``, ``belief_cov``, ``ball_relative``, ``ball_age``):
    what a match student is fed, in the env and in ``activevision match``."""
    if key == "head":
        value = info["head"]
    elif key == "pose":
        mean = info["belief_mean"]
        value = np.column_stack([mean[:, :2], np.cos(mean[:, 2]), np.sin(mean[:, 2])])
    elif key == "belief":
        value = np.sqrt(np.diagonal(info["belief_cov"], axis1=1, axis2=2))
    elif key == "ball":
        age = info["ball_age"] * tick_seconds
        value = np.column_stack([info["ball_relative"], age])
    else:
        raise ValueError(f"unknown match observation key {key!r}")
    vector: np.ndarray = np.clip(value, -VECTOR_BOUND, VECTOR_BOUND).astype(np.float32)
    return vector


def knowledge_vectors(
    info: dict[str, np.ndarray], keys: tuple[str, ...] | list[str], tick_seconds: float
) -> np.ndarray:
    """A match student's vector input (N, V) float32: the vectors ``keys`` concatenated."""
    return np.concatenate([knowledge_vector(k, info, tick_seconds) for k in keys], axis=1)


def single(obs: Observation, i: int = 0) -> Observation:
    """Slot ``i`` of a batched observation."""
    if isinstance(obs, dict):
        return {k: v[i] for k, v in obs.items()}
    one: np.ndarray = obs[i]
    return one
