"""The paper's training figures of a run: its CSV logs read here, drawn by
:mod:`activevision.figures.training`."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from activevision.training.config import MATCH_ENV_ID, load_config
from activevision.training.metrics import read_csv_columns
from activevision.training.state import check_run_config_unchanged

if TYPE_CHECKING:
    from activevision.figures.training import Columns, Curve

#: what drawing a run whose config.json was edited after its checkpoint would do
DRAWING_WOULD = (
    "the figures would be drawn for the edited file's learner and environment, not those the"
    " run trained with; restore the file"
)
#: the loss curve's title where it is not DDQN's TD loss
_LOSS_TITLES = {
    "dagger": "imitation loss (cross-entropy)",
    "sac": "critic loss (SAC)",
    "td3": "critic loss (TD3)",
    "ppo": "PPO loss (clip + value + entropy)",
}


def plot_run(
    run_dir: str | os.PathLike[str], out_dir: str | os.PathLike[str] | None = None
) -> Path:
    """Draw each curve as its own PNG and all of them in ``training.png`` (in
    ``run_dir/plots`` unless ``out_dir``); returns the latter."""
    from activevision.figures.training import CURVES, MATCH_CURVES, plot_training

    run_dir = Path(run_dir)
    if (run_dir / "config.json").exists():
        # the config picks the curves and their titles: one edited after the newest
        # checkpoint drew a match run as an episodic one (a config.json of {} was
        # "evaluations.csv has no 'success_rate' column", blaming the log)
        check_run_config_unchanged(run_dir, DRAWING_WOULD)
    config = load_config(run_dir / "config.json") if (run_dir / "config.json").exists() else None
    match = config is not None and config.on_match  # DDQN's too: a match has no success
    curves = MATCH_CURVES if match else CURVES
    # the columns each log is drawn against, checked in its header with or without rows (an
    # empty log, or one of another table, was drawn as "no data yet"); live: a run still
    # training may be writing a row (left out, with a warning)
    tables = {
        source: read_csv_columns(
            run_dir / _LOG_FILES[source], _x_columns(curves, source), live=True
        )
        for source in ("episodes", "metrics")
    }
    evaluations_csv = run_dir / _LOG_FILES["validation"]
    validation = (
        read_csv_columns(evaluations_csv, ["step", *_x_columns(curves, "validation")], live=True)
        if evaluations_csv.exists()
        else {}
    )
    out = Path(out_dir) if out_dir is not None else run_dir / "plots"
    loss_title = _LOSS_TITLES.get(config.algo, None) if config is not None else None
    if config is not None and config.algo == "dagger":
        if config.env_id == MATCH_ENV_ID and config.match.action_type == "continuous":
            loss_title = "imitation loss (squared error)"
        elif config.env_id != MATCH_ENV_ID and config.env.action_type == "continuous":
            loss_title = "imitation loss (squared error + goal cross-entropy)"
    _check_columns(run_dir, {**tables, "validation": validation}, curves)
    return plot_training(
        tables,
        out,
        title=run_dir.resolve().name,  # the folder's name, also for `plot .`
        validation=validation,
        loss_title=loss_title,
        curves=curves,
    )


#: the log each curve source is read from
_LOG_FILES = {"episodes": "episodes.csv", "metrics": "metrics.csv", "validation": "evaluations.csv"}


def _x_columns(curves: Sequence[Curve], source: str) -> list[str]:
    """The columns the curves of ``source`` are drawn against; a missing y column is drawn
    as "not measured", as in older runs."""
    return sorted({c.x for c in curves if c.source == source})


def _check_columns(run_dir: Path, tables: dict[str, Columns], curves: Sequence[Curve]) -> None:
    """ValueError naming the log and the column where a validation log with rows lacks one
    that the greedy validation is drawn with (a log edited by hand or cut short was a
    KeyError traceback)."""
    needed = set()
    if tables["validation"] and any(c.y == "success_rate" for c in curves):
        # the greedy validation drawn over the success rate, on the metrics' epoch axis
        needed |= {("validation", "step"), ("validation", "success_rate"), ("metrics", "step")}
    for source, column in sorted(needed):
        if tables[source] and column not in tables[source]:
            raise ValueError(
                f"{run_dir / _LOG_FILES[source]} has no {column!r} column: not a training log"
                " of activevision's"
            )
