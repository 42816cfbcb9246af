"""The training loop: Double DQN with prioritised replay on a Gymnasium environment.

The loop follows Stable-Baselines (v2) ``DQN.learn``, which the paper used: one environment
step, then (after ``learning_starts`` steps) ``gradient_steps`` gradient updates (one in the
paper) every ``train_freq`` steps, a target-network sync every ``target_update_interval``
steps, epsilon and beta annealed linearly.

Run directory::

    config.json       the TrainConfig of the run
    metrics.csv       one row per epoch (300 steps): success rate, durations, reward, loss, ...
    episodes.csv      one row per episode: total reward, length, final info
    tensorboard/      the same epoch metrics as TensorBoard scalars
    policy.safetensors  the newest online weights (see ``load_policy``)
    evaluations.csv, best_policy.safetensors
                      with ``eval_interval``: greedy validation scores, the best weights
    checkpoints/      the newest checkpoints (see ``training.checkpoint``)

Reproducibility and resuming. Every random number comes from generators seeded by
``config.seed``: the trainer's own numpy generator (exploration, environment seeds and image
shifts), the replay sampler's generator, and a forked torch generator used once to initialise
the network.
The environment is re-seeded at *every* episode start with a seed drawn from the trainer's
generator, so its state is a function of (episode seed, actions taken so far). A checkpoint
therefore stores that seed and the episode's actions instead of the environment's internals;
resuming replays them (at most one episode) and checks the observation it reaches. An
interrupted run resumed from a checkpoint ends with exactly the weights and metrics of an
uninterrupted one (except the wall-clock ``steps_per_s`` column), provided the environment is
deterministic given its seed and actions, as Gymnasium environments should be.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch

from activevision.agents.augment import random_shifts
from activevision.agents.ddqn import DDQNLearner
from activevision.agents.dqn_math import epsilon_greedy, linear_schedule
from activevision.agents.q_network import QNetwork
from activevision.agents.replay.prioritized import PrioritizedReplayBuffer
from activevision.envs.seeding import episode_seed
from activevision.io import atomic_path
from activevision.training import checkpoint as ckpt
from activevision.training.config import TrainConfig, load_config, save_config
from activevision.training.cpu import configure_torch_cpu, resolve_device
from activevision.training.metrics import (
    EPISODE_FIELDS,
    EPOCH_FIELDS,
    TENSORBOARD_TAGS,
    CsvLog,
    EpochAccumulator,
    episode_record,
)
from activevision.training.validation import (
    EVALUATION_FIELDS,
    greedy_episodes,
    summarise_validation,
)

EnvFactory = Callable[[], gym.Env]
POLICY_FILE = "policy.safetensors"
BEST_POLICY_FILE = "best_policy.safetensors"  #: best greedy validation score (eval_interval)


def make_env(config: TrainConfig) -> gym.Env:
    """``gymnasium.make(config.env_id)``; activevision's own env gets ``config.env``."""
    from activevision.registration import ENV_ID

    kwargs = {"config": config.env} if config.env_id.removeprefix("activevision:") == ENV_ID else {}
    try:
        return gym.make(config.env_id, **kwargs)
    except gym.error.Error as error:  # e.g. NameNotFound: one clear line, not a traceback
        raise ValueError(f"env_id {config.env_id!r}: {error}") from None


class Trainer:
    """Trains a :class:`QNetwork` on one environment; see the module docstring.

    Args:
        config: the run's configuration.
        run_dir: directory for config, logs and checkpoints. Must not hold a checkpoint
            already (continue such a run with :meth:`Trainer.resume`).
        env_factory: builds the environment; default :func:`make_env`. Its observations
            must be uint8 (stack, H, W) or (H, W), its actions Discrete.
    """

    def __init__(
        self,
        config: TrainConfig,
        run_dir: str | os.PathLike[str],
        env_factory: EnvFactory | None = None,
        *,
        _resuming: bool = False,
    ) -> None:
        self.config = config
        self.run_dir = Path(run_dir)
        if not _resuming and ckpt.list_checkpoints(self.run_dir):
            raise ValueError(f"{self.run_dir} already holds a run; use Trainer.resume()")
        self.device = resolve_device(config.run.device)  # bad device or env: before any write
        self.env_factory = env_factory or (lambda: make_env(config))
        self.env = self.env_factory()
        self.run_dir.mkdir(parents=True, exist_ok=True)
        ckpt.remove_stale_writes(self.run_dir)  # left by a checkpoint write that was killed
        configure_torch_cpu(config.run.num_threads)
        self._eval_env: gym.Env | None = None  # built at the first validation
        if not isinstance(self.env.action_space, gym.spaces.Discrete):
            raise ValueError(f"need a Discrete action space, got {self.env.action_space}")
        self.n_actions = int(self.env.action_space.n)
        self.obs_shape = _chw_shape(self.env.observation_space)

        trainer_seed, replay_seed, init_seed = np.random.SeedSequence(config.seed).generate_state(3)
        self.rng = np.random.default_rng(int(trainer_seed))
        aux_dim = GOAL_OFFSET_DIM if config.learner.aux_goal_weight else 0
        with torch.random.fork_rng(devices=[]):  # seed network init without touching global RNG
            torch.manual_seed(int(init_seed))
            network = QNetwork(
                self.n_actions,
                self.obs_shape[0],
                self.obs_shape[1:],
                dueling=config.learner.dueling,
                aux_outputs=aux_dim,
            )
        channels_last = self.device.type == "cpu"
        if channels_last:
            network.to_channels_last()
        self.learner = DDQNLearner(
            network,
            learning_rate=config.learner.learning_rate,
            max_grad_norm=config.learner.max_grad_norm,
            device=self.device,
            channels_last=channels_last,
            aux_weight=config.learner.aux_goal_weight,
        )
        self.buffer = PrioritizedReplayBuffer(
            config.replay.buffer_size,
            self.obs_shape,
            config.replay.alpha,
            config.replay.eps,
            int(replay_seed),
            n_step=config.learner.n_step,
            gamma=config.learner.gamma,
            aux_dim=aux_dim,
        )

        # progress; everything below is saved in checkpoints
        self.step = 0
        self.episode = 0
        self.epoch_log = EpochAccumulator()
        self._obs: np.ndarray | None = None  # current observation, None between episodes
        self._obs_aux: np.ndarray | None = None  # auxiliary target of _obs (aux_goal_weight)
        self._episode_seed = 0
        self._episode_actions: list[int] = []
        self._episode_reward = 0.0
        self.best_eval = -math.inf  # best validation success rate so far ...
        self._best_step = 0  # ... reached at this step by these weights
        self._best_weights: dict[str, torch.Tensor] | None = None

        save_config(config, self.run_dir / "config.json")
        self.metrics_log = CsvLog(self.run_dir / "metrics.csv", EPOCH_FIELDS)
        self.episodes_log = CsvLog(self.run_dir / "episodes.csv", EPISODE_FIELDS)
        self.evaluations_log = CsvLog(self.run_dir / "evaluations.csv", EVALUATION_FIELDS)
        if not _resuming:  # a fresh run starts fresh logs
            self.metrics_log.truncate(0)
            self.episodes_log.truncate(0)
            self.evaluations_log.truncate(0)
        self._writer: Any = None
        self._writer_purge_step: int | None = None

    # ------------------------------------------------------------------ schedules
    @property
    def epsilon(self) -> float:
        """Exploration rate at the current step (SB2 LinearSchedule)."""
        c = self.config
        duration = c.exploration.fraction * c.run.total_timesteps
        return linear_schedule(c.exploration.initial, c.exploration.final, duration, self.step)

    @property
    def beta(self) -> float:
        """Importance-sampling exponent at the current step, beta0 -> 1 over the run."""
        c = self.config
        return linear_schedule(c.replay.beta0, 1.0, c.run.total_timesteps, self.step)

    # ------------------------------------------------------------------ the loop
    def train(self, steps: int | None = None) -> list[dict[str, float]]:
        """Run ``steps`` more environment steps (default: to ``total_timesteps``).

        Returns the rows of ``metrics.csv`` written by this call. Saves a checkpoint every
        ``checkpoint_interval`` steps and when it returns.
        """
        c = self.config
        end = (
            c.run.total_timesteps
            if steps is None
            else min(self.step + steps, c.run.total_timesteps)
        )
        epochs: list[dict[str, float]] = []
        progress = _progress_bar(c, self.step, end)
        epoch_start = (self.step, time.perf_counter())
        start_step = self.step
        try:
            while self.step < end:
                self._env_step()
                progress.update(1)
                if self.step % c.run.epoch_steps == 0:
                    steps_per_s = (self.step - epoch_start[0]) / (
                        time.perf_counter() - epoch_start[1]
                    )
                    epochs.append(self._finish_epoch(steps_per_s))
                    progress.set_postfix(_postfix(epochs[-1]), refresh=False)
                    epoch_start = (self.step, time.perf_counter())
                if c.run.eval_interval and self.step % c.run.eval_interval == 0:
                    self.validate()
                    epoch_start = (self.step, time.perf_counter())  # keep it out of steps/s
                if c.run.checkpoint_interval and self.step % c.run.checkpoint_interval == 0:
                    self.save_checkpoint()
            saved_last_step = (
                c.run.checkpoint_interval and self.step % c.run.checkpoint_interval == 0
            )
            if self.step > start_step and not saved_last_step:
                self.save_checkpoint()
        finally:
            progress.close()
            if self._writer is not None:
                self._writer.flush()
        return epochs

    def _env_step(self) -> None:
        c = self.config
        if self._obs is None:
            self._start_episode()
        obs = self._obs
        assert obs is not None
        action = epsilon_greedy(
            lambda: int(np.argmax(self.learner.q_values(obs))),
            self.n_actions,
            self.epsilon,
            self.rng,
        )
        next_obs, reward, terminated, truncated, info = self.env.step(action)
        next_obs = np.asarray(next_obs, dtype=np.uint8).reshape(self.obs_shape)
        self.buffer.add(
            obs,
            action,
            float(reward),
            next_obs,
            bool(terminated),
            bool(truncated),
            aux=self._obs_aux,
        )
        self._obs_aux = self._aux_target(info)
        self._episode_actions.append(action)
        self._episode_reward += float(reward)
        self.step += 1

        if self.step > c.learner.learning_starts and len(self.buffer) >= c.learner.batch_size:
            if self.step % c.learner.train_freq == 0:
                for _ in range(c.learner.gradient_steps):
                    batch = self.buffer.sample(c.learner.batch_size, self.beta)
                    if c.learner.augment_shift:
                        batch = batch._replace(
                            obs=random_shifts(batch.obs, c.learner.augment_shift, self.rng),
                            next_obs=random_shifts(
                                batch.next_obs, c.learner.augment_shift, self.rng
                            ),
                        )
                    result = self.learner.update(batch)
                    self.buffer.update_priorities(batch.indices, result.td_errors)
                    self.epoch_log.losses.append(result.loss)
            if self.step % c.learner.target_update_interval == 0:
                self.learner.sync_target()

        if terminated or truncated:
            self.episode += 1
            record = episode_record(
                self.episode, self.step, self._episode_reward, len(self._episode_actions), info
            )
            self.episodes_log.append(record)
            self.epoch_log.episodes.append(record)
            writer = self._tensorboard()
            if writer is not None:
                writer.add_scalar("charts/episodic_return", record["reward"], self.step)
                writer.add_scalar("charts/episodic_length", record["length"], self.step)
            self._obs = None
        else:
            self._obs = next_obs

    def validate(self) -> dict[str, float]:
        """Greedy episodes on the validation seeds; keeps the weights if they scored best.

        Uses an environment of its own, so training's environment, generators and replay are
        untouched (a run with validation trains exactly like one without).
        """
        c = self.config
        if self._eval_env is None:
            self._eval_env = self.env_factory()
        seeds = [episode_seed(c.run.eval_seed, i) for i in range(c.run.eval_episodes)]
        records = greedy_episodes(self.learner.q_values, self._eval_env, seeds, self.obs_shape)
        row = summarise_validation(self.step, records, self.best_eval)
        self.evaluations_log.append(row)
        if row["best"]:
            self.best_eval, self._best_step = row["success_rate"], self.step
            online = self.learner.online.state_dict()
            self._best_weights = {k: v.detach().clone() for k, v in online.items()}
            self._write_best_policy()
        writer = self._tensorboard()
        if writer is not None:
            writer.add_scalar("eval/success_rate", row["success_rate"], self.step)
            writer.add_scalar("eval/mean_episodic_return", row["episode_reward"], self.step)
        return row

    def _write_best_policy(self) -> None:
        assert self._best_weights is not None
        metadata = {
            **self._network_metadata(),
            "step": self._best_step,
            "validation_success_rate": self.best_eval,
        }
        with atomic_path(self.run_dir / BEST_POLICY_FILE) as tmp:
            ckpt.save_tensors(tmp, self._best_weights, metadata)

    def _start_episode(self) -> None:
        """Reset with a seed from the trainer's generator (what makes resuming exact)."""
        self._episode_seed = int(self.rng.integers(2**31 - 1))
        obs, info = self.env.reset(seed=self._episode_seed)
        self._obs = np.asarray(obs, dtype=np.uint8).reshape(self.obs_shape)
        self._obs_aux = self._aux_target(info)
        self._episode_actions = []
        self._episode_reward = 0.0

    def _aux_target(self, info: dict[str, Any]) -> np.ndarray | None:
        return goal_offset(info) if self.config.learner.aux_goal_weight else None

    def _finish_epoch(self, steps_per_s: float) -> dict[str, float]:
        epoch = self.step // self.config.run.epoch_steps
        row = self.epoch_log.summary(epoch, self.step, self.epsilon, self.beta, steps_per_s)
        self.metrics_log.append(row)
        writer = self._tensorboard()
        if writer is not None:
            for key, tag in TENSORBOARD_TAGS.items():
                if math.isfinite(row[key]):
                    writer.add_scalar(tag, row[key], self.step)
        self.epoch_log = EpochAccumulator()
        return row

    def _tensorboard(self) -> Any:
        if self.config.run.tensorboard and self._writer is None:
            from torch.utils.tensorboard import SummaryWriter  # heavy import, only when used

            self._writer = SummaryWriter(
                str(self.run_dir / "tensorboard"), purge_step=self._writer_purge_step
            )
        return self._writer

    def close(self) -> None:
        """Close the environment and the TensorBoard writer, and turn flushing of denormals
        (set for training speed, process-wide) back off."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None
        self.env.close()
        if self._eval_env is not None:
            self._eval_env.close()
        torch.set_flush_denormal(False)

    # ------------------------------------------------------------------ checkpoints
    def _network_metadata(self) -> dict[str, Any]:
        return {
            "n_actions": self.n_actions,
            "stack": self.obs_shape[0],
            "image_shape": list(self.obs_shape[1:]),
            "dueling": self.config.learner.dueling,
            "aux_outputs": self.learner.online.aux_outputs,
            "step": self.step,
        }

    def save_checkpoint(self) -> Path:
        """Write a checkpoint of the current step (atomically) and the policy file."""
        online = self.learner.online.state_dict()
        tensors = {f"online.{k}": v for k, v in online.items()}
        tensors.update({f"target.{k}": v for k, v in self.learner.target.state_dict().items()})
        if self._best_weights is not None:
            tensors.update({f"best.{k}": v for k, v in self._best_weights.items()})
        metadata = self._network_metadata()
        state = {
            "step": self.step,
            "episode": self.episode,
            "rng": self.rng.bit_generator.state,
            "epoch_log": self.epoch_log.to_dict(),
            "episode_open": self._obs is not None,
            "episode_seed": self._episode_seed,
            "episode_actions": self._episode_actions,
            "episode_reward": self._episode_reward,
            "obs_sha256": _digest(self._obs),
            "metrics_rows": len(self.metrics_log.rows()),
            "episodes_rows": self.episode,
            "best_eval": self.best_eval if self._best_weights is not None else None,
            "best_step": self._best_step,
            "evaluations_rows": len(self.evaluations_log.rows()),
            "config_sha256": _config_digest(self.run_dir),
        }

        def write_files(directory: Path) -> None:
            ckpt.save_tensors(directory / "model.safetensors", tensors, metadata)
            ckpt.save_torch_state(directory / "optimizer.pt", self.learner.optimizer.state_dict())
            ckpt.save_arrays(directory / "replay.npz", self.buffer.state_dict())
            (directory / "state.json").write_text(json.dumps(state))

        path = ckpt.write_checkpoint(
            self.run_dir, self.step, write_files, self.config.run.keep_checkpoints
        )
        with atomic_path(self.run_dir / POLICY_FILE) as tmp:
            ckpt.save_tensors(tmp, online, metadata)
        return path

    @classmethod
    def resume(
        cls,
        run_dir: str | os.PathLike[str],
        env_factory: EnvFactory | None = None,
        checkpoint: str | os.PathLike[str] | None = None,
    ) -> Trainer:
        """Rebuild a trainer from its run directory's newest (or a given) checkpoint.

        Raises CheckpointError if the checkpoint is missing or corrupt; nothing is written to
        the run directory before the checkpoint has loaded.
        """
        run_dir = Path(run_dir)
        path = Path(checkpoint) if checkpoint is not None else ckpt.latest_checkpoint(run_dir)
        ckpt.verify_checkpoint(path)
        tensors, _ = ckpt.load_tensors(path / "model.safetensors")
        optimizer_state = ckpt.load_torch_state(path / "optimizer.pt")
        replay_state = ckpt.load_arrays(path / "replay.npz")
        try:
            state = json.loads((path / "state.json").read_text())
        except (OSError, json.JSONDecodeError) as error:
            raise ckpt.CheckpointError(f"cannot read {path / 'state.json'}: {error}") from error
        if not isinstance(state, dict):
            raise ckpt.CheckpointError(f"{path / 'state.json'} must hold a JSON object")
        _check_config_unchanged(run_dir, path, state)

        trainer = cls(load_config(run_dir / "config.json"), run_dir, env_factory, _resuming=True)
        try:
            trainer._load_state(tensors, optimizer_state, replay_state, state)
        except (KeyError, TypeError, ValueError, IndexError, RuntimeError) as error:
            trainer.close()
            if isinstance(error, ckpt.CheckpointError):
                raise
            raise ckpt.CheckpointError(
                f"checkpoint {path} does not fit this run ({type(error).__name__}: {error})"
            ) from error
        return trainer

    def _load_state(
        self,
        tensors: dict[str, torch.Tensor],
        optimizer_state: dict[str, Any],
        replay_state: dict[str, np.ndarray],
        state: dict[str, Any],
    ) -> None:
        def part(prefix: str) -> dict[str, torch.Tensor]:
            return {k.removeprefix(prefix): v for k, v in tensors.items() if k.startswith(prefix)}

        self.learner.online.load_state_dict(part("online."))
        self.learner.target.load_state_dict(part("target."))
        self.learner.optimizer.load_state_dict(optimizer_state)
        try:
            buffer = PrioritizedReplayBuffer.from_state_dict(replay_state)
        except KeyError as error:
            raise ckpt.CheckpointError(
                f"the checkpoint's replay buffer lacks {error} (written by an older activevision?)"
            ) from error
        _check_buffer_fits(buffer, self.buffer)
        self.buffer = buffer
        self.step = int(state["step"])
        self.episode = int(state["episode"])
        self.rng.bit_generator.state = state["rng"]
        self.epoch_log = EpochAccumulator.from_dict(state["epoch_log"])
        self._episode_seed = int(state["episode_seed"])
        self._episode_actions = [int(a) for a in state["episode_actions"]]
        self._episode_reward = float(state["episode_reward"])
        self._obs = self._replay_open_episode() if state["episode_open"] else None
        if _digest(self._obs) != state["obs_sha256"]:
            raise ckpt.CheckpointError(
                "replaying the open episode did not reproduce the saved observation;"
                " is the environment deterministic given its seed and actions?"
            )
        # drop log rows written after the checkpoint by the interrupted run
        self.metrics_log.truncate(int(state["metrics_rows"]))
        self.episodes_log.truncate(int(state["episodes_rows"]))
        self.evaluations_log.truncate(int(state.get("evaluations_rows", 0)))
        if state.get("best_eval") is not None:  # the best weights as of the checkpoint
            self.best_eval, self._best_step = float(state["best_eval"]), int(state["best_step"])
            self._best_weights = part("best.")
            self._write_best_policy()
        self._writer_purge_step = self.step

    def _replay_open_episode(self) -> np.ndarray:
        """Bring the environment back to the checkpoint's state: same seed, same actions.

        Returns the observation reached and sets its auxiliary target (``_obs_aux``)."""
        obs, info = self.env.reset(seed=self._episode_seed)
        for action in self._episode_actions:
            obs, _, _, _, info = self.env.step(action)
        self._obs_aux = self._aux_target(info)
        return np.asarray(obs, dtype=np.uint8).reshape(self.obs_shape)


# ---------------------------------------------------------------------- library functions
def train(
    config: TrainConfig, run_dir: str | os.PathLike[str], env_factory: EnvFactory | None = None
) -> list[dict[str, float]]:
    """Train a fresh run to ``config.run.total_timesteps``; returns the per-epoch metrics."""
    trainer = Trainer(config, run_dir, env_factory)
    try:
        return trainer.train()
    finally:
        trainer.close()


def resume(
    run_dir: str | os.PathLike[str],
    env_factory: EnvFactory | None = None,
    steps: int | None = None,
) -> list[dict[str, float]]:
    """Continue an interrupted run from its newest checkpoint (to the end by default)."""
    trainer = Trainer.resume(run_dir, env_factory)
    try:
        return trainer.train(steps)
    finally:
        trainer.close()


def load_policy(
    path: str | os.PathLike[str], device: str = "cpu", weights: str = "final"
) -> QNetwork:
    """A trained QNetwork in eval mode, from a run directory, a checkpoint, or a weights file.

    Reads safetensors only (no code is executed). A run directory's ``policy.safetensors``
    holds its newest online weights (``weights="final"``), ``best_policy.safetensors`` those
    with the best validation score (``weights="best"``, runs with ``eval_interval``).
    """
    path = Path(path)
    if weights not in ("final", "best"):
        raise ValueError(f"weights must be 'final' or 'best', got {weights!r}")
    if path.is_dir() and weights == "best":
        path = path / BEST_POLICY_FILE
        if not path.exists():
            raise ckpt.CheckpointError(
                f"no {path.name} in {path.parent}: train with eval_interval > 0 to keep one"
            )
    elif path.is_dir():
        path = path / POLICY_FILE if (path / POLICY_FILE).exists() else path / "model.safetensors"
    if not path.exists():
        raise ckpt.CheckpointError(f"no policy weights at {path}")
    tensors, meta = ckpt.load_tensors(path)
    if any(k.startswith("online.") for k in tensors):
        tensors = {
            k.removeprefix("online."): v for k, v in tensors.items() if k.startswith("online.")
        }
    try:
        network = QNetwork(
            meta["n_actions"],
            meta["stack"],
            tuple(meta["image_shape"]),
            meta["dueling"],
            aux_outputs=meta.get("aux_outputs", 0),
        )
        network.load_state_dict(tensors)
    except (KeyError, RuntimeError) as error:
        raise ckpt.CheckpointError(f"{path} does not hold QNetwork weights: {error}") from error
    return network.to(device).eval()


# ---------------------------------------------------------------------- helpers
GOAL_OFFSET_DIM = 2


def goal_offset(info: dict[str, Any]) -> np.ndarray:
    """(pan, tilt) from the head to the goal viewpoint, rad: the auxiliary task's target."""
    try:
        offset = np.asarray(info["goal_viewpoint"], np.float32) - np.asarray(info["head"])
    except KeyError as error:
        raise ValueError(
            "aux_goal_weight needs an environment whose info holds 'goal_viewpoint' and 'head'"
            f" (as ActiveVision-v0's does); missing {error}"
        ) from error
    return offset.astype(np.float32).reshape(GOAL_OFFSET_DIM)


def _chw_shape(space: gym.Space) -> tuple[int, int, int]:
    if not isinstance(space, gym.spaces.Box) or space.dtype != np.uint8:
        raise ValueError(f"need a uint8 Box observation space, got {space}")
    if len(space.shape) == 2:
        return (1, *space.shape)
    if len(space.shape) == 3:
        return tuple(space.shape)
    raise ValueError(f"observations must be (H, W) or (stack, H, W), got {space.shape}")


def _check_buffer_fits(loaded: PrioritizedReplayBuffer, fresh: PrioritizedReplayBuffer) -> None:
    """The checkpoint's replay buffer must be one this run's config would build."""
    for name in ("capacity", "obs_shape", "alpha", "eps", "n_step", "gamma", "aux_dim"):
        if getattr(loaded, name) != getattr(fresh, name):
            raise ckpt.CheckpointError(
                f"the checkpoint's replay buffer has {name}={getattr(loaded, name)!r}, the run's"
                f" config gives {getattr(fresh, name)!r}"
            )


def _config_digest(run_dir: Path) -> str:
    return hashlib.sha256((run_dir / "config.json").read_bytes()).hexdigest()


def _check_config_unchanged(run_dir: Path, checkpoint: Path, state: dict[str, Any]) -> None:
    """A resumed run must go on with the config its checkpoint was taken under."""
    saved = state.get("config_sha256")
    if saved is None:
        raise ckpt.CheckpointError(
            f"checkpoint {checkpoint} does not record its config's checksum (written by an"
            " older activevision); start a new run"
        )
    try:
        current = _config_digest(run_dir)
    except OSError as error:
        raise ckpt.CheckpointError(f"cannot read {run_dir / 'config.json'}: {error}") from error
    if current != saved:
        raise ckpt.CheckpointError(
            f"{run_dir / 'config.json'} was changed after checkpoint {checkpoint.name}; resuming"
            " would mix two configurations: restore the file, or start a new run with the"
            " new config"
        )


def _digest(obs: np.ndarray | None) -> str | None:
    return None if obs is None else hashlib.sha256(np.ascontiguousarray(obs).tobytes()).hexdigest()


def _progress_bar(config: TrainConfig, start: int, end: int) -> Any:
    from tqdm.auto import tqdm

    enabled = config.run.progress_bar and sys.stderr.isatty()
    return tqdm(total=end, initial=start, disable=not enabled, unit="step", dynamic_ncols=True)


def _postfix(row: dict[str, float]) -> dict[str, str]:
    return {
        "success": f"{row['success_rate']:.2f}",
        "reward": f"{row['episode_reward']:.2f}",
        "loss": f"{row['loss']:.4f}",
        "eps": f"{row['epsilon']:.2f}",
        "sps": f"{row['steps_per_s']:.0f}",
    }


__all__ = ["Trainer", "load_policy", "make_env", "resume", "train"]
