"""Prioritised experience replay (Schaul et al. 2016) that stores every frame once.

A transition keeps only frame *ids*: ``obs`` and ``next_obs`` are the ids of the newest frame of
each observation, whose ``stack`` frames are consecutive in the :class:`FrameStore`. Along an
episode the ``next_obs`` of one step is the ``obs`` of the next, so a step costs one new frame,
and with frame stacks (``stack > 1``) a step adds only the newest frame whenever ``next_obs`` is
``obs`` shifted by one frame (checked, so any stacking convention is stored exactly).

Priorities follow Stable-Baselines (v2): new transitions get the largest priority seen so far,
updates set ``p = |td error| + eps``, and sampling is proportional to ``p ** alpha``.

With ``n_step > 1`` a sampled transition brings the discounted sum of up to ``n_step`` rewards
along its episode and the observation after them (multi-step returns, Sutton 1988; Rainbow,
Hessel et al. 2018). They are formed at sampling time from the stored one-step transitions, so
nothing is stored twice, and the buffer's contents do not depend on ``n_step``.
"""

from __future__ import annotations

import json
from typing import NamedTuple

import numpy as np

from activevision.agents.dqn_math import importance_weights, priorities_from_td_errors
from activevision.agents.replay.frames import FrameStore
from activevision.agents.replay.sum_tree import ProportionalSampler, SumTree


class ReplayBatch(NamedTuple):
    """A sampled minibatch; arrays have the batch size B as first dimension."""

    obs: np.ndarray  # (B, stack, H, W) uint8
    actions: np.ndarray  # (B,) int64
    rewards: np.ndarray  # (B,) float32
    next_obs: np.ndarray  # (B, stack, H, W) uint8
    terminated: np.ndarray  # (B,) float32, 1.0 where next_obs is terminal (not merely truncated)
    discounts: np.ndarray  # (B,) float32 gamma ** (rewards summed): the bootstrap's discount
    aux: np.ndarray  # (B, aux_dim) float32 auxiliary targets of obs (aux_dim may be 0)
    weights: np.ndarray  # (B,) float32 importance-sampling weights, max 1
    indices: np.ndarray  # (B,) int64 buffer slots, for update_priorities


class PrioritizedReplayBuffer:
    """Circular prioritised replay buffer of (obs, action, reward, next_obs, terminated).

    Args:
        capacity: maximum number of transitions (the paper: 1,000,000).
        obs_shape: (stack, H, W) of one uint8 observation.
        alpha: how much prioritisation is used, 0 = uniform (the paper: 0.6).
        eps: added to |td error| so that no transition has zero priority (SB2: 1e-6).
        seed: seed of the sampler's own generator.
        chunk_frames: frames per storage chunk; storage grows one chunk at a time.
        n_step: rewards summed per sampled transition (1: the paper's one-step targets).
        gamma: discount of those sums and of the bootstrap.
        aux_dim: length of a per-transition vector of auxiliary targets for ``obs`` (e.g. the
            goal's direction, for an auxiliary loss); 0 stores none.
    """

    def __init__(
        self,
        capacity: int,
        obs_shape: tuple[int, int, int],
        alpha: float = 0.6,
        eps: float = 1e-6,
        seed: int | None = None,
        chunk_frames: int = 1024,
        n_step: int = 1,
        gamma: float = 0.99,
        aux_dim: int = 0,
    ) -> None:
        if capacity < 1:
            raise ValueError(f"capacity must be >= 1, got {capacity}")
        if n_step < 1:
            raise ValueError(f"n_step must be >= 1, got {n_step}")
        if len(obs_shape) != 3:
            raise ValueError(f"obs_shape must be (stack, H, W), got {obs_shape}")
        self.capacity = int(capacity)
        self.obs_shape = tuple(int(n) for n in obs_shape)
        self.stack = self.obs_shape[0]
        self.alpha = float(alpha)
        self.eps = float(eps)
        self.chunk_frames = int(chunk_frames)
        self.n_step = int(n_step)
        self.gamma = float(gamma)
        self.aux_dim = int(aux_dim)

        self.frames = FrameStore((self.obs_shape[1], self.obs_shape[2]), chunk_frames)
        # per-transition scalars; np.zeros is lazily backed, so unused slots cost no memory
        self._obs_ids = np.zeros(self.capacity, dtype=np.int64)
        self._next_obs_ids = np.zeros(self.capacity, dtype=np.int64)
        self._actions = np.zeros(self.capacity, dtype=np.int64)
        self._rewards = np.zeros(self.capacity, dtype=np.float32)
        self._terminated = np.zeros(self.capacity, dtype=np.bool_)
        self._aux = np.zeros((self.capacity, self.aux_dim), dtype=np.float32)
        self.tree = SumTree(self.capacity)
        self.sampler = ProportionalSampler(self.tree, seed)

        self.cursor = 0  # slot the next transition is written to
        self.size = 0
        self.max_priority = 1.0
        self._open_episode_obs_id = -1  # id of the last next_obs if its episode goes on

    def __len__(self) -> int:
        return self.size

    # ------------------------------------------------------------------ writing
    def add(
        self,
        obs: np.ndarray,
        action: int,
        reward: float,
        next_obs: np.ndarray,
        terminated: bool,
        truncated: bool,
        aux: np.ndarray | None = None,
    ) -> int:
        """Store one transition at maximal priority; returns its slot."""
        obs = self._check_obs(obs)
        aux = np.zeros(0, np.float32) if aux is None else np.asarray(aux, dtype=np.float32)
        if aux.shape != (self.aux_dim,):
            raise ValueError(f"aux must have shape ({self.aux_dim},), got {aux.shape}")
        next_obs = self._check_obs(next_obs)
        obs_id = self._open_episode_obs_id
        if obs_id < 0 or not np.array_equal(self._stack_of(obs_id), obs):
            obs_id = self.frames.extend(obs)  # a new episode (or a jump): store the whole stack
        newest_block = obs_id == self.frames.next_id - 1
        if newest_block and np.array_equal(next_obs[:-1], obs[1:]):
            next_obs_id = self.frames.append(next_obs[-1])  # the usual case: one new frame
        else:
            next_obs_id = self.frames.extend(next_obs)

        slot = self.cursor
        self._obs_ids[slot] = obs_id
        self._next_obs_ids[slot] = next_obs_id
        self._actions[slot] = action
        self._rewards[slot] = reward
        self._terminated[slot] = terminated
        self._aux[slot] = aux
        self.tree.set(np.array([slot]), np.array([self.max_priority**self.alpha]))
        self.cursor = (slot + 1) % self.capacity
        self.size = min(self.size + 1, self.capacity)
        self._open_episode_obs_id = -1 if (terminated or truncated) else next_obs_id

        oldest_slot = self.cursor if self.size == self.capacity else 0
        self.frames.release_before(self._obs_ids[oldest_slot] - self.stack + 1)
        return slot

    def update_priorities(self, indices: np.ndarray, td_errors: np.ndarray) -> None:
        """Set the priorities of sampled transitions from their new TD errors."""
        priorities = priorities_from_td_errors(td_errors, self.eps)
        self.tree.set(indices, priorities**self.alpha)
        self.max_priority = max(self.max_priority, float(priorities.max()))

    # ------------------------------------------------------------------ reading
    def sample(self, batch_size: int, beta: float) -> ReplayBatch:
        """A prioritised minibatch with importance weights for exponent ``beta``."""
        if self.size == 0:
            raise ValueError("cannot sample from an empty replay buffer")
        indices, probs = self.sampler.sample(batch_size)
        weights = importance_weights(probs, self.size, beta)
        last, rewards, discounts = self._n_step_returns(indices)
        return ReplayBatch(
            obs=self._stack_of(self._obs_ids[indices]),
            actions=self._actions[indices],
            rewards=rewards,
            next_obs=self._stack_of(self._next_obs_ids[last]),
            terminated=self._terminated[last].astype(np.float32),
            discounts=discounts,
            aux=self._aux[indices],
            weights=weights.astype(np.float32),
            indices=indices,
        )

    def _n_step_returns(self, indices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(slot of the last transition used, discounted reward sum, gamma ** steps) per index.

        From each sampled slot, transitions are followed while they continue its episode, for
        ``n_step`` steps at most: near an episode's end (terminal or truncated) or its unfinished
        present the return is shorter and bootstraps sooner, never through termination. A
        transition continues the previous one exactly when it starts from that one's
        ``next_obs`` frame; frame ids only grow and a new episode stores new frames, so this
        also stops at episode ends and at the newest transition (the slot after it is empty or
        holds the oldest).
        """
        offsets = np.arange(self.n_step)
        slots = (indices[:, None] + offsets) % self.capacity  # (B, n_step)
        continues = self._obs_ids[slots[:, 1:]] == self._next_obs_ids[slots[:, :-1]]
        used = np.ones(slots.shape, dtype=np.bool_)
        used[:, 1:] = np.logical_and.accumulate(continues, axis=1)
        steps = used.sum(axis=1)
        last = slots[np.arange(len(indices)), steps - 1]
        powers = self.gamma ** offsets.astype(np.float64)
        rewards = (used * self._rewards[slots] * powers).sum(axis=1)
        return last, rewards.astype(np.float32), (self.gamma**steps).astype(np.float32)

    def _stack_of(self, newest_ids: np.ndarray | int) -> np.ndarray:
        """Observations (..., stack, H, W) whose newest frames have ids ``newest_ids``."""
        offsets = np.arange(-self.stack + 1, 1)
        return self.frames.get(np.asarray(newest_ids)[..., None] + offsets)

    def _check_obs(self, obs: np.ndarray) -> np.ndarray:
        obs = np.asarray(obs)
        if obs.shape != self.obs_shape or obs.dtype != np.uint8:
            raise ValueError(
                f"observation must be uint8 {self.obs_shape}, got {obs.dtype} {obs.shape}"
            )
        return obs

    # ------------------------------------------------------------------ checkpoints
    def state_dict(self) -> dict[str, np.ndarray]:
        """The whole buffer as plain numpy arrays (for ``np.savez``; no pickling needed)."""
        first_frame_id, frames = self.frames.export()
        n = self.size
        return {
            "shape": np.array([self.capacity, *self.obs_shape], dtype=np.int64),
            "alpha_eps": np.array([self.alpha, self.eps], dtype=np.float64),
            "n_step_gamma": np.array([self.n_step, self.gamma], dtype=np.float64),
            "counters": np.array(
                [
                    self.cursor,
                    self.size,
                    first_frame_id,
                    self._open_episode_obs_id,
                    self.chunk_frames,
                ],
                dtype=np.int64,
            ),
            "max_priority": np.array(self.max_priority, dtype=np.float64),
            "frames": frames,
            "obs_ids": self._obs_ids[:n].copy(),
            "next_obs_ids": self._next_obs_ids[:n].copy(),
            "actions": self._actions[:n].copy(),
            "rewards": self._rewards[:n].copy(),
            "terminated": self._terminated[:n].copy(),
            "aux": self._aux[:n].copy(),
            "priorities": self.tree.leaves(n),
            "sampler_rng": np.array(json.dumps(self.sampler.get_state())),
        }

    @classmethod
    def from_state_dict(cls, state: dict[str, np.ndarray]) -> PrioritizedReplayBuffer:
        """Rebuild a buffer, bit for bit, from :meth:`state_dict`."""
        capacity, stack, height, width = (int(v) for v in state["shape"])
        alpha, eps = (float(v) for v in state["alpha_eps"])
        cursor, size, first_frame_id, open_obs_id, chunk_frames = (
            int(v) for v in state["counters"]
        )
        n_step, gamma = state["n_step_gamma"]
        buffer = cls(
            capacity,
            (stack, height, width),
            alpha,
            eps,
            chunk_frames=chunk_frames,
            n_step=int(n_step),
            gamma=float(gamma),
            aux_dim=state["aux"].shape[1] if "aux" in state else 0,
        )
        buffer.frames = FrameStore.restore(first_frame_id, state["frames"], chunk_frames)
        buffer._obs_ids[:size] = state["obs_ids"]
        buffer._next_obs_ids[:size] = state["next_obs_ids"]
        buffer._actions[:size] = state["actions"]
        buffer._rewards[:size] = state["rewards"]
        buffer._terminated[:size] = state["terminated"]
        if buffer.aux_dim:
            buffer._aux[:size] = state["aux"]
        buffer.tree.set(np.arange(size), state["priorities"])
        buffer.sampler.set_state(json.loads(str(state["sampler_rng"])))
        buffer.cursor, buffer.size = cursor, size
        buffer.max_priority = float(state["max_priority"])
        buffer._open_episode_obs_id = open_obs_id
        return buffer
