"""A native batched ``VectorEnv`` for ``ActiveVision-v0``: every sub-environment is a slot
of one :class:`EpisodeBatch`, rendered, stepped and searched in batched calls."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode

from activevision.envs.actions import head_action_space, head_angle
from activevision.envs.config import EnvConfig, resolve_config
from activevision.envs.observations import (
    Observation,
    ObservationBuilder,
    image_space,
    observation_space,
    single,
)
from activevision.envs.simulation import EpisodeBatch, slot_info
from activevision.envs.slots import SlotVectorEnv, check_autoreset_mode
from activevision.envs.time_limit import never, resolve_limit
from activevision.localisation import LocalisationConfig
from activevision.registration import check_num_envs


class ActiveVisionVectorEnv(SlotVectorEnv):
    """N ActiveVision episodes in lock-step (see :class:`ActiveVisionEnv` for the task).

    Sub-environment ``i`` reset with ``seed=s`` is seeded with ``s + i`` and draws from its own
    generator, so its trajectory equals a single ``ActiveVision-v0`` reset with ``seed=s + i``;
    ``reset()`` without a seed goes on drawing from each generator, and ``reset(options=
    {"reset_mask": mask})`` resets only the sub-environments of ``mask``, as with
    ``SyncVectorEnv`` (the others' entries in the infos are zeros, their ``_key`` masks False).
    Autoreset follows Gymnasium's default (``NEXT_STEP``; ``autoreset_mode`` takes no
    other): the step after an episode ends resets that sub-environment and ignores its
    action. Truncation follows Gymnasium's
    ``TimeLimit`` (truncated once ``max_episode_steps`` steps are done, even on a step that
    also terminates), as single envs from ``gymnasium.make`` do; ``max_episode_steps=-1`` never
    truncates and ``None`` is the registration's 20, as ``make`` and the sync and async modes
    read them. Infos hold the single env's
    keys as arrays over sub-environments (landmark sets as (N, K) boolean masks
    ``desired_mask`` and ``observed_mask``): the very arrays ``SyncVectorEnv`` and
    ``AsyncVectorEnv`` stack from single envs. Actions must lie in the action space (integers;
    with ``action_type="continuous"`` an (N, 2) float array in [-1, 1]).
    ``get_attr``, ``set_attr`` and ``call`` act as ``SyncVectorEnv``'s (see
    :class:`SlotVectorEnv`); ``call`` runs ``render``, ``entropy_regret`` and
    ``jump_head`` per sub-environment. ``call("jump_head", pan, tilt)`` jumps every head, as
    ``SyncVectorEnv`` calls each env's ``jump_head``: outside ``step``, so, as there, no
    autoreset follows a sub-environment it ends and the time limit counts ``step`` calls only.
    """

    def __init__(
        self,
        num_envs: int = 1,
        config: EnvConfig | None = None,
        localisation: LocalisationConfig | None = None,
        max_episode_steps: int | None = 20,
        render_mode: str | None = None,
        autoreset_mode: AutoresetMode | str | None = None,
        **config_overrides: Any,
    ) -> None:
        num_envs = check_num_envs(num_envs)  # before the batch is allocated
        check_autoreset_mode(autoreset_mode)
        self.config = config = resolve_config(config, config_overrides)
        # gymnasium.make_vec passes its max_episode_steps as given (20, the registration's,
        # when not given): -1 is no limit, None the registration's 20, as gymnasium.make
        # reads them for the sync and async modes' TimeLimit wrappers
        self.max_episode_steps = resolve_limit(max_episode_steps, 20)
        self.sim = EpisodeBatch(config, num_envs, localisation)
        n_actions = len(self.sim.actions)
        self._set_up_slots(
            num_envs,
            observation_space(config, n_actions),
            head_action_space(config.action_type, n_actions),
            image_space(config).shape,
            render_mode,
        )
        self._observations = ObservationBuilder(config, num_envs, n_actions)
        # step() calls since each sub-environment's reset, as Gymnasium's TimeLimit counts
        # them (the sim's step_count also counts call("jump_head") moves)
        self._elapsed = np.zeros(num_envs, dtype=np.int64)

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        mask = self._reset_mask(seed, options)
        slots = np.flatnonzero(mask)
        self.sim.reset(slots, [self._rngs[i] for i in slots])
        self._observations.start(slots)
        self._elapsed[slots] = 0
        # a reset sub-environment's whole frame stack is its first frame; the others keep
        # theirs (a state renders the same image each time)
        self._frames[slots] = self.sim.render(slots)[:, None]
        self._collect_frames(slots, slots[:0])
        return self._observe(), self._with_masks(self._info_arrays(), mask)

    def _observe(self) -> Observation:
        sim = self.sim
        return self._observations.batch(self._frames, sim)

    def _render(self, started: np.ndarray) -> None:
        """Render every sub-environment in one batched call; sub-environments that just
        started fill their whole frame stack with their first frame."""
        if self.config.frame_stack == 1:
            self.sim.render(out=self._frames[:, 0])  # straight into the observation buffer
            return
        self._frames[:, :-1] = self._frames[:, 1:]
        self._frames[:, -1] = self.sim.render()
        self._frames[started] = self._frames[started, -1:]

    def step(
        self, actions: np.ndarray
    ) -> tuple[Observation, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        # EpisodeBatch.step checks dtype, shape and range of every action (resetting
        # sub-environments ignore theirs, but it must still lie in the action space).
        resetting = self._needs_reset.copy()
        stepping = ~resetting
        reward, terminated, _, _ = self.sim.step(actions, active=stepping)
        self._observations.record(np.asarray(actions)[stepping], np.flatnonzero(stepping))
        # Gymnasium's TimeLimit rule, which single envs from gymnasium.make follow: truncated
        # whenever the limit is reached, even on a step that also terminates.
        limit = self.max_episode_steps
        self._elapsed[stepping] += 1
        truncated = stepping & (self._elapsed >= (np.inf if limit is None else limit))
        started = np.flatnonzero(resetting)
        if len(started):
            self.sim.reset(started, [self._rngs[i] for i in started])
            self._observations.start(started)
            self._elapsed[started] = 0
        self._render(started)
        self._collect_frames(started, np.flatnonzero(stepping))
        infos = self._infos()
        self._needs_reset = terminated | truncated
        return self._observe(), reward, terminated, truncated, infos

    def _slot_calls(self) -> dict[str, Callable[..., tuple[Any, ...]]]:
        def entropy_regret(i: int) -> float:
            return float(self.sim.entropy_regret(np.array([i]))[0])

        return {
            **super()._slot_calls(),
            "entropy_regret": self._per_slot(entropy_regret),
            "jump_head": self._jump_heads,
        }

    def _jump_heads(self, pan: float, tilt: float) -> tuple[Any, ...]:
        """Each sub-environment's ``ActiveVisionEnv.jump_head(pan, tilt)`` result, the heads
        moved in one batched step; ``_needs_reset`` and the step counts are ``step``'s."""
        slots = np.arange(self.num_envs)
        target = [
            np.repeat(head_angle(k, v), self.num_envs) for k, v in (("pan", pan), ("tilt", tilt))
        ]
        reward, terminated, _, _ = self.sim.move_head(slots, *target)
        self._render(slots[:0])
        observations, infos = self._observe(), self._info_arrays()
        return tuple(
            (
                single(observations, i),
                float(reward[i]),
                bool(terminated[i]),
                False,
                slot_info(infos, i),
            )
            for i in range(self.num_envs)
        )

    def _picture(self, i: int) -> np.ndarray:
        from activevision.envs.view import episode_panel  # imports matplotlib: only here

        return episode_panel(self.sim, i, self._frames[i, -1])

    def _infos(self) -> dict[str, Any]:
        return self._with_masks(self._info_arrays())

    def _info_arrays(self) -> dict[str, np.ndarray]:
        return self.sim.info_arrays(never(self.max_episode_steps))
