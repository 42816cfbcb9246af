"""Acting on the goal view rather than the next move: a student with a goal-view head adds,
at every step, the log-probabilities it gives each of the 40 candidate views to what it
gave before, and moves greedily towards the view with the most evidence.

The sum is a naive-Bayes filter over the goal (each frame's prediction taken as independent
evidence about one fixed goal), the episode's memory: a frame that makes another view look
a little better no longer turns the head around, so the swinging between two neighbouring
views of a memoryless greedy policy ends (docs/learned-head-control.md: 11-16% of episodes
at e >= 1 with the action head, 0% with goal evidence). NumPy only: the trainer (batched)
and the evaluator run this code; :class:`~activevision.runtime.HeadController` on a robot
runs its one-head form (:mod:`activevision.runtime.decision`), which gives the same bytes.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

#: what a goal head's logits name: ``"body"``, the candidate views themselves (head angles
#: relative to the body); ``"camera"``, offsets from where the head points now, on a grid
#: twice as wide as the views' (:func:`offset_axes`), turned into views with the head's
#: angles (:func:`offset_weights`)
GoalFrame = Literal["body", "camera"]
GOAL_FRAMES: tuple[GoalFrame, ...] = ("body", "camera")


def offset_axes(views: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pan and tilt offsets (rad) of a camera-frame goal head for evenly spaced
    candidate ``views`` ((V, 2) pan, tilt): every difference between two of the views'
    pans (2 n_pan - 1 values, ascending) and between two tilts."""
    axes = []
    for column in np.asarray(views, dtype=np.float64).T:
        values = np.unique(column)
        span = values[-1] - values[0]
        axes.append(np.linspace(-span, span, 2 * len(values) - 1))
    return axes[0], axes[1]


def offset_count(views: np.ndarray) -> int:
    """The logits of a camera-frame goal head for ``views``."""
    pans, tilts = offset_axes(views)
    return len(pans) * len(tilts)


def goal_output_count(views: np.ndarray, frame: GoalFrame) -> int:
    """The logits of a goal head over ``views`` in ``frame``: one per view, or per offset."""
    return offset_count(views) if frame == "camera" else len(views)


def _axis_weights(x: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(..., len(values)) linear-interpolation weights of ``x`` (clipped) on ascending
    ``values``."""
    weights = np.zeros((*x.shape, len(values)))
    if len(values) == 1:
        weights[...] = 1.0
        return weights
    # minimum/maximum and flat fancy indexing rather than clip and put_along_axis: the same
    # numbers at a third of the time, which a robot's controller spends on every decision
    x = np.minimum(np.maximum(x, values[0]), values[-1])
    low = np.minimum(np.maximum(np.searchsorted(values, x, side="right") - 1, 0), len(values) - 2)
    frac = (x - values[low]) / (values[low + 1] - values[low])
    flat = weights.reshape(-1, len(values))
    rows = np.arange(len(flat))
    flat[rows, low.ravel()] = (1.0 - frac).ravel()
    flat[rows, low.ravel() + 1] = frac.ravel()
    return weights


def offset_weights(offsets: np.ndarray, pans: np.ndarray, tilts: np.ndarray) -> np.ndarray:
    """(..., len(pans) * len(tilts)) bilinear weights (pan-major, each row summing to 1) of
    ``offsets`` ((..., 2) pan, tilt rad, clipped to the axes) on the offset grid: the soft
    label of a goal offset, and how a camera-frame goal head's log-probabilities are read
    at a view's offset."""
    offsets = np.asarray(offsets, dtype=np.float64)
    pan = _axis_weights(offsets[..., 0], pans)
    tilt = _axis_weights(offsets[..., 1], tilts)
    weights: np.ndarray = (pan[..., :, None] * tilt[..., None, :]).reshape(*offsets.shape[:-1], -1)
    return weights


def greedy_actions(head: np.ndarray, target: np.ndarray, table: np.ndarray) -> np.ndarray:
    """(N,) the action of ``table`` ((A, 2) moves, rad) whose move ends closest to
    ``target`` for each of N heads ((N, 2) pan, tilt rad): the oracle's move."""
    after = np.asarray(head)[:, None, :] + np.asarray(table)[None]
    gap = after - np.asarray(target)[:, None, :]
    best: np.ndarray = np.argmin(np.hypot(gap[..., 0], gap[..., 1]), axis=1)
    return best


def continuous_moves(head: np.ndarray, target: np.ndarray, max_move: np.ndarray) -> np.ndarray:
    """(N, 2) continuous actions in [-1, 1]: the move from each of N heads ((N, 2) pan, tilt
    rad) straight towards ``target``, each axis clipped to ``max_move`` (pan, tilt rad) and
    divided by it (the continuous oracle; one step when the target is within reach)."""
    reach = np.asarray(max_move, dtype=np.float64)
    gap = np.asarray(target, dtype=np.float64) - np.asarray(head, dtype=np.float64)
    moves: np.ndarray = np.clip(gap / reach, -1.0, 1.0)
    return moves


def log_softmax(logits: np.ndarray) -> np.ndarray:
    """Row-wise log-softmax, stable for large logits."""
    shifted = logits - logits.max(axis=-1, keepdims=True)
    out: np.ndarray = shifted - np.log(np.exp(shifted).sum(axis=-1, keepdims=True))
    return out


class GoalEvidence:
    """Accumulated goal-view evidence of ``n`` episodes.

    Args:
        n: episodes (slots) tracked at once.
        views: (V, 2) the candidate views (pan, tilt) rad, in the goal head's order.
        table: (A, 2) the head moves (d_pan, d_tilt) rad of the actions.
        switch_margin: hysteresis (nats): once a slot has a goal, another view takes over
            only when its evidence leads by at least this much. 0: always the best-supported
            view. Frames that keep favouring whichever view the head is not at can then no
            longer swing it between the two (docs/continuous-control.md).
        frame: what the goal logits name (:data:`GoalFrame`): with ``"camera"`` each view's
            log-probability is the head's, read at the view's offset from the head, and
            renormalised over the views.
    """

    def __init__(
        self,
        n: int,
        views: np.ndarray,
        table: np.ndarray,
        switch_margin: float = 0.0,
        frame: GoalFrame = "body",
    ) -> None:
        if not (math.isfinite(switch_margin) and switch_margin >= 0):
            raise ValueError(f"switch_margin must be a number >= 0, got {switch_margin!r}")
        if frame not in GOAL_FRAMES:
            raise ValueError(f"frame must be one of {GOAL_FRAMES}, got {frame!r}")
        self.frame = frame
        self.views = np.asarray(views, dtype=np.float64)
        self.offsets = offset_axes(self.views)
        self.table = np.asarray(table, dtype=np.float64)
        self.switch_margin = float(switch_margin)
        self.evidence = np.zeros((n, len(self.views)))
        self.current = np.full(n, -1, dtype=np.int64)  #: each slot's goal index (-1: none yet)

    def reset(self, slots: np.ndarray | slice = slice(None)) -> None:
        """Slots ``slots`` start new episodes: no evidence yet."""
        self.evidence[slots] = 0.0
        self.current[slots] = -1

    def view_log_probs(self, goal_logits: np.ndarray, heads: np.ndarray) -> np.ndarray:
        """(M, V) the log-probability of each view from a goal head's logits (M, V), or a
        camera-frame head's (M, offsets) with the heads ((M, 2) pan, tilt rad) they were
        seen from."""
        logits = np.asarray(goal_logits, dtype=np.float64)
        if self.frame == "body":
            return log_softmax(logits)
        gap = self.views[None] - np.asarray(heads, dtype=np.float64)[:, None]
        weights = offset_weights(gap, *self.offsets)
        return log_softmax(np.einsum("mvr,mr->mv", weights, log_softmax(logits)))

    def target(self, goal_logits: np.ndarray, slots: np.ndarray, heads: np.ndarray) -> np.ndarray:
        """Add this step's ``goal_logits`` (M, V), seen from ``heads`` (M, 2), to slots
        ``slots`` (M,) and return the goal view (M, 2) of each: the best-supported one,
        unless the slot's current goal is within ``switch_margin`` of it."""
        self.evidence[slots] += self.view_log_probs(goal_logits, heads)
        evidence = self.evidence[slots]
        best = np.argmax(evidence, axis=1)
        current = self.current[slots]
        rows = np.arange(len(evidence))
        lead = evidence[rows, best] - evidence[rows, np.maximum(current, 0)]
        goal = np.where((current >= 0) & (lead < self.switch_margin), current, best)
        self.current[slots] = goal
        goals: np.ndarray = self.views[goal]
        return goals


def policy_actions(
    outputs: np.ndarray,
    goal_logits: np.ndarray | None,
    heads: np.ndarray,
    max_move: np.ndarray | None = None,
    evidence: GoalEvidence | None = None,
    slots: np.ndarray | None = None,
) -> np.ndarray:
    """The actions of a student policy for M heads ((M, 2) pan, tilt rad) from its outputs:
    the argmax of its action logits (M, A), (M,) int, or for a continuous policy
    (``max_move``: pan, tilt rad) its move (M, 2) clipped to [-1, 1]. With ``evidence`` and
    ``goal_logits`` (M, V): the move towards the view its summed goal evidence picks for
    slots ``slots`` (default: the first M) instead: a move of the evidence's action table,
    or the continuous move straight there. The trainer and the evaluator act through this
    function, the robot runtime through its one-head form with the same numbers
    (:mod:`activevision.runtime.decision`)."""
    if evidence is not None and goal_logits is not None:
        rows = np.arange(len(heads)) if slots is None else slots
        target = evidence.target(goal_logits, rows, heads)
        if max_move is None:
            return greedy_actions(heads, target, evidence.table)
        return continuous_moves(heads, target, max_move)
    if max_move is None:
        actions: np.ndarray = np.argmax(outputs, axis=1)
        return actions
    moves: np.ndarray = np.clip(np.asarray(outputs, dtype=np.float64), -1.0, 1.0)
    return moves
