"""What the package's native vector envs share: N sub-environments that are the slots of one
batched simulation, each with its own seeded generator, stepped in lock-step with
Gymnasium's default autoreset (``NEXT_STEP``)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, ClassVar

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
    env; subclasses build their simulation and call :meth:`_set_up_slots`.

    ``get_attr``, ``set_attr`` and ``call`` follow ``SyncVectorEnv``'s: ``get_attr(name)``
    is a tuple of each sub-environment's value (``np_random``, ``np_random_seed``, the
    single ``observation_space``, ``action_space``, ``metadata`` and ``spec``; an attribute
    of the user's own, set with ``set_attr``, holds one value per sub-environment; what the
    env has and reads, the config, the render mode, the time limit, is shared by the batch,
    the same for each); ``call("render")`` draws each sub-environment's picture (subclasses
    name their other per-sub-environment methods) and ``call`` of what the batch cannot run
    per sub-environment (``reset``, ``step``, ...) names the vector env's method to use
    instead; ``set_attr`` takes one value or ``num_envs`` of them (all equal for a shared
    attribute; ``np_random`` takes one generator each)."""

    metadata = {
        "render_modes": ["rgb_array"],
        "render_fps": 3,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }
    #: what ``get_attr("metadata")`` reports: a sub-environment's, the single env's metadata
    _SINGLE_METADATA: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 3}
    #: the vector env's own names, which no sub-environment has (``get_attr`` refuses them)
    _VECTOR_ONLY: ClassVar[frozenset[str]] = frozenset(
        {
            "num_envs",
            "single_observation_space",
            "single_action_space",
            "unwrapped",
            "reset",
            "step",
            "close",
            "close_extras",
            "call",
            "get_attr",
            "set_attr",
        }
    )
    #: the single env's methods ``call`` cannot run per sub-environment (Sync runs each env
    #: by itself, outside the batch's autoreset), and the vector env's own to use instead
    _INSTEAD: ClassVar[dict[str, str]] = {
        "reset": "reset(seed=..., options={'reset_mask': mask})",
        "step": "step(actions)",
        "close": "close()",
        "get_wrapper_attr": "get_attr(name)",
        "set_wrapper_attr": "set_attr(name, values)",
    }

    def _set_up_slots(
        self,
        num_envs: int,
        observation_space: gym.Space[Any],
        action_space: gym.Space[Any],
        frame_shape: tuple[int, ...],
        render_mode: str | None = None,
    ) -> None:
        modes = self.metadata["render_modes"]
        # "rgb_array_list" as gymnasium.make (and so the sync and async modes) take it, by
        # Gymnasium's RenderCollection: each sub-environment's pictures since the last render
        check_render_mode(render_mode, [*modes, *(f"{m}_list" for m in modes)])
        self.render_mode = render_mode
        self.single_metadata = self._SINGLE_METADATA
        if render_mode is not None and render_mode.endswith("_list"):
            # as RenderCollection reports its modes (SyncVectorEnv's metadata is its env's)
            self.metadata = {**self.metadata, "render_modes": [*modes, render_mode]}
            self.single_metadata = {**self._SINGLE_METADATA, "render_modes": [*modes, render_mode]}
        self._frame_lists: list[list[np.ndarray]] = [[] for _ in range(num_envs)]
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
        # attributes of the user's own (set_attr of a name the env does not have): one value
        # per sub-environment, as each of SyncVectorEnv's env objects keeps its own
        self._own_attrs: dict[str, list[Any]] = {}
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

    def render(self) -> tuple[Any, ...] | None:
        """With ``render_mode="rgb_array"``: each sub-environment's picture, as its single
        env's ``render()`` draws it (what ``SyncVectorEnv.render`` returns); with
        ``"rgb_array_list"`` each sub-environment's list of pictures since its last reset or
        render, as Gymnasium's ``RenderCollection`` collects them (an autoreset starts the
        list again); None otherwise."""
        if self.render_mode not in ("rgb_array", "rgb_array_list"):
            return None
        return tuple(self._render_slot(i) for i in range(self.num_envs))

    def _render_slot(self, i: int) -> Any:
        """Sub-environment ``i``'s ``render()``."""
        if self.render_mode == "rgb_array":
            return self._picture(i)
        if self.render_mode == "rgb_array_list":
            frames, self._frame_lists[i] = self._frame_lists[i], []
            return frames
        return None

    def _collect_frames(self, restarted: np.ndarray, stepped: np.ndarray) -> None:
        """With ``render_mode="rgb_array_list"``: the pictures after a reset or step, as
        ``RenderCollection`` keeps them (a reset starts a sub-environment's list again)."""
        if self.render_mode != "rgb_array_list":
            return
        for i in restarted:
            self._frame_lists[i] = [self._picture(i)]
        for i in stepped:
            self._frame_lists[i].append(self._picture(i))

    def _picture(self, i: int) -> np.ndarray:
        raise NotImplementedError

    # Gymnasium's VectorEnv API for sub-environment attributes (SyncVectorEnv's semantics):
    # the sub-environments are slots of one batch, so a name is one of the per-slot names
    # below, an attribute of the user's own (one value per sub-environment), or an attribute
    # of the env that every sub-environment shares (the config, the render mode), reported
    # once per sub-environment.

    def _slot_calls(self) -> dict[str, Callable[..., tuple[Any, ...]]]:
        """Single-env methods that ``call`` runs on every sub-environment: ``f(*args,
        **kwargs)`` is each sub-environment's result. Subclasses add theirs."""
        return {"render": self._per_slot(self._render_slot)}

    def _per_slot(self, method: Callable[..., Any]) -> Callable[..., tuple[Any, ...]]:
        """``method(i, *args, **kwargs)`` of sub-environment ``i`` called for each."""

        def each(*args: Any, **kwargs: Any) -> tuple[Any, ...]:
            return tuple(method(i, *args, **kwargs) for i in range(self.num_envs))

        return each

    def _slot_attr(self, name: str, i: int) -> Any:
        """Sub-environment ``i``'s attribute ``name``, as its single env reports it."""
        per_slot: dict[str, Callable[[], Any]] = {
            "np_random": lambda: self._rngs[i],
            "np_random_seed": lambda: self._seeds[i],
            "observation_space": lambda: self.single_observation_space,
            "action_space": lambda: self.single_action_space,
            "metadata": lambda: self.single_metadata,
            "spec": self._single_spec,
        }
        if name in per_slot:
            return per_slot[name]()
        if name in self._own_attrs:
            return self._own_attrs[name][i]
        if name in self._VECTOR_ONLY:
            # e.g. "unwrapped": SyncVectorEnv's sub-environments are env objects, ours are
            # slots of one batch
            raise AttributeError(
                f"{type(self).__name__}: its sub-environments are slots of one batch, with no"
                f" {name!r} of their own (vectorization_mode='sync' makes env objects)"
            )
        if not hasattr(self, name):
            raise AttributeError(
                f"{type(self).__name__}: its sub-environments have no attribute {name!r}"
            )
        return getattr(self, name)

    def _single_spec(self) -> Any:
        """A sub-environment's spec, as ``make_vec``'s sync mode makes them: the vector
        env's without ``num_envs``, ``vectorization_mode`` and ``max_episode_steps`` among
        the keywords (the last is ``make``'s, and so the spec's ``max_episode_steps``)."""
        spec = self.spec
        if spec is None:
            return None
        kwargs = dict(spec.kwargs)
        kwargs.pop("num_envs", None)
        kwargs.pop("vectorization_mode", None)
        limit = kwargs.pop("max_episode_steps", spec.max_episode_steps)
        return dataclasses.replace(spec, kwargs=kwargs, max_episode_steps=limit)

    def call(self, name: str, *args: Any, **kwargs: Any) -> tuple[Any, ...]:
        """``SyncVectorEnv.call``: each sub-environment's method ``name`` called with
        ``args`` and ``kwargs`` (``render``, and the single env's own methods listed in the
        class docstring), or its attribute ``name`` when that is no method. A method the
        batch cannot run per sub-environment is an AttributeError naming what to use."""
        calls = self._slot_calls()
        if name in calls:
            return calls[name](*args, **kwargs)
        if name in self._INSTEAD:
            raise AttributeError(
                f"{type(self).__name__}.call({name!r}): its sub-environments are slots of one"
                f" batch, not envs of their own; use the vector env's {self._INSTEAD[name]}"
                " (vectorization_mode='sync' makes env objects)"
            )
        values = self.get_attr(name)
        if any(callable(v) for v in values):
            raise AttributeError(
                f"{type(self).__name__}.call: runs the sub-environments' methods"
                f" {sorted(calls)}, not {name!r} (vectorization_mode='sync' runs any)"
            )
        return values

    def get_attr(self, name: str) -> tuple[Any, ...]:
        """``SyncVectorEnv.get_attr``: each sub-environment's attribute ``name``."""
        return tuple(self._slot_attr(name, i) for i in range(self.num_envs))

    def set_attr(self, name: str, values: list[Any] | tuple[Any, ...] | Any) -> None:
        """``SyncVectorEnv.set_attr``: one value for every sub-environment, or a list or
        tuple of ``num_envs`` values. ``np_random`` takes a generator per sub-environment,
        and so does an attribute the env does not have (the user's own, kept per
        sub-environment); an attribute of the env is shared by the batch, so its values must
        be equal (a ValueError otherwise), and the vector env's own names are refused."""
        if not isinstance(values, list | tuple):
            values = [values] * self.num_envs
        if len(values) != self.num_envs:
            raise ValueError(
                "Values must be a list or tuple with length equal to the number of"
                f" environments. Got `{len(values)}` values for {self.num_envs} environments."
            )
        if name == "np_random":
            for rng in values:
                if not isinstance(rng, np.random.Generator):
                    raise ValueError(f"set_attr: np_random expects Generators, got {rng!r}")
            self._rngs = list(values)
            self._seeds = [-1] * self.num_envs  # as gymnasium.Env's np_random setter
            return
        if name in self._VECTOR_ONLY or name in (
            "np_random_seed",
            "spec",
            "metadata",
            "observation_space",
            "action_space",
        ):
            raise AttributeError(f"{type(self).__name__}.set_attr: {name!r} cannot be set")
        if name in self._own_attrs or not hasattr(self, name):
            self._own_attrs[name] = list(values)
            return
        if not all(_same(value, values[0]) for value in values[1:]):
            raise ValueError(
                f"{type(self).__name__}.set_attr: the sub-environments share {name!r}, a"
                " slot of one batch each, so they take one value; make one vector env per"
                " value (or vectorization_mode='sync', an env object each), got"
                f" {list(values)!r}"
            )
        setattr(self, name, values[0])

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


def _same(a: Any, b: Any) -> bool:
    """Whether ``a`` and ``b`` are one value (arrays compared element by element)."""
    if a is b:
        return True
    if type(a) is not type(b):
        return False
    try:
        return bool(np.array_equal(a, b)) if isinstance(a, np.ndarray) else bool(a == b)
    except (TypeError, ValueError):
        return False


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
