"""Algorithm 1: the best viewpoint."""

import math
import re

import numba
import numpy as np
import pytest

from activevision.localisation import (
    DEFAULT_UKF,
    LocalisationConfig,
    ViewpointGrid,
    ViewpointStatus,
    best_viewpoint,
    best_viewpoint_loop,
    best_viewpoints,
    candidate_footprints,
    entropy,
    hx_range_bearing,
    kernels,
    ukf_update_sequential,
)
from activevision.localisation.viewpoint import DEFAULT_GRID, search_args

COV0 = DEFAULT_UKF.initial_cov


def test_default_grid_is_the_papers():
    grid = ViewpointGrid()
    assert len(grid) == 40
    assert np.allclose(np.degrees(grid.pan_values), np.arange(-90, 91, 20))
    assert np.allclose(np.degrees(grid.tilt_values), [5, 25, 45, 65])
    assert grid.pans[grid.index(3, 2)] == grid.pan_values[3]
    assert grid.tilts[grid.index(3, 2)] == grid.tilt_values[2]
    assert np.allclose(grid.pan_values, -grid.pan_values[::-1])  # symmetric about 0
    with pytest.raises(ValueError, match="n_pan must be a positive integer"):
        ViewpointGrid(n_pan=0)
    with pytest.raises(ValueError, match=r"n_tilt must be .* up to 20,000, got 1000000000"):
        ViewpointGrid(n_tilt=10**9)
    assert len(ViewpointGrid(n_pan=20_000, n_tilt=1)) == 20_000


@pytest.mark.parametrize(
    ("key", "value", "shown"),
    [
        ("pan_min", "a", "ViewpointGrid.pan_min: expects float, got 'a'"),
        ("tilt_max", float("nan"), "ViewpointGrid.tilt_max: expects float with finite values"),
        ("n_pan", True, "ViewpointGrid.n_pan: expects int, got True"),
        ("n_tilt", 2.0, "ViewpointGrid.n_tilt: expects int, got 2.0"),
    ],
)
def test_grid_refuses_bad_values_naming_them(key, value, shown):
    """A string angle was a TypeError of a comparison, NaN a refusal without its value, and
    True a grid of one pan."""
    with pytest.raises(ValueError, match=re.escape(shown)):
        ViewpointGrid(**{key: value})


@pytest.mark.parametrize(("key", "value"), [("grid", "x"), ("ukf", {"alpha": 1.0})])
def test_localisation_config_refuses_parts_of_another_type(key, value):
    """A grid or UKF of another type failed later, deep in the env's constructor or reset."""
    with pytest.raises(ValueError, match=rf"LocalisationConfig\.{key}: expects"):
        LocalisationConfig(**{key: value})


def test_fast_path_equals_loop(landmarks, cam, random_start):
    rng = np.random.default_rng(0)
    for _ in range(25):
        mean, ball = random_start(rng)
        fast = best_viewpoint(mean, COV0, ball, landmarks, cam)
        slow = best_viewpoint_loop(mean, COV0, ball, landmarks, cam)
        assert np.array_equal(fast.visible, slow.visible)
        assert np.array_equal(fast.ball_visible, slow.ball_visible)
        assert np.allclose(fast.entropies, slow.entropies, rtol=0, atol=1e-10)
        assert np.allclose(fast.covariances, slow.covariances, rtol=0, atol=1e-10)
        assert (fast.status, fast.index, fast.landmark_ids) == (
            slow.status,
            slow.index,
            slow.landmark_ids,
        )


def test_batched_equals_single(landmarks, cam, random_start):
    rng = np.random.default_rng(1)
    starts = [random_start(rng) for _ in range(16)]
    means = np.array([m for m, _ in starts])
    balls = np.array([b for _, b in starts])
    batch = best_viewpoints(means, COV0, balls, landmarks, cam)
    assert len(batch) == 16
    for i, (mean, ball) in enumerate(starts):
        single = best_viewpoint(mean, COV0, ball, landmarks, cam)
        assert np.array_equal(batch.entropies[i], single.entropies)
        assert batch[i].index == single.index == batch.index[i]
        assert batch[i].landmark_ids == single.landmark_ids


def start_arrays(random_start, rng, n):
    """``(means (n, 3), balls (n, 2))`` of ``n`` random episode-like starts."""
    starts = [random_start(rng) for _ in range(n)]
    return np.array([m for m, _ in starts]), np.array([b for _, b in starts])


def test_parallel_search_equals_serial(landmarks, cam, random_start):
    """The threaded search splits (start, view) pairs into blocks; it must change nothing,
    with any number of blocks (more blocks than pairs included)."""
    rng = np.random.default_rng(3)
    means, balls = start_arrays(random_start, rng, 5)
    serial = best_viewpoints(means, COV0, balls, landmarks, cam)
    threaded = best_viewpoints(means, COV0, balls, landmarks, cam, parallel=True)
    assert numba.get_num_threads() == 1 or np.array_equal(serial.entropies, threaded.entropies)
    covs = np.broadcast_to(COV0, (5, 3, 3)).copy()
    args = search_args(means, covs, balls, landmarks, cam, DEFAULT_GRID, DEFAULT_UKF, 0.07, False)
    reference = kernels.search_kernel(*args)
    assert np.array_equal(reference[0], serial.entropies)
    for n_blocks in (1, 3, 7, 1000):
        got = kernels.search_kernel_parallel(*args, n_blocks)
        for a, b in zip(reference, got, strict=True):
            assert np.array_equal(a, b)


def test_ball_views_only_gives_the_same_goal(landmarks, cam, random_start):
    rng = np.random.default_rng(4)
    means, balls = start_arrays(random_start, rng, 30)
    full = best_viewpoints(means, COV0, balls, landmarks, cam)
    fast = best_viewpoints(means, COV0, balls, landmarks, cam, ball_views_only=True)
    assert np.array_equal(full.index, fast.index)
    assert np.array_equal(full.entropy, fast.entropy, equal_nan=True)
    shown = full.ball_visible
    assert np.array_equal(fast.ball_visible, shown)
    assert np.array_equal(full.entropies[shown], fast.entropies[shown])
    assert np.isnan(fast.entropies[~shown]).all() and not fast.visible[~shown].any()
    assert 0 < shown.mean() < 1  # the test sees both kinds of candidates


def test_goal_shows_the_ball_and_has_least_entropy(landmarks, cam, random_start):
    rng = np.random.default_rng(2)
    for _ in range(200):
        mean, ball = random_start(rng)
        res = best_viewpoint(mean, COV0, ball, landmarks, cam)
        if res.status is ViewpointStatus.OK:
            assert res.ball_visible[res.index]
            assert res.entropy == res.entropies[res.index]
            assert res.entropy == res.entropies[res.ball_visible].min()
            assert res.landmark_ids == tuple(np.flatnonzero(res.visible[res.index]))
            # ties go to the first candidate in grid order
            assert res.index == np.flatnonzero(res.ball_visible & (res.entropies == res.entropy))[0]
        else:
            assert not res.ball_visible.any()


def test_goal_posterior_matches_sequential_ukf(landmarks, cam):
    """The goal's covariance is the UKF applied to its landmarks, closest first, z = h(mu)."""
    mean, ball = np.array([-1.0, 0.5, 2.8]), np.array([-3.0, 1.0])
    res = best_viewpoint(mean, COV0, ball, landmarks, cam)
    assert res.ok and res.landmark_ids
    ids = np.array(res.landmark_ids)
    zs = np.array([hx_range_bearing(mean, landmarks.segments[k])[0] for k in ids])
    order = np.argsort(zs[:, 0], kind="stable")
    _, cov = ukf_update_sequential(
        mean, COV0, zs[order], landmarks.segments[ids[order]], landmarks.types[ids[order]]
    )
    assert np.allclose(res.covariances[res.index], cov, rtol=0, atol=1e-12)
    assert res.entropy == pytest.approx(entropy(cov), abs=1e-12)


def test_view_showing_nothing_leaves_the_belief_unchanged(landmarks, cam):
    res = best_viewpoint(np.array([-2.2, 0.4, 0.0]), COV0, np.array([0.0, 0.0]), landmarks, cam)
    empty = ~res.visible.any(axis=1)
    assert empty.any()
    assert np.array_equal(res.covariances[empty], np.broadcast_to(COV0, (empty.sum(), 3, 3)))
    assert np.allclose(res.entropies[empty], entropy(COV0), rtol=0, atol=1e-12)
    assert np.all(res.entropies <= entropy(COV0) + 1e-12)


def test_no_viewpoint_when_ball_behind(landmarks, cam):
    mean = np.array([0.5, -0.5, 0.3])
    behind = mean[:2] - 2.0 * np.array([np.cos(0.3), np.sin(0.3)])
    res = best_viewpoint(mean, COV0, behind, landmarks, cam)
    assert res.status is ViewpointStatus.NO_VIEWPOINT_SHOWS_BALL and not res.ok
    assert res.index == -1 and math.isnan(res.pan) and res.landmark_ids == ()
    assert not res.ball_visible.any() and np.isfinite(res.entropies).all()
    batch = best_viewpoints(
        np.stack([mean, mean]), COV0, np.stack([behind, mean[:2] + 1.5]), landmarks, cam
    )
    assert not batch.ok[0] and batch.index[0] == -1 and np.isnan(batch.pan[0])


def _mirror_ids(landmarks):
    names = list(landmarks.names)
    return np.array(
        [names.index(n.replace("+y", "@").replace("-y", "+y").replace("@", "-y")) for n in names]
    )


def test_mirrored_poses_give_mirrored_choices(landmarks, cam, random_start):
    """Mirror y -> -y, theta -> -theta: the field is symmetric, so the candidate with pan p
    becomes the one with pan -p and shows the mirrored landmarks with the same entropy."""
    rng = np.random.default_rng(3)
    grid = ViewpointGrid()
    mirror_view = np.array(
        [grid.index(grid.n_pan - 1 - i // grid.n_tilt, i % grid.n_tilt) for i in range(len(grid))]
    )
    mirror_lm = _mirror_ids(landmarks)
    flip = np.diag([1.0, -1.0, -1.0])
    checked = 0
    for _ in range(30):
        mean, ball = random_start(rng)
        cov = COV0 + 0.02 * np.array([[0, 1, 0.5], [1, 0, 0.2], [0.5, 0.2, 0]])
        res = best_viewpoint(mean, cov, ball, landmarks, cam)
        mir = best_viewpoint(flip @ mean, flip @ cov @ flip, ball * [1, -1], landmarks, cam)
        assert np.allclose(mir.entropies[mirror_view], res.entropies, rtol=0, atol=1e-9)
        assert np.array_equal(mir.visible[mirror_view][:, mirror_lm], res.visible)
        assert np.array_equal(mir.ball_visible[mirror_view], res.ball_visible)
        assert res.status == mir.status
        if res.ok:
            # the mirror of our choice is one of the mirror's best (candidates that see the
            # same landmarks tie exactly, and grid order breaks ties differently when
            # mirrored); with a unique best it is the mirror's choice itself
            best = mir.ball_visible & (mir.entropies <= mir.entropy + 1e-9)
            assert best[mirror_view[res.index]]
            assert mir.entropy == pytest.approx(res.entropy, abs=1e-9)
            if best.sum() == 1:
                assert mir.index == mirror_view[res.index]
                assert mir.pan == -res.pan and mir.tilt == res.tilt
                checked += 1
    assert checked >= 5


def test_heading_wrap_gives_the_same_choice(landmarks, cam):
    ball = np.array([-3.0, 0.8])
    for theta in (np.pi - 0.05, np.pi, -np.pi + 0.05):
        mean = np.array([-1.0, 0.3, theta])
        a = best_viewpoint(mean, COV0, ball, landmarks, cam)
        for shift in (2 * np.pi, -2 * np.pi):
            b = best_viewpoint(mean + np.array([0, 0, shift]), COV0, ball, landmarks, cam)
            assert b.index == a.index and a.ok
            assert np.array_equal(a.visible, b.visible)
            assert np.allclose(a.entropies, b.entropies, rtol=0, atol=1e-9)


def test_candidate_footprints(cam):
    grid = ViewpointGrid()
    polys = candidate_footprints([0.0, 0.0, 0.0], grid, cam, max_distance=4.0)
    assert polys.shape == (40, 64, 2)
    assert np.all(np.linalg.norm(polys, axis=-1) <= 4.0 + 1e-9)
    # looking left (positive pan) puts the footprint at positive y
    assert polys[grid.index(grid.n_pan - 1, 2)][:, 1].mean() > 0.5


def test_indefinite_belief_raises(landmarks, cam):
    from activevision.localisation import NotPositiveDefiniteError

    with pytest.raises(NotPositiveDefiniteError):
        best_viewpoint(np.zeros(3), np.diag([0.1, -0.1, 0.1]), [1.0, 0.0], landmarks, cam)
    with pytest.raises(ValueError, match="symmetric"):
        best_viewpoint(np.zeros(3), [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]], [1.0, 0.0], landmarks, cam)


@pytest.mark.filterwarnings("error")  # NumPy's 'invalid value' (inf - inf) came first
@pytest.mark.parametrize("variance", [math.inf, math.nan])
def test_a_non_finite_covariance_is_named(landmarks, cam, variance):
    cov = np.diag([0.1, variance, 0.1])
    with pytest.raises(ValueError, match="belief covariances must be finite"):
        best_viewpoint(np.zeros(3), cov, [1.0, 0.0], landmarks, cam)
    with pytest.raises(ValueError, match="belief covariances must be finite"):
        best_viewpoints(np.zeros((2, 3)), np.stack([COV0, cov]), [1.0, 0.0], landmarks, cam)


@pytest.mark.parametrize(
    ("mean", "ball", "shown"),
    [
        ([math.nan, 0.0, 0.0], [1.0, 0.0], r"belief means must be finite, got \[nan, 0\.0, 0\.0\]"),
        ([0.0, 0.0, math.nan], [1.0, 0.0], r"belief means must be finite"),
        ([0.0, 0.0, 0.0], [math.inf, 0.0], r"balls must be finite, got \[inf, 0\.0\]"),
    ],
)
def test_search_refuses_non_finite_poses_and_balls(landmarks, cam, mean, ball, shown):
    """A NaN pose or ball was read as "no view shows the ball" (a robot then told its policy
    there was no proposal), a NaN heading as a covariance not positive definite."""
    with pytest.raises(ValueError, match=shown):
        best_viewpoint(mean, COV0, ball, landmarks, cam)


def test_search_names_the_argument_of_a_bad_shape_or_type(landmarks, cam):
    with pytest.raises(ValueError, match=r"belief_mean must be 3 numbers, shape \(3,\)"):
        best_viewpoint([0.0, 0.0], COV0, [1.0, 0.0], landmarks, cam)
    with pytest.raises(ValueError, match=r"belief_cov must be 9 numbers"):
        best_viewpoint(np.zeros(3), np.eye(2), [1.0, 0.0], landmarks, cam)
    with pytest.raises(ValueError, match=r"ball_xy must be numbers, got 'x'"):
        best_viewpoint(np.zeros(3), COV0, "x", landmarks, cam)
    with pytest.raises(ValueError, match=r"ball_radius must be a number >= 0"):
        best_viewpoint(np.zeros(3), COV0, [1.0, 0.0], landmarks, cam, ball_radius=-0.07)
    with pytest.raises(TypeError, match=r"grid expects ViewpointGrid, got 'x'"):
        best_viewpoint(np.zeros(3), COV0, [1.0, 0.0], landmarks, cam, grid="x")  # type: ignore[arg-type]
    # (N, 2) poses: the kernel read each heading past its row, a silently wrong search
    with pytest.raises(ValueError, match=r"poses, shape \(3,\) or \(N, 3\), got shape \(2, 2\)"):
        best_viewpoints(np.zeros((2, 2)), COV0, [1.0, 0.0], landmarks, cam)
    with pytest.raises(ValueError, match=r"balls must have shape \(2, 2\) or \(2,\)"):
        best_viewpoints(np.zeros((2, 3)), COV0, np.ones((3, 2)), landmarks, cam)


def test_search_of_no_beliefs_is_an_empty_batch(landmarks, cam):
    """Zero starts was numpy's "zero-size array to reduction operation maximum"."""
    batch = best_viewpoints(np.zeros((0, 3)), COV0, [1.0, 0.0], landmarks, cam)
    assert batch.ok.shape == (0,) and batch.entropies.shape == (0, len(DEFAULT_GRID))
