"""The compiled tick of N matches: :func:`move_kernel` (head, walk, drift, ball) and
:func:`sense_kernel` (visibility, detection, UKF, ball model, reward). Between the two the
simulation walks the other robots and updates what they hide (NumPy), when there are any.

The kernels take typed bundles as plain tuples of their fields (``tuple(bundle)``, as the
localisation kernels do) and rebuild them inside.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from activevision.envs.match.detections import detect_one
from activevision.envs.match.dynamics import (
    blocking_robot,
    carry,
    drift_stds,
    move_pose,
    roll_ball,
    sidestep,
    to_robot_frame,
    walk_step,
)
from activevision.geometry.jit import cached_njit
from activevision.geometry.kernels import (
    CameraModel,
    ball_in_image,
    camera_rotation,
    image_halfplanes,
    visible_landmarks,
)
from activevision.localisation.bundles import Landmarks, SigmaWeights, UKFScratch
from activevision.localisation.kernels import LOG_2PIE, NOT_PD, Fields, chol3
from activevision.localisation.tracking import TrackStats, track_one


class MatchState(NamedTuple):
    """The state of N matches, each array (N, ...)."""

    pose: np.ndarray  #: (N, 3) true pose
    mean: np.ndarray  #: (N, 3) belief mean
    cov: np.ndarray  #: (N, 3, 3) belief covariance
    gated_share: np.ndarray  #: (N,) the lost detector's moving share
    head: np.ndarray  #: (N, 2) pan, tilt
    last_move: np.ndarray  #: (N, 2) this tick's head move
    ball: np.ndarray  #: (N, 2)
    ball_velocity: np.ndarray  #: (N, 2)
    ball_relative: np.ndarray  #: (N, 2) the ball model, robot frame
    ball_age: np.ndarray  #: (N,) int64 ticks since the ball was seen
    ball_seen: np.ndarray  #: (N,) bool
    waypoint: np.ndarray  #: (N, 2)
    pause: np.ndarray  #: (N,) int64 ticks left standing
    detected: np.ndarray  #: (N, K) bool this tick
    accepted: np.ndarray  #: (N,) int64 cumulative
    gated: np.ndarray  #: (N,) int64 cumulative
    declared_lost: np.ndarray  #: (N,) bool, ever this match
    hidden: np.ndarray  #: (N, K) bool, behind other robots
    reward: np.ndarray  #: (N,)
    robots: np.ndarray  #: (N, R, 4) the other robots (x, y, height, grey); height 0: none
    detour: np.ndarray  #: (N,) int64 ticks left walking to a detour waypoint, not the ball
    lost_alarm: np.ndarray  #: (N,) bool: the lost detector fired this tick


class MatchParams(NamedTuple):
    """Every number of a :class:`~activevision.envs.match.config.MatchConfig` the tick uses."""

    dt: float
    speed: float
    turn_rate: float
    reach: float
    pause_low: float
    pause_high: float
    waypoint_x: float  #: waypoints within +-waypoint_x, +-waypoint_y
    waypoint_y: float
    walk_to_ball: float  #: 1: the waypoint is the ball
    ball_standoff: float  #: stop this far short of the ball
    carpet_x: float
    carpet_y: float
    field_x: float
    field_y: float
    near: float
    far: float
    false_rate: float
    half_fov: float
    ball_noise: float
    ball_radius: float
    pan_min: float
    pan_max: float
    tilt_min: float
    tilt_max: float
    reward_entropy: float  #: 1: entropy reward, 0: error reward
    entropy_weight: float
    error_weight: float
    ball_weight: float
    travel_weight: float
    spacing: float  #: our robot keeps this far (m) from the other robots' centres


#: ticks (6.4 s) a robot walking to the ball walks to a detour waypoint instead after it
#: gave way to a robot that stands between it and the ball
DETOUR_TICKS = 20


@cached_njit()
def _next_waypoint(n: int, s: MatchState, p: MatchParams, draws: np.ndarray) -> None:
    """A robot at its waypoint (by its belief) pauses, then walks to the next: a random one,
    or (``walk_to_ball``) the ball's believed position less ``ball_standoff``, re-planned
    every tick, but while on a detour (``s.detour``) the detour waypoint until it reaches it
    or the detour's ticks run out."""
    mean, wp = s.mean[n], s.waypoint[n]
    reached = math.hypot(wp[0] - mean[0], wp[1] - mean[1]) < p.reach and s.pause[n] == 0
    if reached:
        width = p.pause_high - p.pause_low + 1
        s.pause[n] = int(p.pause_low + math.floor(draws[2] * width))
    if p.walk_to_ball > 0 and s.detour[n] > 0 and not reached:
        s.detour[n] -= 1
        return
    s.detour[n] = 0
    if p.walk_to_ball > 0:
        c, si = math.cos(mean[2]), math.sin(mean[2])
        rx, ry = s.ball_relative[n, 0], s.ball_relative[n, 1]
        distance = math.hypot(rx, ry)
        keep = max(distance - p.ball_standoff, 0.0) / distance if distance > 0 else 0.0
        rx, ry = rx * keep, ry * keep
        wp[0], wp[1] = mean[0] + c * rx - si * ry, mean[1] + si * rx + c * ry
    elif reached:
        wp[0] = p.waypoint_x * (2 * draws[0] - 1)
        wp[1] = p.waypoint_y * (2 * draws[1] - 1)


@cached_njit()
def _beyond(s: MatchState, n: int, blocker: int) -> bool:
    """Whether match ``n``'s waypoint lies beyond the other robot ``blocker``: their
    directions from our robot, in its own frame, less than 90 degrees apart (the waypoint
    where our robot believes it is, from its belief; the robot where it sees it, where it
    stands), so that the way there passes that robot."""
    bx, by = to_robot_frame(s.robots[n, blocker, 0], s.robots[n, blocker, 1], s.pose[n])
    wx, wy = to_robot_frame(s.waypoint[n, 0], s.waypoint[n, 1], s.mean[n])
    return bx * wx + by * wy > 0.0


@cached_njit()
def _walk(
    moved: np.ndarray,
    pose: np.ndarray,
    step: tuple[float, float, float],
    drift: np.ndarray,
    model: tuple[float, float, float, float, float],
    p: MatchParams,
) -> None:
    """``moved`` (3,): ``pose`` after the commanded robot-frame ``step`` and its drift
    (``drift``: the tick's three standard normals), stopped at the carpet's edge."""
    dx, dy, dth = step
    sx, sy, st = drift_stds(dx, dy, dth, model)
    moved[:] = pose
    move_pose(
        moved, dx + sx * drift[0], dy + sy * drift[1], dth + st * drift[2], p.carpet_x, p.carpet_y
    )


@cached_njit()
def move_kernel(
    idx: np.ndarray,
    targets: np.ndarray,
    state: Fields,
    params: Fields,
    model: tuple[float, float, float, float, float],
    ball_model: tuple[float, float, float, float],
    uniforms: np.ndarray,
    normals: np.ndarray,
) -> np.ndarray:
    """Matches ``idx``: the head to ``targets`` (len(idx), 2) (clipped to its limits), our
    robot's walk and drift, the ball. Returns the odometry (len(idx), 3) (the commanded
    steps; the sidestep, or the turn alone, where our robot gave way). Row ``j`` of
    ``uniforms`` / ``normals`` are match ``idx[j]``'s draws (layout:
    :mod:`activevision.envs.match.simulation`).

    Our robot gives way to the other robots (``s.robots``, where they stand: they move
    after it): a step whose true motion (the commanded step and its drift) would end closer
    than ``spacing`` to one of them while closing in on it is not made. The robot
    sidesteps round that robot instead (:func:`~activevision.envs.match.dynamics.sidestep`,
    with the same drift draws), its odometry the sidestep (turning on the spot instead, it
    stood for up to 533 of a match's 600 ticks among standing robots). Where the step
    leaves no sidestep (that robot about straight ahead) or the sidestep is blocked too, it
    turns on the spot: its position unchanged, its heading turned by the commanded turn and
    that turn's drift alone, its odometry the turn (its walking engine commanded no step,
    and it made none). A waypoint beyond that robot (:func:`_beyond`), or any where its
    sidestep was blocked by another robot (wedged between two: keeping it, it stood up to
    188 ticks), it gives up for a new one from its give-way draws; one clear of it it keeps,
    turning on the spot until a step towards it parts from the robot. Walking to the ball,
    with the ball beyond that robot, it takes such a waypoint as a detour, walked to for
    :data:`DETOUR_TICKS` ticks (or until reached) before it turns to the ball again: it
    waited, turning to the ball, for the ball or the robot to move, for the rest of the
    match where neither did (a standing robot, a ball at rest behind it or out of view)."""
    s, p = MatchState(*state), MatchParams(*params)
    k = s.detected.shape[1]
    odometry = np.zeros((idx.shape[0], 3))
    moved = np.empty(3)
    for j in range(idx.shape[0]):
        n = idx[j]
        pan = min(max(targets[j, 0], p.pan_min), p.pan_max)
        tilt = min(max(targets[j, 1], p.tilt_min), p.tilt_max)
        s.last_move[n, 0], s.last_move[n, 1] = pan - s.head[n, 0], tilt - s.head[n, 1]
        s.head[n, 0], s.head[n, 1] = pan, tilt
        _next_waypoint(n, s, p, uniforms[j, k + 7 :])
        dx, dy, dth = walk_step(
            s.mean[n], s.waypoint[n], s.pause[n] > 0, p.speed, p.turn_rate, p.dt
        )
        s.pause[n] = max(s.pause[n] - 1, 0)
        drift = normals[j, 2 * k : 2 * k + 3]
        _walk(moved, s.pose[n], (dx, dy, dth), drift, model, p)
        blocker = blocking_robot(s.pose[n], moved, s.robots[n], p.spacing)
        wedged = False
        if blocker >= 0:
            # go round it, where the step leaves a sidestep ((0, 0): none)
            rx, ry = s.robots[n, blocker, 0], s.robots[n, blocker, 1]
            side_x, side_y = sidestep(s.pose[n], rx, ry, dx, dy)
            if side_x != 0.0 or side_y != 0.0:
                _walk(moved, s.pose[n], (side_x, side_y, dth), drift, model, p)
                other = blocking_robot(s.pose[n], moved, s.robots[n], p.spacing)
                if other < 0:
                    blocker, dx, dy = -1, side_x, side_y
                wedged = other >= 0 and other != blocker
        if blocker >= 0:
            # give way: turn on the spot, as commanded, with a pure turn's drift (no slip of
            # a step); wedged between two robots, it takes a new waypoint as if beyond them
            # (keeping its own, it stood up to 188 ticks of 600 turning to it)
            if wedged or _beyond(s, n, blocker):
                give_way = uniforms[j, k + 10 : k + 12]
                s.waypoint[n, 0] = p.waypoint_x * (2 * give_way[0] - 1)
                s.waypoint[n, 1] = p.waypoint_y * (2 * give_way[1] - 1)
                if p.walk_to_ball > 0:
                    s.detour[n] = DETOUR_TICKS
            dx = dy = 0.0
            st = drift_stds(0.0, 0.0, dth, model)[2]
            moved[:] = s.pose[n]
            move_pose(moved, 0.0, 0.0, dth + st * drift[2], p.carpet_x, p.carpet_y)
        s.pose[n, :] = moved
        odometry[j, 0], odometry[j, 1], odometry[j, 2] = dx, dy, dth
        roll_ball(
            s.ball[n],
            s.ball_velocity[n],
            uniforms[j, k + 4 : k + 7],
            ball_model,
            p.dt,
            p.field_x,
            p.field_y,
        )
    return odometry


@cached_njit()
def sense_kernel(
    idx: np.ndarray,
    odometry: np.ndarray,
    state: Fields,
    params: Fields,
    landmarks: Fields,
    weights: Fields,
    camera: tuple[float, ...],
    model: tuple[float, float, float, float, float],
    tracker: tuple[float, float, float, float, float, float],
    point_ids: np.ndarray,
    ball_hidden: np.ndarray,
    uniforms: np.ndarray,
    normals: np.ndarray,
) -> np.ndarray:
    """Matches ``idx`` after :func:`move_kernel`: what the camera detects, the UKF's tick,
    the ball model and the reward. ``ball_hidden`` (len(idx),): a robot stands between the
    camera and the ball. Returns error codes (len(idx),) int8 (``NOT_PD``: a covariance
    lost definiteness)."""
    s, p = MatchState(*state), MatchParams(*params)
    lm, sw, cam = Landmarks(*landmarks), SigmaWeights(*weights), CameraModel(*camera)
    n_lm = lm.segments.shape[0]
    rot, planes = np.empty((3, 3)), np.empty((4, 3))
    visible = np.zeros(n_lm, dtype=np.bool_)
    ids, z, ranges = np.empty(n_lm + 1, dtype=np.int64), np.empty((n_lm + 1, 2)), np.empty(n_lm)
    scratch = UKFScratch(np.empty((3, 3)), np.empty((7, 3)), np.empty((7, 2)))
    stats = TrackStats(
        np.zeros(s.pose.shape[0], dtype=np.int64),
        np.zeros(s.pose.shape[0], dtype=np.int64),
        np.zeros(s.pose.shape[0]),
        np.zeros(s.pose.shape[0], dtype=np.bool_),
    )
    errors = np.zeros(idx.shape[0], dtype=np.int8)
    rates = (p.near, p.far, p.false_rate, p.half_fov)
    for j in range(idx.shape[0]):
        n = idx[j]
        pose = s.pose[n]
        camera_rotation(pose[2] + s.head[n, 0], s.head[n, 1], rot)
        image_halfplanes(pose[0], pose[1], rot, cam, planes)
        visible_landmarks(lm.segments, lm.max_distance, pose[0], pose[1], planes, visible)
        for k in range(n_lm):
            visible[k] = visible[k] and not s.hidden[n, k]
        count = detect_one(
            pose,
            s.head[n, 0],
            visible,
            lm.segments,
            lm.max_distance,
            lm.types,
            lm.noise,
            point_ids,
            uniforms[j, :n_lm],
            normals[j, : 2 * n_lm].reshape(n_lm, 2),
            uniforms[j, n_lm : n_lm + 4],
            rates,
            ids,
            z,
            ranges,
        )
        s.detected[n, :] = False
        for d in range(count):
            s.detected[n, ids[d]] = True
        stats.accepted[n] = stats.gated[n] = 0
        odom = (odometry[j, 0], odometry[j, 1], odometry[j, 2])
        if (
            track_one(
                n,
                s.mean,
                s.cov,
                odom,
                ids,
                z,
                s.gated_share,
                lm,
                sw,
                model,
                tracker,
                stats,
                scratch,
            )
            == NOT_PD
        ):
            errors[j] = NOT_PD
            continue
        s.accepted[n] += stats.accepted[n]
        s.gated[n] += stats.gated[n]
        s.declared_lost[n] |= stats.declared_lost[n]
        s.lost_alarm[n] = stats.declared_lost[n]
        # the ball model: measured when seen, else carried along by odometry
        seen = ball_in_image(s.ball[n, 0], s.ball[n, 1], p.ball_radius, pose[0], pose[1], rot, cam)
        seen = seen and not ball_hidden[j]
        s.ball_seen[n] = seen
        if seen:
            mx, my = to_robot_frame(s.ball[n, 0], s.ball[n, 1], pose)
            spread = p.ball_noise * math.hypot(mx, my)
            s.ball_relative[n, 0] = mx + spread * normals[j, 2 * n_lm + 3]
            s.ball_relative[n, 1] = my + spread * normals[j, 2 * n_lm + 4]
            s.ball_age[n] = 0
        else:
            rx, ry = carry(s.ball_relative[n, 0], s.ball_relative[n, 1], *odom)
            s.ball_relative[n, 0], s.ball_relative[n, 1] = rx, ry
            s.ball_age[n] += 1
        if p.reward_entropy > 0:
            chol3(s.cov[n], scratch.L)
            L = scratch.L
            value = -p.entropy_weight * (1.5 * LOG_2PIE + math.log(L[0, 0] * L[1, 1] * L[2, 2]))
        else:
            value = -p.error_weight * math.hypot(s.mean[n, 0] - pose[0], s.mean[n, 1] - pose[1])
        travel = math.degrees(math.hypot(s.last_move[n, 0], s.last_move[n, 1]))
        s.reward[n] = value + p.ball_weight * seen - p.travel_weight * travel
    return errors
