"""Self-localisation: a UKF pose belief, its entropy, and the best-viewpoint search
(Algorithm 1 of the paper). NumPy and numba only."""

from activevision.localisation.angles import (
    circular_mean,
    measurement_mean,
    residual_x,
    residual_z,
    state_mean,
    wrap_angle,
)
from activevision.localisation.config import DEFAULT_UKF, RangeBearingNoise, UKFConfig
from activevision.localisation.entropy import entropy
from activevision.localisation.sigma_points import (
    NotPositiveDefiniteError,
    merwe_sigma_points,
    merwe_weights,
)
from activevision.localisation.ukf import (
    PoseBelief,
    fx_odometry,
    hx_range_bearing,
    measurement_noise,
    odometry_noise,
    ukf_predict,
    ukf_update,
    ukf_update_sequential,
)
from activevision.localisation.viewpoint import (
    best_viewpoint,
    best_viewpoint_loop,
    best_viewpoints,
    candidate_footprints,
)
from activevision.localisation.viewpoint_types import (
    DEFAULT_GRID,
    LocalisationConfig,
    ViewpointBatch,
    ViewpointGrid,
    ViewpointResult,
    ViewpointStatus,
    check_grid_reachable,
    grid_spanning,
)

__all__ = [
    "DEFAULT_GRID",
    "DEFAULT_UKF",
    "LocalisationConfig",
    "NotPositiveDefiniteError",
    "PoseBelief",
    "RangeBearingNoise",
    "UKFConfig",
    "ViewpointBatch",
    "ViewpointGrid",
    "ViewpointResult",
    "ViewpointStatus",
    "best_viewpoint",
    "best_viewpoint_loop",
    "best_viewpoints",
    "candidate_footprints",
    "check_grid_reachable",
    "circular_mean",
    "entropy",
    "fx_odometry",
    "grid_spanning",
    "hx_range_bearing",
    "measurement_mean",
    "measurement_noise",
    "merwe_sigma_points",
    "merwe_weights",
    "odometry_noise",
    "residual_x",
    "residual_z",
    "state_mean",
    "ukf_predict",
    "ukf_update",
    "ukf_update_sequential",
    "wrap_angle",
]
