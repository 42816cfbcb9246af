"""The paper's training figures: each curve of a run as its own PNG, and all of them in
``training.png``. Fed with a run's CSV logs as columns (``activevision.training.plot_run``
reads them)."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.ticker import MaxNLocator

from activevision.figures.canvas import new_figure, save_figure

#: A CSV log as columns: name -> values.
Columns = Mapping[str, Sequence[float]]


@dataclass(frozen=True)
class Curve:
    """One training curve: which CSV column against which, and how to label it."""

    file: str  # PNG written for this curve alone
    source: str  # "episodes", "metrics" or "validation"
    x: str
    y: str
    title: str
    ylabel: str
    xlabel: str = ""  #: the x axis's name where the column's is not the word for it ("match")


CURVES = (
    Curve("reward.png", "episodes", "episode", "reward", "Total reward per episode", "reward"),
    Curve("loss.png", "metrics", "epoch", "loss", "TD loss (Huber)", "loss"),
    Curve("success_rate.png", "metrics", "epoch", "success_rate", "Success rate", "rate"),
    Curve(
        "success_duration.png", "metrics", "epoch", "success_duration", "Success duration", "steps"
    ),
    Curve(
        "ball_loss_duration.png",
        "metrics",
        "epoch",
        "ball_loss_duration",
        "Ball-loss duration",
        "steps",
    ),
)

#: a match run's curves: a match has no success, so its validation matches take those panels
MATCH_CURVES = (
    dataclasses.replace(CURVES[0], title="Total reward per match", xlabel="match"),
    CURVES[1],
    Curve(
        "validation_position_rmse.png",
        "validation",
        "step",
        "position_rmse",
        "Validation matches: position RMSE",
        "m",
    ),
    Curve(
        "validation_ball_in_view.png",
        "validation",
        "step",
        "ball_in_view",
        "Validation matches: ball in view",
        "share of ticks",
    ),
)


def moving_average(values: np.ndarray, window: int) -> np.ndarray:
    """Trailing mean over up to ``window`` finite values (shorter at the start)."""
    values = np.asarray(values, dtype=np.float64)
    finite = np.isfinite(values)
    sums = np.cumsum(np.where(finite, values, 0.0))
    counts = np.cumsum(finite)
    start = np.maximum(np.arange(values.size) - window, -1)
    shifted_sums = np.where(start >= 0, sums[np.maximum(start, 0)], 0.0)
    shifted_counts = np.where(start >= 0, counts[np.maximum(start, 0)], 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        means: np.ndarray = (sums - shifted_sums) / (counts - shifted_counts)
    return means


def steps_on_axis(steps: np.ndarray, x: np.ndarray, table_steps: np.ndarray) -> np.ndarray:
    """Where ``steps`` sit on the axis ``x`` of rows logged at ``table_steps``: between two
    rows as far as their steps are (a run that ends between two epochs logs a short last
    one, so one factor of epochs per step misplaced them), from 0 at step 0, and past the
    last row at its epochs per step (a run still training)."""
    steps, x, table_steps = (np.asarray(a, dtype=float) for a in (steps, x, table_steps))
    inside = np.interp(steps, np.r_[0.0, table_steps], np.r_[0.0, x])
    beyond = x[-1] + (steps - table_steps[-1]) * (x[-1] / table_steps[-1])
    placed: np.ndarray = np.where(steps > table_steps[-1], beyond, inside)
    return placed


def _draw_validation(ax: Axes, x: np.ndarray, table: Columns, validation: Columns) -> None:
    """Greedy validation's success rate on the epoch axis of ``table``."""
    ax.plot(
        steps_on_axis(np.asarray(validation["step"]), x, np.asarray(table["step"])),
        validation["success_rate"],
        color="tab:orange",
        marker="s",
        markersize=3,
        linewidth=1.2,
        label="greedy validation",
    )
    ax.legend(loc="lower right", fontsize=8)


def draw_curve(ax: Axes, curve: Curve, table: Columns, validation: Columns) -> None:
    """``curve`` from ``table`` (its source's columns; empty: "no data yet"; all NaN: "not
    measured (yet, or in this task)"), with the greedy ``validation`` over the success rate when
    given."""
    if not table:
        text = "no validation yet" if curve.source == "validation" else None
        ax.text(0.5, 0.5, text or "no data yet", ha="center", va="center", transform=ax.transAxes)
    elif curve.y not in table or not np.isfinite(np.asarray(table[curve.y], dtype=float)).any():
        # e.g. a match run: a match has no success and no goal view
        ax.text(
            0.5,
            0.5,
            "not measured (yet, or in this task)",
            ha="center",
            va="center",
            transform=ax.transAxes,
        )
    else:
        x, y = np.asarray(table[curve.x]), np.asarray(table[curve.y])
        if curve.source == "episodes":  # noisy: raw values faint, moving average on top
            raw = curve.xlabel or curve.x  # one value an episode (or match)
            ax.plot(x, y, color="tab:blue", alpha=0.25, linewidth=0.8, label=raw)
            window = max(len(y) // 50, 10)
            ax.plot(x, moving_average(y, window), color="tab:blue", label=f"mean of {window}")
            ax.legend(loc="lower right", fontsize=8)
        else:
            # beside the greedy validation, say whose these are: the training episodes'
            # (exploring, or a DAgger run's teacher acting for part of them)
            label = "training episodes" if curve.y == "success_rate" else None
            ax.plot(x, y, color="tab:blue", marker="o", markersize=3, linewidth=1.2, label=label)
        if curve.y == "success_rate" and validation:
            _draw_validation(ax, x, table, validation)
    ax.set_title(curve.title)
    if curve.x in ("epoch", "episode"):  # counts: a short run's axis read "epoch 1.2"
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        low, high = ax.get_xlim()
        if np.floor(high) - np.ceil(low) < 1:  # < 2 whole counts in view: it fell back on 0.945...
            ax.set_xlim(np.floor(low), max(np.ceil(high), np.floor(low) + 2))
    ax.set_xlabel(curve.xlabel or curve.x)
    ax.set_ylabel(curve.ylabel)
    ax.grid(True, alpha=0.3)


def plot_training(
    tables: Mapping[str, Columns],
    out_dir: str | os.PathLike[str],
    title: str,
    validation: Columns | None = None,
    loss_title: str | None = None,
    curves: Sequence[Curve] = CURVES,
) -> Path:
    """Each of ``curves`` (:data:`CURVES`, a match run's :data:`MATCH_CURVES`) as its own
    PNG in ``out_dir`` and all of them in ``training.png`` (titled "Training: ``title``");
    returns the latter. ``tables`` maps each curve source ("episodes", "metrics") to its
    columns, ``validation`` is ``evaluations.csv``'s; ``loss_title`` renames the loss curve
    (a DAgger run's is an imitation loss, not a TD loss)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    validation = validation or {}
    tables = {**tables, "validation": validation}
    curves = tuple(
        dataclasses.replace(c, title=loss_title) if loss_title and c.y == "loss" else c
        for c in curves
    )
    for curve in curves:
        fig = new_figure(figsize=(6, 4), layout="constrained")
        draw_curve(fig.subplots(), curve, tables[curve.source], validation)
        save_figure(fig, out_dir / curve.file, dpi=120)

    fig = new_figure(figsize=(15, 8) if len(curves) > 4 else (10, 8), layout="constrained")
    axes = fig.subplots(2, 3) if len(curves) > 4 else fig.subplots(2, 2)
    for ax, curve in zip(axes.flat, curves, strict=False):
        draw_curve(ax, curve, tables[curve.source], validation)
    for ax in axes.flat[len(curves) :]:
        ax.set_axis_off()
    fig.suptitle(f"Training: {title}")
    combined = out_dir / "training.png"
    save_figure(fig, combined, dpi=110)
    return combined
