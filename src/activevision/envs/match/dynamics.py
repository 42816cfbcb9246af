"""What moves in a match besides the head: our robot walking (with odometry drift) and the
ball rolling and being kicked. Pure functions over N matches at once; the random numbers
come in as arrays drawn from each match's own generator (``envs.match.simulation``)."""

from __future__ import annotations

import numpy as np

from activevision.envs.match.config import BallConfig, WalkConfig
from activevision.geometry.angles import wrap_angle
from activevision.localisation.config import UKFConfig


def walk_command(
    believed: np.ndarray,
    waypoint: np.ndarray,
    paused: np.ndarray,
    walk: WalkConfig,
    dt: float,
) -> np.ndarray:
    """The walking engine's step ``(dx, dy, dtheta)`` (N, 3) in the robot frame for one tick:
    turn towards the waypoint at ``turn_rate``, walk forward at ``speed`` scaled by how well
    the robot faces it (``cos`` of the heading error, never backwards). The robot plans from
    its *believed* pose ``believed`` (N, 3), as a real one does; ``paused`` (N,) bool robots
    stand."""
    to = waypoint - believed[:, :2]
    error = wrap_angle(np.arctan2(to[:, 1], to[:, 0]) - believed[:, 2])
    max_turn = walk.turn_rate * dt
    turn = np.clip(error, -max_turn, max_turn)
    distance = np.hypot(to[:, 0], to[:, 1])
    forward = np.minimum(walk.speed * dt, distance) * np.maximum(np.cos(error), 0.0)
    command = np.column_stack([forward, np.zeros_like(forward), turn])
    command[paused] = 0.0
    return command


def odometry_stds(command: np.ndarray, ukf: UKFConfig) -> np.ndarray:
    """Std (N, 3) of the true motion around the commanded step, robot frame: the UKF's
    odometry model (``localisation.ukf.odometry_noise``), i.e. drift proportional to the
    distance walked and the angle turned, plus a small slip per tick."""
    bx, by, bt = ukf.odometry_base
    trans = ukf.odometry_translation_fraction * np.hypot(command[:, 0], command[:, 1])
    rot = ukf.odometry_rotation_fraction * np.abs(command[:, 2])
    return np.column_stack([bx + trans, by + trans, bt + rot])


def apply_motion(pose: np.ndarray, step: np.ndarray, half_carpet: tuple[float, float]) -> None:
    """Move poses (N, 3) in place by robot-frame steps (N, 3); a robot stays on the carpet
    (it is stopped at its edge)."""
    c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    pose[:, 0] = np.clip(
        pose[:, 0] + c * step[:, 0] - s * step[:, 1], -half_carpet[0], half_carpet[0]
    )
    pose[:, 1] = np.clip(
        pose[:, 1] + s * step[:, 0] + c * step[:, 1], -half_carpet[1], half_carpet[1]
    )
    pose[:, 2] = wrap_angle(pose[:, 2] + step[:, 2])


def roll_ball(
    ball: np.ndarray,
    velocity: np.ndarray,
    kicks: np.ndarray,
    config: BallConfig,
    dt: float,
    half_field: tuple[float, float],
) -> None:
    """One tick of N balls, in place: positions (N, 2), velocities (N, 2). ``kicks`` (N, 3)
    uniforms decide a kick (``u0 < kick_rate``), its direction and its speed. The ball
    decelerates at ``deceleration`` and bounces back off the field lines (the referee puts a
    ball that left the field back in; a bounce keeps it in play without a throw-in rule)."""
    kicked = kicks[:, 0] < config.kick_rate
    angle = 2 * np.pi * kicks[kicked, 1]
    lo, hi = config.kick_speed
    speed = lo + (hi - lo) * kicks[kicked, 2]
    velocity[kicked] = np.column_stack([np.cos(angle), np.sin(angle)]) * speed[:, None]
    speed_now = np.hypot(velocity[:, 0], velocity[:, 1])
    slower = np.maximum(speed_now - config.deceleration * dt, 0.0)
    # exact under constant deceleration, also in the tick the ball stops
    if config.deceleration > 0:
        travel = (speed_now**2 - slower**2) / (2 * config.deceleration)
    else:
        travel = speed_now * dt
    moving = speed_now > 0
    unit = np.divide(
        velocity, speed_now[:, None], out=np.zeros_like(velocity), where=moving[:, None]
    )
    ball += unit * travel[:, None]
    velocity[:] = unit * slower[:, None]
    for axis, half in enumerate(half_field):
        over = ball[:, axis] > half
        under = ball[:, axis] < -half
        ball[over, axis] = 2 * half - ball[over, axis]
        ball[under, axis] = -2 * half - ball[under, axis]
        velocity[over | under, axis] *= -1.0
        np.clip(ball[:, axis], -half, half, out=ball[:, axis])


def to_robot_frame(points: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """World points (N, 2) in the frames of poses (N, 3)."""
    d = points - pose[:, :2]
    c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    return np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])


def move_relative(points: np.ndarray, step: np.ndarray) -> np.ndarray:
    """Robot-frame points (N, 2) after the robot moved by ``step`` (N, 3) (its own frame):
    how a robot carries its ball model along with its odometry."""
    d = points - step[:, :2]
    c, s = np.cos(step[:, 2]), np.sin(step[:, 2])
    return np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])
