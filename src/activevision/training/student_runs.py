"""What DAgger runs and Stable-Baselines3 runs share: their policy is a
:class:`~activevision.agents.student.StudentNetwork`, written to the same policy files,
logged to the same CSVs, validated on the same batched episodes and checkpointed alike
(``model.safetensors`` with the newest and best weights, ``optimizer.pt``, ``replay.npz``,
``state.json``). Each learner adds how it trains and what its checkpoint restores."""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Self

import numpy as np
import torch

from activevision.agents.student import StudentNetwork
from activevision.envs.seeding import episode_seed
from activevision.io import loads_json
from activevision.training import checkpoint as ckpt
from activevision.training import state as run_state
from activevision.training.config import TrainConfig, load_config, save_config
from activevision.training.loggers import Logger, LoggerGroup, LogPosition, default_loggers
from activevision.training.metrics import EpochAccumulator, episode_record, epoch_number
from activevision.training.policy_files import BestWeights, write_policy
from activevision.training.run_lock import RunLock
from activevision.training.validation import (
    evaluation_fields,
    summarise_validation,
    validation_score,
)

#: ``(network, seeds) -> episodes.csv-style records``: one greedy episode per seed
PlayGreedy = Callable[[StudentNetwork, Sequence[int]], list[dict[str, float]]]


class StudentRun:
    """A run directory whose policy is a student network. Subclasses set ``config`` and
    ``step`` (the environment steps so far) and implement :meth:`_restore`."""

    config: TrainConfig
    step: int

    def _open_run(
        self, run_dir: str | os.PathLike[str], loggers: Sequence[Logger] | None, resuming: bool
    ) -> None:
        """Create (or reopen) the run directory, its config.json and its logs."""
        self.run_dir = Path(run_dir)
        if not resuming and ckpt.list_checkpoints(self.run_dir):
            raise ValueError(f"{self.run_dir} already holds a run; resume it")
        # one trainer a run, from before its first write (a resume holds it already)
        self._lock: RunLock | None = None
        try:
            self._lock = None if resuming else RunLock(self.run_dir)
            ckpt.remove_stale_writes(self.run_dir)
            if not resuming:  # before config.json is written: it tells an earlier attempt
                ckpt.remove_earlier_outputs(self.run_dir)
            self.episode = 0
            self.epoch_log = EpochAccumulator()
            self.best = BestWeights()
            self._epochs_logged = 0
            self._validations_logged = 0
            save_config(self.config, self.run_dir / run_state.CONFIG_FILE)
            self.logger = LoggerGroup(
                default_loggers(self.config, run_dir) if loggers is None else loggers
            )
            if not resuming:  # fresh logs, and no weights of an earlier attempt
                ckpt.remove_earlier_weights(self.run_dir)
                self.logger.start(None)
        except BaseException:
            self.close()  # the lock, and what the subclass built before
            raise

    # ------------------------------------------------------------------ records
    def record_episode(self, reward: float, length: int, info: dict[str, Any]) -> None:
        """An episode ended with this total reward, length and final info."""
        record = episode_record(self.episode, self.step, reward, length, info)
        self.logger.record_episode(record, self.step)
        self.epoch_log.episodes.append(record)
        self.episode += 1

    def finish_epoch(
        self, epsilon: float, steps_per_s: float, final: bool = False
    ) -> dict[str, float]:
        """Log the epoch's ``metrics.csv`` row and start the next epoch. ``final``: the row
        of the run's last steps, which ended between two ``epoch_steps`` boundaries,
        numbered as the epoch they lie in (``ceil(step / epoch_steps)``)."""
        epoch = epoch_number(self.step, self.config.run.epoch_steps, final)
        row = self.epoch_log.summary(epoch, self.step, epsilon, 0.0, steps_per_s)
        self.logger.record_epoch(row, self.step)
        self._epochs_logged += 1
        self.epoch_log = EpochAccumulator()
        return row

    def validate_network(
        self,
        network: StudentNetwork,
        play: PlayGreedy,
        metadata: dict[str, Any],
    ) -> dict[str, float]:
        """Greedy episodes of ``network`` on the validation seeds (the episodes of
        ``activevision evaluate --seed eval_seed``), logged as the run's evaluation fields;
        keeps the weights with the best validation score (``validation.validation_score``)."""
        run = self.config.run
        seeds = [episode_seed(run.eval_seed, i) for i in range(run.eval_episodes)]
        fields, score = evaluation_fields(self.config), validation_score(self.config)
        records = play(network, seeds)
        row = summarise_validation(self.step, records, self.best.score, fields, score)
        self.logger.record_validation(row, self.step)
        self._validations_logged += 1
        if row["best"]:
            self.best.keep(network, self.step, row[score])
            self.best.write(self.run_dir, metadata, score)
        return row

    # ------------------------------------------------------------------ checkpoints
    def run_state(self, algo: str, **extra: Any) -> str:
        """``state.json``: counters, logged rows, the best validation and the config's
        digest, plus the learner's ``extra``."""
        return json.dumps(
            {
                "algo": algo,
                "step": self.step,
                "episode": self.episode,
                **extra,
                "epoch_log": self.epoch_log.to_dict(),
                "metrics_rows": self._epochs_logged,
                "evaluations_rows": self._validations_logged,
                "best_eval": self.best.score if self.best.weights is not None else None,
                "best_step": self.best.step,
                "config_sha256": run_state.config_digest(self.run_dir),
            }
        )

    def write_checkpoint(
        self,
        network: StudentNetwork,
        metadata: dict[str, Any],
        optimizer_state: dict[str, Any],
        arrays: dict[str, np.ndarray],
        state_json: str,
    ) -> Path:
        """Write a checkpoint (atomically) and ``policy.safetensors``."""
        tensors = {f"online.{k}": v for k, v in network.state_dict().items()}
        if self.best.weights is not None:
            tensors.update({f"best.{k}": v for k, v in self.best.weights.items()})

        def write_files(directory: Path) -> None:
            ckpt.save_tensors(directory / "model.safetensors", tensors, metadata)
            ckpt.save_torch_state(directory / "optimizer.pt", optimizer_state)
            ckpt.save_arrays(directory / "replay.npz", arrays)
            (directory / run_state.STATE_FILE).write_text(state_json)

        path = ckpt.write_checkpoint(
            self.run_dir, self.step, write_files, self.config.run.keep_checkpoints
        )
        write_policy(self.run_dir, network.state_dict(), metadata)
        return path

    @classmethod
    def resume(
        cls, run_dir: str | os.PathLike[str], *, loggers: Sequence[Logger] | None = None
    ) -> Self:
        """Rebuild the trainer from the run's newest checkpoint (verified first; a
        config.json edited after it is refused), holding the run's lock from before it
        reads (another trainer may be replacing the checkpoint)."""
        run_dir = Path(run_dir)
        lock = RunLock(run_dir)
        trainer: Self | None = None
        path: Path | None = None  # set once the checkpoint and config are read and checked
        try:
            newest = ckpt.latest_checkpoint(run_dir)
            ckpt.verify_checkpoint(newest)
            config = load_config(run_dir / run_state.CONFIG_FILE)
            path = newest
            state = loads_json((path / run_state.STATE_FILE).read_text())
            run_state.check_config_unchanged(run_dir, path, state.get("config_sha256"))
            trainer = cls(config, run_dir, loggers=loggers, _resuming=True)  # type: ignore[call-arg]
            trainer._lock = lock  # handed over: close() releases it
            tensors, _ = ckpt.load_tensors(path / "model.safetensors")
            trainer._restore(path, state, _prefixed(tensors, "online."))
            trainer.episode = int(state["episode"])
            trainer.epoch_log = EpochAccumulator.from_dict(state["epoch_log"])
            trainer._epochs_logged = int(state["metrics_rows"])
            trainer._validations_logged = int(state["evaluations_rows"])
            if state["best_eval"] is not None:
                best = _prefixed(tensors, "best.")
                trainer.best.keep_weights(best, int(state["best_step"]), float(state["best_eval"]))
        except BaseException as error:
            if trainer is not None:
                trainer.close()
            else:
                lock.release()
            fits = isinstance(error, KeyError | TypeError | ValueError | RuntimeError)
            if path is None or isinstance(error, ckpt.CheckpointError) or not fits:
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

    def _restore(self, path: Path, state: dict[str, Any], weights: dict[str, torch.Tensor]) -> None:
        """Put the learner's part of checkpoint ``path`` back: its network ``weights``,
        optimiser, dataset or replay, step and generators."""
        raise NotImplementedError

    def close(self) -> None:
        """Close the logs and let another trainer take the run (also of a trainer whose
        construction failed part-way)."""
        logger = getattr(self, "logger", None)  # none yet if construction failed before it
        if logger is not None:
            logger.close()
        if self._lock is not None:
            self._lock.release()


def _prefixed(tensors: dict[str, torch.Tensor], prefix: str) -> dict[str, torch.Tensor]:
    return {k.removeprefix(prefix): v for k, v in tensors.items() if k.startswith(prefix)}


__all__ = ["PlayGreedy", "StudentRun"]
