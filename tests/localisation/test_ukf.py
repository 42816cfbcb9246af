"""The pose UKF: FilterPy reference, covariance health, heading wrap, information."""

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from activevision.geometry import LandmarkType
from activevision.localisation import (
    NotPositiveDefiniteError,
    PoseBelief,
    UKFConfig,
    entropy,
    fx_odometry,
    hx_range_bearing,
    measurement_mean,
    measurement_noise,
    odometry_noise,
    residual_x,
    residual_z,
    state_mean,
    ukf_predict,
    ukf_update,
    ukf_update_sequential,
)
from activevision.localisation.ukf import is_point, line_normal

filterpy_kalman = pytest.importorskip("filterpy.kalman")

CFG = UKFConfig()


def random_cov(rng: np.random.Generator, scale: float = 0.4) -> np.ndarray:
    a = rng.normal(size=(3, 3)) * scale
    return a @ a.T + np.diag([0.01, 0.01, 0.005])


def _filterpy_ukf(x, P, cfg=CFG):
    points = filterpy_kalman.MerweScaledSigmaPoints(
        3, alpha=cfg.alpha, beta=cfg.beta, kappa=cfg.kappa, subtract=residual_x
    )
    f = filterpy_kalman.UnscentedKalmanFilter(
        dim_x=3,
        dim_z=2,
        dt=1.0,
        hx=None,
        fx=None,
        points=points,
        x_mean_fn=state_mean,
        z_mean_fn=measurement_mean,
        residual_x=residual_x,
        residual_z=residual_z,
    )
    f.x, f.P = np.array(x, float), np.array(P, float)
    return f


def _random_observation(rng, x):
    seg = rng.uniform(-5, 5, size=(2, 2))
    if rng.random() < 0.5:
        seg[1] = seg[0]  # a point landmark
    z = hx_range_bearing(x, seg)[0] + rng.normal(size=2) * [0.2, 0.1]
    return (
        z,
        seg,
        int(rng.choice([LandmarkType.L_CORNER, LandmarkType.LINE, LandmarkType.FIELD_BOUNDARY])),
    )


@pytest.mark.parametrize("cfg", [CFG, UKFConfig(alpha=0.5, beta=2.0, kappa=1.0)])
def test_update_matches_filterpy_sequentially(cfg):
    rng = np.random.default_rng(0)
    for _ in range(100):
        x = np.array([rng.uniform(-4, 4), rng.uniform(-3, 3), rng.uniform(-np.pi, np.pi)])
        P = random_cov(rng)
        f = _filterpy_ukf(x, P, cfg)
        mean, cov = x, P
        for _ in range(3):
            z, seg, t = _random_observation(rng, x)
            # fresh sigma points for every detection (Algorithm 1 applies one at a time)
            f.sigmas_f = f.points_fn.sigma_points(f.x, f.P)
            normal = None if is_point(seg) else line_normal(seg, f.x[2], z[1])
            f.update(
                z,
                R=measurement_noise(abs(z[0]), t, cfg),
                hx=lambda s, seg=seg, n=normal: hx_range_bearing(s, seg, n)[0],
            )
            mean, cov = ukf_update(mean, cov, z, seg, t, cfg)
            assert np.abs(residual_x(mean, f.x)).max() < 1e-9
            assert np.abs(cov - f.P).max() < 1e-9


def test_predict_matches_filterpy():
    rng = np.random.default_rng(1)
    for _ in range(100):
        x = np.array([rng.uniform(-4, 4), rng.uniform(-3, 3), rng.uniform(-np.pi, np.pi)])
        P = random_cov(rng)
        odom = rng.normal(size=3) * [0.1, 0.05, 0.3]
        f = _filterpy_ukf(x, P)
        f.Q = odometry_noise(x, odom, CFG)
        f.predict(fx=lambda s, dt, odom=odom: fx_odometry(s, odom)[0])
        mean, cov = ukf_predict(x, P, odom, CFG)
        assert np.abs(residual_x(mean, f.x)).max() < 1e-9
        assert np.abs(cov - f.P).max() < 1e-9


def test_covariance_stays_symmetric_pd_over_10000_updates():
    rng = np.random.default_rng(2)
    mean, cov = np.array([0.0, 0.0, 3.0]), CFG.initial_cov
    for i in range(10_000):
        if i % 10 == 0:
            mean, cov = ukf_predict(mean, cov, rng.normal(size=3) * [0.05, 0.02, 0.1], CFG)
        if i % 500 == 0:  # re-inflate so updates keep doing something
            cov = cov + np.diag([0.1, 0.1, 0.05])
        z, seg, t = _random_observation(rng, mean)
        mean, cov = ukf_update(mean, cov, z, seg, t, CFG)
        assert np.array_equal(cov, cov.T)
        assert -np.pi < mean[2] <= np.pi
    assert np.all(np.linalg.eigvalsh(cov) > 0)


def test_indefinite_covariance_raises():
    bad = np.diag([0.1, -0.1, 0.1])
    with pytest.raises(NotPositiveDefiniteError, match="not positive definite"):
        ukf_update(np.zeros(3), bad, [1.0, 0.0], [[1, 0], [1, 0]], LandmarkType.L_CORNER)
    with pytest.raises(NotPositiveDefiniteError):
        ukf_predict(np.zeros(3), bad, [0.1, 0.0, 0.0])
    with pytest.raises(NotPositiveDefiniteError):
        PoseBelief(np.zeros(3), bad)


def _rotate(mean, cov, seg, phi):
    c, s = np.cos(phi), np.sin(phi)
    R = np.array([[c, -s], [s, c]])
    T = np.eye(3)
    T[:2, :2] = R
    return (np.array([*(R @ mean[:2]), mean[2] + phi]), T @ cov @ T.T, np.asarray(seg) @ R.T, T)


@pytest.mark.parametrize("theta", [np.pi - 0.01, -np.pi + 0.01, np.pi])
def test_heading_wrap_equals_unwrapped_equivalent(theta):
    """Sigma headings straddle +-pi; turning the whole world by -pi/2 moves them away from
    the wrap. The posterior must be the same (turned back)."""
    rng = np.random.default_rng(3)
    for _ in range(20):
        mean = np.array([rng.uniform(-3, 3), rng.uniform(-2, 2), theta])
        cov = CFG.initial_cov
        seg = rng.uniform(-4, 4, size=(2, 2))
        z = hx_range_bearing(mean, seg)[0] + rng.normal(size=2) * [0.1, 0.05]
        m1, c1 = ukf_update(mean, cov, z, seg, LandmarkType.LINE)
        m_r, c_r, seg_r, _ = _rotate(mean, cov, seg, -np.pi / 2)
        m2, c2 = ukf_update(m_r, c_r, z, seg_r, LandmarkType.LINE)
        m2, c2, _, _ = _rotate(m2, c2, seg_r, np.pi / 2)
        assert np.abs(residual_x(m1, m2)).max() < 1e-9
        assert np.allclose(c1, c2, rtol=0, atol=1e-12)
        # and a 2 pi shifted heading is the same belief
        m3, c3 = ukf_update(mean + np.array([0, 0, 2 * np.pi]), cov, z, seg, LandmarkType.LINE)
        assert np.abs(residual_x(m1, m3)).max() < 1e-9 and np.allclose(c1, c3, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 6))
def test_entropy_never_rises_when_a_landmark_is_added(seed, n):
    rng = np.random.default_rng(seed)
    mean = np.array([rng.uniform(-4, 4), rng.uniform(-3, 3), rng.uniform(-np.pi, np.pi)])
    cov = random_cov(rng)
    h = entropy(cov)
    for _ in range(n):
        z, seg, t = _random_observation(rng, mean)
        new_mean, new_cov = ukf_update(mean, cov, z, seg, t)
        h_new = entropy(new_cov)
        assert h_new <= h + 1e-12
        # P' <= P in the Loewner order (all Merwe weights are non-negative by default)
        assert np.linalg.eigvalsh(cov - new_cov).min() > -1e-12
        mean, cov, h = new_mean, new_cov, h_new


def test_closer_and_more_landmarks_give_lower_entropy():
    """Closer is better while the belief is small against the distance. (With the 0.5 m
    episode-start belief the sigma points reach +-0.87 m, and the UKF rightly finds a point
    1 m away less informative than one 3 m away: seen from the sigma points its bearing
    swings by up to 90 deg, a strongly nonlinear measurement.)"""
    mean, cov = np.array([0.0, 0.0, 0.3]), np.diag([0.1, 0.1, 0.05]) ** 2
    direction = np.array([np.cos(0.5), np.sin(0.5)])
    hs = []
    for d in (1.0, 1.5, 2.0, 3.0, 4.0):
        p = d * direction
        z = hx_range_bearing(mean, [p, p])[0]
        hs.append(entropy(ukf_update(mean, cov, z, [p, p], LandmarkType.L_CORNER)[1]))
    assert np.all(np.diff(hs) > 0)
    points = np.array([[2.0, 1.0], [2.0, -1.0], [3.0, 0.0], [1.0, 2.0]])
    segs = np.repeat(points[:, None], 2, axis=1)
    cov = CFG.initial_cov
    hs = [entropy(cov)]
    for m in range(1, len(points) + 1):
        zs = np.array([hx_range_bearing(mean, s)[0] for s in segs[:m]])
        hs.append(entropy(ukf_update_sequential(mean, cov, zs, segs[:m], [0] * m)[1]))
    assert np.all(np.diff(hs) < 0)


def test_line_observation_does_not_inform_along_the_line():
    """A long line seen side-on fixes the distance to it and the heading, not the position
    along it: the posterior keeps the prior's variance along the line."""
    mean, cov = np.array([0.0, 0.0, np.pi / 2]), np.diag([0.25, 0.25, 0.09])
    line = np.array([[-50.0, 2.0], [50.0, 2.0]])
    z = hx_range_bearing(mean, line)[0]
    _, post = ukf_update(mean, cov, z, line, LandmarkType.LINE)
    assert post[0, 0] == pytest.approx(0.25, rel=1e-9)
    assert post[1, 1] < 0.1 and post[2, 2] < 0.09


def test_pose_belief_wrapper_is_pure():
    b0 = PoseBelief.initial([1.0, 2.0, 0.5])
    assert np.allclose(b0.cov, CFG.initial_cov)
    b1 = b0.predict([0.1, 0.0, 0.05])
    b2 = b1.update([2.0, 0.1], [[3.0, 3.0], [3.0, 3.0]], LandmarkType.T_JUNCTION)
    assert b0.mean[0] == 1.0 and not b0.mean.flags.writeable
    assert entropy(b2.cov) < entropy(b1.cov)


def test_measurement_noise_grows_with_range():
    r1 = measurement_noise(1.0, LandmarkType.L_CORNER)
    r3 = measurement_noise(3.0, LandmarkType.L_CORNER)
    assert r3[0, 0] > r1[0, 0] and r3[1, 1] == r1[1, 1]
    assert r1[0, 0] == pytest.approx((0.05 + 0.1) ** 2)


def test_config_pickles_and_deep_copies_with_its_read_only_noise():
    import copy
    import pickle
    from types import MappingProxyType

    from activevision.localisation.config import RangeBearingNoise

    noise = dict(UKFConfig().noise)
    noise[LandmarkType.L_CORNER] = RangeBearingNoise(0.2, 0.1, 0.05)
    cfg = UKFConfig(noise=MappingProxyType(noise), initial_std=(0.3, 0.3, 0.2))
    for twin in (pickle.loads(pickle.dumps(cfg)), copy.deepcopy(cfg)):
        assert twin == cfg and twin is not cfg
        with pytest.raises(TypeError, match="read-only"):  # still read-only
            twin.noise[LandmarkType.L_CORNER] = RangeBearingNoise(0.1, 0.1, 0.05)
        assert twin.noise[LandmarkType.L_CORNER] == RangeBearingNoise(0.2, 0.1, 0.05)


def test_config_read_back_from_json_is_the_same_config():
    """config.json holds the noise by type id with plain objects and lists for tuples: the
    config rebuilt from that equals the original; malformed values are one clear error."""
    import dataclasses
    import json

    cfg = UKFConfig(initial_std=(0.3, 0.3, 0.2))
    values = {f.name: getattr(cfg, f.name) for f in dataclasses.fields(cfg)}
    values["noise"] = {
        str(int(kind)): dataclasses.asdict(noise) for kind, noise in cfg.noise.items()
    }
    values = json.loads(json.dumps(values))  # tuples -> lists
    assert UKFConfig(**values) == cfg
    with pytest.raises(ValueError, match="odometry_base: expects 3 numbers"):
        UKFConfig(odometry_base=0.1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"UKFConfig\.noise"):
        UKFConfig(noise={"0": {"range": 1.0}})  # type: ignore[dict-item]


@pytest.mark.parametrize(
    ("changes", "shown"),
    [
        ({"beta": float("nan")}, "UKFConfig.beta: expects float with finite values"),
        ({"beta": "2"}, "UKFConfig.beta: expects float, got '2'"),
        ({"alpha": True}, "UKFConfig.alpha: expects float, got True"),
        ({"kappa": float("inf")}, "UKFConfig.kappa: expects float with finite values"),
        ({"alpha": 1e200}, "alpha^2 (n + kappa) finite"),
        ({"odometry_rotation_fraction": -0.1}, "odometry_rotation_fraction: must be >= 0.0"),
        ({"initial_std": (True, 0.5, 0.3)}, "initial_std: expects 3 numbers"),
        ({"initial_std": ("0.5", 0.5, 0.3)}, "initial_std: expects 3 numbers"),
        ({"noise": [1, 2]}, "UKFConfig.noise: expects a mapping"),
    ],
)
def test_config_refuses_bad_values_naming_them(changes, shown):
    """Each was taken (a NaN or infinite parameter failing the first goal search as a
    covariance "not positive definite", a string or True kept as given) or an
    AttributeError / OverflowError of the check itself."""
    with pytest.raises(ValueError, match=re.escape(shown)):
        UKFConfig(**changes)


def test_sensor_noise_refuses_non_finite_and_non_numbers():
    from activevision.localisation.config import RangeBearingNoise

    with pytest.raises(ValueError, match=r"range_base: expects float with finite"):
        RangeBearingNoise(float("inf"), 0.1, 0.05)
    with pytest.raises(ValueError, match=r"RangeBearingNoise\.bearing: expects float, got 'x'"):
        RangeBearingNoise(0.05, 0.1, "x")  # type: ignore[arg-type]
    assert RangeBearingNoise(1, 0, 1) == RangeBearingNoise(1.0, 0.0, 1.0)
