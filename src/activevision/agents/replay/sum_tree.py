"""A vectorised sum tree and a proportional sampler over it (Dopamine-style).

The tree is a binary heap in one flat array: node 1 is the root, node ``k`` has children
``2k`` and ``2k + 1``, and the leaves (one per replay slot) are nodes ``P .. 2P - 1`` where ``P``
is the capacity rounded up to a power of two. Every internal node holds the sum of its children,
so the root is the total priority and a prefix sum finds its leaf in ``log2(P)`` steps — for a
whole batch at once.

Parents are recomputed from their children (never updated by deltas), so no floating-point
drift accumulates over millions of updates.
"""

from __future__ import annotations

from typing import Any

import numpy as np


class SumTree:
    """Sum of non-negative leaf values with O(log n) batch update and prefix-sum search.

    Args:
        capacity: number of leaves.
    """

    def __init__(self, capacity: int) -> None:
        if capacity < 1:
            raise ValueError(f"capacity must be >= 1, got {capacity}")
        self.capacity = int(capacity)
        self.depth = max(int(np.ceil(np.log2(self.capacity))), 0)
        self._first_leaf = 1 << self.depth
        # np.zeros is lazily backed by the OS: untouched leaves cost no memory
        self._nodes = np.zeros(2 * self._first_leaf, dtype=np.float64)

    @property
    def total(self) -> float:
        """Sum of all leaves."""
        return float(self._nodes[1])

    def get(self, indices: np.ndarray) -> np.ndarray:
        """Leaf values at ``indices``."""
        return self._nodes[self._first_leaf + np.asarray(indices, dtype=np.int64)]

    def set(self, indices: np.ndarray, values: np.ndarray) -> None:
        """Set leaves ``indices`` to ``values`` and refresh their ancestors.

        With repeated indices the last value wins, as with numpy fancy assignment.
        """
        indices = np.asarray(indices, dtype=np.int64)
        values = np.asarray(values, dtype=np.float64)
        if indices.size == 0:
            return
        if indices.min() < 0 or indices.max() >= self.capacity:
            raise IndexError("sum-tree index out of range")
        if np.any(values < 0.0) or not np.all(np.isfinite(values)):
            raise ValueError("sum-tree values must be finite and non-negative")
        nodes = self._first_leaf + indices
        self._nodes[nodes] = values
        for _ in range(self.depth):
            nodes = np.unique(nodes >> 1)
            self._nodes[nodes] = self._nodes[2 * nodes] + self._nodes[2 * nodes + 1]

    def find_prefix_sums(self, targets: np.ndarray) -> np.ndarray:
        """For each target t in [0, total), the leaf i with ``sum(leaves[:i]) <= t < ...[:i+1]``.

        Rounding can push a target past the last non-zero leaf; such results are moved back to the
        nearest leaf with a positive value on the left, so a zero-priority leaf is never returned.
        """
        remaining = np.asarray(targets, dtype=np.float64).copy()
        nodes = np.ones(remaining.shape, dtype=np.int64)
        for _ in range(self.depth):
            left = 2 * nodes
            left_sums = self._nodes[left]
            go_right = remaining >= left_sums
            remaining = np.where(go_right, remaining - left_sums, remaining)
            nodes = np.where(go_right, left + 1, left)
        leaves = nodes - self._first_leaf
        empty = self._nodes[nodes] <= 0.0
        if np.any(empty):
            nonzero = np.flatnonzero(
                self._nodes[self._first_leaf : self._first_leaf + self.capacity]
            )
            if nonzero.size == 0:
                raise ValueError("cannot search an empty sum tree")
            # the nearest positive leaf at or before the landing leaf (else the first positive)
            position = np.searchsorted(nonzero, leaves[empty], side="right") - 1
            leaves[empty] = nonzero[np.maximum(position, 0)]
        return np.minimum(leaves, self.capacity - 1)

    def leaves(self, count: int | None = None) -> np.ndarray:
        """A copy of the first ``count`` leaves (all by default), e.g. for checkpoints."""
        count = self.capacity if count is None else count
        return self._nodes[self._first_leaf : self._first_leaf + count].copy()


class ProportionalSampler:
    """Draws leaf indices with probability proportional to their value, with its own generator.

    Stratified like Dopamine: the total mass is cut into ``batch_size`` equal segments and one
    index is drawn uniformly within each, which lowers the variance of a batch while every single
    draw still has probability ``leaf / total``.

    Args:
        tree: the sum tree to sample from.
        seed: seed of the sampler's own ``numpy.random.Generator``.
    """

    def __init__(self, tree: SumTree, seed: int | None = None) -> None:
        self.tree = tree
        self.rng = np.random.default_rng(seed)

    def sample(self, batch_size: int) -> tuple[np.ndarray, np.ndarray]:
        """``batch_size`` indices and their sampling probabilities ``P(i) = p_i / sum p``."""
        total = self.tree.total
        if total <= 0.0:
            raise ValueError("cannot sample from a sum tree whose total is zero")
        segment = total / batch_size
        targets = (np.arange(batch_size) + self.rng.random(batch_size)) * segment
        indices = self.tree.find_prefix_sums(np.minimum(targets, np.nextafter(total, 0.0)))
        return indices, self.tree.get(indices) / total

    def get_state(self) -> dict[str, Any]:
        """The generator's state (a JSON-serialisable dict)."""
        return dict(self.rng.bit_generator.state)

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore a state from :meth:`get_state`."""
        self.rng.bit_generator.state = state
