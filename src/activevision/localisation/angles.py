"""Heading arithmetic: angle wrapping, residuals and circular means (FilterPy's
``residual_x`` / ``residual_z`` / ``x_mean_fn`` / ``z_mean_fn`` for the pose UKF).

Every heading difference is wrapped to ``(-pi, pi]`` (the package's one convention,
:func:`activevision.geometry.angles.wrap_angle`) and every mean of headings is a circular mean
(``atan2`` of the weighted sine and cosine sums): averaging 179 deg and -179 deg must give
180 deg, not 0.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from activevision.geometry.angles import wrap_angle


def circular_mean(angles: npt.ArrayLike, weights: npt.ArrayLike) -> float:
    """Weighted circular mean of ``angles`` (rad), in ``(-pi, pi]``."""
    s = np.dot(weights, np.sin(angles))
    c = np.dot(weights, np.cos(angles))
    return float(wrap_angle(np.arctan2(s, c)))


def residual_x(a: npt.ArrayLike, b: np.ndarray) -> np.ndarray:
    """State difference ``a - b`` for poses ``(x, y, theta)``, heading wrapped."""
    y: np.ndarray = np.asarray(a, dtype=np.float64) - b
    y[..., 2] = wrap_angle(y[..., 2])
    return y


def residual_z(a: npt.ArrayLike, b: np.ndarray) -> np.ndarray:
    """Measurement difference ``a - b`` for ``(range, bearing)``, bearing wrapped."""
    y: np.ndarray = np.asarray(a, dtype=np.float64) - b
    y[..., 1] = wrap_angle(y[..., 1])
    return y


def state_mean(sigmas: npt.ArrayLike, Wm: npt.ArrayLike) -> np.ndarray:
    """Weighted mean of pose sigma points (M, 3): arithmetic in x, y, circular in theta."""
    sigmas = np.asarray(sigmas, dtype=np.float64)
    x = np.dot(Wm, sigmas[:, :2])
    return np.array([x[0], x[1], circular_mean(sigmas[:, 2], Wm)])


def measurement_mean(sigmas: npt.ArrayLike, Wm: npt.ArrayLike) -> np.ndarray:
    """Weighted mean of range-bearing sigma points (M, 2): arithmetic range, circular
    bearing."""
    sigmas = np.asarray(sigmas, dtype=np.float64)
    return np.array([np.dot(Wm, sigmas[:, 0]), circular_mean(sigmas[:, 1], Wm)])
