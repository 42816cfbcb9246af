"""The training loop: Double DQN with prioritised replay on a Gymnasium environment.

The loop follows Stable-Baselines (v2) ``DQN.learn``, which the paper used: one environment
step, then (after ``learning_starts`` steps) ``gradient_steps`` gradient updates (one in the
paper) every ``train_freq`` steps, a target-network sync every ``target_update_interval``
steps, epsilon and beta annealed linearly. Around it: ``training.build`` (what the config
builds), ``state`` (checkpoints), ``policy_files`` (``load_policy``), ``loggers`` (CSV,
TensorBoard or your own) and ``aux_targets`` (the auxiliary head's target).

Reproducibility and resuming. Every random number comes from generators seeded by
``config.seed``. The environment is re-seeded at *every* episode start with a seed drawn from
the trainer's generator, so its state is a function of (episode seed, actions so far): a
checkpoint stores those instead of the environment's internals, and resuming replays them
(at most one episode) and checks the observation it reaches. An interrupted run resumed from
a checkpoint ends with exactly the weights and metrics of an uninterrupted one (except the
wall-clock ``steps_per_s`` column), provided the environment is deterministic given its seed
and actions, as Gymnasium environments should be.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch

from activevision.agents.augment import random_shifts
from activevision.agents.dqn_math import epsilon_greedy, linear_schedule
from activevision.envs.seeding import episode_seed
from activevision.training import checkpoint as ckpt
from activevision.training import state as run_state
from activevision.training.aux_targets import AuxTarget, aux_dim, aux_vector, resolve_aux_target
from activevision.training.build import build_learning
from activevision.training.config import TrainConfig, load_config, save_config
from activevision.training.cpu import configure_torch_cpu, training_device
from activevision.training.environment import EnvFactory, chw_shape, discrete_actions, make_env
from activevision.training.loggers import Logger, LoggerGroup, default_loggers
from activevision.training.metrics import (
    EpochAccumulator,
    RunLogError,
    episode_record,
    epoch_number,
)
from activevision.training.policy_files import BestWeights, network_metadata, write_policy
from activevision.training.progress import postfix, progress_bar
from activevision.training.run_lock import RunLock
from activevision.training.validation import (
    evaluation_fields,
    greedy_episodes,
    summarise_validation,
    validation_score,
)


class Trainer:
    """Trains a :class:`~activevision.agents.q_network.QNetwork` on one environment.

    Args:
        config: the run's configuration.
        run_dir: directory for config, logs and checkpoints. Must not hold a checkpoint
            already (continue such a run with :meth:`Trainer.resume`).
        env_factory: builds the environment; default :func:`make_env`. Its observations
            must be uint8 (stack, H, W) or (H, W), its actions Discrete.
        aux_target: with ``learner.aux_goal_weight > 0``: info -> the auxiliary head's target
            (float vector, its length read from one reset) of the observation returned with
            that info. Default ``aux_targets.goal_offset`` for ActiveVision-v0; other envs
            must pass one.
        loggers: where records go (``training.loggers.Logger``); default the CSV logs, and
            TensorBoard with ``run.tensorboard``.
    """

    def __init__(
        self,
        config: TrainConfig,
        run_dir: str | os.PathLike[str],
        env_factory: EnvFactory | None = None,
        *,
        aux_target: AuxTarget | None = None,
        loggers: Sequence[Logger] | None = None,
        _resuming: bool = False,
    ) -> None:
        self.config = config
        self.run_dir = Path(run_dir)
        if not _resuming and ckpt.list_checkpoints(self.run_dir):
            raise ValueError(f"{self.run_dir} already holds a run; use Trainer.resume()")
        self.device = training_device(config.run.device)  # bad device or env: before any write
        self.aux_target = resolve_aux_target(config, aux_target)
        self.env_factory = env_factory or (lambda: make_env(config))
        self.env = self.env_factory()
        self._eval_env: gym.Env | None = None  # built at the first validation
        try:
            self.n_actions = discrete_actions(self.env)
            self.obs_shape = chw_shape(self.env.observation_space)
        except ValueError as error:  # a custom env_id's env: say which, not a bare "need ..."
            self.env.close()
            source = "env_factory's env" if env_factory else f"TrainConfig.env_id {config.env_id!r}"
            raise ValueError(f"{source}: {error}") from None
        aux_size = aux_dim(self.aux_target, self.env, config.seed)
        # one trainer a run, from before its first write (a resume holds it already)
        self._lock: RunLock | None = None
        try:
            self._lock = None if _resuming else RunLock(self.run_dir)
            self._set_up(config, loggers, aux_size, _resuming)
        except BaseException:
            self.close()  # the lock and the environment
            raise

    def _set_up(
        self,
        config: TrainConfig,
        loggers: Sequence[Logger] | None,
        aux_size: int,
        resuming: bool,
    ) -> None:
        """The constructor's writes, with the run's lock held: the learner, the replay, the
        progress counters, config.json and the logs."""
        ckpt.remove_stale_writes(self.run_dir)  # left by a checkpoint write that was killed
        if not resuming:  # before config.json is written: it tells an earlier attempt
            ckpt.remove_earlier_outputs(self.run_dir)
        configure_torch_cpu(config.run.num_threads)
        self.rng, self.learner, self.buffer = build_learning(
            config, self.n_actions, self.obs_shape, self.device, aux_size
        )

        # progress; everything below is saved in checkpoints
        self.step = 0
        self.episode = 0
        self.epoch_log = EpochAccumulator()
        self._obs: np.ndarray | None = None  # current observation, None between episodes
        self._obs_aux: np.ndarray | None = None  # auxiliary target of _obs (aux_target)
        self._episode_seed = 0
        self._episode_actions: list[int] = []
        self._episode_reward = 0.0
        self.best = BestWeights()  # the best validation so far
        self._epochs_logged = 0  # records handed to the loggers (episodes: self.episode)
        self._validations_logged = 0

        save_config(config, self.run_dir / run_state.CONFIG_FILE)
        self.logger = LoggerGroup(
            default_loggers(config, self.run_dir) if loggers is None else loggers
        )
        if not resuming:  # a fresh run starts fresh logs (a resumed one: at its checkpoint)
            ckpt.remove_earlier_weights(self.run_dir)
            self.logger.start(None)

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

        Returns the epoch rows (``metrics.csv``) of this call. Saves a checkpoint every
        ``checkpoint_interval`` steps and when it returns.
        """
        run = self.config.run
        end = run.total_timesteps if steps is None else min(self.step + steps, run.total_timesteps)
        epochs: list[dict[str, float]] = []
        progress = progress_bar(self.config, self.step, end)
        epoch_start = (self.step, time.perf_counter())
        start_step = self.step
        try:
            while self.step < end:
                self._env_step()
                progress.update(1)
                if self.step % run.epoch_steps == 0:
                    seconds = time.perf_counter() - epoch_start[1]
                    epochs.append(self._finish_epoch((self.step - epoch_start[0]) / seconds))
                    progress.set_postfix(postfix(epochs[-1]), refresh=False)
                    epoch_start = (self.step, time.perf_counter())
                if run.eval_interval and self.step % run.eval_interval == 0:
                    self.validate()
                    epoch_start = (self.step, time.perf_counter())  # keep it out of steps/s
                if run.checkpoint_interval and self.step % run.checkpoint_interval == 0:
                    self.save_checkpoint()
            if self.step >= run.total_timesteps and self.step > start_step:
                if self.step % run.epoch_steps:
                    # the run ends between two epoch_steps boundaries: its last steps get
                    # their row (a run shorter than epoch_steps left metrics.csv empty)
                    seconds = time.perf_counter() - epoch_start[1]
                    rate = (self.step - epoch_start[0]) / max(seconds, 1e-9)
                    epochs.append(self._finish_epoch(rate, final=True))
            saved_last_step = run.checkpoint_interval and self.step % run.checkpoint_interval == 0
            if self.step > start_step and not saved_last_step:
                self.save_checkpoint()
        finally:
            progress.close()
            self.logger.flush()
        return epochs

    def _env_step(self) -> None:
        """One environment step: act, store the transition, learn, end the episode if over."""
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
            obs, action, float(reward), next_obs, bool(terminated), bool(truncated), self._obs_aux
        )
        self._obs_aux = self._aux(info)
        self._episode_actions.append(action)
        self._episode_reward += float(reward)
        self.step += 1
        self._learn()
        if terminated or truncated:
            self._end_episode(info)
        else:
            self._obs = next_obs

    def _learn(self) -> None:
        """After ``learning_starts``: updates every ``train_freq`` steps, target syncs."""
        c = self.config.learner
        if self.step <= c.learning_starts or len(self.buffer) < c.batch_size:
            return
        if self.step % c.train_freq == 0:
            for _ in range(c.gradient_steps):
                self._update()
        if self.step % c.target_update_interval == 0:
            self.learner.sync_target()

    def _update(self) -> None:
        """One gradient step on a prioritised (with ``augment_shift``: shifted) batch."""
        c = self.config.learner
        batch = self.buffer.sample(c.batch_size, self.beta)
        if c.augment_shift:
            batch = batch._replace(
                obs=random_shifts(batch.obs, c.augment_shift, self.rng),
                next_obs=random_shifts(batch.next_obs, c.augment_shift, self.rng),
            )
        result = self.learner.update(batch)
        self.buffer.update_priorities(batch.indices, result.td_errors)
        self.epoch_log.losses.append(result.loss)

    def _start_episode(self) -> None:
        """Reset with a seed from the trainer's generator (what makes resuming exact)."""
        self._episode_seed = int(self.rng.integers(2**31 - 1))
        obs, info = self.env.reset(seed=self._episode_seed)
        self._obs = np.asarray(obs, dtype=np.uint8).reshape(self.obs_shape)
        self._obs_aux = self._aux(info)
        self._episode_actions = []
        self._episode_reward = 0.0

    def _end_episode(self, info: dict[str, Any]) -> None:
        """Log the finished episode (``info``: its last); the next step starts another."""
        self.episode += 1
        length = len(self._episode_actions)
        if self.config.on_match:  # a match has no success (as the match student logs it)
            info = {"success_rate": math.nan}
        record = episode_record(self.episode, self.step, self._episode_reward, length, info)
        self.logger.record_episode(record, self.step)
        self.epoch_log.episodes.append(record)
        self._obs = None

    def _aux(self, info: dict[str, Any]) -> np.ndarray | None:
        return None if self.aux_target is None else aux_vector(self.aux_target, info)

    def _finish_epoch(self, steps_per_s: float, final: bool = False) -> dict[str, float]:
        epoch = epoch_number(self.step, self.config.run.epoch_steps, final)
        row = self.epoch_log.summary(epoch, self.step, self.epsilon, self.beta, steps_per_s)
        self.logger.record_epoch(row, self.step)
        self._epochs_logged += 1
        self.epoch_log = EpochAccumulator()
        return row

    def validate(self) -> dict[str, float]:
        """Greedy episodes on the validation seeds; keeps the weights if they scored best.

        Uses an environment of its own, so training's environment, generators and replay are
        untouched (a run with validation trains exactly like one without).
        """
        run = self.config.run
        if self._eval_env is None:
            self._eval_env = self.env_factory()
        seeds = [episode_seed(run.eval_seed, i) for i in range(run.eval_episodes)]
        match = self.config.match if self.config.on_match else None
        records = greedy_episodes(
            self.learner.q_values, self._eval_env, seeds, self.obs_shape, match=match
        )
        fields, score = evaluation_fields(self.config), validation_score(self.config)
        row = summarise_validation(self.step, records, self.best.score, fields, score)
        self.logger.record_validation(row, self.step)
        self._validations_logged += 1
        if row["best"]:
            self.best.keep(self.learner.online, self.step, row[score])
            metadata = network_metadata(self.learner.online, self.step)
            self.best.write(self.run_dir, metadata, score)
        return row

    def close(self) -> None:
        """Close the environments and the loggers, and turn flushing of denormals (set for
        training speed, process-wide) back off."""
        logger = getattr(self, "logger", None)  # none yet if construction failed before it
        if logger is not None:
            logger.close()
        self.env.close()
        if self._eval_env is not None:
            self._eval_env.close()
        torch.set_flush_denormal(False)
        if self._lock is not None:
            self._lock.release()

    # ------------------------------------------------------------------ checkpoints
    def state(self) -> run_state.TrainerState:
        """The trainer's progress now, as a checkpoint stores it (a snapshot)."""
        return run_state.TrainerState(
            step=self.step,
            episode=self.episode,
            rng=dict(self.rng.bit_generator.state),
            epoch_log=EpochAccumulator.from_dict(self.epoch_log.to_dict()),
            episode_open=self._obs is not None,
            episode_seed=self._episode_seed,
            episode_actions=tuple(self._episode_actions),
            episode_reward=self._episode_reward,
            obs_sha256=run_state.obs_digest(self._obs),
            metrics_rows=self._epochs_logged,
            episodes_rows=self.episode,
            best_eval=self.best.score if self.best.weights is not None else None,
            best_step=self.best.step,
            evaluations_rows=self._validations_logged,
            config_sha256=run_state.config_digest(self.run_dir),
        )

    def save_checkpoint(self) -> Path:
        """Write a checkpoint of the current step (atomically) and the policy file."""
        metadata = network_metadata(self.learner.online, self.step)
        keep = self.config.run.keep_checkpoints
        path = run_state.save_checkpoint(
            self.run_dir, self.state(), self.learner, self.buffer, self.best.weights, metadata, keep
        )
        write_policy(self.run_dir, self.learner.online.state_dict(), metadata)
        return path

    @classmethod
    def resume(
        cls,
        run_dir: str | os.PathLike[str],
        env_factory: EnvFactory | None = None,
        checkpoint: str | os.PathLike[str] | None = None,
        *,
        aux_target: AuxTarget | None = None,
        loggers: Sequence[Logger] | None = None,
    ) -> Trainer:
        """Rebuild a trainer from its run directory's newest (or a given) checkpoint
        (``aux_target``, ``loggers``: as for a new one). CheckpointError if the checkpoint is
        missing or corrupt; nothing is written to the run directory before it has loaded
        (but the lock, ``run_lock``, taken before it reads: another trainer may be replacing
        the checkpoint)."""
        run_dir = Path(run_dir)
        lock = RunLock(run_dir)
        trainer: Trainer | None = None
        try:
            loaded = run_state.load_checkpoint(
                run_dir, None if checkpoint is None else Path(checkpoint)
            )
            config = load_config(run_dir / run_state.CONFIG_FILE)
            trainer = cls(
                config, run_dir, env_factory, aux_target=aux_target, loggers=loggers, _resuming=True
            )
            trainer._lock = lock  # handed over: close() releases it
            try:
                trainer._restore(loaded)
            except (KeyError, TypeError, ValueError, IndexError, RuntimeError) as error:
                if isinstance(error, ckpt.CheckpointError | RunLogError):  # names its file
                    raise
                raise ckpt.CheckpointError(
                    f"checkpoint {loaded.path} does not fit this run"
                    f" ({type(error).__name__}: {error})"
                ) from error
        except BaseException:
            if trainer is not None:
                trainer.close()
            else:
                lock.release()
            raise
        return trainer

    def _restore(self, loaded: run_state.LoadedCheckpoint) -> None:
        """Take on a loaded checkpoint: weights, replay, progress; then start the loggers."""
        self.buffer = run_state.restore_learning(loaded, self.learner, self.buffer)
        state = loaded.state
        self.step, self.episode = state.step, state.episode
        self.rng.bit_generator.state = state.rng
        self.epoch_log = EpochAccumulator.from_dict(state.epoch_log.to_dict())
        self._episode_seed = state.episode_seed
        self._episode_actions = list(state.episode_actions)
        self._episode_reward = state.episode_reward
        self._obs = self._replay_open_episode() if state.episode_open else None
        if run_state.obs_digest(self._obs) != state.obs_sha256:
            raise ckpt.CheckpointError(
                "replaying the open episode did not reproduce the saved observation;"
                " is the environment deterministic given its seed and actions?"
            )
        self._epochs_logged, self._validations_logged = state.metrics_rows, state.evaluations_rows
        if state.best_eval is not None:  # the best weights as of the checkpoint
            self.best.keep_weights(loaded.weights("best"), state.best_step, state.best_eval)
            self.best.write(self.run_dir, network_metadata(self.learner.online, self.step))
        self.logger.start(state.log_position)  # forget what was logged after the checkpoint

    def _replay_open_episode(self) -> np.ndarray:
        """Bring the environment back to the checkpoint's state: same seed, same actions.
        Returns the observation reached and sets its auxiliary target (``_obs_aux``)."""
        obs, info = self.env.reset(seed=self._episode_seed)
        for action in self._episode_actions:
            obs, _, _, _, info = self.env.step(action)
        self._obs_aux = self._aux(info)
        return np.asarray(obs, dtype=np.uint8).reshape(self.obs_shape)


__all__ = ["Trainer", "make_env"]
