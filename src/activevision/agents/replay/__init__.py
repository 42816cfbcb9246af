"""Prioritised experience replay: frame storage, a vectorised sum tree, the buffer (numpy)."""

from activevision.agents.replay.frames import FrameStore
from activevision.agents.replay.prioritized import PrioritizedReplayBuffer, ReplayBatch
from activevision.agents.replay.sum_tree import ProportionalSampler, SumTree

__all__ = ["FrameStore", "PrioritizedReplayBuffer", "ProportionalSampler", "ReplayBatch", "SumTree"]
