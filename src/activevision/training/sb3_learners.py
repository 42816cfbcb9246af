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

import json
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
from stable_baselines3.common.noise import NormalActionNoise
from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm
from stable_baselines3.common.vec_env import DummyVecEnv

from activevision.agents.sb3_features import StudentFeatures, actor_network
from activevision.agents.student import StudentNetwork
from activevision.envs.observations import vector_keys
from activevision.envs.seeding import episode_seed
from activevision.training import checkpoint as ckpt
from activevision.training import state as run_state
from activevision.training.config import SB3_ALGORITHMS, TrainConfig, load_config, save_config
from activevision.training.cpu import configure_torch_cpu, resolve_device
from activevision.training.dagger import play_greedy
from activevision.training.environment import make_env
from activevision.training.loggers import Logger, LoggerGroup, LogPosition, default_loggers
from activevision.training.metrics import EpochAccumulator, episode_record
from activevision.training.policy_files import BestWeights, write_policy
from activevision.training.validation import summarise_validation

_ALGORITHMS: dict[str, type[BaseAlgorithm]] = {"sac": SAC, "td3": TD3, "ppo": PPO}
#: the SB3 logger key each learner's loss is read from (``metrics.csv``'s ``loss``)
_LOSS_KEY = {"sac": "train/critic_loss", "td3": "train/critic_loss", "ppo": "train/loss"}


def build_model(config: TrainConfig, env: DummyVecEnv, device: torch.device) -> BaseAlgorithm:
    """The SB3 model of ``config.algo`` on ``env``, seeded from ``config.seed``."""
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


class Sb3Trainer:
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
        self.run_dir = Path(run_dir)
        if not _resuming and ckpt.list_checkpoints(self.run_dir):
            raise ValueError(f"{self.run_dir} already holds a run; resume it")
        self.device = resolve_device(config.run.device)
        configure_torch_cpu(config.run.num_threads)
        self.env = make_vec_env(config)
        self.env.seed(config.seed)
        self.model = build_model(config, self.env, self.device)
        self.n_actions = int(getattr(make_env(config).action_space, "n", 2))
        self.run_dir.mkdir(parents=True, exist_ok=True)
        ckpt.remove_stale_writes(self.run_dir)
        self.episode = 0
        self.epoch_log = EpochAccumulator()
        self.best = BestWeights()
        self._epochs_logged = 0
        self._validations_logged = 0
        self._updates_seen = 0
        save_config(config, self.run_dir / run_state.CONFIG_FILE)
        self.logger = LoggerGroup(default_loggers(config, run_dir) if loggers is None else loggers)
        if not _resuming:
            self.logger.start(None)

    @property
    def step(self) -> int:
        """Environment steps so far (SB3's ``num_timesteps``)."""
        return int(self.model.num_timesteps)

    # ------------------------------------------------------------------ the loop
    def train(self, steps: int | None = None) -> list[dict[str, float]]:
        """Learn until ``steps`` more environment steps are done (default: to
        ``total_timesteps``); returns this call's ``metrics.csv`` rows. PPO ends on a whole
        rollout (``n_steps * num_envs``), so it may pass the target by less than one."""
        total = self.config.run.total_timesteps
        target = total if steps is None else min(self.step + steps, total)
        callback = _RunCallback(self)
        if self.step < target:
            self.model.learn(
                total_timesteps=target - self.step,
                callback=callback,
                reset_num_timesteps=False,
                progress_bar=False,
            )
        self.save_checkpoint()  # after the last update (a mid-run one may hold this step)
        self.logger.flush()
        return callback.rows

    def record_episode(self, reward: float, length: int, info: dict[str, Any]) -> None:
        """An episode ended with this total reward, length and final info."""
        record = episode_record(self.episode, self.step, reward, length, info)
        self.logger.record_episode(record, self.step)
        self.epoch_log.episodes.append(record)
        self.episode += 1

    def finish_epoch(self, steps_per_s: float) -> dict[str, float]:
        epoch = self.step // self.config.run.epoch_steps
        row = self.epoch_log.summary(epoch, self.step, 0.0, 0.0, steps_per_s)
        self.logger.record_epoch(row, self.step)
        self._epochs_logged += 1
        self.epoch_log = EpochAccumulator()
        return row

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
        run = self.config.run
        seeds = [episode_seed(run.eval_seed, i) for i in range(run.eval_episodes)]
        actor = self.actor()
        records = play_greedy(actor, torch.device("cpu"), self.config.env, seeds)
        row = summarise_validation(self.step, records, self.best.score)
        self.logger.record_validation(row, self.step)
        self._validations_logged += 1
        if row["best"]:
            self.best.keep(actor, self.step, row["success_rate"])
            self.best.write(self.run_dir, self.metadata(actor))
        return row

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

    def state_json(self) -> str:
        model = self.model
        return json.dumps(
            {
                "algo": self.config.algo,
                "step": self.step,
                "n_updates": int(getattr(model, "_n_updates", 0)),
                "sb3_episodes": int(getattr(model, "_episode_num", 0)),
                "episode": self.episode,
                "epoch_log": self.epoch_log.to_dict(),
                "metrics_rows": self._epochs_logged,
                "evaluations_rows": self._validations_logged,
                "best_eval": self.best.score if self.best.weights is not None else None,
                "best_step": self.best.step,
                "config_sha256": run_state.config_digest(self.run_dir),
            }
        )

    def save_checkpoint(self) -> Path:
        """Write a checkpoint (atomically) and ``policy.safetensors``."""
        actor = self.actor()
        metadata = self.metadata(actor)
        tensors = {f"online.{k}": v for k, v in actor.state_dict().items()}
        if self.best.weights is not None:
            tensors.update({f"best.{k}": v for k, v in self.best.weights.items()})

        def write_files(directory: Path) -> None:
            ckpt.save_tensors(directory / "model.safetensors", tensors, metadata)
            ckpt.save_torch_state(directory / "optimizer.pt", model_state(self.model))
            ckpt.save_arrays(directory / "replay.npz", buffer_arrays(self.model))
            (directory / run_state.STATE_FILE).write_text(self.state_json())

        path = ckpt.write_checkpoint(
            self.run_dir, self.step, write_files, self.config.run.keep_checkpoints
        )
        write_policy(self.run_dir, actor.state_dict(), metadata)
        return path

    @classmethod
    def resume(
        cls, run_dir: str | os.PathLike[str], *, loggers: Sequence[Logger] | None = None
    ) -> Sb3Trainer:
        """Rebuild the trainer from the run's newest checkpoint."""
        run_dir = Path(run_dir)
        path = ckpt.latest_checkpoint(run_dir)
        ckpt.verify_checkpoint(path)
        config = load_config(run_dir / run_state.CONFIG_FILE)
        try:
            state = json.loads((path / run_state.STATE_FILE).read_text())
            if state.get("config_sha256") != run_state.config_digest(run_dir):
                raise ckpt.CheckpointError(
                    f"{run_dir / run_state.CONFIG_FILE} was changed after checkpoint {path.name}"
                )
            trainer = cls(config, run_dir, loggers=loggers, _resuming=True)
            model = trainer.model
            load_model_state(model, ckpt.load_torch_state(path / "optimizer.pt"))
            load_buffer_arrays(model, ckpt.load_arrays(path / "replay.npz"))
            step = int(state["step"])
            model.num_timesteps = step
            model._n_updates = trainer._updates_seen = int(state["n_updates"])
            model._episode_num = int(state["sb3_episodes"])
            # fresh draws from here on: reseeded from the seed and the step
            model.set_random_seed(config.seed + step)
            trainer.env.seed(config.seed + step)
            trainer.episode = int(state["episode"])
            trainer.epoch_log = EpochAccumulator.from_dict(state["epoch_log"])
            trainer._epochs_logged = int(state["metrics_rows"])
            trainer._validations_logged = int(state["evaluations_rows"])
            if state["best_eval"] is not None:
                tensors, _ = ckpt.load_tensors(path / "model.safetensors")
                best = {
                    k.removeprefix("best."): v for k, v in tensors.items() if k.startswith("best.")
                }
                trainer.best.keep_weights(best, int(state["best_step"]), float(state["best_eval"]))
        except (KeyError, TypeError, ValueError, RuntimeError) as error:
            if isinstance(error, ckpt.CheckpointError):
                raise
            raise ckpt.CheckpointError(
                f"checkpoint {path} does not fit this run ({type(error).__name__}: {error})"
            ) from error
        trainer.logger.start(
            LogPosition(
                trainer.step, trainer._epochs_logged, trainer.episode, trainer._validations_logged
            )
        )
        return trainer

    def close(self) -> None:
        self.logger.close()
        self.env.close()


class _RunCallback(BaseCallback):
    """Feeds SB3's steps to the trainer: episodes, losses, epochs, validation, checkpoints.
    A checkpoint falls due on a step but is written when the rollout ends: SB3 stores a
    step's transitions only after the step's callback, and updates only after the rollout."""

    def __init__(self, trainer: Sb3Trainer) -> None:
        super().__init__()
        self.trainer = trainer
        self.rows: list[dict[str, float]] = []
        n = trainer.config.sb3.num_envs
        self.returns, self.lengths = np.zeros(n), np.zeros(n, dtype=np.int64)
        self.epoch_start = (trainer.step, time.perf_counter())
        self.checkpoint_due = False

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
        if step // run.epoch_steps > before // run.epoch_steps:
            start_step, start_time = self.epoch_start
            rate = (step - start_step) / max(time.perf_counter() - start_time, 1e-9)
            self.rows.append(trainer.finish_epoch(rate))
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


def train_sb3(
    config: TrainConfig,
    run_dir: str | os.PathLike[str],
    *,
    loggers: Sequence[Logger] | None = None,
) -> list[dict[str, float]]:
    """Train a fresh SB3 run to ``config.run.total_timesteps``."""
    trainer = Sb3Trainer(config, run_dir, loggers=loggers)
    try:
        return trainer.train()
    finally:
        trainer.close()


__all__ = ["Sb3Trainer", "build_model", "make_vec_env", "train_sb3"]
