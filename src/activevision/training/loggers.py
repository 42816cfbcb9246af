"""Where a run's records go: a small logger protocol with CSV and TensorBoard backends.

The shape is Stable-Baselines3's (``stable_baselines3.common.logger``): the trainer is handed
loggers, as an SB3 model is handed a ``Logger`` of ``KVWriter`` backends, and sends every
record to each of them (:class:`LoggerGroup`). The records are the trainer's three kinds:

* an epoch row (``metrics.EPOCH_FIELDS``) every ``epoch_steps`` steps;
* an episode record (``metrics.EPISODE_FIELDS``) at every episode end;
* a validation row (``validation.EVALUATION_FIELDS``) every ``eval_interval`` steps.

Resuming a run must forget what the interrupted run logged after its checkpoint, so a
logger is told, before its first record, where the run starts: :meth:`Logger.start` gets
None for a fresh run, or the checkpoint's :class:`LogPosition` (how many rows of each kind
it covers, and its step).

Backends: :class:`CsvLogger` (``metrics.csv``, ``episodes.csv``, ``evaluations.csv``) and
:class:`TensorBoardLogger` (``tensorboard/``, CleanRL-style tags). :func:`default_loggers`
builds the set a run's config asks for.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from activevision.training.config import TrainConfig
from activevision.training.metrics import EPISODE_FIELDS, EPOCH_FIELDS, TENSORBOARD_TAGS, CsvLog
from activevision.training.validation import EVALUATION_FIELDS, evaluation_fields

Record = Mapping[str, float]

METRICS_CSV = "metrics.csv"  #: one row per epoch
EPISODES_CSV = "episodes.csv"  #: one row per episode
EVALUATIONS_CSV = "evaluations.csv"  #: one row per validation
TENSORBOARD_DIR = "tensorboard"
EVENTS_PREFIX = "events.out.tfevents."  #: the names of TensorBoard's event files

#: TensorBoard tags of an episode's record fields and of a validation row's
EPISODE_TAGS = {"reward": "charts/episodic_return", "length": "charts/episodic_length"}
VALIDATION_TAGS = {
    "success_rate": "eval/success_rate",
    "episode_reward": "eval/mean_episodic_return",
    "position_rmse": "eval/position_rmse",  # match runs
    "ball_in_view": "eval/ball_in_view",  # match runs
}


#: the loss's tag of each learner (``metrics.csv``'s ``loss``: a DAgger run's is its
#: imitation loss, an SB3 learner's its critic's or PPO's total, never a TD loss)
LOSS_TAGS = {
    "ddqn": "losses/td_loss",
    "dagger": "losses/imitation_loss",
    "sac": "losses/critic_loss",
    "td3": "losses/critic_loss",
    "ppo": "losses/loss",
}


def epoch_tags(algo: str) -> dict[str, str]:
    """The TensorBoard tag of each epoch column a run of ``algo`` measures: DDQN's are
    :data:`metrics.TENSORBOARD_TAGS`; a DAgger run's ``epsilon`` is the teacher's share, and
    the columns that hold unused 0s (PER's beta but in DDQN, epsilon in SB3's) get none."""
    tags = {**TENSORBOARD_TAGS, "loss": LOSS_TAGS.get(algo, TENSORBOARD_TAGS["loss"])}
    if algo in LOSS_TAGS and algo != "ddqn":
        del tags["beta"]
        if algo == "dagger":
            tags["epsilon"] = "charts/teacher_share"
        else:
            del tags["epsilon"]
    return tags


@dataclass(frozen=True)
class LogPosition:
    """How far a checkpoint's logs go: records of each kind logged, and the step."""

    step: int
    epochs: int
    episodes: int
    validations: int


class Logger(Protocol):
    """What the trainer calls on each of its loggers."""

    def start(self, resume: LogPosition | None) -> None:
        """Called before the first record: None for a fresh run (discard earlier logs), else
        the checkpoint being resumed (discard what was logged after it)."""

    def record_epoch(self, row: Record, step: int) -> None:
        """One epoch's metrics (``metrics.EPOCH_FIELDS``), at environment step ``step``."""

    def record_episode(self, record: Record, step: int) -> None:
        """One finished training episode (``metrics.EPISODE_FIELDS``)."""

    def record_validation(self, row: Record, step: int) -> None:
        """One greedy validation (``validation.EVALUATION_FIELDS``)."""

    def flush(self) -> None:
        """Write out anything buffered (the trainer calls it when ``train`` returns)."""

    def close(self) -> None:
        """Release files; a later record may reopen them."""


class LoggerGroup:
    """Several loggers as one (SB3's ``Logger`` over its output formats), called in order."""

    def __init__(self, loggers: Iterable[Logger]) -> None:
        self.loggers = list(loggers)

    def start(self, resume: LogPosition | None) -> None:
        for logger in self.loggers:
            logger.start(resume)

    def record_epoch(self, row: Record, step: int) -> None:
        for logger in self.loggers:
            logger.record_epoch(row, step)

    def record_episode(self, record: Record, step: int) -> None:
        for logger in self.loggers:
            logger.record_episode(record, step)

    def record_validation(self, row: Record, step: int) -> None:
        for logger in self.loggers:
            logger.record_validation(row, step)

    def flush(self) -> None:
        for logger in self.loggers:
            logger.flush()

    def close(self) -> None:
        for logger in self.loggers:
            logger.close()


class CsvLogger:
    """``metrics.csv``, ``episodes.csv`` and ``evaluations.csv`` in ``run_dir``, a flushed
    row per record (:class:`~activevision.training.metrics.CsvLog`). ``evaluation_fields``:
    the validation columns, a match student's ``MATCH_EVALUATION_FIELDS``
    (``validation.evaluation_fields(config)`` gives a run's)."""

    def __init__(
        self,
        run_dir: str | os.PathLike[str],
        evaluation_fields: Sequence[str] = EVALUATION_FIELDS,
    ) -> None:
        self.run_dir = Path(run_dir)
        self.evaluation_fields = tuple(evaluation_fields)
        self._logs: dict[str, CsvLog] | None = None

    def start(self, resume: LogPosition | None) -> None:
        self.run_dir.mkdir(parents=True, exist_ok=True)
        self._logs = {
            METRICS_CSV: CsvLog(self.run_dir / METRICS_CSV, EPOCH_FIELDS),
            EPISODES_CSV: CsvLog(self.run_dir / EPISODES_CSV, EPISODE_FIELDS),
            EVALUATIONS_CSV: CsvLog(self.run_dir / EVALUATIONS_CSV, self.evaluation_fields),
        }
        if resume is None:
            for log in self._logs.values():
                log.clear()
            return
        rows = (resume.epochs, resume.episodes, resume.validations)
        for log, keep in zip(self._logs.values(), rows, strict=True):
            log.truncate(keep)

    def record_epoch(self, row: Record, step: int) -> None:
        self._log(METRICS_CSV).append(row)

    def record_episode(self, record: Record, step: int) -> None:
        self._log(EPISODES_CSV).append(record)

    def record_validation(self, row: Record, step: int) -> None:
        self._log(EVALUATIONS_CSV).append(row)

    def flush(self) -> None:  # every row is flushed as it is written
        pass

    def close(self) -> None:
        pass

    def _log(self, name: str) -> CsvLog:
        if self._logs is None:
            raise RuntimeError("CsvLogger.start() must be called before the first record")
        return self._logs[name]


class TensorBoardLogger:
    """TensorBoard scalars in ``log_dir``: epoch columns under :func:`epoch_tags` of the run's
    ``algo`` (non-finite values skipped), :data:`EPISODE_TAGS` and :data:`VALIDATION_TAGS`.

    The writer (and torch's TensorBoard module, a heavy import) is made at the first record;
    a resumed run's writer purges the events logged after the checkpoint's step (those at
    its step were logged before it was written, and are its CSV logs' last rows too).
    """

    def __init__(self, log_dir: str | os.PathLike[str], algo: str = "ddqn") -> None:
        self.log_dir = Path(log_dir)
        self.epoch_tags = epoch_tags(algo)
        self._purge_step: int | None = None
        self._writer: Any = None

    def start(self, resume: LogPosition | None) -> None:
        # TensorBoard drops the events at purge_step and after: the checkpoint's own step
        # (its epoch row, validation, last episode) was dropped and never logged again
        self._purge_step = None if resume is None else resume.step + 1
        if resume is None and self.log_dir.is_dir():  # an earlier attempt's curves
            for events in self.log_dir.glob(f"{EVENTS_PREFIX}*"):
                if events.is_file():
                    events.unlink()

    def record_epoch(self, row: Record, step: int) -> None:
        for key, tag in self.epoch_tags.items():
            if math.isfinite(row[key]):
                self._add(tag, row[key], step)

    def record_episode(self, record: Record, step: int) -> None:
        for key, tag in EPISODE_TAGS.items():
            self._add(tag, record[key], step)

    def record_validation(self, row: Record, step: int) -> None:
        for key, tag in VALIDATION_TAGS.items():
            if key in row:  # an episodic run's columns, or a match run's
                self._add(tag, row[key], step)

    def flush(self) -> None:
        if self._writer is not None:
            self._writer.flush()

    def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
            self._writer = None

    def _add(self, tag: str, value: float, step: int) -> None:
        if self._writer is None:
            from torch.utils.tensorboard import SummaryWriter  # heavy import, only when used

            self._writer = SummaryWriter(str(self.log_dir), purge_step=self._purge_step)
        self._writer.add_scalar(tag, value, step)


def default_loggers(config: TrainConfig, run_dir: str | os.PathLike[str]) -> list[Logger]:
    """The CSV logs, and TensorBoard's with ``config.run.tensorboard`` (SB3's ``configure``)."""
    loggers: list[Logger] = [CsvLogger(run_dir, evaluation_fields(config))]
    if config.run.tensorboard:
        loggers.append(TensorBoardLogger(Path(run_dir) / TENSORBOARD_DIR, config.algo))
    return loggers


__all__ = [
    "EPISODE_TAGS",
    "LOSS_TAGS",
    "VALIDATION_TAGS",
    "CsvLogger",
    "LogPosition",
    "Logger",
    "LoggerGroup",
    "TensorBoardLogger",
    "default_loggers",
    "epoch_tags",
]
