"""A native batched ``VectorEnv`` for ``ActiveVisionMatch-v0``: every sub-environment is a
slot of one :class:`MatchBatch`, stepped, tracked and rendered in batched calls."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode

from activevision.envs.actions import head_action_space
from activevision.envs.match.config import MatchConfig
from activevision.envs.match.env import resolve_match_config
from activevision.envs.match.observations import (
    Observation,
    image_space,
    observation_space,
    observe,
)
from activevision.envs.match.simulation import MatchBatch
from activevision.envs.match.view import match_panel
from activevision.envs.slots import SlotVectorEnv, check_autoreset_mode
from activevision.envs.time_limit import resolve_limit
from activevision.registration import check_num_envs


class ActiveVisionMatchVectorEnv(SlotVectorEnv):
    """N matches in lock-step (see :class:`ActiveVisionMatchEnv`). Sub-environment ``i``
    reset with ``seed=s`` is seeded with ``s + i``, so its trajectory equals a single env's
    reset with ``seed=s + i``; ``reset()`` without a seed and ``options={"reset_mask": mask}``
    behave as in ``ActiveVisionVectorEnv``. Autoreset follows Gymnasium's default
    (``NEXT_STEP``; ``autoreset_mode`` takes no other); infos hold the single env's keys as
    arrays over sub-environments.
    ``max_episode_steps`` (``gymnasium.make_vec(..., max_episode_steps=n)``, which gives the
    sync and async modes Gymnasium's ``TimeLimit``) truncates a match after ``n`` ticks when
    that comes before ``ticks``, as the ``TimeLimit`` does; ``None`` and ``-1`` (Gymnasium's
    "no ``TimeLimit``") leave matches their ``ticks``."""

    def __init__(
        self,
        num_envs: int = 1,
        config: MatchConfig | None = None,
        render_mode: str | None = None,
        max_episode_steps: int | None = None,
        autoreset_mode: AutoresetMode | str | None = None,
        **config_overrides: Any,
    ) -> None:
        num_envs = check_num_envs(num_envs)  # before the batch is allocated
        check_autoreset_mode(autoreset_mode)
        self.config = config = resolve_match_config(config, config_overrides)
        # the match truncates itself after config.ticks; a time limit may end it sooner
        # (None or -1: none, as gymnasium.make applies no TimeLimit for either here)
        self.max_episode_steps = resolve_limit(max_episode_steps, None)
        limit = self.max_episode_steps
        self._last_tick = config.ticks if limit is None else min(config.ticks, limit)
        self.sim = MatchBatch(config, num_envs)
        self._set_up_slots(
            num_envs,
            observation_space(config),
            head_action_space(config.action_type, len(self.sim.actions)),
            image_space(config).shape,
            render_mode,
        )

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        mask = self._reset_mask(seed, options)
        slots = np.flatnonzero(mask)
        self.sim.reset(slots, [self._rngs[i] for i in slots])
        observation = self._observe()
        self._collect_frames(slots, slots[:0])
        return observation, self._with_masks(self.sim.info_arrays(), mask)

    def step(
        self, actions: np.ndarray
    ) -> tuple[Observation, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        resetting = self._needs_reset.copy()
        reward = self.sim.step(actions, active=~resetting)
        truncated = ~resetting & (self.sim.tick >= self._last_tick)
        started = np.flatnonzero(resetting)
        if len(started):
            self.sim.reset(started, [self._rngs[i] for i in started])
        terminated = np.zeros(self.num_envs, dtype=bool)
        self._needs_reset = truncated.copy()
        observation = self._observe()
        self._collect_frames(started, np.flatnonzero(~resetting))
        return observation, reward, terminated, truncated, self._infos()

    def _observe(self) -> Observation:
        self.sim.render(out=self._frames[:, 0])
        return observe(self._frames, self.sim)

    def _picture(self, i: int) -> np.ndarray:
        return match_panel(self.sim, i, self._frames[i, 0])

    def _infos(self) -> dict[str, Any]:
        return self._with_masks(self.sim.info_arrays())
