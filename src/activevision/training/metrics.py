"""Training metrics: what an episode and an epoch report, and the CSV logs they go to.

Episode metrics come from the environment's final ``info`` dict, read with defaults so any
Gymnasium environment works:

| info key           | meaning (ActiveVision-v0)                             | default       |
|--------------------|-------------------------------------------------------|---------------|
| ``success``        | the goal viewpoint was reached                        | False         |
| ``success_rate``   | fraction of the goal view's landmarks observed        | success (0/1) |
| ``steps_to_success`` | steps until success (the time limit, 20, if never)  | NaN           |
| ``ball_lost_step`` | step the ball left the view (the limit if never)      | NaN           |
"""

from __future__ import annotations

import csv
import io
import math
import os
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from activevision.io import read_csv_text, write_text

EPISODE_FIELDS = (
    "episode",
    "step",
    "reward",
    "length",
    "success",
    "success_rate",
    "steps_to_success",
    "ball_lost_step",
)
EPOCH_FIELDS = (
    "epoch",
    "step",
    "episodes",
    "success_rate",
    "success_duration",
    "ball_loss_duration",
    "episode_reward",
    "loss",
    "updates",
    "epsilon",
    "beta",
    "steps_per_s",
)
#: epoch columns measured with a clock, so they differ between otherwise identical runs
TIMING_FIELDS = ("steps_per_s",)

#: TensorBoard tag of each epoch column
TENSORBOARD_TAGS = {
    "success_rate": "charts/success_rate",
    "success_duration": "charts/success_duration",
    "ball_loss_duration": "charts/ball_loss_duration",
    "episode_reward": "charts/mean_episodic_return",
    "episodes": "charts/episodes",
    "loss": "losses/td_loss",
    "epsilon": "charts/epsilon",
    "beta": "charts/per_beta",
    "steps_per_s": "charts/SPS",
}


def episode_record(
    episode: int, step: int, reward: float, length: int, info: Mapping[str, Any]
) -> dict[str, float]:
    """One row of ``episodes.csv`` from an episode's totals and its final info dict."""
    success = bool(info.get("success", False))
    return {
        "episode": episode,
        "step": step,
        "reward": float(reward),
        "length": length,
        "success": float(success),
        "success_rate": float(info.get("success_rate", float(success))),
        "steps_to_success": float(info.get("steps_to_success", math.nan)),
        "ball_lost_step": float(info.get("ball_lost_step", math.nan)),
    }


def nan_mean(values: Sequence[float]) -> float:
    """Mean of the finite values; NaN when there are none (e.g. no episode ended)."""
    finite = [v for v in values if math.isfinite(v)]
    return sum(finite) / len(finite) if finite else math.nan


def epoch_number(step: int, epoch_steps: int, final: bool = False) -> int:
    """A ``metrics.csv`` row's epoch: the boundaries passed (``step // epoch_steps``), or for
    the ``final`` row of a run that ends between two boundaries the epoch it ends in."""
    return -(-step // epoch_steps) if final else step // epoch_steps


@dataclass
class EpochAccumulator:
    """Episodes and losses collected since the current epoch began (checkpointable)."""

    episodes: list[dict[str, float]] = field(default_factory=list)
    losses: list[float] = field(default_factory=list)

    def summary(
        self, epoch: int, step: int, epsilon: float, beta: float, steps_per_s: float
    ) -> dict[str, float]:
        """The epoch's row of ``metrics.csv``."""

        def mean_of(key: str) -> float:
            return nan_mean([e[key] for e in self.episodes])

        return {
            "epoch": epoch,
            "step": step,
            "episodes": len(self.episodes),
            "success_rate": mean_of("success_rate"),
            "success_duration": mean_of("steps_to_success"),
            "ball_loss_duration": mean_of("ball_lost_step"),
            "episode_reward": mean_of("reward"),
            "loss": nan_mean(self.losses),
            "updates": len(self.losses),
            "epsilon": epsilon,
            "beta": beta,
            "steps_per_s": steps_per_s,
        }

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> EpochAccumulator:
        return cls(episodes=list(values["episodes"]), losses=list(values["losses"]))


class CsvLog:
    """An append-only CSV file with a fixed header, one flushed row at a time.

    Args:
        path: the file; created with a header if missing.
        fieldnames: the columns.
    """

    def __init__(self, path: str | os.PathLike[str], fieldnames: Sequence[str]) -> None:
        self.path = Path(path)
        self.fieldnames = list(fieldnames)
        if not self.path.exists():  # atomically: a kill here left an empty file
            self.clear()

    def append(self, row: Mapping[str, Any]) -> None:
        with open(self.path, "a", newline="") as file:
            csv.DictWriter(file, self.fieldnames).writerow({k: row[k] for k in self.fieldnames})

    def rows(self) -> list[dict[str, str]]:
        with open(self.path, newline="") as file:
            return list(csv.DictReader(file))

    def clear(self) -> None:
        """Leave the header alone in the file (a new run's log)."""
        write_text(self.path, ",".join(self.fieldnames) + "\r\n")

    def truncate(self, n_rows: int) -> None:
        """Keep the header and the first ``n_rows`` rows (rows written after a checkpoint).

        RunLogError naming the file when it does not start with this log's header and
        ``n_rows`` whole rows (emptied, cut short, binary, another table): appending to it
        would make a log that reads as whole but is not. The cut is written atomically."""
        if n_rows == 0:  # nothing to lose
            self.clear()
            return
        try:
            with open(self.path, newline="", encoding="utf-8") as file:
                lines = file.readlines()
        except UnicodeDecodeError:
            raise RunLogError(f"{self.path} is not a CSV table (binary data){_RESTORE}") from None
        rows = list(csv.reader(lines[: 1 + n_rows]))
        if not rows or rows[0] != self.fieldnames:
            raise RunLogError(f"{self.path} does not start with its header row{_RESTORE}")
        width = len(self.fieldnames)
        whole = [a.endswith("\n") and len(b) == width for a, b in zip(lines, rows, strict=False)]
        if len(rows) < 1 + n_rows or not all(whole):
            raise RunLogError(
                f"{self.path} holds {sum(whole) - 1} whole rows where the checkpoint logged"
                f" {n_rows}{_RESTORE}"
            )
        if len(lines) > 1 + n_rows:
            write_text(self.path, "".join(lines[: 1 + n_rows]))


class RunLogError(ValueError):
    """A training log (``metrics.csv``...) that a resumed run cannot continue."""


_RESTORE = ": it was damaged after the checkpoint; restore it, or train a new run"


def read_csv_columns(
    path: str | os.PathLike[str], columns: Sequence[str] = (), *, live: bool = False
) -> dict[str, list[float]]:
    """A CSV written by :class:`CsvLog` as float columns (empty cells become NaN); ``{}``
    for a log of no rows yet. ValueError naming the file where it has no header row (a
    :class:`CsvLog` is made with its header, atomically, so an empty file was damaged: it
    was drawn as "no data yet"), the header lacks one of ``columns``, with or without
    rows, or its last line has no end of line (a row cut inside its last cell has all its
    cells: ``0.12`` of ``0.1234`` was drawn as a value). ``live``: the log of a run that
    may still be training, whose last row may be half written: that line is left out, with
    a warning saying so."""
    try:
        text, cut = read_csv_text(path, live=live)
        if cut:
            warnings.warn(
                f"{path}: its last line has no end of line (a row still being written, or"
                " cut by a crash): read without it",
                stacklevel=2,
            )
        with io.StringIO(text, newline="") as file:
            reader = csv.DictReader(file)
            header = reader.fieldnames or []
            rows = list(reader)
    except (UnicodeDecodeError, csv.Error) as error:
        raise ValueError(f"{path} is not a CSV table: {error}") from None
    if not any(header):
        raise ValueError(
            f"{path} is empty (no header row): a training log starts with its header, so it"
            " was damaged; restore it"
        )
    for column in columns:
        if column not in header:
            raise ValueError(
                f"{path} has no {column!r} column: not a training log of activevision's"
            )
    if not rows:
        return {}
    table: dict[str, list[float]] = {key: [] for key in rows[0]}
    for line, row in enumerate(rows, start=2):  # the header is line 1
        if None in row or None in row.values():  # DictReader's marks of a row cut or run on
            raise ValueError(
                f"{path} line {line} has {'more' if None in row else 'fewer'} cells than its"
                " header: not a metrics table"
            )
        for key, text in row.items():
            try:
                table[key].append(float(text) if text != "" else math.nan)
            except ValueError:
                raise ValueError(
                    f"{path} line {line}, column {key!r}: {text!r} is not a number"
                ) from None
    return table
