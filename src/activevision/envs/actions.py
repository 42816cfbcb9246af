"""The discrete head actions: stay, or move the head by a fixed step in one of 4 or 8
directions. Diagonals move ``step * sqrt(2) / 2`` on each axis, so every move has the same
length (the release's convention)."""

from __future__ import annotations

import math

import numpy as np

from activevision.runtime.goal_evidence import greedy_actions

ACTION_NAMES_8WAY = (
    "stay",
    "pan_left",
    "pan_right",
    "tilt_up",
    "tilt_down",
    "pan_left_tilt_up",
    "pan_left_tilt_down",
    "pan_right_tilt_up",
    "pan_right_tilt_down",
)


def action_table(step_deg: float, action_set: str = "8way") -> np.ndarray:
    """(A, 2) head moves ``(d_pan, d_tilt)`` in radians; pan left and tilt down positive."""
    s = math.radians(step_deg)
    d = s * math.sqrt(2) / 2
    moves = [(0, 0), (s, 0), (-s, 0), (0, -s), (0, s), (d, -d), (d, d), (-d, -d), (-d, d)]
    count = {"8way": 9, "4way": 5}.get(action_set)
    if count is None:
        raise ValueError(f"action_set must be '8way' or '4way', got {action_set!r}")
    return np.asarray(moves[:count], dtype=np.float64)


def check_actions(actions: object, n_actions: int, shape: tuple[int, ...]) -> np.ndarray:
    """``actions`` as an integer array of ``shape`` with values in ``0..n_actions - 1``.

    Floats (even whole ones), bools, NaN, strings, None and wrongly shaped input are a
    ValueError naming the value: NumPy would otherwise index the action table with them
    (bools as masks, negatives from the end) or fail deep inside with an IndexError.
    """
    try:
        array = np.asarray(actions)
    except (TypeError, ValueError):  # ragged nested lists
        array = np.asarray(None)
    span = f"0..{n_actions - 1}"
    expects = f"an integer in {span}" if shape == () else f"integers in {span}, shape {shape}"
    if array.dtype == np.bool_ or not np.issubdtype(array.dtype, np.integer):
        raise ValueError(f"invalid action {actions!r}: expects {expects}, got dtype {array.dtype}")
    if array.shape != shape:
        raise ValueError(f"invalid action {actions!r}: expects {expects}, got shape {array.shape}")
    bad = (array < 0) | (array >= n_actions)
    if bad.any():
        where = "" if shape == () else f" {int(array[bad].flat[0])} in"
        raise ValueError(f"invalid action{where} {actions!r}: expects {expects}")
    return array


__all__ = ["ACTION_NAMES_8WAY", "action_table", "check_actions", "greedy_actions"]
