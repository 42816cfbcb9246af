"""Unscented Kalman filter over the robot pose ``(x, y, theta)``.

Models are plain functions in FilterPy's style: ``fx_odometry`` moves sigma points by an
odometry step given in the robot frame, ``hx_range_bearing`` measures the range and bearing
of a landmark. Every function is pure (mean and covariance in, new mean and covariance out).

Measurement of a landmark (every landmark is a ground segment ``(a, b)``; points have
``a == b``):

* a point: its range and bearing (robot frame) from the pose;
* a line (painted line or field-boundary edge): its polar form ``(rho, alpha)`` -- the signed
  distance from the pose to the (infinite) line along a unit normal ``n``, and the direction
  of ``n`` relative to the heading. ``n`` is the normal pointing from the believed pose
  towards the line (chosen to agree with the measured bearing, :func:`line_normal`), so for
  the believed pose ``(rho, alpha)`` *is* the range and bearing of the line's closest point
  whenever the foot of the perpendicular lies on the segment. A line detector sees a line's
  distance and direction, not a position along it, and this is what the polar form carries.
  (The range-bearing of the closest point itself is unusable for sigma points: its bearing
  flips by exactly pi when a sigma point crosses the line -- i.e. whenever the robot stands
  within about 0.9 m of a line -- and the wrapped residual +-pi is then decided by rounding.)

Symbols as in FilterPy: ``x``/``P`` mean and covariance, ``Wm``/``Wc`` sigma-point weights,
``S`` innovation covariance, ``K`` gain, ``R``/``Q`` measurement/process noise.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from activevision.geometry.field import LandmarkType
from activevision.localisation.angles import (
    measurement_mean,
    residual_x,
    residual_z,
    state_mean,
    wrap_angle,
)
from activevision.localisation.config import DEFAULT_UKF, UKFConfig
from activevision.localisation.sigma_points import (
    cholesky,
    merwe_sigma_points,
    merwe_weights,
)

#: An odometry step ``(dx, dy, dtheta)`` in the robot frame.
Odometry = Sequence[float] | np.ndarray


def fx_odometry(sigmas: npt.ArrayLike, odom: Odometry) -> np.ndarray:
    """Apply the odometry step ``odom = (dx, dy, dtheta)`` (robot frame) to poses (M, 3)."""
    sigmas = np.atleast_2d(np.asarray(sigmas, dtype=np.float64))
    c, s = np.cos(sigmas[:, 2]), np.sin(sigmas[:, 2])
    dx, dy, dtheta = odom
    return np.stack(
        [sigmas[:, 0] + c * dx - s * dy, sigmas[:, 1] + s * dx + c * dy, sigmas[:, 2] + dtheta],
        axis=-1,
    )


def is_point(segment: npt.ArrayLike) -> bool:
    """Whether the landmark ``segment`` (2, 2) is a point (``a == b``)."""
    a, b = np.asarray(segment, dtype=np.float64)
    return bool(a[0] == b[0] and a[1] == b[1])


def line_normal(segment: npt.ArrayLike, heading: float, bearing: float) -> np.ndarray:
    """Unit normal (2,) of the line through ``segment``, oriented to agree with a detection at
    ``bearing`` by a robot with ``heading``: ``n . (cos, sin)(heading + bearing) >= 0``."""
    a, b = np.asarray(segment, dtype=np.float64)
    dx, dy = b[0] - a[0], b[1] - a[1]
    length = np.hypot(dx, dy)
    n = np.array([-dy / length, dx / length])
    along = n[0] * np.cos(heading + bearing) + n[1] * np.sin(heading + bearing)
    return n if along >= 0.0 else -n


def hx_range_bearing(
    sigmas: npt.ArrayLike, segment: npt.ArrayLike, normal: np.ndarray | None = None
) -> np.ndarray:
    """Measurement ``(range, bearing)`` of a landmark from each pose (M, 3); (M, 2).

    Points: range and wrapped bearing of the point. Lines: the polar form ``(rho, alpha)``
    along the unit ``normal`` (2,) (see the module docstring); by default the normal points
    from each pose towards the line, which is what that pose would measure (``rho >= 0``).
    """
    sigmas = np.atleast_2d(np.asarray(sigmas, dtype=np.float64))
    a = np.asarray(segment, dtype=np.float64)[0]
    if is_point(segment):
        dx, dy = a[0] - sigmas[:, 0], a[1] - sigmas[:, 1]
        return np.stack([np.hypot(dx, dy), wrap_angle(np.arctan2(dy, dx) - sigmas[:, 2])], axis=-1)
    if normal is None:
        return np.stack(
            [hx_range_bearing(s, segment, _normal_towards(s, segment))[0] for s in sigmas]
        )
    rho = normal[0] * (a[0] - sigmas[:, 0]) + normal[1] * (a[1] - sigmas[:, 1])
    alpha = wrap_angle(np.arctan2(normal[1], normal[0]) - sigmas[:, 2])
    return np.stack([rho, alpha], axis=-1)


def _normal_towards(pose: np.ndarray, segment: npt.ArrayLike) -> np.ndarray:
    a, b = np.asarray(segment, dtype=np.float64)
    d = b - a
    n: np.ndarray = np.array([-d[1], d[0]]) / np.hypot(d[0], d[1])
    return n if n @ (a - pose[:2]) >= 0.0 else -n


def measurement_noise(
    z_range: float, landmark_type: int, ukf: UKFConfig = DEFAULT_UKF
) -> np.ndarray:
    """Measurement covariance R (2, 2) of a detection of ``landmark_type`` at ``z_range``."""
    nz = ukf.noise[LandmarkType(int(landmark_type))]
    sigma_r = nz.range_base + nz.range_fraction * z_range
    return np.diag([sigma_r**2, nz.bearing**2])


def odometry_noise(mean: np.ndarray, odom: Odometry, ukf: UKFConfig = DEFAULT_UKF) -> np.ndarray:
    """Process covariance Q (3, 3) of one odometry step: stds grow with the distance walked
    and the angle turned; the robot-frame xy part is rotated into the world by the heading."""
    dx, dy, dtheta = odom
    bx, by, bt = ukf.odometry_base
    trans = ukf.odometry_translation_fraction * np.hypot(dx, dy)
    q_robot = np.diag([(bx + trans) ** 2, (by + trans) ** 2])
    c, s = np.cos(mean[2]), np.sin(mean[2])
    rot = np.array([[c, -s], [s, c]])
    Q = np.zeros((3, 3))
    Q[:2, :2] = rot @ q_robot @ rot.T
    Q[2, 2] = (bt + ukf.odometry_rotation_fraction * abs(dtheta)) ** 2
    return Q


def unscented_transform(
    sigmas: np.ndarray,
    Wm: np.ndarray,
    Wc: np.ndarray,
    noise_cov: np.ndarray,
    mean_fn: Callable[[np.ndarray, np.ndarray], np.ndarray],
    residual_fn: Callable[[np.ndarray, np.ndarray], np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """Mean and covariance of transformed sigma points (FilterPy's ``unscented_transform``
    with a named mean and residual)."""
    mean = mean_fn(sigmas, Wm)
    y = residual_fn(sigmas, mean)
    return mean, (y.T * Wc) @ y + noise_cov


def symmetrised(P: np.ndarray) -> np.ndarray:
    """``(P + P^T) / 2``, after checking that ``P`` is positive definite."""
    P = 0.5 * (P + P.T)
    cholesky(P)
    return P


def ukf_predict(
    mean: npt.ArrayLike,
    cov: npt.ArrayLike,
    odom: Odometry,
    ukf: UKFConfig = DEFAULT_UKF,
    process_cov: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Predict the belief after an odometry step ``odom = (dx, dy, dtheta)`` (robot frame).

    ``process_cov`` (3, 3) defaults to :func:`odometry_noise`. Returns ``(mean, cov)``.
    """
    mean = np.asarray(mean, dtype=np.float64)
    Wm, Wc = merwe_weights(ukf.n, ukf.alpha, ukf.beta, ukf.kappa)
    sigmas = fx_odometry(merwe_sigma_points(mean, cov, ukf.alpha, ukf.kappa), odom)
    Q = odometry_noise(mean, odom, ukf) if process_cov is None else process_cov
    mean, P = unscented_transform(sigmas, Wm, Wc, Q, state_mean, residual_x)
    return mean, symmetrised(P)


def ukf_update(
    mean: npt.ArrayLike,
    cov: npt.ArrayLike,
    z: npt.ArrayLike,
    segment: npt.ArrayLike,
    landmark_type: int,
    ukf: UKFConfig = DEFAULT_UKF,
    R: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Update the belief with one detection ``z = (range, bearing)`` of the landmark
    ``segment`` (2, 2) of type ``landmark_type`` (for a line: the range and bearing of the
    foot of the perpendicular, see the module docstring).

    ``R`` defaults to :func:`measurement_noise` at the measured range. Returns
    ``(mean, cov)``; the heading is wrapped and the covariance symmetrised, and
    :class:`NotPositiveDefiniteError` is raised if it is not positive definite.
    """
    mean = np.asarray(mean, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    Wm, Wc = merwe_weights(ukf.n, ukf.alpha, ukf.beta, ukf.kappa)
    sigmas = merwe_sigma_points(mean, cov, ukf.alpha, ukf.kappa)
    normal = None if is_point(segment) else line_normal(segment, mean[2], z[1])
    sigmas_h = hx_range_bearing(sigmas, segment, normal)
    R = measurement_noise(abs(z[0]), landmark_type, ukf) if R is None else R
    zp, S = unscented_transform(sigmas_h, Wm, Wc, R, measurement_mean, residual_z)
    Pxz = (residual_x(sigmas, mean).T * Wc) @ residual_z(sigmas_h, zp)
    K = np.linalg.solve(S, Pxz.T).T  # Pxz S^-1, S symmetric
    x = mean + K @ residual_z(z, zp)
    x[2] = wrap_angle(x[2])
    return x, symmetrised(cov - K @ S @ K.T)


def ukf_update_sequential(
    mean: npt.ArrayLike,
    cov: npt.ArrayLike,
    zs: Iterable[npt.ArrayLike],
    segments: Iterable[npt.ArrayLike],
    types: Iterable[int],
    ukf: UKFConfig = DEFAULT_UKF,
) -> tuple[npt.ArrayLike, npt.ArrayLike]:
    """Apply :func:`ukf_update` for each detection in turn (Algorithm 1, lines 5-7), fresh
    sigma points each time. ``zs`` (M, 2), ``segments`` (M, 2, 2), ``types`` (M,)."""
    for z, segment, t in zip(zs, segments, types, strict=True):
        mean, cov = ukf_update(mean, cov, z, segment, t, ukf)
    return mean, cov


@dataclass(frozen=True)
class PoseBelief:
    """A Gaussian belief over the pose: ``mean`` (3,) ``(x, y, theta)`` and ``cov`` (3, 3).
    A thin immutable wrapper over the pure functions; the arrays are copied and made
    read-only."""

    mean: np.ndarray
    cov: np.ndarray

    def __post_init__(self) -> None:
        mean = np.array(self.mean, dtype=np.float64).reshape(3)
        cov = np.array(self.cov, dtype=np.float64).reshape(3, 3)
        if not np.allclose(cov, cov.T, rtol=0, atol=1e-12):
            raise ValueError("PoseBelief.cov must be symmetric")
        cholesky(cov)
        mean.flags.writeable = False
        cov.flags.writeable = False
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "cov", cov)

    @classmethod
    def initial(cls, pose: npt.ArrayLike, ukf: UKFConfig = DEFAULT_UKF) -> PoseBelief:
        """Belief centred on ``pose`` with the episode-start covariance."""
        return cls(np.asarray(pose, dtype=np.float64), ukf.initial_cov)

    def predict(self, odom: Odometry, ukf: UKFConfig = DEFAULT_UKF) -> PoseBelief:
        return PoseBelief(*ukf_predict(self.mean, self.cov, odom, ukf))

    def update(
        self,
        z: npt.ArrayLike,
        segment: npt.ArrayLike,
        landmark_type: int,
        ukf: UKFConfig = DEFAULT_UKF,
    ) -> PoseBelief:
        return PoseBelief(*ukf_update(self.mean, self.cov, z, segment, landmark_type, ukf))
