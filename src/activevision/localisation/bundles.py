"""The typed bundles (numba namedtuples) the viewpoint-search kernels take instead of long
argument lists (see :mod:`activevision.localisation.kernels`)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class Starts(NamedTuple):
    """The N beliefs searched from, and the ball each must keep in view."""

    means: np.ndarray  #: (N, 3) believed poses (x, y, theta)
    covs: np.ndarray  #: (N, 3, 3) their covariances
    balls: np.ndarray  #: (N, 2) ball positions on the ground
    ball_radius: float
    hidden: np.ndarray  #: (N, K) bool: landmarks hidden from each start (by other robots)


class Landmarks(NamedTuple):
    """The K landmarks (the arrays of a ``geometry.LandmarkSet``) and the noise model of
    their detections."""

    segments: np.ndarray  #: (K, 2, 2) end points; a point landmark has both equal
    max_distance: np.ndarray  #: (K,) detection range (m)
    types: np.ndarray  #: (K,) LandmarkType values: rows of ``noise``
    noise: np.ndarray  #: (T, 3) range base (m), range fraction, bearing (rad) std per type


class SigmaWeights(NamedTuple):
    """The UKF's sigma-point weights."""

    Wm: np.ndarray  #: (7,) mean weights
    Wc: np.ndarray  #: (7,) covariance weights
    n_lambda: float  #: n + lambda, the spread of the sigma points


class Views(NamedTuple):
    """The V candidate head positions."""

    pans: np.ndarray  #: (V,)
    tilts: np.ndarray  #: (V,)
    ball_views_only: bool  #: skip the filter for views that miss the ball


class Plan(NamedTuple):
    """What each start expects of each landmark (:func:`plan_starts`), each (N, K) but
    ``zs``."""

    zs: np.ndarray  #: (N, K, 2) expected detection (range, bearing) from the mean
    var_r: np.ndarray  #: its range variance
    var_b: np.ndarray  #: its bearing variance
    in_range: np.ndarray  #: whether some part of the landmark is within range
    r_lo: np.ndarray  #: that part: segment parameters [r_lo, r_hi]
    r_hi: np.ndarray
    order: np.ndarray  #: (N, K) landmarks by expected range, closest first (ties by id)


class SearchOutput(NamedTuple):
    """The results of a search, each (N, V, ...)."""

    entropies: np.ndarray  #: (N, V) entropy of the expected posterior (NaN: skipped or error)
    ball_visible: np.ndarray  #: (N, V) whether the view shows the ball
    visible: np.ndarray  #: (N, V, K) landmarks in view
    posteriors: np.ndarray  #: (N, V, 3, 3) expected posterior covariances
    errors: np.ndarray  #: (N, V) int8: OK, or NOT_PD where a covariance lost definiteness


class UKFScratch(NamedTuple):
    """Scratch of :func:`ukf_update_rb` (one per thread)."""

    L: np.ndarray  #: (3, 3) Cholesky factor
    sig: np.ndarray  #: (7, 3) sigma points
    hz: np.ndarray  #: (7, 2) their expected detections
