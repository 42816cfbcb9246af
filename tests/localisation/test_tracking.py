"""The match's tracker: the compiled batched UKF against the pure NumPy UKF (itself checked
against FilterPy), its validation gate, and what a trusted tracker must show on simulated
walks: a consistent error (NEES within chi-square bounds), a bounded error over 10^5 ticks,
and a kidnapping detected."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from activevision.envs.match.config import DetectionConfig, MatchConfig
from activevision.envs.match.simulation import MatchBatch
from activevision.geometry.angles import wrap_angle
from activevision.localisation import (
    hx_range_bearing,
    measurement_noise,
    ukf_predict,
    ukf_update,
)
from activevision.localisation.tracking import Tracker, TrackerConfig

FULL = DetectionConfig(near=1.0, far=1.0, false_rate=0.0)


def scan_actions(tick: int, n: int) -> np.ndarray:
    """Pan left for 30 ticks, then right for 30: a head that sweeps the field."""
    return np.full(n, 1 if (tick // 30) % 2 == 0 else 2)


def random_case(rng, landmarks, n=6, per=3):
    means = np.column_stack([rng.uniform(-3, 3, n), rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)])
    covs = np.stack([np.diag(rng.uniform(0.02, 0.2, 3) ** 2) for _ in range(n)])
    odometry = rng.normal(0, [0.05, 0.02, 0.1], (n, 3))
    ids = np.full((n, per + 1), -1)
    z = np.zeros((n, per + 1, 2))
    for i in range(n):
        ks = rng.choice(len(landmarks), per, replace=False)
        ids[i, :per] = ks
        truth = means[i] + rng.normal(0, 0.05, 3)
        for d, k in enumerate(ks):
            z[i, d] = hx_range_bearing(truth, landmarks.segments[k])[0]
    return means, covs, odometry, ids, z


def test_tracker_matches_the_numpy_ukf(landmarks):
    """Predict by odometry, then each detection in order: as ``ukf_predict`` and
    ``ukf_update`` with R at the range the belief expects, to rounding."""
    rng = np.random.default_rng(3)
    means, covs, odometry, ids, z = random_case(rng, landmarks)
    config = TrackerConfig(gate=1e9)
    expected = []
    for i in range(len(means)):
        m, P = ukf_predict(means[i], covs[i], odometry[i], config.ukf)
        for d in range(ids.shape[1]):
            k = ids[i, d]
            if k < 0:
                break
            segment, kind = landmarks.segments[k], landmarks.types[k]
            r = abs(hx_range_bearing(m, segment)[0, 0])
            m, P = ukf_update(
                m, P, z[i, d], segment, kind, config.ukf, measurement_noise(r, kind, config.ukf)
            )
        expected.append((m, P))
    stats = Tracker(landmarks, config).step(means, covs, odometry, ids, z, np.zeros(len(means)))
    for i, (m, P) in enumerate(expected):
        np.testing.assert_allclose(means[i], m, rtol=0, atol=1e-12)
        np.testing.assert_allclose(covs[i], P, rtol=0, atol=1e-12)
    assert stats.accepted.tolist() == [3] * len(means)
    assert not stats.gated.any()


def test_gate_drops_a_wild_detection(landmarks):
    """A detection 3 m from where the belief expects it fails the gate: the belief is the
    prediction alone, and the detection is counted as gated."""
    rng = np.random.default_rng(4)
    means, covs, odometry, ids, z = random_case(rng, landmarks, n=1, per=1)
    z[0, 0, 0] += 3.0
    predicted = ukf_predict(means[0], covs[0], odometry[0], TrackerConfig().ukf)
    stats = Tracker(landmarks).step(means, covs, odometry, ids, z, np.zeros(1))
    assert stats.gated.tolist() == [1] and stats.accepted.tolist() == [0]
    np.testing.assert_allclose(means[0], predicted[0], atol=1e-12)
    np.testing.assert_allclose(covs[0], predicted[1], atol=1e-12)


def test_tracker_config_rejects_bad_values():
    with pytest.raises(ValueError, match="gate"):
        TrackerConfig(gate=0.0)
    with pytest.raises(ValueError, match="lost_std"):
        TrackerConfig(lost_std=(1.0, 0.0, 1.0))


def normalised_errors(sim: MatchBatch) -> np.ndarray:
    """NEES (N,): the squared Mahalanobis distance of the true pose from the belief."""
    e = sim.pose - sim.mean
    e[:, 2] = wrap_angle(e[:, 2])
    return np.einsum("ni,nij,nj->n", e, np.linalg.inv(sim.cov), e)


def test_nees_within_chi_square_bounds():
    """The textbook consistency test (Bar-Shalom et al., 2001, 5.4): over M Monte Carlo
    walks with every landmark in view detected, the average NEES at each tick lies within
    the two-sided 95% chi-square bounds (3M degrees of freedom) at about 95% of ticks.
    An overconfident filter (as with R at the measured range: 31% inside) fails."""
    m, ticks = 60, 150
    sim = MatchBatch(MatchConfig(detection=FULL), m)
    sim.reset(np.arange(m), [np.random.default_rng(s) for s in range(m)])
    average = np.zeros(ticks)
    for t in range(ticks):
        sim.step(scan_actions(t, m))
        average[t] = normalised_errors(sim).mean()
    low, high = chi2.ppf(0.025, 3 * m) / m, chi2.ppf(0.975, 3 * m) / m
    inside = np.mean((average >= low) & (average <= high))
    assert inside >= 0.85, (inside, average.mean())
    assert 2.7 < average.mean() < 3.3


def test_error_stays_bounded_over_100000_ticks():
    """One robot walks for 10^5 ticks (8.9 hours of play) with the default detector (misses
    and false detections) and a sweeping head: the error never grows beyond 0.5 m and the
    robot never declares itself lost."""
    sim = MatchBatch(MatchConfig(ticks=100_000), 1)
    sim.reset(np.arange(1), [np.random.default_rng(11)])
    worst = 0.0
    for t in range(100_000):
        sim.step(scan_actions(t, 1))
        worst = max(worst, float(sim.position_error()[0]))
    assert worst < 0.5, worst
    assert not sim.declared_lost[0]
    assert sim.accepted[0] > 100_000  # it kept seeing landmarks all along


def test_kidnapping_is_detected():
    """Teleported 2 m along the field, 1 m across it and turned 0.8 rad mid-match, every
    robot declares itself lost within 100 ticks (half of them within 20: 6.4 s); the same matches
    without the teleport raise no alarm in twice that time. Then most relocalise: the
    widened belief lets the gate pass detections again (README: detected, mostly
    recovered)."""
    m = 16
    for kidnap in (False, True):
        sim = MatchBatch(MatchConfig(), m)
        sim.reset(np.arange(m), [np.random.default_rng(100 + s) for s in range(m)])
        for t in range(100):
            sim.step(scan_actions(t, m))
        assert not sim.declared_lost.any()
        if kidnap:
            sim.pose[:, 0] -= 2.0 * np.sign(sim.pose[:, 0])
            sim.pose[:, 1] -= 1.0 * np.sign(sim.pose[:, 1])
            sim.pose[:, 2] = wrap_angle(sim.pose[:, 2] + 0.8)
        declared_at = np.full(m, -1)
        for t in range(100, 300 if not kidnap else 200):
            sim.step(scan_actions(t, m))
            declared_at[(declared_at < 0) & sim.declared_lost] = t - 100
        assert (declared_at >= 0).all() == kidnap, declared_at
        if kidnap:
            assert np.median(declared_at) <= 20, declared_at
            # and the widened belief relocks: most robots are back within 0.3 m
            for t in range(200, 400):
                sim.step(scan_actions(t, m))
            assert np.mean(sim.position_error() < 0.3) >= 0.75, sim.position_error()
