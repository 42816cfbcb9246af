"""Double DQN with prioritised replay: the paper's Q-network, the update math, the replay buffer.

This subpackage needs PyTorch (the ``train`` extra).
"""

from activevision.agents.ddqn import DDQNLearner, TorchBatch, UpdateResult, ddqn_update
from activevision.agents.dqn_math import (
    double_q_targets,
    epsilon_greedy,
    importance_weights,
    linear_schedule,
    weighted_huber_loss,
)
from activevision.agents.q_network import QNetwork, count_parameters
from activevision.agents.replay import PrioritizedReplayBuffer, ReplayBatch, SumTree

__all__ = [
    "DDQNLearner",
    "PrioritizedReplayBuffer",
    "QNetwork",
    "ReplayBatch",
    "SumTree",
    "TorchBatch",
    "UpdateResult",
    "count_parameters",
    "ddqn_update",
    "double_q_targets",
    "epsilon_greedy",
    "importance_weights",
    "linear_schedule",
    "weighted_huber_loss",
]
