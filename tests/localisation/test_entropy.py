import numpy as np
import pytest

from activevision.localisation import NotPositiveDefiniteError, entropy


def test_entropy_hand_computed():
    # n = 3, |Sigma| = 4 * 1 * 0.25 = 1: H = 3/2 ln(2 pi e) = 4.256815599614018
    assert entropy(np.diag([4.0, 1.0, 0.25])) == pytest.approx(4.256815599614018, abs=1e-14)
    # |Sigma| = 0.25^2 * 0.09: H = 1.5 ln(2 pi e) + 0.5 ln(0.005625)
    cov = np.diag([0.25, 0.25, 0.09])
    assert entropy(cov) == pytest.approx(4.256815599614018 + 0.5 * np.log(0.005625), abs=1e-14)
    # 1-D: H = 0.5 ln(2 pi e sigma^2)
    assert entropy(np.array([[2.0]])) == pytest.approx(0.5 * np.log(2 * np.pi * np.e * 2.0))


def test_entropy_batched_and_tiny():
    covs = np.stack([np.eye(3), 1e-200 * np.eye(3)])
    h = entropy(covs)
    assert h.shape == (2,)
    assert h[1] == pytest.approx(h[0] + 1.5 * np.log(1e-200))  # no underflow


def test_entropy_rejects_indefinite():
    with pytest.raises(NotPositiveDefiniteError):
        entropy(np.diag([1.0, -1.0, 1.0]))
