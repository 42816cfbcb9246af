"""What moves in a match besides the head: our robot walking (with odometry drift) and the
ball rolling and being kicked. Compiled functions of one match (row ``n`` of the batch's
arrays), composed by :mod:`activevision.envs.match.kernels`; the random numbers come in as
each match's own draws of the tick."""

from __future__ import annotations

import math

import numpy as np

from activevision.geometry.angles import wrap_angle as wrap
from activevision.geometry.jit import cached_njit


@cached_njit()
def walk_step(
    believed: np.ndarray,
    waypoint: np.ndarray,
    paused: bool,
    speed: float,
    turn_rate: float,
    dt: float,
) -> tuple[float, float, float]:
    """The walking engine's step ``(dx, dy, dtheta)`` (robot frame) for one tick from the
    believed pose ``believed`` (3,) to ``waypoint`` (2,): turn towards it at ``turn_rate``,
    walk forward at ``speed`` scaled by how well the robot faces it (``cos`` of the heading
    error, never backwards); a paused robot stands. The robot plans from its *belief*, as a
    real one does."""
    if paused:
        return 0.0, 0.0, 0.0
    tx, ty = waypoint[0] - believed[0], waypoint[1] - believed[1]
    error = wrap(math.atan2(ty, tx) - believed[2])
    max_turn = turn_rate * dt
    turn = min(max(error, -max_turn), max_turn)
    forward = min(speed * dt, math.hypot(tx, ty)) * max(math.cos(error), 0.0)
    return forward, 0.0, turn


@cached_njit()
def drift_stds(
    dx: float, dy: float, dth: float, model: tuple[float, float, float, float, float]
) -> tuple[float, float, float]:
    """Std of the true motion around the commanded step (robot frame): the UKF's odometry
    model (``localisation.ukf.odometry_noise``; ``model = (base x, y, theta, translation
    fraction, rotation fraction)``): drift proportional to the distance walked and the
    angle turned, plus a small slip per tick."""
    bx, by, bt, tf, rf = model
    trans = tf * math.hypot(dx, dy)
    return bx + trans, by + trans, bt + rf * abs(dth)


@cached_njit()
def move_pose(pose: np.ndarray, dx: float, dy: float, dth: float, hx: float, hy: float) -> None:
    """Move ``pose`` (3,) in place by a robot-frame step; a robot stays within ``(hx, hy)``
    of the centre (stopped at the carpet's edge)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    pose[0] = min(max(pose[0] + c * dx - s * dy, -hx), hx)
    pose[1] = min(max(pose[1] + s * dx + c * dy, -hy), hy)
    pose[2] = wrap(pose[2] + dth)


@cached_njit()
def blocking_robot(
    before: np.ndarray, after: np.ndarray, robots: np.ndarray, spacing: float
) -> int:
    """Of ``robots`` (R, 4) rows ``(x, y, height, grey)`` (height 0: an empty slot), the
    one that a robot stepping from ``before`` to ``after`` ((2,) or more: x, y first) would
    end nearest to, of those it would end closer than ``spacing`` to while closing in on
    them (a robot already too close may part); -1 when there is none. The nearest, not the
    first by index: the sidestep goes round the robot most in the way."""
    nearest, nearest_gap = -1, spacing
    for r in range(robots.shape[0]):
        if robots[r, 2] <= 0:
            continue
        gap = math.hypot(after[0] - robots[r, 0], after[1] - robots[r, 1])
        closing = gap < math.hypot(before[0] - robots[r, 0], before[1] - robots[r, 1])
        if gap < nearest_gap and closing:
            nearest, nearest_gap = r, gap
    return nearest


@cached_njit()
def roll_ball(
    ball: np.ndarray,
    velocity: np.ndarray,
    kick: np.ndarray,
    ball_model: tuple[float, float, float, float],
    dt: float,
    hx: float,
    hy: float,
) -> None:
    """One tick of a ball, in place: position and velocity (2,). ``kick`` (3,) uniforms
    decide a kick (``u0 < kick_rate``), its direction and speed; ``ball_model =
    (deceleration, kick_rate, kick speed low, high)``. The ball decelerates uniformly
    (exactly, also in the tick it stops) and bounces back off the field lines ``(hx, hy)``
    (the referee puts a ball that left back in; a bounce keeps it in play)."""
    decel, kick_rate, lo, hi = ball_model
    if kick[0] < kick_rate:
        angle = 2 * math.pi * kick[1]
        speed = lo + (hi - lo) * kick[2]
        velocity[0], velocity[1] = speed * math.cos(angle), speed * math.sin(angle)
    speed = math.hypot(velocity[0], velocity[1])
    if speed == 0.0:
        return
    slower = max(speed - decel * dt, 0.0)
    travel = (speed * speed - slower * slower) / (2 * decel) if decel > 0 else speed * dt
    ux, uy = velocity[0] / speed, velocity[1] / speed
    ball[0] += ux * travel
    ball[1] += uy * travel
    velocity[0], velocity[1] = ux * slower, uy * slower
    for axis, half in ((0, hx), (1, hy)):
        if ball[axis] > half:
            ball[axis] = min(max(2 * half - ball[axis], -half), half)
            velocity[axis] = -velocity[axis]
        elif ball[axis] < -half:
            ball[axis] = min(max(-2 * half - ball[axis], -half), half)
            velocity[axis] = -velocity[axis]


#: a sidestep round a robot also parts from it by this share of the step: the drift of a
#: step (a quarter of it, plus slip) would bring a bare sidestep closer every other tick
SIDESTEP_OUTWARD = 0.5
#: the least share of its step that a sidestep keeps across the way to the robot: less
#: (the robot about straight ahead) is no sidestep, and the robot gives way instead
MIN_SIDESTEP = 0.25


@cached_njit()
def sidestep(
    pose: np.ndarray, robot_x: float, robot_y: float, dx: float, dy: float
) -> tuple[float, float]:
    """The sidestep round the robot at ``(robot_x, robot_y)`` that a walking engine makes
    of the robot-frame step ``(dx, dy)`` of a robot at ``pose`` (3,): the step's part
    across the way to that robot, and a part away from it of :data:`SIDESTEP_OUTWARD` of
    the step, instead of its part towards it, at the step's length (no faster than it
    walks). ``(0, 0)`` where the part across is less than :data:`MIN_SIDESTEP` of the step
    (or there is no step)."""
    bx, by = to_robot_frame(robot_x, robot_y, pose)
    distance, length = math.hypot(bx, by), math.hypot(dx, dy)
    if distance == 0.0 or length == 0.0:
        return 0.0, 0.0
    ux, uy = bx / distance, by / distance
    closing = dx * ux + dy * uy
    across_x, across_y = dx - closing * ux, dy - closing * uy
    if math.hypot(across_x, across_y) < MIN_SIDESTEP * length:
        return 0.0, 0.0
    away = SIDESTEP_OUTWARD * length
    side_x, side_y = across_x - away * ux, across_y - away * uy
    scale = length / math.hypot(side_x, side_y)
    return side_x * scale, side_y * scale


@cached_njit()
def to_robot_frame(px: float, py: float, pose: np.ndarray) -> tuple[float, float]:
    """The world point ``(px, py)`` in the frame of ``pose`` (3,)."""
    dx, dy = px - pose[0], py - pose[1]
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return c * dx + s * dy, -s * dx + c * dy


@cached_njit()
def carry(rx: float, ry: float, dx: float, dy: float, dth: float) -> tuple[float, float]:
    """A robot-frame point after the robot moved by ``(dx, dy, dth)`` (its own frame): how a
    robot carries its ball model along with its odometry."""
    ex, ey = rx - dx, ry - dy
    c, s = math.cos(dth), math.sin(dth)
    return c * ex + s * ey, -s * ex + c * ey
