"""Other robots in a match (``MatchConfig.robots``, ``MatchConfig.others``): their walk and
the ball bouncing off them. Pure functions over all matches and robot slots at once (NumPy:
a handful of robots per match, so the arrays are small and the work is a few vector
operations per tick, not worth a compiled kernel).

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
    (N, R, 2)). A robot standing on its waypoint, or whose step would bring it closer than
    ``spacing`` to another robot (where it stands at the start of the tick: two robots
    stepping towards each other may both step) or to ours (``own`` (N, 2)) while closing in
    on it, stands
    this tick and takes a new waypoint, uniform within ``half = (hx, hy)`` of the centre,
    from its ``draws`` (N, R, 2) uniforms: robots give way and turn to elsewhere, so two
    that meet never lock each other."""
    used = robots[..., 2] > 0
    xy = robots[..., :2]
    to = waypoints - xy
    distance = np.hypot(to[..., 0], to[..., 1])
    scale = np.divide(
        np.minimum(distance, step), distance, out=np.zeros_like(distance), where=distance > 0
    )
    proposed = xy + to * scale[..., None]
    # everyone a robot must keep clear of: the other robots (as they stand now) and ours
    others = np.concatenate([xy, own[:, None, :]], axis=1)  # N, R + 1, 2
    present = np.concatenate([used, np.ones((len(own), 1), dtype=bool)], axis=1)
    r = robots.shape[1]
    self_pair = np.eye(r, r + 1, dtype=bool)[None]
    keep_clear = present[:, None, :] & ~self_pair  # N, R, R + 1
    after = _distances(proposed, others)
    before = _distances(xy, others)
    blocked = (keep_clear & (after < spacing) & (after < before)).any(axis=2)
    arrived = distance <= 0.0
    turn = used & (blocked | arrived)
    moves = used & ~turn
    xy[moves] = proposed[moves]
    fresh = np.stack([half[0] * (2 * draws[..., 0] - 1), half[1] * (2 * draws[..., 1] - 1)], -1)
    waypoints[turn] = fresh[turn]


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
) -> None:
    """The balls (N, 2) that overlap a robot's body (a vertical cylinder of
    ``body_radius``) are put back at contact, on the line from the robot's centre, and
    their velocity (N, 2) towards the robot is reflected, keeping ``restitution`` of it
    (a ball moving away, or pushed by a walking robot, keeps its velocity). In place; slots
    in order, so a ball between two robots ends against the last it met. Only where the
    ball ends its tick is tested: a ball whose roll carried it past a robot's centre is put
    out on the far side with its velocity kept, and one that crossed a body entirely is
    untouched (it passed through)."""
    contact = body_radius + ball_radius
    for k in range(robots.shape[1]):
        d = ball - robots[:, k, :2]
        distance = np.hypot(d[:, 0], d[:, 1])
        hit = (robots[:, k, 2] > 0) & (distance < contact)
        if not hit.any():
            continue
        # a ball exactly at a robot's centre leaves along +x (any direction would do)
        normal = np.where(
            (distance > 0)[:, None], d / np.maximum(distance, 1e-12)[:, None], [1.0, 0.0]
        )
        ball[hit] = robots[hit, k, :2] + contact * normal[hit]
        towards = np.minimum(np.einsum("ij,ij->i", velocity, normal), 0.0)
        velocity[hit] -= ((1.0 + restitution) * towards[hit])[:, None] * normal[hit]
