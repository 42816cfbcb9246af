"""What ``reset(options=...)`` accepts: nothing for the single envs (an option they would
silently ignore is refused), and Gymnasium's ``reset_mask`` for the native vector envs,
checked as ``SyncVectorEnv`` checks it, so that every vectorizer resets the same
sub-environments."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

RESET_MASK = "reset_mask"


def check_no_options(options: Mapping[str, Any] | None) -> None:
    """A single env's reset options: None or empty (``SyncVectorEnv`` passes ``{}``)."""
    if options:
        raise ValueError(f"reset takes no options, got {sorted(map(str, options))}")


def reset_mask(options: Mapping[str, Any] | None, num_envs: int) -> np.ndarray:
    """The sub-environments (bool (num_envs,)) a vector env's reset resets: every one, or
    ``options["reset_mask"]``'s, which must be a bool array of shape (num_envs,) with at
    least one True (Gymnasium's rules)."""
    if not options:
        return np.ones(num_envs, dtype=bool)
    unknown = sorted(map(str, set(options) - {RESET_MASK}))
    if unknown:
        raise ValueError(f"reset takes only the option {RESET_MASK!r}, got {unknown}")
    mask = options[RESET_MASK]
    if not isinstance(mask, np.ndarray):
        raise TypeError(f"options['{RESET_MASK}'] must be a numpy array, got {type(mask)}")
    if mask.shape != (num_envs,):
        raise ValueError(f"options['{RESET_MASK}'] must have shape ({num_envs},), got {mask.shape}")
    if mask.dtype != np.bool_:
        raise TypeError(f"options['{RESET_MASK}'] must have dtype bool, got {mask.dtype}")
    if not mask.any():
        raise ValueError(f"options['{RESET_MASK}'] must hold at least one True, got {mask}")
    return mask.copy()


__all__ = ["RESET_MASK", "check_no_options", "reset_mask"]
