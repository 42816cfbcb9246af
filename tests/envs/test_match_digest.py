"""Same seeds, same bytes for ``ActiveVisionMatch-v0``'s default world (no other robots):
observations, rewards and infos of the single and the native vector env against digests
stored on 2026-12-05, before our robot learned to give way to the others. A change to the
match physics must leave the empty field's matches unchanged; a change that is meant to
alter them must say so and store new digests."""

from __future__ import annotations

import hashlib

import gymnasium as gym
import numpy as np
import pytest

import activevision.envs  # noqa: F401  (registers ActiveVisionMatch-v0)
from activevision.envs.match.config import BallConfig, MatchConfig, WalkConfig

STORED = {
    "single": "6aed945434d4caa2d769a3ea9dc512705a0e2c28e6fb77962bb152447297996c",
    "vector": "87bcabd2c454f3930f07efcc981ea2c1264641d95efa820f63dee6fc2478c5c2",
    "striker": "e944a0ee9f4e29ca7eee2b0dfd991731d269278750f0b4770fd9cf03ac3783f9",
}

#: our robot walking onto the ball, which bounces off it: the empty field's other walk
STRIKER = MatchConfig(
    observation="image+head+belief",
    ticks=40,
    walk=WalkConfig(target="ball", ball_standoff=0.0),
    ball=BallConfig(kick_rate=0.05, bounces_off_own_robot=True),
)


def _feed(sha, *arrays) -> None:
    for a in arrays:
        if isinstance(a, dict):
            for key in sorted(a):
                _feed(sha, a[key])
            continue
        a = np.ascontiguousarray(a)
        sha.update(str(a.dtype).encode() + str(a.shape).encode() + a.tobytes())


def _info(sha, info: dict) -> None:
    for key in sorted(info):
        if not key.startswith("_"):
            _feed(sha, np.asarray(info[key]))


def single_digest(steps: int = 70, **kwargs) -> str:
    """One env over ``steps`` ticks, reset with a new seed at each truncation."""
    env = gym.make("ActiveVisionMatch-v0", **kwargs)
    rng = np.random.default_rng(7)
    sha = hashlib.sha256()
    obs, info = env.reset(seed=11)
    _feed(sha, obs)
    _info(sha, info)
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(int(rng.integers(9)))
        _feed(sha, obs, np.float64(reward), np.bool_(terminated), np.bool_(truncated))
        _info(sha, info)
        if terminated or truncated:
            obs, info = env.reset(seed=int(rng.integers(2**31 - 1)))
            _feed(sha, obs)
            _info(sha, info)
    env.close()
    return sha.hexdigest()


def vector_digest(steps: int = 50, num_envs: int = 4, **kwargs) -> str:
    """The native vector env over ``steps`` ticks (autoresets included)."""
    env = gym.make_vec(
        "ActiveVisionMatch-v0", num_envs=num_envs, vectorization_mode="vector_entry_point", **kwargs
    )
    rng = np.random.default_rng(3)
    sha = hashlib.sha256()
    obs, info = env.reset(seed=5)
    _feed(sha, obs)
    _info(sha, info)
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(rng.integers(9, size=num_envs))
        _feed(sha, obs, reward, terminated, truncated)
        _info(sha, info)
    env.close()
    return sha.hexdigest()


@pytest.mark.parametrize(
    ("name", "digest"),
    [
        ("single", lambda: single_digest(observation="image+head+belief", ticks=40)),
        ("vector", lambda: vector_digest(ticks=30)),
        ("striker", lambda: single_digest(config=STRIKER)),
    ],
    ids=["single", "vector", "striker"],
)
def test_default_world_matches_the_stored_digest(name, digest):
    assert digest() == STORED[name]
