"""The head actions. Discrete (the paper's): stay, or move the head by a fixed step in one
of 4 or 8 directions; diagonals move ``step * sqrt(2) / 2`` on each axis, so every move has
the same length (the release's convention). Continuous (the paper's future work): a
``Box(-1, 1, (2,))`` scaled to a maximum move per tick on each axis."""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded

from activevision.runtime.goal_evidence import continuous_moves, greedy_actions

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


def require_reset(started: np.ndarray, idx: np.ndarray, what: str = "step") -> None:
    """Gymnasium's ResetNeeded unless every slot of ``idx`` was reset: a step (or a
    ``what="render"``) before the first reset would play from (or draw) the zeros the state
    starts as (an env made by ``gymnasium.make`` refuses it too; the vector envs and
    ``.unwrapped`` did not)."""
    if not started[idx].all():
        never = np.flatnonzero(~started)
        raise ResetNeeded(
            f"{what} before reset: call reset() first (sub-environments never reset: "
            f"{_shown(never.tolist())})"
        )


def _shown(actions: object, limit: int = 60) -> str:
    """``actions`` on one line for an error message (an array's repr spans several, and a
    batch's is long): its repr with the line breaks folded, cut at ``limit`` characters."""
    text = " ".join(repr(actions).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


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
    # _shown only when raising: check_actions runs on every env step.
    if array.dtype == np.bool_ or not np.issubdtype(array.dtype, np.integer):
        raise ValueError(
            f"invalid action {_shown(actions)}: expects {expects}, got dtype {array.dtype}"
        )
    if array.shape != shape:
        raise ValueError(
            f"invalid action {_shown(actions)}: expects {expects}, got shape {array.shape}"
        )
    bad = (array < 0) | (array >= n_actions)
    if bad.any():
        where = "" if shape == () else f" {int(array[bad].flat[0])} in"
        raise ValueError(f"invalid action{where} {_shown(actions)}: expects {expects}")
    return array


ActionType = Literal["discrete", "continuous"]


def check_continuous_actions(actions: object, shape: tuple[int, ...]) -> np.ndarray:
    """``actions`` as a float64 array of ``shape`` (ending in 2: pan, tilt) with finite
    values in [-1, 1]; anything else is a ValueError naming the value. Only real numbers
    (bool, integer or float arrays) are read: NumPy would otherwise turn strings such as
    ``"0.5"`` into numbers and drop a complex value's imaginary part, with a warning at
    most."""
    try:
        array = np.asarray(actions)
        if array.dtype.kind not in "biuf":  # strings, complex, objects, dates
            raise TypeError
        array = array.astype(np.float64, copy=False)
    except (TypeError, ValueError):
        raise ValueError(
            f"invalid action {_shown(actions)}: expects numbers in [-1, 1], shape {shape}"
        ) from None
    if array.shape != shape:
        raise ValueError(
            f"invalid action {_shown(actions)}: expects numbers in [-1, 1], shape {shape},"
            f" got shape {array.shape}"
        )
    if not (np.isfinite(array).all() and (np.abs(array) <= 1.0).all()):
        raise ValueError(f"invalid action {_shown(actions)}: expects finite numbers in [-1, 1]")
    return array


def head_angle(name: str, value: object) -> np.ndarray:
    """A ``jump_head`` angle as a (1,) array (of its own dtype); a value that is not one
    finite real number is a ValueError naming it (a NaN head would fail every later step
    until a reset)."""
    array = np.asarray(value)
    if array.shape != () or array.dtype.kind not in "iuf" or not np.isfinite(array):
        raise ValueError(f"jump_head: {name} expects a finite number (rad), got {value!r}")
    return array.reshape(1)


def head_action_space(action_type: ActionType, n_actions: int) -> spaces.Box | spaces.Discrete:
    """``Discrete(n_actions)``, or ``Box(-1, 1, (2,), float32)`` for continuous moves."""
    if action_type == "continuous":
        return spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
    return spaces.Discrete(n_actions)


def head_moves(
    actions: object,
    action_type: ActionType,
    table: np.ndarray,
    max_move: tuple[float, float],
    n: int,
) -> np.ndarray:
    """The head moves (n, 2) rad of n actions: rows of the discrete ``table``, or continuous
    actions times ``max_move`` (pan, tilt rad). Each action is checked first."""
    if action_type == "continuous":
        scaled: np.ndarray = check_continuous_actions(actions, (n, 2)) * np.asarray(max_move)
        return scaled
    moves: np.ndarray = table[check_actions(actions, len(table), (n,))]
    return moves


def oracle_actions(
    head: np.ndarray,
    target: np.ndarray,
    action_type: ActionType,
    table: np.ndarray,
    max_move: tuple[float, float],
) -> np.ndarray:
    """The oracle's actions from heads (N, 2) towards targets (N, 2) rad: the discrete move
    of ``table`` that ends closest, (N,) int; or the continuous move straight there, clipped
    to ``max_move``, (N, 2) in [-1, 1]."""
    if action_type == "continuous":
        return continuous_moves(head, target, np.asarray(max_move))
    return greedy_actions(head, target, table)


__all__ = [
    "ACTION_NAMES_8WAY",
    "ActionType",
    "action_table",
    "check_actions",
    "check_continuous_actions",
    "continuous_moves",
    "greedy_actions",
    "head_action_space",
    "head_angle",
    "head_moves",
    "oracle_actions",
]
