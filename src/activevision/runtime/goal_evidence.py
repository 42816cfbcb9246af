"""Acting on the goal view rather than the next move: a student with a goal-view head adds,
at every step, the log-probabilities it gives each of the 40 candidate views to what it
gave before, and moves greedily towards the view with the most evidence.

The sum is a naive-Bayes filter over the goal (each frame's prediction taken as independent
evidence about one fixed goal), the episode's memory: a frame that makes another view look
a little better no longer turns the head around, so the swinging between two neighbouring
views of a memoryless greedy policy ends (README: 11-16% of episodes at e >= 1 with the
action head, 0% with goal evidence). NumPy only: the trainer (batched), the evaluator and
:class:`~activevision.runtime.HeadController` on a robot run this same code.
"""

from __future__ import annotations

import math

import numpy as np


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
            longer swing it between the two (README: continuous head control).
    """

    def __init__(
        self, n: int, views: np.ndarray, table: np.ndarray, switch_margin: float = 0.0
    ) -> None:
        if not (math.isfinite(switch_margin) and switch_margin >= 0):
            raise ValueError(f"switch_margin must be a number >= 0, got {switch_margin!r}")
        self.views = np.asarray(views, dtype=np.float64)
        self.table = np.asarray(table, dtype=np.float64)
        self.switch_margin = float(switch_margin)
        self.evidence = np.zeros((n, len(self.views)))
        self.current = np.full(n, -1, dtype=np.int64)  #: each slot's goal index (-1: none yet)

    def reset(self, slots: np.ndarray | slice = slice(None)) -> None:
        """Slots ``slots`` start new episodes: no evidence yet."""
        self.evidence[slots] = 0.0
        self.current[slots] = -1

    def target(self, goal_logits: np.ndarray, slots: np.ndarray) -> np.ndarray:
        """Add this step's ``goal_logits`` (M, V) to slots ``slots`` (M,) and return the
        goal view (M, 2) of each: the best-supported one, unless the slot's current goal is
        within ``switch_margin`` of it."""
        self.evidence[slots] += log_softmax(np.asarray(goal_logits, dtype=np.float64))
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
    or the continuous move straight there. The trainer, the evaluator and the robot runtime
    all act through this function."""
    if evidence is not None and goal_logits is not None:
        rows = np.arange(len(heads)) if slots is None else slots
        target = evidence.target(goal_logits, rows)
        if max_move is None:
            return greedy_actions(heads, target, evidence.table)
        return continuous_moves(heads, target, max_move)
    if max_move is None:
        actions: np.ndarray = np.argmax(outputs, axis=1)
        return actions
    moves: np.ndarray = np.clip(np.asarray(outputs, dtype=np.float64), -1.0, 1.0)
    return moves
