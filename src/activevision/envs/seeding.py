"""Seeds: of fixed-seed episode sets (evaluation and training's validation) and of the
sub-environments of the native vector envs."""

from __future__ import annotations

import numbers

import numpy as np
from gymnasium.utils import seeding

#: Episodes in one fixed-seed set: past it, the set of ``base_seed`` runs into the next's
EPISODES_PER_SEED = 1_000_003


def episode_seed(base_seed: int, episode: int) -> int:
    """Seed of episode ``episode`` of the set ``base_seed``: every method sees the same start
    for the same seed, and sets of different base seeds do not overlap for up to
    :data:`EPISODES_PER_SEED` episodes."""
    return base_seed * EPISODES_PER_SEED + episode


def check_seed(seed: object) -> int:
    """``seed`` as an int, if it is an integer >= 0 (a NumPy one too): a ValueError naming
    it otherwise (a bool, a float; a negative one was Gymnasium's refusal of a derived
    seed)."""
    if isinstance(seed, bool | np.bool_) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise ValueError(f"seed: expects an integer >= 0, got {seed!r}")
    return int(seed)


def single_env_seed(seed: int | None) -> int | None:
    """A single env's ``reset(seed=...)`` as Gymnasium checks it, a NumPy integer read as its
    int: Gymnasium refuses ``np.int64(7)`` ("must be a python integer"), which the native
    vector envs take (seeds drawn with NumPy are NumPy integers)."""
    return int(seed) if isinstance(seed, np.integer) else seed


def reseed_generators(
    rngs: list[np.random.Generator],
    seed: int | list[int | None] | None,
    slots: np.ndarray | None = None,
) -> list[int | None]:
    """Gymnasium's ``VectorEnv.reset(seed=...)`` for N sub-environment generators, in place,
    as ``SyncVectorEnv`` resets its sub-environments: an int ``s`` seeds sub-environment
    ``i`` with ``s + i``; a list gives each its own seed; None (for all, or in the list)
    keeps the generator, so that ``reset(seed=s)`` then ``reset()`` goes on drawing from the
    seeded streams. Only the sub-environments ``slots`` (default: all) are reset. Any other
    ``seed`` (a float, a string, a dict) is a TypeError naming it; each seed of a list (a
    NumPy integer read as its int) is checked as Gymnasium checks a single env's, every one
    before any generator changes, so a refused seed leaves every generator as it was.
    Returns each sub-environment's seed (None: its generator was kept)."""
    n = len(rngs)
    seeds: list[int | None]
    if seed is None:
        seeds = [None] * n
    elif isinstance(seed, int | np.integer):
        seeds = [int(seed) + i for i in range(n)]
    elif isinstance(seed, list | tuple) or (isinstance(seed, np.ndarray) and seed.ndim == 1):
        # a NumPy array's (or list's) np.int64 as its int: Gymnasium takes Python ints only
        seeds = [int(s) if isinstance(s, np.integer) else s for s in seed]
        if len(seeds) != n:
            raise ValueError(f"seed: expected {n} seeds, got {len(seeds)}: {seed!r}")
    else:
        raise TypeError(
            f"seed: expects an int, a list of {n} ints (None keeps a sub-environment's"
            f" generator) or None, got {seed!r}"
        )
    # every new generator first (Gymnasium refuses a negative seed, a float, ...), so that a
    # refused seed of the list leaves the generators before it unchanged too
    drawn = {
        int(i): seeding.np_random(seeds[i])[0]
        for i in (range(n) if slots is None else slots)
        if seeds[i] is not None
    }
    for i, rng in drawn.items():
        rngs[i] = rng
    return seeds
