"""Continuous head control (``action_type="continuous"``, the paper's future work) in both
environments: the Gymnasium contract, the move scaled by ``max_move_deg``, the same rules as
discrete moves, every vectorizer, and bad actions."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import activevision.envs  # noqa: F401  (registers the envs)
from activevision.envs import ActiveVisionEnv, EnvConfig

CONTINUOUS = {"action_type": "continuous"}


@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
def test_gymnasium_env_checker(env_id):
    env = gym.make(env_id, **CONTINUOUS)
    assert env.action_space == gym.spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
    check_env(env.unwrapped, skip_render_check=True)


def test_a_full_action_moves_max_move_deg():
    env = ActiveVisionEnv(action_type="continuous", max_move_deg=(8.0, 4.0))
    _, info = env.reset(seed=3)
    pan, tilt = info["head"]
    *_, info = env.step(np.array([-0.5, 1.0], dtype=np.float32))
    expected_tilt = min(tilt + math.radians(4.0), math.radians(65.0))
    np.testing.assert_allclose(info["head"], [pan - math.radians(4.0), expected_tilt], atol=1e-12)


def test_continuous_moves_follow_the_discrete_rules():
    """The continuous action equal to a discrete move (3 deg = 0.3 of 10 deg) gives the same
    episode: head angles to rounding, the same rewards, ends and outcomes."""
    discrete = ActiveVisionEnv()
    continuous = ActiveVisionEnv(action_type="continuous")
    as_continuous = {1: (0.3, 0.0), 2: (-0.3, 0.0), 3: (0.0, -0.3), 4: (0.0, 0.3)}
    rng = np.random.default_rng(0)
    for seed in range(5):
        _, a = discrete.reset(seed=seed)
        _, b = continuous.reset(seed=seed)
        for _ in range(20):
            action = int(rng.integers(1, 5))
            _, ra, ta, _, a = discrete.step(action)
            _, rb, tb, _, b = continuous.step(np.array(as_continuous[action], dtype=np.float32))
            np.testing.assert_allclose(a["head"], b["head"], atol=1e-12)
            assert (ra, ta, a["success"], a["ball_lost"]) == (rb, tb, b["success"], b["ball_lost"])
            if ta:
                break


def test_moving_towards_the_goal_earns_plus_one():
    env = ActiveVisionEnv(action_type="continuous")
    for seed in range(10):
        _, info = env.reset(seed=seed)
        direction = np.degrees(np.asarray(info["goal_viewpoint"]) - info["head"])
        action = np.clip(direction / 10.0, -1, 1).astype(np.float32) * 0.5
        _, reward, _, _, info = env.step(action)
        assert reward == 1.0 or info["ball_lost"], (seed, reward)


@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
@pytest.mark.parametrize("mode", ["sync", "async"])
def test_every_vectorizer_agrees_with_the_native_one(env_id, mode):
    n, steps = 3, 25
    actions = np.random.default_rng(1).uniform(-1, 1, (steps, n, 2)).astype(np.float32)
    kwargs = {**CONTINUOUS, **({"ticks": 10} if "Match" in env_id else {})}
    native = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    other = gym.make_vec(env_id, num_envs=n, vectorization_mode=mode, **kwargs)
    try:
        a, b = native.reset(seed=7), other.reset(seed=7)
        np.testing.assert_array_equal(a[0], b[0])
        for step in actions:
            a, b = native.step(step), other.step(step)
            for x, y in zip(a[:4], b[:4], strict=True):
                np.testing.assert_array_equal(x, y)
            np.testing.assert_array_equal(a[4]["head"], b[4]["head"])
    finally:
        native.close()
        other.close()


@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
@pytest.mark.parametrize(
    "action",
    [
        np.array([1.5, 0.0]),
        np.array([np.nan, 0.0]),
        np.array([0.1, 0.2, 0.3]),
        3,
        "left",
        None,
        # NumPy reads these as numbers: the strings parsed, the imaginary part dropped
        ["0.5", "0.1"],
        np.array([0.5j, 0.0]),
    ],
)
def test_bad_actions_are_one_clear_error(env_id, action):
    env = gym.make(env_id, **CONTINUOUS).unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match="invalid action"):
        env.step(action)


def test_bad_continuous_config():
    with pytest.raises(ValueError, match="max_move_deg"):
        EnvConfig(max_move_deg=(0.0, 10.0))
    with pytest.raises(ValueError, match="action_history"):
        EnvConfig(action_type="continuous", observation="image+head", action_history=2)
    with pytest.raises(ValueError, match="action_type"):
        EnvConfig(action_type="analog")
    with pytest.raises(ValueError, match="max_move_deg"):
        gym.make("ActiveVisionMatch-v0", action_type="continuous", max_move_deg=(100.0, 5.0))
