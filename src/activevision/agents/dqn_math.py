"""The math of Double DQN with prioritised replay, as small pure functions.

Each function is one equation of the paper (or of the papers it builds on) and is tested on a
hand-computed case in ``tests/agents/test_dqn_math.py``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch
from torch.nn import functional as F


def double_q_targets(
    rewards: torch.Tensor,
    terminated: torch.Tensor,
    discounts: float | torch.Tensor,
    next_q_online: torch.Tensor,
    next_q_target: torch.Tensor,
) -> torch.Tensor:
    """Double-DQN targets (van Hasselt et al. 2016; the paper's Eq. for Y^DoubleQ).

    ``Y = r + gamma * Q_target(s', argmax_a Q_online(s', a))``: the online network *selects* the
    next action and the target network *evaluates* it. For n-step returns ``r`` is the
    discounted sum of n rewards, ``s'`` the state after them and the discount ``gamma ** n``.

    Only ``terminated`` stops bootstrapping: a terminal state has no future. An episode cut by
    the 20-step time limit (truncated) is not terminal, so its target still bootstraps from s'.

    Args:
        rewards: (B,) rewards r_{t+1} (or n-step reward sums).
        terminated: (B,) 1.0 / True where s' is terminal.
        discounts: the discount factor, or (B,) discounts of each bootstrap.
        next_q_online: (B, A) online-network Q-values of s'.
        next_q_target: (B, A) target-network Q-values of s'.

    Returns:
        (B,) targets, carrying no gradient.
    """
    next_actions = next_q_online.argmax(dim=1, keepdim=True)
    next_values = next_q_target.gather(1, next_actions).squeeze(1)
    not_terminal = 1.0 - terminated.to(next_values.dtype)
    return (rewards + discounts * not_terminal * next_values).detach()


def weighted_huber_loss(
    q_taken: torch.Tensor, targets: torch.Tensor, weights: torch.Tensor, delta: float = 1.0
) -> torch.Tensor:
    """Mean of importance-weighted Huber losses, ``mean(w_i * huber(q_i - y_i))``.

    The Huber loss (quadratic within ``delta``, linear outside) is Stable-Baselines' DQN loss;
    the weights ``w_i`` correct the bias of prioritised sampling (Schaul et al. 2016).
    """
    elementwise = F.huber_loss(q_taken, targets, reduction="none", delta=delta)
    return (weights * elementwise).mean()


def importance_weights(probs: np.ndarray, size: int, beta: float) -> np.ndarray:
    """Prioritised-replay importance-sampling weights ``w = (N * P)^-beta / max w``.

    Schaul et al. (2016), Algorithm 1. Normalising by the largest weight of the batch keeps every
    weight in (0, 1], so the correction only ever scales updates down.

    Args:
        probs: (B,) sampling probabilities P(i) of the sampled transitions, all > 0.
        size: N, the number of transitions in the buffer.
        beta: exponent, annealed from beta0 to 1 over training.
    """
    probs = np.asarray(probs, dtype=np.float64)
    if size < 1 or np.any(probs <= 0.0):
        raise ValueError("importance weights need size >= 1 and positive probabilities")
    weights = (size * probs) ** (-beta)
    normalised: np.ndarray = weights / weights.max()
    return normalised


def priorities_from_td_errors(td_errors: np.ndarray, eps: float) -> np.ndarray:
    """Raw priorities ``p_i = |delta_i| + eps``; eps keeps every transition sampleable."""
    return np.abs(np.asarray(td_errors, dtype=np.float64)) + eps


def linear_schedule(start: float, end: float, duration: int | float, step: int | float) -> float:
    """Linear interpolation from ``start`` to ``end`` over ``duration`` steps, then ``end``.

    Used for epsilon-greedy exploration and for the prioritised-replay exponent beta, as in
    Stable-Baselines' ``LinearSchedule``. A zero duration returns ``end`` at once.
    """
    if duration <= 0:
        return float(end)
    fraction = min(max(float(step) / float(duration), 0.0), 1.0)
    return float(start + fraction * (end - start))


def epsilon_greedy(
    greedy_action: Callable[[], int], n_actions: int, epsilon: float, rng: np.random.Generator
) -> int:
    """With probability epsilon a uniformly random action, otherwise ``greedy_action()``.

    The greedy action is a callable so the network runs only when its answer is used; the
    generator draws the same numbers whatever the Q-values are.
    """
    if rng.random() < epsilon:
        return int(rng.integers(n_actions))
    return int(greedy_action())
