"""One head's decision at a time: what :func:`~activevision.runtime.goal_evidence.
policy_actions` gives for a batch of one, bit for bit, in a fraction of its time.

The batched functions spend a robot's decision on NumPy calls over arrays of two or three
numbers, a few microseconds each (0.12 ms of a 0.48 ms decision of the shipped policy).
Here the head angles, the goal and the move stay Python floats:

* Basic arithmetic (``+ - * /``, min, max, comparisons) is correctly rounded in IEEE 754,
  so Python floats, and a numba kernel without fastmath, give the same bits as NumPy's
  float64 arrays. The kernel builds a camera-frame head's offset weights
  (:func:`offset_weight_kernel`), some thirty NumPy calls in the batched path.
* Everything else (exp and log in :func:`~activevision.runtime.goal_evidence.log_softmax`,
  the einsum that reads a camera-frame head at the views' offsets, argmax, hypot) runs
  through the same NumPy call on arrays of the same shape, dtype and layout as the
  batched path: SIMD loops may round differently by length and stride.

``tests/runtime/test_decision.py`` replays random inputs through both and compares bytes.
"""

from __future__ import annotations

import numpy as np

from activevision.runtime.goal_evidence import GoalEvidence, greedy_actions, log_softmax
from activevision.runtime.preprocess import compiled


@compiled
def _axis_row(x: float, values: np.ndarray, out: np.ndarray) -> None:
    """``out`` (len(values),): :func:`~activevision.runtime.goal_evidence._axis_weights` of
    one ``x`` on ascending ``values``, with the same operations (clip, searchsorted on the
    right, the fraction of the interval)."""
    n = values.shape[0]
    out[:] = 0.0
    if n == 1:
        out[0] = 1.0
        return
    x = min(max(x, values[0]), values[n - 1])
    low = 0
    while low < n and values[low] <= x:  # searchsorted(values, x, side="right")
        low += 1
    low = min(max(low - 1, 0), n - 2)
    frac = (x - values[low]) / (values[low + 1] - values[low])
    out[low] = 1.0 - frac
    out[low + 1] = frac


@compiled
def offset_weight_kernel(
    views: np.ndarray, pan: float, tilt: float, pans: np.ndarray, tilts: np.ndarray, out: np.ndarray
) -> None:
    """``out`` (V, len(pans) * len(tilts)): :func:`~activevision.runtime.goal_evidence.
    offset_weights` of the offsets of ``views`` ((V, 2) pan, tilt rad) from the head at
    ``(pan, tilt)``: each row the products of its pan and tilt weights, pan-major. Only
    subtraction, min, max, division and multiplication, each correctly rounded, so the
    same bits as NumPy's (numba without fastmath neither fuses nor reorders them)."""
    n_tilts = tilts.shape[0]
    pan_row = np.empty(pans.shape[0])
    tilt_row = np.empty(n_tilts)
    for v in range(views.shape[0]):
        _axis_row(views[v, 0] - pan, pans, pan_row)
        _axis_row(views[v, 1] - tilt, tilts, tilt_row)
        for p in range(pans.shape[0]):
            for t in range(n_tilts):
                out[v, p * n_tilts + t] = pan_row[p] * tilt_row[t]


class OneHeadGoal:
    """The goal of one head from a goal head's logits: :meth:`GoalEvidence.target` for slot
    0 of ``evidence`` (a one-slot :class:`GoalEvidence`, whose evidence and current goal
    it updates), with the same numbers."""

    def __init__(self, evidence: GoalEvidence) -> None:
        self.evidence = evidence
        self._views = [(float(p), float(t)) for p, t in evidence.views]
        self._margin = evidence.switch_margin
        self._camera = evidence.frame == "camera"
        pans, tilts = evidence.offsets
        self._pans = np.ascontiguousarray(pans, dtype=np.float64)
        self._tilts = np.ascontiguousarray(tilts, dtype=np.float64)
        self._view_array = np.ascontiguousarray(evidence.views, dtype=np.float64)
        self._shape = (1, len(self._views), len(pans) * len(tilts))
        if self._camera:  # compile (or load from numba's cache) now, not in a decision
            self.offset_weights(0.0, 0.0)

    def offset_weights(self, pan: float, tilt: float) -> np.ndarray:
        """(1, V, offsets): :func:`~activevision.runtime.goal_evidence.offset_weights` of the
        views' offsets from the head at ``(pan, tilt)``."""
        weights = np.empty(self._shape)
        offset_weight_kernel(self._view_array, pan, tilt, self._pans, self._tilts, weights[0])
        return weights

    def view_log_probs(self, goal_logits: np.ndarray, pan: float, tilt: float) -> np.ndarray:
        """(1, V): :meth:`GoalEvidence.view_log_probs` of ``goal_logits`` (one row) seen from
        the head at ``(pan, tilt)``."""
        logits = np.asarray(goal_logits, dtype=np.float64).reshape(1, -1)
        if not self._camera:
            return log_softmax(logits)
        weights = self.offset_weights(pan, tilt)
        return log_softmax(np.einsum("mvr,mr->mv", weights, log_softmax(logits)))

    def target(self, goal_logits: np.ndarray, pan: float, tilt: float) -> tuple[float, float]:
        """Add this step's ``goal_logits`` (one row), seen from ``(pan, tilt)``, to the
        evidence and return the goal view ``(pan, tilt)``."""
        evidence = self.evidence.evidence
        evidence += self.view_log_probs(goal_logits, pan, tilt)
        row = evidence[0]
        best = int(np.argmax(row))
        current = int(self.evidence.current[0])
        lead = row[best] - row[max(current, 0)]
        goal = current if current >= 0 and lead < self._margin else best
        self.evidence.current[0] = goal
        return self._views[goal]


def continuous_move(
    pan: float, tilt: float, goal: tuple[float, float], max_move: tuple[float, float]
) -> tuple[float, float]:
    """:func:`~activevision.runtime.goal_evidence.continuous_moves` for one head: the move
    towards ``goal``, each axis a fraction of ``max_move`` clipped to [-1, 1]."""
    return (
        min(max((goal[0] - pan) / max_move[0], -1.0), 1.0),
        min(max((goal[1] - tilt) / max_move[1], -1.0), 1.0),
    )


def greedy_action(pan: float, tilt: float, goal: tuple[float, float], table: np.ndarray) -> int:
    """:func:`~activevision.runtime.goal_evidence.greedy_actions` for one head (the batched
    function itself: its hypot runs in NumPy)."""
    return int(greedy_actions(np.array([[pan, tilt]]), np.array([goal]), table)[0])


def clipped_move(outputs: np.ndarray) -> tuple[float, float]:
    """A continuous policy's output (pan, tilt) clipped to [-1, 1], as ``policy_actions``."""
    return min(max(float(outputs[0]), -1.0), 1.0), min(max(float(outputs[1]), -1.0), 1.0)
