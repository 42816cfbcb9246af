"""Tracking the pose of a walking robot: the UKF's odometry prediction and its gated landmark
updates, compiled and batched over N robots (the filter of the match environment).

It is the filter of :mod:`activevision.localisation.ukf` -- the same sigma points, motion
model, measurement models and noise -- run every control tick instead of once per episode,
with two things a tracker needs and a one-shot search does not:

* a **validation gate**: a detection whose innovation lies further than ``gate`` (squared
  Mahalanobis distance, chi-square with 2 degrees of freedom) from what the belief expects
  is discarded, the standard defence against false detections;
* a **lost detector** for a kidnapped robot: the share of detections that failed the gate,
  per tick with two or more detections (a false detection comes alone: at most one a tick),
  as an exponential moving average over such ticks. When it passes ``lost_share`` the robot declares
  itself lost and the covariance is widened to ``lost_std`` around the mean, so that the
  gate lets detections in again. A UKF cannot relocalise globally (the field is
  symmetric), so this *detects* a kidnapping and recovers only from a teleport within
  about ``lost_std`` of the believed pose (tests/localisation/test_tracking.py).

The pure functions ``ukf_predict`` / ``ukf_update`` are the reference the kernels are tested
against; :class:`Tracker` is the batched entry point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from activevision.geometry.angles import wrap_angle as wrap
from activevision.geometry.jit import cached_njit
from activevision.geometry.landmarks import LandmarkSet
from activevision.localisation.bundles import Landmarks, SigmaWeights, UKFScratch
from activevision.localisation.config import DEFAULT_UKF, UKFConfig
from activevision.localisation.kernels import (
    GATED,
    NOT_PD,
    OK,
    Fields,
    chol3,
    expected_rb,
    sigma_points3,
    ukf_update_rb,
)
from activevision.localisation.sigma_points import NotPositiveDefiniteError, merwe_weights
from activevision.localisation.viewpoint import landmark_fields
from activevision.typecheck import check_dataclass_fields

#: chi-square quantile, 2 degrees of freedom, 0.999: a true detection fails the gate once in
#: a thousand
CHI2_2DOF_999 = 13.815510557964274


@dataclass(frozen=True)
class TrackerConfig:
    """The tracker around the UKF (not in the paper, whose robot stands still)."""

    ukf: UKFConfig = DEFAULT_UKF  #: sigma points, sensor and odometry noise
    gate: float = CHI2_2DOF_999  #: squared Mahalanobis distance beyond which a detection is dropped
    #: weight of each tick (with two or more detections) in the moving share of gated ones
    lost_rate: float = 0.2
    #: that share above which the robot declares itself lost (kidnapped)
    lost_share: float = 0.5
    #: the belief's std (m, m, rad) after declaring itself lost
    lost_std: tuple[float, float, float] = (1.0, 1.0, 0.5)

    def __post_init__(self) -> None:
        check_dataclass_fields(self)
        if not self.gate > 0:
            raise ValueError(f"TrackerConfig.gate must be positive, got {self.gate!r}")
        if not 0 < self.lost_rate <= 1 or not 0 < self.lost_share < 1:
            raise ValueError("TrackerConfig.lost_rate must lie in (0, 1], lost_share in (0, 1)")
        if not all(s > 0 for s in self.lost_std):
            raise ValueError(f"TrackerConfig.lost_std must be positive, got {self.lost_std!r}")


class TrackStats(NamedTuple):
    """What one :func:`track` call did, per robot (each (N,))."""

    accepted: np.ndarray  #: int64: detections used
    gated: np.ndarray  #: int64: detections dropped by the gate
    nis: np.ndarray  #: sum of the accepted detections' squared innovation distances
    declared_lost: np.ndarray  #: bool: the lost detector fired this call


@cached_njit()
def predict_odometry(
    x: np.ndarray,
    P: np.ndarray,
    odom: tuple[float, float, float],
    model: tuple[float, float, float, float, float],
    weights: SigmaWeights,
    scratch: UKFScratch,
) -> bool:
    """The UKF prediction (as ``ukf.ukf_predict``) of ``x`` (3,) and ``P`` (3, 3) in place by
    the odometry step ``odom = (dx, dy, dtheta)`` (robot frame), with the process noise of
    ``ukf.odometry_noise``: ``model = (base_x, base_y, base_theta, translation_fraction,
    rotation_fraction)``. False if a covariance is not positive definite."""
    dx, dy, dth = odom
    bx, by, bt, tf, rf = model
    Wm, Wc = weights.Wm, weights.Wc
    L, sig, _ = scratch
    A = weights.n_lambda * P
    if not chol3(A, L):
        return False
    # the process noise is rotated by the heading before the step (``odometry_noise(mean)``)
    c0, s0 = math.cos(x[2]), math.sin(x[2])
    trans = tf * math.hypot(dx, dy)
    qx, qy = (bx + trans) ** 2, (by + trans) ** 2
    qt = (bt + rf * abs(dth)) ** 2
    sigma_points3(x, L, sig)
    mx = my = ms = mc = 0.0
    for i in range(7):
        c, s = math.cos(sig[i, 2]), math.sin(sig[i, 2])
        sig[i, 0] += c * dx - s * dy
        sig[i, 1] += s * dx + c * dy
        sig[i, 2] += dth
        mx += Wm[i] * sig[i, 0]
        my += Wm[i] * sig[i, 1]
        ms += Wm[i] * math.sin(sig[i, 2])
        mc += Wm[i] * math.cos(sig[i, 2])
    x[0], x[1], x[2] = mx, my, wrap(math.atan2(ms, mc))
    P[:, :] = 0.0
    for i in range(7):
        e0, e1, e2 = sig[i, 0] - x[0], sig[i, 1] - x[1], wrap(sig[i, 2] - x[2])
        w = Wc[i]
        P[0, 0] += w * e0 * e0
        P[1, 0] += w * e1 * e0
        P[1, 1] += w * e1 * e1
        P[2, 0] += w * e2 * e0
        P[2, 1] += w * e2 * e1
        P[2, 2] += w * e2 * e2
    P[0, 0] += c0 * c0 * qx + s0 * s0 * qy
    P[1, 0] += c0 * s0 * (qx - qy)
    P[1, 1] += s0 * s0 * qx + c0 * c0 * qy
    P[2, 2] += qt
    P[0, 1], P[0, 2], P[1, 2] = P[1, 0], P[2, 0], P[2, 1]
    return chol3(P, L)


@cached_njit()
def track_one(
    n: int,
    means: np.ndarray,
    covs: np.ndarray,
    odom: tuple[float, float, float],
    det_ids: np.ndarray,
    det_z: np.ndarray,
    gated_share: np.ndarray,
    landmarks: Landmarks,
    weights: SigmaWeights,
    model: tuple[float, float, float, float, float],
    tracker: tuple[float, float, float, float, float, float],
    stats: TrackStats,
    scratch: UKFScratch,
) -> int:
    """Robot ``n``'s tick (see :meth:`Tracker.step`): predict ``means[n]``, ``covs[n]`` by
    ``odom``, then update with the detections ``det_ids`` (D,) / ``det_z`` (D, 2) in order,
    gated, counting into row ``n`` of ``stats``. ``tracker = (gate, lost_rate, lost_share,
    lost_std x, y, theta)``. Returns :data:`OK` or :data:`NOT_PD`."""
    segments, _, types, noise = landmarks
    gate, lost_rate, lost_share, lx, ly, lt = tracker
    accepted, gated, nis, declared = stats
    x, P = means[n], covs[n]
    if not predict_odometry(x, P, odom, model, weights, scratch):
        return NOT_PD
    for d in range(det_ids.shape[0]):
        k = det_ids[d]
        if k < 0:
            break
        t = types[k]
        ax, ay = segments[k, 0, 0], segments[k, 0, 1]
        bx, by = segments[k, 1, 0], segments[k, 1, 1]
        # the noise at the range the belief expects, not the measured one: weighting by the
        # measured range trusts detections that err short more, a bias that repeated
        # updates turn into overconfidence
        expected_range = abs(expected_rb(x[0], x[1], x[2], ax, ay, bx, by)[0])
        sr = noise[t, 0] + noise[t, 1] * expected_range
        status, distance = ukf_update_rb(
            x,
            P,
            (det_z[d, 0], det_z[d, 1]),
            (ax, ay, bx, by),
            (sr * sr, noise[t, 2] * noise[t, 2]),
            weights,
            scratch,
            gate,
        )
        if status == NOT_PD:
            return NOT_PD
        if status == GATED:
            gated[n] += 1
        else:
            accepted[n] += 1
            nis[n] += distance
    seen = accepted[n] + gated[n]
    if seen < 2:  # a lone false detection must not look like a kidnapping
        return OK
    gated_share[n] += lost_rate * (gated[n] / seen - gated_share[n])
    if gated_share[n] > lost_share:
        declared[n] = True
        gated_share[n] = 0.0
        P[:, :] = 0.0
        P[0, 0], P[1, 1], P[2, 2] = lx * lx, ly * ly, lt * lt
    return OK


@cached_njit()
def track_kernel(
    means: np.ndarray,
    covs: np.ndarray,
    odometry: np.ndarray,
    det_ids: np.ndarray,
    det_z: np.ndarray,
    gated_share: np.ndarray,
    landmarks: Fields,
    weights: Fields,
    model: tuple[float, float, float, float, float],
    tracker: tuple[float, float, float, float, float, float],
    stats: Fields,
) -> np.ndarray:
    """:func:`track_one` for every robot. Returns the error codes (N,) int8."""
    lm = Landmarks(*landmarks)
    sw = SigmaWeights(*weights)
    counts = TrackStats(*stats)
    scratch = UKFScratch(np.empty((3, 3)), np.empty((7, 3)), np.empty((7, 2)))
    errors = np.zeros(means.shape[0], dtype=np.int8)
    for n in range(means.shape[0]):
        odom = (odometry[n, 0], odometry[n, 1], odometry[n, 2])
        errors[n] = track_one(
            n,
            means,
            covs,
            odom,
            det_ids[n],
            det_z[n],
            gated_share,
            lm,
            sw,
            model,
            tracker,
            counts,
            scratch,
        )
    return errors


class Tracker:
    """N pose trackers over the landmarks ``landmarks`` (a ``geometry.LandmarkSet``): the
    compiled bundles are built once, :meth:`step` runs a tick."""

    def __init__(self, landmarks: LandmarkSet, config: TrackerConfig | None = None) -> None:
        self.config = config = config or TrackerConfig()
        ukf = config.ukf
        Wm, Wc = merwe_weights(ukf.n, ukf.alpha, ukf.beta, ukf.kappa)
        self._landmarks = landmark_fields(landmarks, ukf)
        self._weights = tuple(SigmaWeights(Wm, Wc, ukf.n + ukf.lambda_))
        self._model = (
            *ukf.odometry_base,
            ukf.odometry_translation_fraction,
            ukf.odometry_rotation_fraction,
        )
        self._tracker = (config.gate, config.lost_rate, config.lost_share, *config.lost_std)

    def step(
        self,
        means: np.ndarray,
        covs: np.ndarray,
        odometry: np.ndarray,
        det_ids: np.ndarray,
        det_z: np.ndarray,
        gated_share: np.ndarray,
    ) -> TrackStats:
        """One tick of N trackers, **in place**: ``means`` (N, 3) and ``covs`` (N, 3, 3)
        (contiguous float64) are predicted by ``odometry`` (N, 3) (robot-frame ``dx, dy,
        dtheta``), then updated with the detections ``det_ids`` (N, D) int64 (landmark ids,
        padded with -1 after the last) measuring ``det_z`` (N, D, 2) ``(range, bearing)``
        (lines: their polar form, see :mod:`activevision.localisation.ukf`), each gated.
        ``gated_share`` (N,) is the lost detector's moving share, updated in place.

        Raises :class:`NotPositiveDefiniteError` if a covariance lost definiteness (a bug:
        the default sigma-point weights are non-negative, so updates never lose it)."""
        n = len(means)
        stats = TrackStats(
            np.zeros(n, dtype=np.int64),
            np.zeros(n, dtype=np.int64),
            np.zeros(n),
            np.zeros(n, dtype=np.bool_),
        )
        errors = track_kernel(
            means,
            covs,
            np.ascontiguousarray(odometry, dtype=np.float64),
            np.ascontiguousarray(det_ids, dtype=np.int64),
            np.ascontiguousarray(det_z, dtype=np.float64),
            gated_share,
            self._landmarks,
            self._weights,
            self._model,
            self._tracker,
            tuple(stats),
        )
        if errors.any():
            bad = int(np.flatnonzero(errors != OK)[0])
            raise NotPositiveDefiniteError(
                f"tracker {bad}: the covariance is not positive definite"
            )
        return stats
