"""Configuration of the pose UKF: sigma-point parameters, sensor and odometry noise, and
the belief the environment starts each episode with."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
import numpy.typing as npt

from activevision.geometry.field import LandmarkType
from activevision.typecheck import check_dataclass_fields, in_range, is_real


@dataclass(frozen=True)
class RangeBearingNoise:
    """Standard deviations of one range-bearing detection: ``sigma_r = range_base +
    range_fraction * range`` (ground-plane ranges from a monocular camera degrade with
    distance), ``sigma_b = bearing`` (rad)."""

    range_base: float  #: m
    range_fraction: float  #: dimensionless, times the measured range
    bearing: float  #: rad

    def __post_init__(self) -> None:
        # types first (finite numbers): an infinite std passed the check below and failed
        # the first goal search as a "not positive definite" covariance
        check_dataclass_fields(self)
        if not (self.range_base > 0 and self.range_fraction >= 0 and self.bearing > 0):
            raise ValueError(f"RangeBearingNoise needs positive stds, got {self!r}")


# The paper gives no sensor model. Reasoning for the defaults: one pixel of the 160 px wide,
# 58 deg image is 6.3 mrad, so a detection a few pixels off plus head-joint and torso sway of
# 2-3 deg gives bearing errors of about 0.05 rad. Range comes from back-projecting onto the
# ground from 0.5 m height: a pitch error d gives dr ~ r^2/h * d, i.e. about 10 % of the range
# at 1-3 m on top of a few centimetres of base error. Features located less sharply (a post's
# foot, the circle's centre from an arc fit, the ragged end of the green) get more.
_DEFAULT_NOISE = {
    LandmarkType.L_CORNER: RangeBearingNoise(0.05, 0.10, 0.05),
    LandmarkType.T_JUNCTION: RangeBearingNoise(0.05, 0.10, 0.05),
    LandmarkType.X_CROSSING: RangeBearingNoise(0.05, 0.10, 0.05),
    LandmarkType.PENALTY_MARK: RangeBearingNoise(0.05, 0.10, 0.05),
    LandmarkType.GOAL_POST: RangeBearingNoise(0.10, 0.10, 0.05),
    LandmarkType.CENTRE_CIRCLE: RangeBearingNoise(0.10, 0.10, 0.08),
    LandmarkType.LINE: RangeBearingNoise(0.05, 0.10, 0.08),
    LandmarkType.FIELD_BOUNDARY: RangeBearingNoise(0.20, 0.20, 0.10),
}


class NoiseTable(dict[LandmarkType, RangeBearingNoise]):
    """:attr:`UKFConfig.noise`: a dict that refuses changes, as the frozen config does. A
    dict rather than a ``MappingProxyType``: ``dataclasses.asdict`` (which Gymnasium's
    ``EnvSpec.to_json`` applies to an env's keywords) rebuilds a dict item by item but
    deep-copies anything else, and a mappingproxy cannot be copied, so ``to_json`` of an env
    made with a UKF config failed with "cannot pickle 'mappingproxy' object"."""

    def _read_only(self, *args: Any, **kwargs: Any) -> Any:
        raise TypeError("UKFConfig.noise is read-only; give UKFConfig a new noise instead")

    __setitem__ = __delitem__ = clear = pop = popitem = setdefault = update = __ior__ = _read_only

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickle and deep-copy as the plain dict of its items (dict's own way would fill the
        copy through the refused ``__setitem__``)."""
        return (NoiseTable, (dict(self),))


def _default_noise() -> Mapping[LandmarkType, RangeBearingNoise]:
    return NoiseTable(_DEFAULT_NOISE)


@dataclass(frozen=True)
class UKFConfig:
    """The pose UKF over ``(x, y, theta)``.

    Sigma points are Van der Merwe's scaled set (FilterPy's ``MerweScaledSigmaPoints``
    semantics). The defaults ``alpha=1, beta=2, kappa=0`` (so ``lambda = 0`` for n = 3) make
    every weight non-negative (Wm = [0, 1/6, ...], Wc = [2, 1/6, ...]): the joint covariance
    of state and measurement sigma points is then positive semidefinite, so an update can
    never increase the covariance (P' <= P) and the entropy never rises when a landmark is
    added. The often-quoted ``alpha=1e-3`` gives W0 ~ -1e6 and cancels about six digits in
    every mean, for no benefit in three dimensions. Points lie at +-sqrt(3) sigma, i.e.
    +-0.87 m and +-0.52 rad for the default initial belief: far from the +-pi wrap.
    """

    alpha: float = 1.0  #: spread of the sigma points (Merwe)
    beta: float = 2.0  #: prior-distribution knowledge; 2 is optimal for Gaussians
    kappa: float = 0.0  #: secondary scaling; 3 - n = 0 (Julier's heuristic)
    #: sensor noise per landmark type (see the module comment for the reasoning)
    noise: Mapping[LandmarkType, RangeBearingNoise] = field(default_factory=_default_noise)
    odometry_base: tuple[float, float, float] = (0.005, 0.005, 0.01)  #: per-step std (m, m, rad)
    #: xy std per metre travelled
    odometry_translation_fraction: float = field(default=0.1, metadata=in_range(0.0))
    #: theta std per radian turned
    odometry_rotation_fraction: float = field(default=0.1, metadata=in_range(0.0))
    #: std of the belief at an episode start (m, m, rad). The paper does not give it; half a
    #: metre and 17 deg is a robot that has walked a while since its last good fix: uncertain
    #: enough that the choice of landmarks matters, small enough that the sigma points stay
    #: within +-0.9 m / +-0.5 rad, where the range-bearing model is still nearly linear.
    initial_std: tuple[float, float, float] = (0.5, 0.5, 0.3)

    def __post_init__(self) -> None:
        # as read back from JSON (a run's config.json): type ids as keys, noise as objects,
        # lists for tuples; stored in one canonical form so that equal configs compare equal
        if not isinstance(self.noise, Mapping):
            raise ValueError(
                "UKFConfig.noise: expects a mapping of landmark types to RangeBearingNoise,"
                f" got {self.noise!r}"
            )
        try:
            noise = {
                LandmarkType(int(kind)): value
                if isinstance(value, RangeBearingNoise)
                else RangeBearingNoise(**value)
                for kind, value in self.noise.items()
            }
        except (TypeError, ValueError) as error:
            raise ValueError(f"UKFConfig.noise: {error}") from None
        object.__setattr__(self, "noise", NoiseTable(noise))
        for name in ("odometry_base", "initial_std"):
            given = getattr(self, name)
            values = tuple(given) if isinstance(given, tuple | list | np.ndarray) else ()
            # real numbers only: float() took True and "0.5" too
            if len(values) != 3 or not all(is_real(v) for v in values):
                raise ValueError(
                    f"UKFConfig.{name}: expects 3 numbers (m, m, rad), got {getattr(self, name)!r}"
                )
            object.__setattr__(self, name, tuple(float(v) for v in values))
        # alpha, beta, kappa and the odometry fractions: finite numbers (a string, True or
        # NaN passed, to fail the first goal search as a covariance "not positive definite")
        check_dataclass_fields(self)
        if not self.alpha > 0:
            raise ValueError(f"UKFConfig.alpha must be positive, got {self.alpha!r}")
        try:
            spread = self.lambda_ + 3
        except OverflowError:  # alpha**2 past the largest float
            spread = math.inf
        if not 0 < spread < math.inf:
            raise ValueError(
                "UKFConfig needs alpha^2 (n + kappa) finite and > 0 for n = 3, got"
                f" alpha={self.alpha!r}, kappa={self.kappa!r}"
            )
        missing = [t.name for t in LandmarkType if t not in self.noise]
        if missing:
            raise ValueError(f"UKFConfig.noise lacks landmark types {missing}")
        stds = (*self.odometry_base, *self.initial_std)
        if not all(s > 0 and math.isfinite(s) for s in stds):
            raise ValueError("UKFConfig odometry_base and initial_std must be positive")

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickle and deep-copy through a plain dict of the noise: configs travel to worker
        processes, and Gymnasium's env checker deep-copies an env's arguments."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        values["noise"] = dict(self.noise)
        return (_ukf_config, (values,))

    @property
    def n(self) -> int:
        """State dimension."""
        return 3

    @property
    def lambda_(self) -> float:
        """Merwe's ``lambda = alpha^2 (n + kappa) - n``."""
        return self.alpha**2 * (self.n + self.kappa) - self.n

    @property
    def initial_cov(self) -> np.ndarray:
        """Covariance of the belief at an episode start: ``diag(initial_std)^2``."""
        return np.diag(np.square(self.initial_std))

    def noise_arrays(self, types: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(range_base, range_fraction, bearing)``, each (K,), for landmark ``types``."""
        rows = [self.noise[LandmarkType(int(t))] for t in np.asarray(types).ravel()]
        return (
            np.array([r.range_base for r in rows], dtype=np.float64),
            np.array([r.range_fraction for r in rows], dtype=np.float64),
            np.array([r.bearing for r in rows], dtype=np.float64),
        )


def _ukf_config(values: dict[str, Any]) -> UKFConfig:
    """A :class:`UKFConfig` from :meth:`UKFConfig.__reduce__`'s values."""
    return UKFConfig(**{**values, "noise": NoiseTable(values["noise"])})


#: The default configuration (a module-level constant so it can be a default argument).
DEFAULT_UKF = UKFConfig()
