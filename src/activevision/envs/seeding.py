"""Seeds: of fixed-seed episode sets (evaluation and training's validation) and of the
sub-environments of the native vector envs."""

from __future__ import annotations

import numpy as np
from gymnasium.utils import seeding


def episode_seed(base_seed: int, episode: int) -> int:
    """Seed of episode ``episode`` of the set ``base_seed``: every method sees the same start
    for the same seed, and sets of different base seeds do not overlap for < 1,000,003
    episodes."""
    return base_seed * 1_000_003 + episode


def reseed_generators(rngs: list[np.random.Generator], seed: int | list[int | None] | None) -> None:
    """Gymnasium's ``VectorEnv.reset(seed=...)`` for N sub-environment generators, in place:
    an int ``s`` seeds sub-environment ``i`` with ``s + i``; a list gives each its own seed
    (None: keep its generator); None draws fresh entropy for all."""
    n = len(rngs)
    seeds: list[int | None]
    if seed is None:
        seeds = [None] * n
    elif isinstance(seed, int | np.integer):
        seeds = [int(seed) + i for i in range(n)]
    else:
        seeds = list(seed)
        if len(seeds) != n:
            raise ValueError(f"expected {n} seeds, got {len(seeds)}")
    for i, s in enumerate(seeds):
        if s is not None or seed is None:
            rngs[i] = seeding.np_random(s)[0]
