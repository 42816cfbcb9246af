"""The one angle wrap (geometry.angles.wrap_angle): the same bits called from jitted code,
on arrays and on scalars, and the arithmetic the stored env digests depend on."""

import numpy as np
from numba import njit

from activevision.geometry.angles import wrap_angle


@njit
def _wrap_each(values):
    """``wrap_angle`` called on one float at a time, as the jitted kernels call it."""
    out = np.empty_like(values)
    for i in range(values.shape[0]):
        out[i] = wrap_angle(values[i])
    return out


def test_compiled_wrap_equals_numpy():
    rng = np.random.default_rng(2)
    values = np.concatenate(
        [rng.uniform(-20, 20, 1000), np.arange(-5, 6) * np.pi, [np.pi + 1e-17, -np.pi - 1e-16, 0.0]]
    )
    got = _wrap_each(values)
    assert np.array_equal(got, wrap_angle(values))
    assert np.array_equal(got, [wrap_angle(float(v)) for v in values])


def test_wrap_keeps_the_arithmetic_of_the_digests():
    # pi - ((pi - a) mod 2 pi), then (-pi, pi]: the viewpoint search's wrap before there was
    # one; tests/envs/test_digest.py depends on its rounding, not just on its interval.
    values = np.random.default_rng(3).uniform(-10, 10, 2000)
    expected = np.pi - np.mod(np.pi - values, 2 * np.pi)
    expected = np.where(expected <= -np.pi, expected + 2 * np.pi, expected)
    assert np.array_equal(wrap_angle(values), expected)
