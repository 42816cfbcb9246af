"""The learner finds the optimal Q-values of a tiny deterministic MDP."""

import numpy as np
import pytest
import torch
from torch import nn

from activevision.agents.ddqn import DDQNLearner
from activevision.agents.q_network import QNetwork
from activevision.agents.replay.prioritized import PrioritizedReplayBuffer

GAMMA = 0.9
N_STATES = 3  # a chain: action 0 = left, 1 = right; right from the last state ends with +1


def one_hot_image(state: int) -> np.ndarray:
    image = np.zeros((1, 1, N_STATES), dtype=np.uint8)
    image[0, 0, state] = 255
    return image


def chain_transitions():
    """(s, a, r, s', terminated, truncated) of every state-action pair."""
    out = []
    for s in range(N_STATES):
        out.append((s, 0, 0.0, max(s - 1, 0), False, False))
        if s == N_STATES - 1:
            out.append((s, 1, 1.0, s, True, False))  # s' is irrelevant: terminal
        else:
            out.append((s, 1, 0.0, s + 1, False, False))
            out.append((s, 1, 0.0, s + 1, False, True))  # time-limit cut: still bootstraps
    return out


def optimal_q() -> np.ndarray:
    q = np.zeros((N_STATES, 2))
    for _ in range(200):  # value iteration
        v = q.max(axis=1)
        for s in range(N_STATES):
            q[s, 0] = GAMMA * v[max(s - 1, 0)]
            q[s, 1] = 1.0 if s == N_STATES - 1 else GAMMA * v[s + 1]
    return q


class TinyQ(nn.Module):
    def __init__(self) -> None:
        super().__init__()
        self.net = nn.Sequential(nn.Flatten(), nn.Linear(N_STATES, 32), nn.ReLU(), nn.Linear(32, 2))

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return self.net(obs.float() / 255.0)


@pytest.fixture
def one_torch_thread():
    """Tiny networks gain nothing from threads, and lose much on a busy machine."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


def test_ddqn_learns_optimal_q_values_of_a_chain(one_torch_thread):
    with torch.random.fork_rng():
        torch.manual_seed(0)
        learner = DDQNLearner(TinyQ(), learning_rate=5e-3, max_grad_norm=10.0)
    buffer = PrioritizedReplayBuffer(100, (1, 1, N_STATES), alpha=0.6, seed=0, gamma=GAMMA)
    for s, a, r, s_next, terminated, truncated in chain_transitions():
        buffer.add(one_hot_image(s), a, r, one_hot_image(s_next), terminated, truncated)
    for step in range(1, 1001):
        batch = buffer.sample(16, beta=min(0.4 + step / 1000, 1.0))
        result = learner.update(batch)
        buffer.update_priorities(batch.indices, result.td_errors)
        if step % 50 == 0:
            learner.sync_target()
    learned = np.stack([learner.q_values(one_hot_image(s)) for s in range(N_STATES)])
    np.testing.assert_allclose(learned, optimal_q(), atol=0.03)


def test_auxiliary_loss_trains_the_auxiliary_head(one_torch_thread):
    """With aux_weight the update also fits the aux head to the stored targets."""
    with torch.random.fork_rng():
        torch.manual_seed(1)
        learner = DDQNLearner(
            QNetwork(2, image_shape=(36, 36), aux_outputs=2), learning_rate=1e-3, aux_weight=1.0
        )
    rng = np.random.default_rng(1)
    buffer = PrioritizedReplayBuffer(64, (1, 36, 36), alpha=0.0, seed=1, aux_dim=2)
    for _ in range(32):  # target: the image's mean brightness and its left-right difference
        image = rng.integers(0, 256, size=(1, 36, 36), dtype=np.uint8)
        target = [image.mean() / 255, (image[..., :18].mean() - image[..., 18:].mean()) / 25]
        buffer.add(image, 0, 0.0, image, True, False, aux=np.array(target))

    def aux_error() -> float:
        batch = buffer.sample(32, beta=1.0)
        with torch.no_grad():
            _, predicted = learner.online.forward_with_aux(torch.from_numpy(batch.obs))
        return float(((predicted.numpy() - batch.aux) ** 2).mean())

    before = aux_error()
    for _ in range(150):
        learner.update(buffer.sample(32, beta=1.0))
    assert aux_error() < 0.1 * before
