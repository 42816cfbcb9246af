"""What a run's config builds: the trainer's generator, the network, its learner and the
replay buffer, all seeded from ``config.seed``."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import torch

from activevision.agents.ddqn import DDQNLearner
from activevision.agents.q_network import QNetwork
from activevision.agents.replay.prioritized import PrioritizedReplayBuffer
from activevision.training.config import TrainConfig


class Learning(NamedTuple):
    """The trainer's generator (exploration, episode seeds, image shifts), the learner and
    the replay buffer."""

    rng: np.random.Generator
    learner: DDQNLearner
    buffer: PrioritizedReplayBuffer


def build_learning(
    config: TrainConfig,
    n_actions: int,
    obs_shape: tuple[int, int, int],
    device: torch.device,
    aux_dim: int = 0,
) -> Learning:
    """Three generators from ``config.seed``: the trainer's, the replay sampler's, and a
    forked torch generator used once to initialise the network (the global one is left
    alone). ``aux_dim``: length of the auxiliary target (0: no auxiliary head)."""
    learner_config, replay_config = config.learner, config.replay
    trainer_seed, replay_seed, init_seed = np.random.SeedSequence(config.seed).generate_state(3)
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(int(init_seed))
        network = QNetwork(
            n_actions,
            obs_shape[0],
            obs_shape[1:],
            dueling=learner_config.dueling,
            aux_outputs=aux_dim,
        )
    channels_last = device.type == "cpu"
    if channels_last:
        network.to_channels_last()
    learner = DDQNLearner(
        network,
        learning_rate=learner_config.learning_rate,
        max_grad_norm=learner_config.max_grad_norm,
        device=device,
        channels_last=channels_last,
        aux_weight=learner_config.aux_goal_weight,
    )
    buffer = PrioritizedReplayBuffer(
        replay_config.buffer_size,
        obs_shape,
        replay_config.alpha,
        replay_config.eps,
        int(replay_seed),
        n_step=learner_config.n_step,
        gamma=learner_config.gamma,
        aux_dim=aux_dim,
    )
    return Learning(np.random.default_rng(int(trainer_seed)), learner, buffer)


__all__ = ["Learning", "build_learning"]
