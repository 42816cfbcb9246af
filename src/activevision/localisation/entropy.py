"""Differential entropy of a Gaussian belief (Algorithm 1, line 8)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from activevision.localisation.sigma_points import NotPositiveDefiniteError


def entropy(cov: npt.ArrayLike) -> float | np.ndarray:
    """``H = 1/2 ln |2 pi e Sigma| = n/2 ln(2 pi e) + 1/2 ln |Sigma|`` (nats).

    ``cov``: (..., n, n); computed with ``slogdet`` so tiny or huge determinants neither
    underflow nor overflow. Returns a float, or an array of shape ``cov.shape[:-2]``.
    """
    cov = np.asarray(cov, dtype=np.float64)
    n = cov.shape[-1]
    sign, logdet = np.linalg.slogdet(cov)
    if np.any(sign <= 0):
        raise NotPositiveDefiniteError("entropy needs a positive definite covariance")
    h = 0.5 * (n * np.log(2 * np.pi * np.e) + logdet)
    return float(h) if np.ndim(h) == 0 else h
