"""Benchmark: milliseconds per DDQN update and environment steps per second of training.

Compares activevision's update (channels-last CNN with max-pool before ReLU, fused Adam,
inference-mode targets, glibc keeping freed pages, prioritised replay sampling and priority
updates included) with a plain PyTorch implementation of the same gradient step (NCHW, ReLU
then pool, separate no-grad forwards, foreach Adam, default allocator), in the same process.
Then trains a few hundred steps on ActiveVision-v0 (or a fake image env if it cannot be
imported) and reports the steps per second once an update runs every step
(``env_steps_per_s``), the same with a free fake env (the learner's own cost,
``fake_env_training_steps_per_s``) and the environment alone (``env_only_steps_per_s``).

Usage: python bench/train.py [--updates 40] [--threads 0]
Prints each measurement beside its reference in the same run and their ratio (the plain
update's time over activevision's, the training pace over the fake env's), then one JSON
object as the last line.
"""

from __future__ import annotations

import copy
import json
import os
import platform
import statistics
import tempfile
import time
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from activevision.agents.ddqn import DDQNLearner
from activevision.agents.q_network import QNetwork
from activevision.agents.replay.prioritized import PrioritizedReplayBuffer
from activevision.cli.args import ArgumentParser, int_in, positive_int
from activevision.training.config import TrainConfig
from activevision.training.cpu import configure_torch_cpu, resolve_num_threads
from activevision.training.trainer import Trainer

OBS_SHAPE = (1, 120, 160)
N_ACTIONS = 9
BATCH = 32


class PlainQNetwork(nn.Module):
    """The paper's CNN written the obvious way: NCHW, conv -> ReLU -> pool."""

    def __init__(self) -> None:
        super().__init__()
        self.layers = nn.Sequential(
            nn.Conv2d(1, 32, 5, stride=2), nn.ReLU(), nn.MaxPool2d(2, 2),
            nn.Conv2d(32, 64, 3, stride=2), nn.ReLU(),
            nn.Conv2d(64, 64, 3, stride=2), nn.ReLU(),
            nn.Flatten(), nn.Linear(3456, 512), nn.ReLU(), nn.Linear(512, N_ACTIONS),
        )  # fmt: skip

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return self.layers(obs.float() / 255.0)


def plain_update_fn(buffer: PrioritizedReplayBuffer) -> Callable[[], None]:
    """One straightforward Double-DQN step (the reference), sampling from the same buffer."""
    online = PlainQNetwork()
    target = copy.deepcopy(online)
    optimizer = torch.optim.Adam(online.parameters(), lr=5e-4)

    def update() -> None:
        batch = buffer.sample(BATCH, beta=0.4)
        obs, next_obs = torch.from_numpy(batch.obs), torch.from_numpy(batch.next_obs)
        actions = torch.from_numpy(batch.actions)
        rewards, weights = torch.from_numpy(batch.rewards), torch.from_numpy(batch.weights)
        terminated = torch.from_numpy(batch.terminated)
        with torch.no_grad():
            next_actions = online(next_obs).argmax(1, keepdim=True)
            next_values = target(next_obs).gather(1, next_actions).squeeze(1)
            targets = rewards + 0.99 * (1.0 - terminated) * next_values
        q = online(obs).gather(1, actions.unsqueeze(1)).squeeze(1)
        loss = (weights * F.smooth_l1_loss(q, targets, reduction="none")).mean()
        optimizer.zero_grad()
        loss.backward()
        nn.utils.clip_grad_norm_(online.parameters(), 10.0)
        optimizer.step()
        buffer.update_priorities(batch.indices, (q - targets).detach().numpy())

    return update


def our_update_fn(buffer: PrioritizedReplayBuffer) -> Callable[[], None]:
    """activevision's update: sample, DDQN step, new priorities."""
    learner = DDQNLearner(QNetwork(N_ACTIONS).to_channels_last(), channels_last=True)

    def update() -> None:
        batch = buffer.sample(BATCH, beta=0.4)
        result = learner.update(batch)
        buffer.update_priorities(batch.indices, result.td_errors)

    return update


def median_ms(fn: Callable[[], None], repeats: int, warmup: int = 5) -> float:
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return 1000.0 * statistics.median(times)


def filled_buffer(seed: int = 0, transitions: int = 2000) -> PrioritizedReplayBuffer:
    rng = np.random.default_rng(seed)
    buffer = PrioritizedReplayBuffer(100_000, OBS_SHAPE, seed=seed)
    obs = rng.integers(0, 256, OBS_SHAPE, dtype=np.uint8)
    for t in range(transitions):
        next_obs = rng.integers(0, 256, OBS_SHAPE, dtype=np.uint8)
        done = t % 20 == 19
        buffer.add(obs, int(rng.integers(N_ACTIONS)), float(rng.normal()), next_obs, False, done)
        obs = rng.integers(0, 256, OBS_SHAPE, dtype=np.uint8) if done else next_obs
    return buffer


class FakeCameraEnv(gym.Env):
    """Stand-in with the real observation and action spaces (random images)."""

    def __init__(self) -> None:
        self.observation_space = gym.spaces.Box(0, 255, OBS_SHAPE, dtype=np.uint8)
        self.action_space = gym.spaces.Discrete(N_ACTIONS)
        self._t = 0

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> Any:
        super().reset(seed=seed)
        self._t = 0
        return self.np_random.integers(0, 256, OBS_SHAPE, dtype=np.uint8), {}

    def step(self, action: int) -> Any:
        self._t += 1
        obs = self.np_random.integers(0, 256, OBS_SHAPE, dtype=np.uint8)
        return obs, float(self.np_random.normal()), False, self._t >= 20, {}


def env_factory() -> tuple[Callable[[], gym.Env], str]:
    try:
        import activevision.envs  # noqa: F401

        gym.make("ActiveVision-v0").close()
        return (lambda: gym.make("ActiveVision-v0")), "ActiveVision-v0"
    except Exception as error:  # not written yet, or broken: measure the learner alone
        print(f"ActiveVision-v0 unavailable ({type(error).__name__}: {error}); using a fake env")
        return FakeCameraEnv, "fake"


def env_only_steps_per_s(make: Callable[[], gym.Env], steps: int = 300, warmup: int = 30) -> float:
    """Random-action steps per second of the environment alone (after JIT warm-up)."""
    env = make()
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    for t in range(warmup + steps):
        if t == warmup:
            start = time.perf_counter()
        _, _, terminated, truncated, _ = env.step(int(rng.integers(N_ACTIONS)))
        if terminated or truncated:
            env.reset(seed=int(rng.integers(2**31 - 1)))
    env.close()
    return steps / (time.perf_counter() - start)


def training_steps_per_s(make: Callable[[], gym.Env], threads: int, epoch: int = 300) -> float:
    """Steps/s of the trainer in an epoch where every step also runs an update."""
    config = TrainConfig().replace(
        total_timesteps=2 * epoch,
        epoch_steps=epoch,
        learning_starts=epoch,
        buffer_size=10_000,
        checkpoint_interval=0,
        num_threads=threads,
        tensorboard=False,
        progress_bar=False,
        env_id="bench",
    )
    with tempfile.TemporaryDirectory() as run_dir:
        trainer = Trainer(config, run_dir, make)
        try:
            epochs = trainer.train()
        finally:
            trainer.close()
    return epochs[-1]["steps_per_s"]


def report_lines(result: dict[str, Any]) -> list[str]:
    """The plain-text lines printed before the JSON one: each measurement, the reference
    measured in the same run, and their ratio (the JSON's ``speedup``,
    ``speedup_tuned_allocator`` and ``env_vs_fake_env_training``)."""
    return [
        f"activevision update : {result['update_ms']:8.2f} ms (batch {BATCH},"
        f" {result['threads']} threads; sampling and priority updates included)",
        f"plain PyTorch update: {result['reference_update_ms']:8.2f} ms;"
        f" {result['reference_update_ms_tuned_allocator']:.2f} ms with the tuned allocator"
        " (alternating rounds)",
        f"speed-up over the plain update in the same run: {result['speedup']:.2f}x"
        f" ({result['speedup_tuned_allocator']:.2f}x over the tuned one)",
        f"training, an update every step ({result['env']}):"
        f" {result['env_steps_per_s']:,.1f} steps/s, {result['env_vs_fake_env_training']:.2f}x"
        f" the same trainer on a free fake env ({result['fake_env_training_steps_per_s']:,.1f}"
        f" steps/s); the env alone {result['env_only_steps_per_s']:,.1f} steps/s",
        f"the paper's 30,000-step run at this pace: {result['paper_run_minutes_estimate']} min",
    ]


def main() -> None:
    parser = ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--updates", type=positive_int, default=40, help="timed updates per round")
    parser.add_argument("--rounds", type=positive_int, default=3, help="alternating rounds")
    parser.add_argument(
        "--threads", type=int_in(0, 1024), default=0, help="torch threads (0: all cores)"
    )
    args = parser.parse_args()
    threads = resolve_num_threads(args.threads)
    torch.set_num_threads(threads)
    torch.manual_seed(0)
    buffer = filled_buffer()

    # the reference first, before any process-wide tuning
    reference = plain_update_fn(buffer)
    reference_default = median_ms(reference, args.updates)
    configure_torch_cpu(threads)
    ours = our_update_fn(buffer)
    our_runs, reference_runs = [], []
    for _ in range(args.rounds):  # alternate, so that load changes hit both alike
        our_runs.append(median_ms(ours, args.updates))
        reference_runs.append(median_ms(reference, args.updates))

    make, env_name = env_factory()
    learner_steps_per_s = training_steps_per_s(FakeCameraEnv, threads)
    env_steps_per_s = (
        learner_steps_per_s if env_name == "fake" else training_steps_per_s(make, threads)
    )
    result = {
        "update_ms": round(min(our_runs), 2),
        "reference_update_ms": round(reference_default, 2),
        "reference_update_ms_tuned_allocator": round(min(reference_runs), 2),
        "speedup": round(reference_default / min(our_runs), 2),
        "env": env_name,
        "env_only_steps_per_s": round(env_only_steps_per_s(make), 1),
        "env_steps_per_s": round(env_steps_per_s, 1),
        "fake_env_training_steps_per_s": round(learner_steps_per_s, 1),
        "threads": threads,
        "cpu_count": os.cpu_count(),
        "torch": torch.__version__,
        "machine": platform.machine(),
        "load_avg_1min": round(os.getloadavg()[0], 2),
    }
    result["paper_run_minutes_estimate"] = round(30_000 / result["env_steps_per_s"] / 60, 1)
    result["speedup_tuned_allocator"] = round(
        result["reference_update_ms_tuned_allocator"] / result["update_ms"], 2
    )
    result["env_vs_fake_env_training"] = round(env_steps_per_s / learner_steps_per_s, 3)
    print("\n".join(report_lines(result)))
    print(json.dumps(result))


if __name__ == "__main__":
    main()
