"""Seeds of fixed-seed episode sets, shared by evaluation and training's validation."""

from __future__ import annotations


def episode_seed(base_seed: int, episode: int) -> int:
    """Seed of episode ``episode`` of the set ``base_seed``: every method sees the same start
    for the same seed, and sets of different base seeds do not overlap for < 1,000,003
    episodes."""
    return base_seed * 1_000_003 + episode
