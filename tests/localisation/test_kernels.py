"""The compiled angle wrap agrees exactly with the NumPy one."""

import numpy as np

from activevision.localisation import kernels, wrap_angle


def test_compiled_wrap_equals_numpy():
    rng = np.random.default_rng(2)
    values = np.concatenate(
        [rng.uniform(-20, 20, 1000), np.arange(-5, 6) * np.pi, [np.pi + 1e-17, -np.pi - 1e-16, 0.0]]
    )
    got = np.array([kernels.wrap(v) for v in values])
    assert np.array_equal(got, wrap_angle(values))
