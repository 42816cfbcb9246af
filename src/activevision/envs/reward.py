"""The paper's reward: +1 for moving the head closer to the goal viewpoint, -1 for moving
away, 0 otherwise, and a penalty for losing the ball.

The paper prints ``sign(D' - D)`` (D before, D' after the action), which would reward moving
*away*; its text ("encourage the robot to move its head through the goal position and
penalises the robot from moving its head away") means ``sign(D - D')``. We implement the text.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def viewpoint_distance_deg(
    pan: ArrayLike, tilt: ArrayLike, goal_pan: np.ndarray, goal_tilt: np.ndarray
) -> np.ndarray:
    """Euclidean distance between head poses in (pan, tilt) degrees."""
    distance: np.ndarray = np.degrees(
        np.hypot(np.asarray(pan) - goal_pan, np.asarray(tilt) - goal_tilt)
    )
    return distance


def approach_reward(
    dist_before: ArrayLike, dist_after: ArrayLike, resolution_deg: float = 0.0
) -> np.ndarray:
    """``sign(D - D')``; with ``resolution_deg > 0`` the change is first truncated to whole
    multiples of it (the release: ``sign(int(D - D'))`` in degrees)."""
    change = np.asarray(dist_before, float) - np.asarray(dist_after, float)
    if resolution_deg > 0:
        change = np.trunc(change / resolution_deg)
    # Moves shorter than 1e-9 deg are no move at all (stay, or pushed against a head limit).
    return np.where(np.abs(change) < 1e-9, 0.0, np.sign(change))
