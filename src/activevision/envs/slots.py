"""What the package's native vector envs share: N sub-environments that are the slots of one
batched simulation, each with its own seeded generator, stepped in lock-step with
Gymnasium's default autoreset (``NEXT_STEP``)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from activevision.envs.config import check_render_mode
from activevision.envs.reset_options import reset_mask
from activevision.envs.seeding import reseed_generators


class SlotVectorEnv(VectorEnv):
    """Spaces, per-slot generators, the frame buffer and the info masks of a native vector
    env; subclasses build their simulation and call :meth:`_set_up_slots`."""

    metadata = {
        "render_modes": ["rgb_array"],
        "render_fps": 3,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def _set_up_slots(
        self,
        num_envs: int,
        observation_space: gym.Space[Any],
        action_space: gym.Space[Any],
        frame_shape: tuple[int, ...],
        render_mode: str | None = None,
    ) -> None:
        check_render_mode(render_mode, self.metadata["render_modes"])
        self.render_mode = render_mode
        self.num_envs = num_envs
        self.single_observation_space = observation_space
        self.single_action_space = action_space
        self.observation_space = batch_space(observation_space, num_envs)
        self.action_space = batch_space(action_space, num_envs)
        drawn = [seeding.np_random() for _ in range(num_envs)]
        self._rngs = [rng for rng, _ in drawn]
        self._seeds = [seed for _, seed in drawn]  # each sub-environment's, as its generator's
        self._frames = np.zeros((num_envs, *frame_shape), dtype=np.uint8)
        self._needs_reset = np.zeros(num_envs, dtype=bool)
        # Gymnasium's "_key" masks: every sub-environment reports every key, every step.
        self._every_env = np.ones(num_envs, dtype=bool)
        self._every_env.flags.writeable = False

    def _reset_mask(
        self, seed: int | list[int | None] | None, options: dict[str, Any] | None
    ) -> np.ndarray:
        """The sub-environments (bool (N,)) a ``reset(seed, options)`` resets: every one, or
        those of ``options["reset_mask"]``, reseeded: sub-environment ``i`` reset with
        ``seed=s`` draws from a generator seeded ``s + i`` (``envs.seeding.
        reseed_generators``). None of them awaits an autoreset after; the others keep their
        state, their generators and their flags."""
        mask = reset_mask(options, self.num_envs)
        slots = np.flatnonzero(mask)
        seeds = reseed_generators(self._rngs, seed, slots)
        for i in slots:
            new = seeds[i]
            if new is not None:
                self._seeds[i] = new
        self._needs_reset[slots] = False
        return mask

    @property
    def np_random_seed(self) -> tuple[int, ...]:  # type: ignore[override]
        """Each sub-environment's seed, as ``SyncVectorEnv`` reports its envs' (``(s, s + 1,
        ...)`` after ``reset(seed=s)``). ``VectorEnv``'s own was a random seed of a generator
        no sub-environment draws from, whatever seed the reset was given."""
        return tuple(self._seeds)

    @property  # type: ignore[misc]
    def np_random(self) -> tuple[np.random.Generator, ...]:  # type: ignore[override]
        """Each sub-environment's generator, as ``SyncVectorEnv`` reports its envs'."""
        return tuple(self._rngs)

    def render(self) -> tuple[np.ndarray, ...] | None:
        """With ``render_mode="rgb_array"``: each sub-environment's picture, as its single
        env's ``render()`` draws it (what ``SyncVectorEnv.render`` returns); None
        otherwise."""
        if self.render_mode != "rgb_array":
            return None
        return tuple(self._picture(i) for i in range(self.num_envs))

    def _picture(self, i: int) -> np.ndarray:
        raise NotImplementedError

    def _with_masks(
        self, infos: dict[str, Any], present: np.ndarray | None = None
    ) -> dict[str, Any]:
        """``infos`` (arrays over sub-environments) with Gymnasium's ``_key`` masks. With
        ``present`` (a partial reset's mask), only those sub-environments report, and the
        others' entries are zeros, as ``SyncVectorEnv`` fills them."""
        if present is None or present.all():
            infos.update({f"_{key}": self._every_env for key in list(infos)})
            return infos
        for key in list(infos):
            values = np.array(infos[key])
            values[~present] = 0
            infos[key] = values
            infos[f"_{key}"] = present.copy()  # one array a key, as Sync gives
        return infos


def check_autoreset_mode(mode: object) -> None:
    """ValueError unless ``mode`` (``gymnasium.make_vec(..., autoreset_mode=...)`` in
    ``vector_entry_point`` mode) is None or ``NEXT_STEP``, the one mode the native vector envs
    run: without this, the keyword would reach the config and be refused as an unknown
    field, as if the env had never heard of autoresets."""
    if mode is None or mode == AutoresetMode.NEXT_STEP or mode == AutoresetMode.NEXT_STEP.value:
        return
    raise ValueError(
        "autoreset_mode: the native vector env (vectorization_mode='vector_entry_point')"
        " autoresets on the next step only (AutoresetMode.NEXT_STEP); for"
        f" {[m.value for m in AutoresetMode if m != AutoresetMode.NEXT_STEP]} use"
        f" vectorization_mode='sync' or 'async', got {mode!r}"
    )


__all__ = ["SlotVectorEnv", "check_autoreset_mode"]
