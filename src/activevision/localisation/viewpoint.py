"""The best viewpoint: Algorithm 1 of the paper ("viewpoint exploration").

For every candidate head position ``(pan, tilt)`` of a :class:`ViewpointGrid`: take the
landmarks visible from the *believed* mean pose, update the belief with the UKF as if each
were detected exactly where expected (``z = h(mu)``: the covariance update does not depend
on the measured value, so this is the expected posterior), and score the posterior by its
entropy. The goal is the least-entropy candidate from which the ball (also judged from the
believed pose) is in view; ties go to the first candidate in grid order.

Detections are applied sequentially, as in Algorithm 1 (lines 5-7), with fresh sigma points
for each. The paper leaves the order open; we take the closest landmark first (ties by id),
which makes the result independent of how the landmarks are numbered -- in particular,
mirrored poses on the symmetric field give exactly mirrored entropies. (A joint update with
all detections stacked would differ slightly for a UKF; it is not used.)

:func:`best_viewpoint_loop` is the plain NumPy reference (a Python loop over candidates and
landmarks); :func:`best_viewpoint` / :func:`best_viewpoints` run the same computation
compiled with numba (:mod:`activevision.localisation.kernels`) and agree with it to rounding.
"""

from __future__ import annotations

import math
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from activevision.geometry.camera import CameraConfig, footprint_polygon
from activevision.geometry.field import LandmarkType
from activevision.geometry.kernels import camera_fields
from activevision.geometry.landmarks import LandmarkSet
from activevision.geometry.visibility import ball_visible, visible_landmarks
from activevision.localisation import kernels
from activevision.localisation.bundles import Landmarks, SigmaWeights, Starts, Views
from activevision.localisation.config import DEFAULT_UKF, UKFConfig
from activevision.localisation.entropy import entropy
from activevision.localisation.sigma_points import (
    NotPositiveDefiniteError,
    merwe_weights,
)
from activevision.localisation.ukf import hx_range_bearing, ukf_update_sequential
from activevision.localisation.viewpoint_types import (
    DEFAULT_GRID,
    ViewpointBatch,
    ViewpointGrid,
    ViewpointResult,
    choose_goal,
    search_result,
)
from activevision.threads import numba_threads


def _noise_table(ukf: UKFConfig) -> np.ndarray:
    """(T, 3) rows ``(range_base, range_fraction, bearing)`` indexed by LandmarkType value."""
    table = np.zeros((max(LandmarkType) + 1, 3))
    for t, nz in ukf.noise.items():
        table[int(t)] = (nz.range_base, nz.range_fraction, nz.bearing)
    return table


def landmark_fields(landmarks: LandmarkSet, ukf: UKFConfig) -> kernels.Fields:
    """The fields of the kernels' ``Landmarks`` bundle: ``landmarks`` and ``ukf``'s noise."""
    return tuple(
        Landmarks(landmarks.segments, landmarks.max_distance, landmarks.types, _noise_table(ukf))
    )


def search_args(
    means: np.ndarray,
    covs: np.ndarray,
    balls: np.ndarray,
    landmarks: LandmarkSet,
    cam: CameraConfig,
    grid: ViewpointGrid,
    ukf: UKFConfig,
    ball_radius: float,
    ball_views_only: bool,
    hidden: np.ndarray | None = None,
) -> tuple[kernels.Fields, kernels.Fields, kernels.Fields, kernels.Fields, tuple[float, ...]]:
    """The bundles of :func:`kernels.search_kernel` (``Starts``, ``Landmarks``,
    ``SigmaWeights``, ``Views``, ``CameraModel``) for contiguous float64 ``means`` (N, 3),
    ``covs`` (N, 3, 3), ``balls`` (N, 2) and bool ``hidden`` (N, K) (None: nothing hidden),
    each as the plain tuple of its fields."""
    if hidden is None:
        hidden = np.zeros((len(means), len(landmarks)), dtype=bool)
    starts = tuple(Starts(means, covs, balls, float(ball_radius), hidden))
    return (starts, *_static_bundles(landmarks, cam, grid, ukf, ball_views_only))


#: The last :func:`_static_bundles` and what they were made from.
_last_static: tuple[tuple[object, ...], tuple[Any, ...]] = ((), ())


def _static_bundles(
    landmarks: LandmarkSet,
    cam: CameraConfig,
    grid: ViewpointGrid,
    ukf: UKFConfig,
    ball_views_only: bool,
) -> tuple[kernels.Fields, kernels.Fields, kernels.Fields, tuple[float, ...]]:
    """The fields of the ``Landmarks``, ``SigmaWeights``, ``Views`` and ``CameraModel`` of a
    search; the last ones are kept for the same (``is``) inputs, which an environment passes
    every time (building them takes about as long as 5% of a single search)."""
    global _last_static
    made_from = (landmarks, cam, grid, ukf, ball_views_only)
    cached_from, bundles = _last_static
    if len(cached_from) == len(made_from) and all(
        a is b for a, b in zip(cached_from, made_from, strict=True)
    ):
        return bundles
    Wm, Wc = merwe_weights(ukf.n, ukf.alpha, ukf.beta, ukf.kappa)
    bundles = (
        landmark_fields(landmarks, ukf),
        tuple(SigmaWeights(Wm, Wc, ukf.n + ukf.lambda_)),
        tuple(Views(grid.pans, grid.tilts, bool(ball_views_only))),
        camera_fields(cam),
    )
    _last_static = (made_from, bundles)
    return bundles


def _search(
    means: ArrayLike,
    covs: ArrayLike,
    balls: ArrayLike,
    landmarks: LandmarkSet,
    cam: CameraConfig,
    grid: ViewpointGrid,
    ukf: UKFConfig,
    ball_radius: float,
    parallel: bool = False,
    ball_views_only: bool = False,
    hidden: ArrayLike | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Validate and run the compiled search: ``(entropies, ball_visible, visible, post)``."""
    _check_setting("cam", cam, CameraConfig)
    _check_setting("grid", grid, ViewpointGrid)
    _check_setting("ukf", ukf, UKFConfig)
    radius = _float_array("ball_radius", ball_radius)
    if radius.shape != () or not (np.isfinite(radius) and radius >= 0):
        raise ValueError(
            f"best viewpoint search: ball_radius must be a number >= 0 (m), got {ball_radius!r}"
        )
    means = np.ascontiguousarray(np.atleast_2d(_float_array("means", means)))
    if means.ndim != 2 or means.shape[1] != 3:
        # a kernel reads three numbers a pose: (N, 2) poses read past each row
        raise ValueError(
            "best viewpoint search: belief means must be (x, y, theta) poses, shape (3,) or"
            f" (N, 3), got shape {means.shape}"
        )
    n = len(means)
    hidden_arr = None
    if hidden is not None:
        hidden_arr = np.ascontiguousarray(_broadcast("hidden", hidden, (n, len(landmarks)), bool))
    covs = np.ascontiguousarray(_broadcast("covs", covs, (n, 3, 3)))
    balls = np.ascontiguousarray(_broadcast("balls", balls, (n, 2)))
    for name, values in (("belief means", means), ("balls", balls)):
        if not np.isfinite(values).all():
            # a NaN x or ball read as "no view shows the ball", a NaN heading as a covariance
            # not positive definite
            bad = values[~np.isfinite(values).all(axis=1)][0]
            raise ValueError(f"best viewpoint search: {name} must be finite, got {bad.tolist()}")
    if not np.isfinite(covs).all():
        # an infinite variance was NumPy's 'invalid value' warning (inf - inf), then a
        # covariance 'not positive definite'
        s = int(np.argwhere(~np.isfinite(covs))[0, 0])
        raise ValueError(
            f"best viewpoint search: belief covariances must be finite, got:\n{covs[s]}"
        )
    if n and np.abs(covs - covs.transpose(0, 2, 1)).max() > 1e-12:
        raise ValueError("best viewpoint search: belief covariances must be symmetric")
    args = search_args(
        means, covs, balls, landmarks, cam, grid, ukf, ball_radius, ball_views_only, hidden_arr
    )
    threads = numba_threads() if parallel and n > 1 else 1  # serial: never start the pool
    if threads > 1:
        # a few blocks per thread evens out views that see many landmarks
        H, ball_vis, visible, post, errors = kernels.search_kernel_parallel(*args, 4 * threads)
    else:
        H, ball_vis, visible, post, errors = kernels.search_kernel(*args)
    if errors.any():
        s, v = np.argwhere(errors)[0]
        raise NotPositiveDefiniteError(
            f"belief covariance of start {s}, or its expected posterior for candidate {v}, "
            f"is not positive definite; prior covariance:\n{covs[s]}"
        )
    return H, ball_vis, visible, post


def _check_setting(name: str, value: object, kind: type) -> None:
    """TypeError unless ``value`` (a search's ``cam``, ``grid`` or ``ukf``) is a ``kind``."""
    if not isinstance(value, kind):
        raise TypeError(f"best viewpoint search: {name} expects {kind.__name__}, got {value!r}")


def _float_array(name: str, value: object, dtype: type = np.float64) -> np.ndarray:
    """``value`` as an array of ``dtype``; what NumPy cannot convert (a string, a ragged
    list, None) is a ValueError naming ``name``."""
    try:
        array = np.asarray(value)
        if array.dtype.kind not in "biuf":  # strings, None, objects: float() would guess
            raise TypeError
        return array.astype(dtype, copy=False)
    except (TypeError, ValueError):
        raise ValueError(f"best viewpoint search: {name} must be numbers, got {value!r}") from None


def _broadcast(
    name: str, value: object, shape: tuple[int, ...], dtype: type = np.float64
) -> np.ndarray:
    """``value`` broadcast to ``shape`` (one shared row, or one a start); ValueError naming
    ``name`` and both shapes where it does not fit."""
    array = _float_array(name, value, dtype)
    try:
        return np.broadcast_to(array, shape)
    except ValueError:
        raise ValueError(
            f"best viewpoint search: {name} must have shape {shape} or {shape[1:]} (shared),"
            f" got shape {array.shape}"
        ) from None


def best_viewpoints(
    means: ArrayLike,
    covs: ArrayLike,
    balls: ArrayLike,
    landmarks: LandmarkSet,
    cam: CameraConfig,
    grid: ViewpointGrid = DEFAULT_GRID,
    ukf: UKFConfig = DEFAULT_UKF,
    ball_radius: float = 0.07,
    parallel: bool = False,
    ball_views_only: bool = False,
    hidden: ArrayLike | None = None,
) -> ViewpointBatch:
    """Algorithm 1 for N beliefs at once (compiled), e.g. every episode start of a
    vectorised environment.

    Args:
        means: (N, 3) believed poses ``(x, y, theta)``; covs: (N, 3, 3), or (3, 3) shared;
        balls: (N, 2) ball positions on the ground (or (2,) shared).
        parallel: spread the N x V (start, view) pairs over the numba threads (same
            results). Leave off when other busy threads share the cores (e.g. a trainer's):
            a parallel call waits until every thread is scheduled.
        ball_views_only: run the filter only for candidates that show the ball, the only
            possible goals (the environment's episode starts); the others get NaN entropies
            and posteriors and no visible landmarks. The goal is the same either way.
        hidden: (N, K) bool, or (K,) shared: landmarks that no view of a start shows, hidden
            behind other robots (``geometry.occlusion``); None: none.
    """
    H, ball_vis, visible, post = _search(
        means,
        covs,
        balls,
        landmarks,
        cam,
        grid,
        ukf,
        ball_radius,
        parallel,
        ball_views_only,
        hidden,
    )
    found, index = choose_goal(H, ball_vis)
    ok = cast(np.ndarray, found)  # (N, V) in, so (N,) out: an array, not a NumPy bool
    pick = np.maximum(index, 0)
    return ViewpointBatch(
        ok=ok,
        index=index,
        pan=np.where(ok, grid.pans[pick], np.nan),
        tilt=np.where(ok, grid.tilts[pick], np.nan),
        entropy=np.where(ok, H[np.arange(len(H)), pick], np.nan),
        entropies=H,
        ball_visible=ball_vis,
        visible=visible,
        covariances=post,
        grid=grid,
    )


def best_viewpoint(
    belief_mean: ArrayLike,
    belief_cov: ArrayLike,
    ball_xy: ArrayLike,
    landmarks: LandmarkSet,
    cam: CameraConfig,
    grid: ViewpointGrid = DEFAULT_GRID,
    ukf: UKFConfig = DEFAULT_UKF,
    ball_radius: float = 0.07,
) -> ViewpointResult:
    """Algorithm 1: the goal viewpoint for the belief ``N(belief_mean, belief_cov)`` and the
    ball at ``ball_xy`` (compiled; :func:`best_viewpoint_loop` is the reference)."""
    H, ball_vis, visible, post = _search(
        _one("belief_mean", belief_mean, (3,)),
        _one("belief_cov", belief_cov, (3, 3)),
        _one("ball_xy", ball_xy, (2,)),
        landmarks,
        cam,
        grid,
        ukf,
        ball_radius,
    )
    return search_result(H[0], ball_vis[0], visible[0], post[0], grid)


def _one(name: str, value: ArrayLike, shape: tuple[int, ...]) -> np.ndarray:
    """:func:`best_viewpoint`'s ``value`` as a batch of one, shape ``(1, *shape)``: as many
    numbers as ``shape`` holds, or a ValueError naming ``name`` (not numpy's "cannot
    reshape")."""
    array = _float_array(name, value)
    if array.size != math.prod(shape):
        raise ValueError(
            f"best_viewpoint: {name} must be {math.prod(shape)} numbers, shape {shape}, got"
            f" shape {array.shape}"
        )
    return array.reshape(1, *shape)


def best_viewpoint_loop(
    belief_mean: ArrayLike,
    belief_cov: ArrayLike,
    ball_xy: ArrayLike,
    landmarks: LandmarkSet,
    cam: CameraConfig,
    grid: ViewpointGrid = DEFAULT_GRID,
    ukf: UKFConfig = DEFAULT_UKF,
    ball_radius: float = 0.07,
) -> ViewpointResult:
    """Algorithm 1 written out plainly: a Python loop over candidates and landmarks, using
    the geometry package's visibility and :func:`ukf_update`. The reference for tests and
    the benchmark baseline."""
    mean = np.asarray(belief_mean, dtype=np.float64)
    cov = np.asarray(belief_cov, dtype=np.float64)
    # z = h(mu) for every landmark; closest first, ties by id
    zs = np.array([hx_range_bearing(mean, seg)[0] for seg in landmarks.segments])
    order = np.argsort(zs[:, 0], kind="stable")
    V, K = len(grid), len(landmarks)
    entropies = np.empty(V)
    ball_vis = np.zeros(V, dtype=bool)
    visible = np.zeros((V, K), dtype=bool)
    post = np.empty((V, 3, 3))
    for v, (pan, tilt) in enumerate(zip(grid.pans, grid.tilts, strict=True)):
        visible[v] = visible_landmarks(landmarks, mean, pan, tilt, cam).visible[0]
        ball_vis[v] = ball_visible(ball_xy, mean, pan, tilt, cam, ball_radius)[0]
        seen = [k for k in order if visible[v, k]]
        _, post[v] = ukf_update_sequential(
            mean, cov, zs[seen], landmarks.segments[seen], landmarks.types[seen], ukf
        )
        entropies[v] = entropy(post[v])
    return search_result(entropies, ball_vis, visible, post, grid)


def candidate_footprints(
    pose: ArrayLike,
    grid: ViewpointGrid,
    cam: CameraConfig,
    max_distance: float = 4.0,
    points_per_side: int = 16,
) -> np.ndarray:
    """Ground polygon each candidate's image covers from ``pose``, cut at ``max_distance``:
    (V, 4 * points_per_side, 2), grid order (for plotting the candidates)."""
    poses = np.broadcast_to(np.asarray(pose, dtype=np.float64), (len(grid), 3))
    return footprint_polygon(poses, grid.pans, grid.tilts, cam, max_distance, points_per_side)
