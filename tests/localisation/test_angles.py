import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from activevision.localisation import (
    circular_mean,
    measurement_mean,
    residual_x,
    residual_z,
    state_mean,
    wrap_angle,
)


@settings(max_examples=200, deadline=None)
# No subnormals: a trainer turns on flush-to-zero for the whole process while it trains
# (training/cpu.py; Trainer.close turns it off), and a test may hold an unclosed trainer.
@given(st.floats(-1e3, 1e3, allow_nan=False, allow_subnormal=False))
def test_wrap_angle_interval_and_equivalence(a):
    w = float(wrap_angle(a))
    assert -np.pi < w <= np.pi
    assert np.isclose(np.cos(w), np.cos(a), atol=1e-9)
    assert np.isclose(np.sin(w), np.sin(a), atol=1e-9)


def test_wrap_angle_edges():
    assert wrap_angle(np.pi) == np.pi
    assert wrap_angle(-np.pi) == np.pi
    assert wrap_angle(3 * np.pi) == np.pi
    assert wrap_angle(0.0) == 0.0
    assert -np.pi < wrap_angle(np.pi + 1e-17) <= np.pi
    assert np.allclose(wrap_angle([0.5 + 2 * np.pi, -0.5 - 4 * np.pi]), [0.5, -0.5])


def test_circular_mean_across_pi():
    w = np.array([0.5, 0.5])
    assert np.isclose(abs(circular_mean(np.array([np.pi - 0.1, -np.pi + 0.1]), w)), np.pi)
    assert np.isclose(circular_mean(np.array([0.1, -0.1]), w), 0.0)


def test_residuals_wrap_only_the_angle():
    a, b = np.array([1.0, 2.0, 3.0]), np.array([0.5, -1.0, -3.0])
    assert np.allclose(residual_x(a, b), [0.5, 3.0, 6.0 - 2 * np.pi])
    assert np.allclose(
        residual_z(np.array([2.0, -3.1]), np.array([1.0, 3.1])), [1.0, -6.2 + 2 * np.pi]
    )


def test_means_of_sigma_points():
    Wm = np.full(4, 0.25)
    s = np.array([[0, 0, 3.1], [1, 0, -3.1], [0, 1, 3.0], [1, 1, -3.0]], float)
    m = state_mean(s, Wm)
    assert np.allclose(m[:2], [0.5, 0.5]) and np.isclose(abs(m[2]), np.pi)
    z = measurement_mean(s[:, 1:], Wm)
    assert np.isclose(z[0], 0.5) and np.isclose(abs(z[1]), np.pi)
