"""A small fake camera environment for training tests (ActiveVision-v0 is tested elsewhere)."""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
import pytest


class FakeViewEnv(gym.Env):
    """A 1-D "head pan" task seen through a tiny camera image.

    A hidden pan position in 0..9 and a hidden goal; the image shows a bright column at the pan
    position and a dimmer one at the goal. Action 0 pans left, 1 right, others do nothing.
    Reward +1 for getting closer to the goal, -1 for moving away; success (terminated) at the
    goal, truncated after 20 steps. Deterministic given the reset seed and the actions.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": []}

    def __init__(self, image_shape: tuple[int, int] = (120, 160), n_actions: int = 9) -> None:
        self.image_shape = image_shape
        self.observation_space = gym.spaces.Box(0, 255, (1, *image_shape), dtype=np.uint8)
        self.action_space = gym.spaces.Discrete(n_actions)
        self.pan = 0
        self.goal = 0
        self.steps = 0

    def _obs(self) -> np.ndarray:
        image = self.np_random.integers(0, 30, size=(1, *self.image_shape), dtype=np.uint8)
        width = self.image_shape[1]
        image[0, :, self.pan * width // 10] = 255
        image[0, :, self.goal * width // 10 + 1] = 128
        return image

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.pan, self.goal = (int(v) for v in self.np_random.choice(10, size=2, replace=False))
        self.steps = 0
        return self._obs(), self._angles()

    def _angles(self) -> dict[str, np.ndarray]:
        """Head and goal as (pan, tilt), as ActiveVision-v0 reports them."""
        return {
            "head": np.array([0.1 * self.pan, 0.0]),
            "goal_viewpoint": np.array([0.1 * self.goal, 0.0]),
        }

    def step(self, action: int):
        before = abs(self.pan - self.goal)
        self.pan = int(np.clip(self.pan + {0: -1, 1: 1}.get(int(action), 0), 0, 9))
        self.steps += 1
        after = abs(self.pan - self.goal)
        reward = float(np.sign(before - after))
        terminated = after == 0
        truncated = not terminated and self.steps >= 20
        info: dict[str, Any] = self._angles()
        if terminated or truncated:
            info |= {
                "success": terminated,
                "success_rate": 1.0 if terminated else 1.0 - after / 10.0,
                "steps_to_success": self.steps if terminated else 20,
                "ball_lost_step": 20,
            }
        return self._obs(), reward, terminated, truncated, info


@pytest.fixture
def fake_env_factory():
    """Factory of small fake envs: image (1, 60, 80) keeps the CNN valid and fast."""
    return lambda: FakeViewEnv(image_shape=(60, 80))


@pytest.fixture
def paper_image_env_factory():
    """Factory of fake envs with the paper's (1, 120, 160) images."""
    return lambda: FakeViewEnv(image_shape=(120, 160))
