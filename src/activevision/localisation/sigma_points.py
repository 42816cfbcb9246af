"""Van der Merwe's scaled sigma points (FilterPy's ``MerweScaledSigmaPoints``)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt


class NotPositiveDefiniteError(np.linalg.LinAlgError):
    """A covariance that must be symmetric positive definite is not."""


def merwe_weights(n: int, alpha: float, beta: float, kappa: float) -> tuple[np.ndarray, np.ndarray]:
    """Mean and covariance weights ``(Wm, Wc)``, each (2n+1,)."""
    lambda_ = alpha**2 * (n + kappa) - n
    c = 0.5 / (n + lambda_)
    Wm = np.full(2 * n + 1, c)
    Wc = np.full(2 * n + 1, c)
    Wm[0] = lambda_ / (n + lambda_)
    Wc[0] = lambda_ / (n + lambda_) + (1 - alpha**2 + beta)
    return Wm, Wc


def cholesky(P: np.ndarray) -> np.ndarray:
    """Lower Cholesky factor of ``P``; raises :class:`NotPositiveDefiniteError` (never
    repairs the matrix: an indefinite covariance is a bug upstream)."""
    try:
        return np.linalg.cholesky(P)
    except np.linalg.LinAlgError:
        raise NotPositiveDefiniteError(
            f"covariance is not positive definite:\n{np.array2string(np.asarray(P))}"
        ) from None


def merwe_sigma_points(
    x: npt.ArrayLike, P: npt.ArrayLike, alpha: float, kappa: float
) -> np.ndarray:
    """Sigma points (2n+1, n): ``x``, then ``x + L[:, k]``, then ``x - L[:, k]``, with
    ``L L^T = (n + lambda) P``. Headings are left unwrapped (the models wrap)."""
    x = np.asarray(x, dtype=np.float64)
    n = len(x)
    lambda_ = alpha**2 * (n + kappa) - n
    L = cholesky((n + lambda_) * np.asarray(P, dtype=np.float64))
    return np.concatenate([x[None], x + L.T, x - L.T])
