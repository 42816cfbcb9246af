"""Where a head should look in a match, from what the robot knows (its head angles, belief
and ball model: the env's info keys ``head``, ``belief_mean``, ``belief_cov``,
``ball_relative``), and the moves that get it there: the pieces the match strategies
(``experiments.match_methods``) are built from, and the match student's teacher
(``training.match_dagger``).

:func:`entropy_track_targets` is this package's planner: every tick, Algorithm 1 from the
belief over a 5-degree grid among the views that keep the ball model's direction (clipped to
the head's limits) at least ``margin`` inside the image on both axes (an angular box, not
the projection, so that the views near a ball behind the robot count too: measured, 0.081 m
against 0.085 where only views that show the ball do). The margin trades localisation for
ball in view: 0 looks wherever the ball is about in view; from half the vertical field of
view (22.6 degrees for the default camera) no view is allowed and it is ball tracking.

:func:`glance_track_targets` spends the head on localisation only when it pays: it tracks
the ball, turns to entropy_track's view (margin 0) while the belief is unsure (position std
above a threshold), and to Algorithm 1's best view anywhere while the ball model lies beyond
the head's reach by more than a margin (the ball cannot be seen from any head angle then,
so watching for it costs localisation and gains nothing).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from activevision.envs.actions import action_table, oracle_actions
from activevision.envs.match.config import MATCH_ACTION_SET, MatchConfig
from activevision.geometry import CameraConfig, LandmarkSet, clip_head, field_landmarks
from activevision.localisation import ViewpointGrid, best_viewpoints, grid_spanning


@functools.lru_cache(maxsize=8)
def track_grid(camera: CameraConfig) -> ViewpointGrid:
    """entropy_track's candidate views: 37 pans and 13 tilts over ``camera``'s head limits
    (for the paper's camera, pan -90..90 deg and tilt 5..65 in 5-degree steps). One object
    per camera, so that the search reuses what it builds from the grid."""
    return grid_spanning(camera, n_pan=37, n_tilt=13)


def ball_direction(info: dict[str, np.ndarray], config: MatchConfig) -> np.ndarray:
    """Head angles (N, 2) that centre the ball of the ball model (clipped to the limits)."""
    rel = info["ball_relative"]
    pan = np.arctan2(rel[:, 1], rel[:, 0])
    distance = np.maximum(np.hypot(rel[:, 0], rel[:, 1]), 0.05)
    tilt = np.arctan2(config.camera.camera_height - config.field.ball_radius, distance)
    return np.column_stack(clip_head(pan, tilt, config.camera))


def ball_on_field(info: dict[str, np.ndarray]) -> np.ndarray:
    """The ball model's position (N, 2) on the field, through the believed pose."""
    mean, rel = info["belief_mean"], info["ball_relative"]
    c, s = np.cos(mean[:, 2]), np.sin(mean[:, 2])
    return np.column_stack(
        [mean[:, 0] + c * rel[:, 0] - s * rel[:, 1], mean[:, 1] + s * rel[:, 0] + c * rel[:, 1]]
    )


def move_towards(head: np.ndarray, target: np.ndarray, config: MatchConfig) -> np.ndarray:
    """The actions of ``config``'s kind that move heads (N, 2) towards targets (N, 2) rad at
    head speed: the discrete move of ``step_deg`` that ends closest, or the continuous move
    straight there, at most ``max_move_deg`` per axis."""
    table = action_table(config.step_deg, MATCH_ACTION_SET)
    return oracle_actions(head, target, config.action_type, table, config.max_move)


def entropy_track_targets(
    info: dict[str, np.ndarray],
    config: MatchConfig,
    margin: float,
    landmarks: LandmarkSet | None = None,
    grid: ViewpointGrid | None = None,
) -> np.ndarray:
    """Head targets (N, 2) rad: the least expected entropy (Algorithm 1 from each belief's
    mean and covariance) among ``grid``'s views (default: :func:`track_grid`) within half
    the field of view less ``margin`` (rad) of the ball model's direction on each axis; the
    ball's direction where none is."""
    ball = ball_direction(info, config)
    grid = track_grid(config.camera) if grid is None else grid
    result = best_viewpoints(
        info["belief_mean"],
        info["belief_cov"],
        ball_on_field(info),
        field_landmarks(config.field) if landmarks is None else landmarks,
        config.camera,
        grid=grid,
        ukf=config.tracker.ukf,
        ball_radius=config.field.ball_radius,
    )
    cam = config.camera
    allowed = (np.abs(grid.pans[None] - ball[:, :1]) <= cam.hfov / 2 - margin) & (
        np.abs(grid.tilts[None] - ball[:, 1:]) <= cam.vfov / 2 - margin
    )
    entropy = np.where(allowed, result.entropies, np.inf)
    pick = np.argmin(entropy, axis=1)
    found = allowed[np.arange(len(pick)), pick]
    targets: np.ndarray = np.where(found[:, None], grid.views[pick], ball)
    return targets


DEFAULT_TRACK_MARGIN_DEG = 5.0  #: entropy_track's margin (docs/match.md)
#: glance_track's position std (m) above which it localises, and how far (deg) beyond the
#: head's reach the ball model must lie for it to look anywhere: chosen on validation
#: matches (seeds 3000-3049, weaker detector; docs/match.md)
DEFAULT_GLANCE_STD_M = 0.10
DEFAULT_GLANCE_REACH_DEG = 30.0
#: the info keys Algorithm 1 plans from: the robot's belief and ball model
PLANNING_KEYS = ("belief_mean", "belief_cov", "ball_relative")


def glance_track_targets(
    info: dict[str, np.ndarray],
    config: MatchConfig,
    std_m: float,
    reach_margin: float,
    landmarks: LandmarkSet | None = None,
    grid: ViewpointGrid | None = None,
    track_margin: float = math.inf,
) -> np.ndarray:
    """Head targets (N, 2) rad: the ball model's direction (with a finite ``track_margin``,
    rad: :func:`entropy_track_targets` with that margin); :func:`entropy_track_targets`
    (margin 0) where the belief's position std exceeds ``std_m`` (m); Algorithm 1's best view
    of all where the ball model's bearing lies more than ``reach_margin`` (rad) beyond what
    the head can bring into the image (the pan limit plus half the field of view)."""
    targets = ball_direction(info, config)
    cov = info["belief_cov"]
    unsure = np.sqrt(cov[:, 0, 0] + cov[:, 1, 1]) > std_m
    rel = info["ball_relative"]
    bearing = np.arctan2(rel[:, 1], rel[:, 0])
    cam = config.camera
    reach = cam.hfov / 2 + reach_margin
    away = (bearing > cam.pan_max + reach) | (bearing < cam.pan_min - reach)
    tracking = ~unsure & ~away
    if track_margin >= max(cam.hfov, cam.vfov) / 2:  # no view keeps the ball so far inside
        tracking[:] = False
    # margin -inf: every view of the grid is allowed, wherever the ball is
    for chosen, margin in ((unsure & ~away, 0.0), (away, -math.inf), (tracking, track_margin)):
        if chosen.any():
            known = {key: info[key][chosen] for key in PLANNING_KEYS}
            targets[chosen] = entropy_track_targets(known, config, margin, landmarks, grid)
    return targets


class EntropyTrackTeacher:
    """:func:`entropy_track_targets` as actions of the match's kind (the greedy discrete
    move, or the continuous one straight there): a match student's teacher."""

    def __init__(self, config: MatchConfig, margin_deg: float = DEFAULT_TRACK_MARGIN_DEG) -> None:
        self.config = config
        self.margin = math.radians(margin_deg)
        self.landmarks = field_landmarks(config.field)

    def targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        return entropy_track_targets(info, self.config, self.margin, self.landmarks)

    def actions(self, info: dict[str, np.ndarray]) -> np.ndarray:
        return move_towards(info["head"], self.targets(info), self.config)


class GlanceTrackTeacher(EntropyTrackTeacher):
    """:func:`glance_track_targets` as actions of the match's kind: a match student's
    teacher."""

    def __init__(
        self,
        config: MatchConfig,
        std_m: float = DEFAULT_GLANCE_STD_M,
        reach_deg: float = DEFAULT_GLANCE_REACH_DEG,
        track_margin_deg: float = math.inf,
    ) -> None:
        super().__init__(config, 0.0)
        self.std_m = std_m
        self.reach = math.radians(reach_deg)
        self.track_margin = math.radians(track_margin_deg)

    def targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        return glance_track_targets(
            info,
            self.config,
            self.std_m,
            self.reach,
            self.landmarks,
            track_margin=self.track_margin,
        )
