"""Other robots in a match (``MatchConfig.robots``, ``MatchConfig.others``): their walk and
the ball bouncing off them. Pure functions over all matches at once, looping over the
robot slots (NumPy: a handful of robots per match, so the arrays are small and the work is
a few vector operations per slot and tick, not worth a compiled kernel).

A robot is a row ``(x, y, height, grey)`` of the batch's ``robots`` (N, R, 4); height 0
marks an empty slot (:func:`activevision.envs.robots.draw_robots`), which never moves.
"""

from __future__ import annotations

import numpy as np


def walk_others(
    robots: np.ndarray,
    waypoints: np.ndarray,
    own: np.ndarray,
    draws: np.ndarray,
    step: float,
    spacing: float,
    half: tuple[float, float],
) -> None:
    """One tick of the other robots' walks, in place.

    Each robot steps up to ``step`` (m) straight towards its waypoint (``waypoints``
    (N, R, 2)). The robots move one after another, in slot order (vectorised over the
    matches): each checks its step against where every other robot stands *now* -- those
    before it in the slot order where they just stepped to, the rest where they stand -- and
    against ours (``own`` (N, 2), already moved this tick). A robot standing on its
    waypoint, or whose step would end closer than ``spacing`` to one of them while closing
    in on it, stands this tick and takes a new waypoint, uniform within ``half = (hx, hy)``
    of the centre, from its ``draws`` (N, R, 2) uniforms: robots give way and turn to
    elsewhere, so two that meet never lock each other. So the walk keeps the spacing: every
    pair that began the tick at least ``spacing`` apart ends it so (a pair already closer
    may only part)."""
    used = robots[..., 2] > 0
    fresh = np.stack([half[0] * (2 * draws[..., 0] - 1), half[1] * (2 * draws[..., 1] - 1)], -1)
    r = robots.shape[1]
    # everyone a robot must keep clear of: the other robots (as they stand when it steps)
    # and ours
    present = np.concatenate([used, np.ones((len(own), 1), dtype=bool)], axis=1)
    for k in range(r):
        xy = robots[:, k, :2]
        to = waypoints[:, k] - xy
        distance = np.hypot(to[:, 0], to[:, 1])
        scale = np.divide(
            np.minimum(distance, step), distance, out=np.zeros_like(distance), where=distance > 0
        )
        proposed = xy + to * scale[:, None]
        others = np.concatenate([robots[..., :2], own[:, None, :]], axis=1)  # N, R + 1, 2
        keep_clear = present.copy()
        keep_clear[:, k] = False
        after = _distances(proposed[:, None], others)[:, 0]
        before = _distances(xy[:, None], others)[:, 0]
        blocked = (keep_clear & (after < spacing) & (after < before)).any(axis=1)
        turn = used[:, k] & (blocked | (distance <= 0.0))
        moves = used[:, k] & ~turn
        robots[moves, k, :2] = proposed[moves]
        waypoints[turn, k] = fresh[turn, k]


def _distances(points: np.ndarray, others: np.ndarray) -> np.ndarray:
    """Distances (N, P, Q) between ``points`` (N, P, 2) and ``others`` (N, Q, 2)."""
    d = points[:, :, None, :] - others[:, None, :, :]
    return np.asarray(np.hypot(d[..., 0], d[..., 1]))


def bounce_ball(
    ball: np.ndarray,
    velocity: np.ndarray,
    robots: np.ndarray,
    body_radius: float,
    ball_radius: float,
    restitution: float,
    start: np.ndarray | None = None,
) -> None:
    """The balls (N, 2) that met a robot's body (a vertical cylinder of ``body_radius``) in
    this tick are put back at contact and their velocity (N, 2) towards the robot is
    reflected, keeping ``restitution`` of it (a ball moving away, or pushed by a walking
    robot, keeps its velocity). In place; slots in order, so a ball between two robots ends
    against the last it met.

    With ``start`` (N, 2), where each ball began the tick, the ball's straight path from
    there is tested (a swept test): a ball that entered a body on its way stops where it
    first touched it, even if the roll carried it past the robot's centre or through the
    body entirely (a ball faster than the contact radius per tick, ~0.6 m/s at 0.32 s ticks,
    did pass through). A ball that began the tick already touching a body (a robot walked
    onto it), and every ball without ``start``, is tested where it ends: put back on the
    line from the robot's centre."""
    contact = body_radius + ball_radius
    for k in range(robots.shape[1]):
        centre = robots[:, k, :2]
        used = robots[:, k, 2] > 0
        d = ball - centre
        distance = np.hypot(d[:, 0], d[:, 1])
        # a ball exactly at a robot's centre leaves along +x (any direction would do)
        normal = np.where(
            (distance > 0)[:, None], d / np.maximum(distance, 1e-12)[:, None], [1.0, 0.0]
        )
        hit = used & (distance < contact)
        place = centre + contact * normal
        if start is not None:
            # the path start + t (ball - start), t in [0, 1], entering the circle of contact
            # around the robot: the smaller root of |f + t seg|^2 = contact^2
            seg = ball - start
            f = start - centre
            a = np.einsum("ij,ij->i", seg, seg)
            half_b = np.einsum("ij,ij->i", f, seg)
            c = np.einsum("ij,ij->i", f, f) - contact * contact
            disc = half_b * half_b - a * c
            t = (-half_b - np.sqrt(np.maximum(disc, 0.0))) / np.maximum(a, 1e-300)
            entered = used & (c > 0.0) & (a > 0.0) & (disc >= 0.0) & (t >= 0.0) & (t <= 1.0)
            entry = start + t[:, None] * seg
            normal = np.where(entered[:, None], (entry - centre) / contact, normal)
            place = np.where(entered[:, None], entry, place)
            hit |= entered
        if not hit.any():
            continue
        ball[hit] = place[hit]
        towards = np.minimum(np.einsum("ij,ij->i", velocity, normal), 0.0)
        velocity[hit] -= ((1.0 + restitution) * towards[hit])[:, None] * normal[hit]
