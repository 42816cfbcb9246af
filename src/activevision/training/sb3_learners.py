"""Stable-Baselines3's learners for head control: SAC, TD3 and PPO (``algo`` "sac", "td3",
"ppo"; the paper's future work names policy-gradient and actor-critic methods).

SB3 is used for these and the package's own code for DDQN + PER because SB3 has neither
prioritised replay nor a double-Q target for DQN, the paper's learner; for SAC, TD3 and PPO
it is the maintained reference implementation a user would otherwise pick.

Every learner sees the observation through the DAgger student's trunk
(:class:`~activevision.agents.sb3_features.StudentFeatures`) and has a linear actor on it,
so its deterministic actor *is* a :class:`~activevision.agents.student.StudentNetwork`
(:func:`~activevision.agents.sb3_features.actor_network`). A run directory therefore has
the DDQN and DAgger layout: ``config.json``, ``metrics.csv`` (``loss``: SAC's and TD3's
critic loss, PPO's total loss; ``epsilon`` 0), ``episodes.csv``, ``evaluations.csv`` and
``best_policy.safetensors`` (greedy validation on the ``eval_seed`` episodes),
``policy.safetensors``, TensorBoard, plots, ``export`` and ``checkpoints/``.

A checkpoint holds the actor (``model.safetensors``), every SB3 state dict and variable
(``optimizer.pt``: ``model.get_parameters()`` and SAC's entropy coefficient, read back with
``torch.load(weights_only=True)``) and the replay buffer as plain arrays (``replay.npz``),
so resuming executes no pickled code. It continues from those weights, optimisers and
transitions; the episodes in flight start over, and the generators are reseeded from the
seed and the step (resuming is reproducible, not bit-identical to an uninterrupted run).
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch
from stable_baselines3 import PPO, SAC, TD3
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.buffers import DictReplayBuffer, ReplayBuffer
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.logger import Logger as Sb3Logger
from stable_baselines3.common.noise import NormalActionNoise
from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm
from stable_baselines3.common.vec_env import DummyVecEnv

from activevision.agents.sb3_features import StudentFeatures, actor_network
from activevision.agents.student import StudentNetwork
from activevision.envs.observations import vector_keys
from activevision.training import checkpoint as ckpt
from activevision.training.config import SB3_ALGORITHMS, TrainConfig
from activevision.training.cpu import configure_torch_cpu, training_device
from activevision.training.dagger import play_greedy
from activevision.training.environment import make_env
from activevision.training.loggers import Logger
from activevision.training.progress import advance, postfix, progress_bar
from activevision.training.student_runs import StudentRun

#: the SB3 logger key each learner's loss is read from (``metrics.csv``'s ``loss``)
_LOSS_KEY = {"sac": "train/critic_loss", "td3": "train/critic_loss", "ppo": "train/loss"}


def build_model(config: TrainConfig, env: DummyVecEnv, device: torch.device) -> BaseAlgorithm:
    """The SB3 model of ``config.algo`` on ``env``, seeded from ``config.seed``, logging to
    memory only: the run's own loggers write its logs, and SB3's default logger would make an
    empty ``SB3-<time>`` folder in the temporary directory at every ``learn``."""
    model = _algorithm(config, env, device)
    model.set_logger(Sb3Logger(folder=None, output_formats=[]))  # values kept, none written
    return model


def _algorithm(config: TrainConfig, env: DummyVecEnv, device: torch.device) -> BaseAlgorithm:
    learner, sb3, env_cfg = config.learner, config.sb3, config.env
    features = {
        "features_extractor_class": StudentFeatures,
        "features_extractor_kwargs": {
            "vector_keys": vector_keys(env_cfg),
            "downsample": sb3.downsample,
        },
    }
    policy = "MultiInputPolicy" if env_cfg.observation != "image" else "CnnPolicy"
    common: dict[str, Any] = {
        "learning_rate": learner.learning_rate,
        "gamma": learner.gamma,
        "batch_size": learner.batch_size,
        "seed": config.seed,
        "device": device,
        "verbose": 0,
    }
    if config.algo == "ppo":
        return PPO(
            policy,
            env,
            n_steps=sb3.n_steps,
            n_epochs=sb3.n_epochs,
            gae_lambda=sb3.gae_lambda,
            clip_range=sb3.clip_range,
            ent_coef=sb3.ent_coef,
            max_grad_norm=learner.max_grad_norm,
            policy_kwargs={**features, "net_arch": {"pi": [], "vf": [sb3.critic_hidden]}},
            **common,
        )
    off_policy: dict[str, Any] = {
        "buffer_size": config.replay.buffer_size,
        "learning_starts": learner.learning_starts,
        "train_freq": learner.train_freq,
        "gradient_steps": learner.gradient_steps,
        "tau": sb3.tau,
        "policy_kwargs": {
            **features,
            "net_arch": {"pi": [], "qf": [sb3.critic_hidden]},
            "share_features_extractor": False,
        },
    }
    if config.algo == "td3":
        noise = NormalActionNoise(np.zeros(2), np.full(2, sb3.action_noise))
        return TD3(policy, env, action_noise=noise, **off_policy, **common)
    return SAC(policy, env, **off_policy, **common)


def make_vec_env(config: TrainConfig) -> DummyVecEnv:
    """``sb3.num_envs`` copies of the run's ``ActiveVision-v0`` (with its 20-step limit)."""
    return DummyVecEnv([lambda: make_env(config)] * config.sb3.num_envs)


class Sb3Trainer(StudentRun):
    """Trains ``config.algo`` ("sac", "td3" or "ppo") with Stable-Baselines3 into a run
    directory laid out like the package's own learners'."""

    def __init__(
        self,
        config: TrainConfig,
        run_dir: str | os.PathLike[str],
        *,
        loggers: Sequence[Logger] | None = None,
        _resuming: bool = False,
    ) -> None:
        if config.algo not in SB3_ALGORITHMS:
            raise ValueError(f"Sb3Trainer trains {SB3_ALGORITHMS}, got algo={config.algo!r}")
        self.config = config
        self.device = training_device(config.run.device)
        configure_torch_cpu(config.run.num_threads)
        self.env = make_vec_env(config)
        self.env.seed(config.seed)
        self.model = build_model(config, self.env, self.device)
        self.n_actions = int(getattr(self.env.action_space, "n", 2))
        self._updates_seen = 0
        self._open_run(run_dir, loggers, _resuming)

    @property
    def step(self) -> int:  # type: ignore[override]  # SB3 counts the steps
        """Environment steps so far (SB3's ``num_timesteps``)."""
        return int(self.model.num_timesteps)

    # ------------------------------------------------------------------ the loop
    def train(self, steps: int | None = None) -> list[dict[str, float]]:
        """Learn until ``steps`` more environment steps are done (default: to
        ``total_timesteps``); returns this call's ``metrics.csv`` rows. PPO ends on a whole
        rollout (``n_steps * num_envs``), so it may pass the target by less than one."""
        total = self.config.run.total_timesteps
        target = total if steps is None else min(self.step + steps, total)
        progress = progress_bar(self.config, self.step, target)
        callback = _RunCallback(self, progress)
        try:
            if self.step < target:
                self.model.learn(
                    total_timesteps=target - self.step,
                    callback=callback,
                    reset_num_timesteps=False,
                    progress_bar=False,  # SB3's own bar needs rich; the run's is tqdm's
                )
                if self.step >= total and callback.epoch_start[0] < self.step:
                    # the run ends between two epoch_steps boundaries: its last steps get
                    # their row (a run shorter than epoch_steps left metrics.csv empty)
                    self.record_updates()
                    callback.rows.append(self.finish_epoch(0.0, callback.rate(), final=True))
            self.save_checkpoint()  # after the last update (a mid-run one may hold this step)
        finally:
            progress.close()
            self.logger.flush()
        return callback.rows

    def record_updates(self) -> None:
        """Take the loss of the updates SB3 made since the last call (``metrics.csv``)."""
        updates = int(getattr(self.model, "_n_updates", 0))
        loss = self.model.logger.name_to_value.get(_LOSS_KEY[self.config.algo])
        if updates > self._updates_seen and loss is not None:
            self.epoch_log.losses.append(float(loss))
        self._updates_seen = updates

    def actor(self) -> StudentNetwork:
        """The deterministic actor now, as a StudentNetwork (CPU)."""
        return actor_network(self.model, self.n_actions)

    def validate(self) -> dict[str, float]:
        """The actor's greedy episodes on the validation seeds (those of ``activevision
        evaluate --seed eval_seed``), batched; keeps the best weights."""
        actor, cpu, env = self.actor(), torch.device("cpu"), self.config.env

        def play(network: StudentNetwork, seeds: Sequence[int]) -> list[dict[str, float]]:
            return play_greedy(network, cpu, env, seeds)

        return self.validate_network(actor, play, self.metadata(actor))

    # ------------------------------------------------------------------ files
    def metadata(self, actor: StudentNetwork) -> dict[str, Any]:
        """The policy files' metadata (as a DAgger run's: ``load_policy`` and ``export``
        read both)."""
        cfg = self.config.env
        return {
            **actor.metadata(),
            "observation": cfg.observation,
            "action_history": cfg.action_history,
            "vector_keys": list(vector_keys(cfg)),
            "act_by": "action",
            "max_move_deg": list(cfg.max_move_deg),
            "algo": self.config.algo,
            "step": self.step,
        }

    def save_checkpoint(self) -> Path:
        """Write a checkpoint (atomically) and ``policy.safetensors``."""
        actor, model = self.actor(), self.model
        return self.write_checkpoint(
            actor,
            self.metadata(actor),
            model_state(model),
            buffer_arrays(model),
            self.run_state(
                self.config.algo,
                n_updates=int(getattr(model, "_n_updates", 0)),
                sb3_episodes=int(getattr(model, "_episode_num", 0)),
            ),
        )

    def _restore(self, path: Path, state: dict[str, Any], weights: dict[str, torch.Tensor]) -> None:
        # the actor's weights are in the SB3 state dicts of optimizer.pt as well
        model, config = self.model, self.config
        load_model_state(model, ckpt.load_torch_state(path / "optimizer.pt"))
        load_buffer_arrays(model, ckpt.load_arrays(path / "replay.npz"))
        step = int(state["step"])
        model.num_timesteps = step
        model._n_updates = self._updates_seen = int(state["n_updates"])
        model._episode_num = int(state["sb3_episodes"])
        # fresh draws from here on: reseeded from the seed and the step
        model.set_random_seed(config.seed + step)
        self.env.seed(config.seed + step)

    def close(self) -> None:
        super().close()
        self.env.close()


class _RunCallback(BaseCallback):
    """Feeds SB3's steps to the trainer: episodes, losses, epochs, validation, checkpoints.
    A checkpoint falls due on a step but is written when the rollout ends: SB3 stores a
    step's transitions only after the step's callback, and updates only after the rollout."""

    def __init__(self, trainer: Sb3Trainer, progress: Any) -> None:
        super().__init__()
        self.trainer = trainer
        self.progress = progress  # the run's tqdm bar (disabled off a terminal)
        self.rows: list[dict[str, float]] = []
        n = trainer.config.sb3.num_envs
        self.returns, self.lengths = np.zeros(n), np.zeros(n, dtype=np.int64)
        self.epoch_start = (trainer.step, time.perf_counter())
        self.checkpoint_due = False

    def rate(self) -> float:
        """Environment steps per second since the current epoch began."""
        start_step, start_time = self.epoch_start
        return (self.trainer.step - start_step) / max(time.perf_counter() - start_time, 1e-9)

    def _on_rollout_start(self) -> None:
        self.trainer.record_updates()

    def _on_rollout_end(self) -> None:
        if self.checkpoint_due:
            self.trainer.save_checkpoint()
            self.checkpoint_due = False

    def _on_step(self) -> bool:
        trainer, run = self.trainer, self.trainer.config.run
        rewards, dones = np.asarray(self.locals["rewards"]), np.asarray(self.locals["dones"])
        infos = self.locals["infos"]
        self.returns += rewards
        self.lengths += 1
        for i in np.flatnonzero(dones):
            trainer.record_episode(float(self.returns[i]), int(self.lengths[i]), infos[i])
        self.returns[dones], self.lengths[dones] = 0.0, 0
        step, before = trainer.step, trainer.step - len(rewards)
        advance(self.progress, step)
        if step // run.epoch_steps > before // run.epoch_steps:
            self.rows.append(trainer.finish_epoch(0.0, self.rate()))
            self.progress.set_postfix(postfix(self.rows[-1], trainer.config.algo), refresh=False)
            self.epoch_start = (step, time.perf_counter())
        if run.eval_interval and step // run.eval_interval > before // run.eval_interval:
            trainer.validate()
        interval = run.checkpoint_interval
        if interval and step // interval > before // interval:
            self.checkpoint_due = True
        return True


# ---------------------------------------------------------------------- SB3 state as data
def model_state(model: BaseAlgorithm) -> dict[str, Any]:
    """Every state dict of the model (policy, optimisers) and its torch variables (SAC's
    entropy coefficient): tensors and numbers only, for ``torch.load(weights_only=True)``."""
    _, variables = model._get_torch_save_params()
    values = {name: _attribute(model, name).detach().cpu() for name in variables}
    return {"parameters": model.get_parameters(), "variables": values}


def load_model_state(model: BaseAlgorithm, state: dict[str, Any]) -> None:
    """Put :func:`model_state`'s output back into a model built from the same config."""
    model.set_parameters(state["parameters"], exact_match=True, device=model.device)
    for name, value in state["variables"].items():
        with torch.no_grad():
            _attribute(model, name).copy_(value)


def buffer_arrays(model: BaseAlgorithm) -> dict[str, np.ndarray]:
    """The replay buffer's filled part as plain arrays (nothing for PPO)."""
    buffer = getattr(model, "replay_buffer", None)
    if not isinstance(buffer, ReplayBuffer | DictReplayBuffer):
        return {"position": np.array([0, 0])}
    size = buffer.buffer_size if buffer.full else buffer.pos
    arrays = {"position": np.array([buffer.pos, int(buffer.full)])}
    for name in _BUFFER_FIELDS:
        value = getattr(buffer, name)
        if isinstance(value, dict):
            arrays.update({f"{name}.{k}": v[:size] for k, v in value.items()})
        else:
            arrays[name] = value[:size]
    return arrays


def load_buffer_arrays(model: BaseAlgorithm, arrays: dict[str, np.ndarray]) -> None:
    """Refill the replay buffer from :func:`buffer_arrays`' output."""
    buffer = getattr(model, "replay_buffer", None)
    if not isinstance(model, OffPolicyAlgorithm) or buffer is None:
        return
    pos, full = (int(v) for v in arrays["position"])
    for name in _BUFFER_FIELDS:
        target = getattr(buffer, name)
        parts = (
            {k: (target[k], arrays[f"{name}.{k}"]) for k in target}
            if isinstance(target, dict)
            else {name: (target, arrays[name])}
        )
        for into, values in parts.values():
            if len(values) > len(into):
                raise ckpt.CheckpointError("the checkpoint's replay buffer exceeds this run's")
            into[: len(values)] = values
    buffer.pos, buffer.full = pos, bool(full)


_BUFFER_FIELDS = ("observations", "next_observations", "actions", "rewards", "dones", "timeouts")


def _attribute(model: BaseAlgorithm, name: str) -> torch.Tensor:
    value: Any = model
    for part in name.split("."):
        value = getattr(value, part)
    if not isinstance(value, torch.Tensor):
        raise TypeError(f"{name} is not a tensor")
    return value


__all__ = ["Sb3Trainer", "build_model", "make_vec_env"]
