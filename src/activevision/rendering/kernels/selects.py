"""Scalar helpers for the kernels' per-pixel loops, written as selects.

numba lowers the ``min`` and ``max`` builtins to branches (a switch), and LLVM does not
vectorise a loop that holds one: a loop over a row that clamps with ``min(max(...))`` runs a
pixel at a time. These compute the same values with selects, which vectorise.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from activevision.geometry.jit import cached_njit
from activevision.rendering.kernels.bundles import JIT_PART

#: A float scalar of Python or NumPy (numba compiles :func:`clamp` for each).
Real = float | np.floating[Any]


@cached_njit(**JIT_PART)
def clamp(x: Real, lo: Real, hi: Real) -> Real:
    """``min(max(x, lo), hi)`` (the same value for every number but nan)."""
    return lo if x < lo else (hi if x > hi else x)
