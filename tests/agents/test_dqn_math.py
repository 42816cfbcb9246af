import numpy as np
import pytest
import torch

from activevision.agents.dqn_math import (
    double_q_targets,
    epsilon_greedy,
    importance_weights,
    linear_schedule,
    weighted_huber_loss,
)


def test_double_q_targets_online_selects_target_evaluates():
    rewards = torch.tensor([1.0, 0.5, -1.0])
    terminated = torch.tensor([0.0, 1.0, 0.0])  # the third is truncated: still bootstraps
    next_q_online = torch.tensor([[1.0, 3.0], [5.0, 0.0], [0.0, 2.0]])
    next_q_target = torch.tensor([[10.0, 20.0], [30.0, 40.0], [7.0, -4.0]])
    targets = double_q_targets(rewards, terminated, 0.9, next_q_online, next_q_target)
    # online argmax -> [1, 0, 1]; target values [20, 30, -4]; the terminal one gets no bootstrap
    expected = torch.tensor([1.0 + 0.9 * 20.0, 0.5, -1.0 + 0.9 * -4.0])
    torch.testing.assert_close(targets, expected)
    assert not targets.requires_grad


def test_weighted_huber_loss_hand_case():
    q = torch.tensor([0.0, 0.0, 0.0])
    y = torch.tensor([0.5, 3.0, -2.0])
    w = torch.tensor([1.0, 0.5, 0.0])
    # huber(0.5) = 0.125, huber(3) = 2.5, huber(-2) = 1.5
    expected = (0.125 * 1.0 + 2.5 * 0.5 + 1.5 * 0.0) / 3
    assert weighted_huber_loss(q, y, w).item() == pytest.approx(expected)


def test_importance_weights_hand_case():
    probs = np.array([0.5, 0.25, 0.125])
    weights = importance_weights(probs, size=4, beta=0.5)
    raw = (4 * probs) ** -0.5  # [1/sqrt(2), 1, sqrt(2)]
    np.testing.assert_allclose(weights, raw / raw.max())
    np.testing.assert_allclose(weights, [0.5, 1 / np.sqrt(2), 1.0])
    np.testing.assert_allclose(importance_weights(probs, 4, beta=0.0), 1.0)
    with pytest.raises(ValueError):
        importance_weights(np.array([0.0, 1.0]), 2, 0.4)


def test_linear_schedule():
    assert linear_schedule(1.0, 0.02, 100, 0) == 1.0
    assert linear_schedule(1.0, 0.0, 100, 25) == pytest.approx(0.75)
    assert linear_schedule(1.0, 0.02, 100, 100) == pytest.approx(0.02)
    assert linear_schedule(1.0, 0.02, 100, 10_000) == pytest.approx(0.02)
    assert linear_schedule(0.4, 1.0, 0, 0) == 1.0


def test_epsilon_greedy_uses_the_network_only_when_greedy():
    rng = np.random.default_rng(0)
    calls = []

    def greedy():
        calls.append(1)
        return 7

    actions = [epsilon_greedy(greedy, 9, 0.0, rng) for _ in range(5)]
    assert actions == [7] * 5 and len(calls) == 5
    explored = [epsilon_greedy(greedy, 9, 1.0, rng) for _ in range(200)]
    assert len(calls) == 5 and set(explored) == set(range(9))
