"""The package's one angle-wrap convention: headings and bearings in ``(-pi, pi]``.

:func:`wrap_angle` is a numba ufunc, so the same compiled code serves NumPy callers (any
array, list or scalar; it returns an array or a NumPy scalar) and jitted kernels (one float,
called like any function): the UKF in NumPy (:mod:`activevision.localisation.ukf`) and its
compiled twin in the viewpoint search (:mod:`activevision.localisation.kernels`) wrap bit for
bit alike.

The arithmetic, ``pi - ((pi - a) mod 2 pi)``, is the one the viewpoint search has always used;
the stored env digests (tests/envs/test_digest.py) depend on its rounding, so it stays as is.
It is not the identity on angles already in range (``pi - (pi - a)`` rounds ``a`` to the
spacing of doubles near ``pi - a``); a caller that must keep such an angle bit for bit, like
the env's believed pose with no localisation error, wraps only angles out of range.
"""

from __future__ import annotations

import math

from activevision.geometry.jit import cached_vectorize

PI = math.pi
TWO_PI = 2.0 * math.pi


@cached_vectorize(["float64(float64)"], nopython=True)
def wrap_angle(angle: float) -> float:
    """``angle`` (rad) wrapped to ``(-pi, pi]``."""
    wrapped = PI - ((PI - angle) % TWO_PI)
    # the modulo can round up to exactly 2 pi for tiny negative inputs: keep it half-open
    if wrapped <= -PI:
        wrapped += TWO_PI
    return wrapped
