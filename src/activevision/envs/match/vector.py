"""A native batched ``VectorEnv`` for ``ActiveVisionMatch-v0``: every sub-environment is a
slot of one :class:`MatchBatch`, stepped, tracked and rendered in batched calls."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from activevision.envs.actions import head_action_space
from activevision.envs.config import check_count
from activevision.envs.match.config import MatchConfig
from activevision.envs.match.env import resolve_match_config
from activevision.envs.match.observations import (
    Observation,
    image_space,
    observation_space,
    observe,
)
from activevision.envs.match.simulation import MatchBatch
from activevision.envs.seeding import reseed_generators


class ActiveVisionMatchVectorEnv(VectorEnv):
    """N matches in lock-step (see :class:`ActiveVisionMatchEnv`). Sub-environment ``i``
    reset with ``seed=s`` is seeded with ``s + i``, so its trajectory equals a single env's
    reset with ``seed=s + i``. Autoreset follows Gymnasium's default (``NEXT_STEP``); infos
    hold the single env's keys as arrays over sub-environments."""

    metadata = {"render_modes": [], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(
        self, num_envs: int = 1, config: MatchConfig | None = None, **config_overrides: Any
    ) -> None:
        self.num_envs = check_count("num_envs", num_envs)
        self.config = config = resolve_match_config(config, config_overrides)
        self.sim = MatchBatch(config, self.num_envs)
        self.single_observation_space = observation_space(config)
        self.single_action_space = head_action_space(config.action_type, len(self.sim.actions))
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._rngs = [seeding.np_random()[0] for _ in range(self.num_envs)]
        self._frames = np.zeros((self.num_envs, *image_space(config).shape), dtype=np.uint8)
        self._needs_reset = np.zeros(self.num_envs, dtype=bool)
        self._all = np.arange(self.num_envs)
        self._every_env = np.ones(self.num_envs, dtype=bool)
        self._every_env.flags.writeable = False

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        reseed_generators(self._rngs, seed)
        self.sim.reset(self._all, self._rngs)
        self._needs_reset[:] = False
        return self._observe(), self._infos()

    def step(
        self, actions: np.ndarray
    ) -> tuple[Observation, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        resetting = self._needs_reset.copy()
        reward = self.sim.step(actions, active=~resetting)
        truncated = ~resetting & (self.sim.tick >= self.config.ticks)
        started = np.flatnonzero(resetting)
        if len(started):
            self.sim.reset(started, [self._rngs[i] for i in started])
        terminated = np.zeros(self.num_envs, dtype=bool)
        self._needs_reset = truncated.copy()
        return self._observe(), reward, terminated, truncated, self._infos()

    def _observe(self) -> Observation:
        self.sim.render(out=self._frames[:, 0])
        return observe(self._frames, self.sim)

    def _infos(self) -> dict[str, Any]:
        infos: dict[str, Any] = self.sim.info_arrays()
        infos.update({f"_{key}": self._every_env for key in list(infos)})
        return infos
