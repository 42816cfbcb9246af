"""Registers activevision's environments with Gymnasium.

``import activevision`` calls :func:`register_envs`, as ale_py and minigrid do, so
``gymnasium.make("activevision:ActiveVision-v0")`` works. Registration names the entry points
as strings: nothing heavy (numba, the renderer, torch) is imported until an env is made.
"""

from __future__ import annotations

import numbers
import os
from typing import Any

ENV_ID = "ActiveVision-v0"
MATCH_ENV_ID = "ActiveVisionMatch-v0"

#: The most sub-environments a vector env of ours (``num_envs``) steps together: far beyond
#: any batch of this package (DAgger's 64 episodes, a match comparison's 50 matches), yet
#: small enough that a typo (10**12) is refused naming ``num_envs``, not numpy's MemoryError
#: allocating the batch's arrays (or, in the sync and async modes, Gymnasium building a list
#: of 10**12 env factories until the machine runs out of memory).
MAX_VECTOR_ENVS = 65_536

#: The least memory one sub-environment takes, per ``make_vec`` vectorization mode (default
#: configs of both envs, Linux x86-64, peak resident memory after a reset and a few steps,
#: rounded down): a slot of the native batch 128 KiB, a single env of SyncVectorEnv 256 KiB,
#: a worker process of AsyncVectorEnv 32 MiB (its own share, forked). A ``num_envs`` whose
#: sub-environments need more than the machine's whole memory is refused up front: it
#: would swap for minutes, then be killed (sync and async spend that time inside
#: Gymnasium, building one env after the other).
BYTES_PER_ENV = {"vector_entry_point": 128 << 10, "sync": 256 << 10, "async": 32 << 20}


def machine_memory() -> int | None:
    """This machine's physical memory in bytes (None where the OS does not say)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return None


def check_num_envs(num_envs: object, mode: object = None) -> int:
    """``num_envs`` as an int: a positive integer up to :data:`MAX_VECTOR_ENVS` whose
    sub-environments (``mode``: a vectorization mode, None the native one) fit in this
    machine's memory at :data:`BYTES_PER_ENV` each; a ValueError naming ``num_envs``
    otherwise."""
    if isinstance(num_envs, bool) or not isinstance(num_envs, numbers.Integral):
        raise ValueError(f"num_envs: expects a positive integer, got {num_envs!r}")
    if not 1 <= int(num_envs) <= MAX_VECTOR_ENVS:
        raise ValueError(
            f"num_envs: expects a positive integer up to {MAX_VECTOR_ENVS}, got {num_envs!r}"
        )
    name = str(getattr(mode, "value", mode) or "vector_entry_point")
    each, memory = BYTES_PER_ENV.get(name), machine_memory()
    if each is not None and memory is not None and int(num_envs) * each > memory:
        raise ValueError(
            f"num_envs: {int(num_envs):,} sub-environments need at least"
            f" {_size(int(num_envs) * each)} in vectorization_mode={name!r} ({_size(each)}"
            f" each), more than this machine's {_size(memory)} of memory"
        )
    return int(num_envs)


def _size(n: int) -> str:
    for unit, shift in (("GiB", 30), ("MiB", 20), ("KiB", 10)):
        if n >= 1 << shift:
            value = n / (1 << shift)
            return f"{value:,.0f} {unit}" if value >= 100 else f"{value:.3g} {unit}"
    return f"{n} B"


def plain(value: Any) -> Any:
    """``value`` with every NumPy scalar in it (in lists, tuples and dicts too) made the
    Python number or bool it holds; anything else as it is."""
    if hasattr(value, "dtype") and hasattr(value, "item") and getattr(value, "shape", None) == ():
        return value.item()
    if isinstance(value, list | tuple):
        return type(value)(plain(v) for v in value)
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    return value


class SpecKwargs(dict[str, Any]):
    """The ``EnvSpec.kwargs`` our envs register with. ``gymnasium.make`` and ``make_vec``
    copy it (the copy keeps this class) and pour the caller's keywords into it before any
    code of ours runs, so it is where two of their failures can be stopped:

    * ``update`` makes NumPy scalars plain Python values: ``env.spec.to_json()`` failed
      ("Object of type int64 is not JSON serializable") for ``make(id, frame_stack=
      np.int64(4))`` or ``make_vec(id, num_envs=np.int64(8))``, in every mode;
    * ``make_vec`` pops ``num_envs``, then ``vectorization_mode``: the first is checked
      as an integer up to :data:`MAX_VECTOR_ENVS`, the second with it against this
      machine's memory (:func:`check_num_envs`), before the sync and async modes build
      their list of ``num_envs`` env factories and envs, where a huge ``num_envs`` hung.
    """

    _num_envs: int | None = None

    def update(self, *args: Any, **kwargs: Any) -> None:
        super().update({k: plain(v) for k, v in dict(*args, **kwargs).items()})

    def pop(self, key: str, *default: Any) -> Any:
        value = super().pop(key, *default)
        if key == "num_envs":
            value = self._num_envs = check_num_envs(value)
        elif key == "vectorization_mode" and self._num_envs is not None:
            check_num_envs(self._num_envs, value)
        return value


def register_envs() -> None:
    """Register ``ActiveVision-v0`` and ``ActiveVisionMatch-v0`` (single and native vector
    entry points) once."""
    try:
        from gymnasium.envs.registration import register, registry
    except ImportError:  # the robot runtime needs no Gymnasium
        return
    # Without Gymnasium's passive env checker: the tests run the full ``check_env`` on both
    # envs, and the checker (Gymnasium 1.4) breaks an env for good once its first reset
    # raises (a bad seed or option): every later step fails inside the checker.
    if ENV_ID not in registry:
        register(
            id=ENV_ID,
            entry_point="activevision.envs.active_vision:ActiveVisionEnv",
            vector_entry_point="activevision.envs.vector:ActiveVisionVectorEnv",
            max_episode_steps=20,
            disable_env_checker=True,
            kwargs=SpecKwargs(),
        )
    if MATCH_ENV_ID not in registry:
        # no max_episode_steps: the match truncates itself after MatchConfig.ticks
        register(
            id=MATCH_ENV_ID,
            entry_point="activevision.envs.match.env:ActiveVisionMatchEnv",
            vector_entry_point="activevision.envs.match.vector:ActiveVisionMatchVectorEnv",
            disable_env_checker=True,
            kwargs=SpecKwargs(),
        )
