"""The paper's training figures, drawn from a run's CSV logs (matplotlib, Agg backend)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from activevision.training.metrics import read_csv_columns


@dataclass(frozen=True)
class Curve:
    """One training curve: which CSV column against which, and how to label it."""

    file: str  # PNG written for this curve alone
    source: str  # "episodes" or "metrics"
    x: str
    y: str
    title: str
    ylabel: str


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
        return (sums - shifted_sums) / (counts - shifted_counts)


def plot_run(
    run_dir: str | os.PathLike[str], out_dir: str | os.PathLike[str] | None = None
) -> Path:
    """Draw each curve as its own PNG and all of them in ``training.png``; returns the latter."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    run_dir = Path(run_dir)
    out_dir = Path(out_dir) if out_dir is not None else run_dir / "plots"
    out_dir.mkdir(parents=True, exist_ok=True)
    tables = {
        "episodes": read_csv_columns(run_dir / "episodes.csv"),
        "metrics": read_csv_columns(run_dir / "metrics.csv"),
    }
    evaluations_csv = run_dir / "evaluations.csv"
    validation = read_csv_columns(evaluations_csv) if evaluations_csv.exists() else {}

    def draw(ax: plt.Axes, curve: Curve) -> None:
        table = tables[curve.source]
        if not table:
            ax.text(0.5, 0.5, "no data yet", ha="center", va="center", transform=ax.transAxes)
        else:
            x, y = np.asarray(table[curve.x]), np.asarray(table[curve.y])
            if curve.source == "episodes":  # noisy: raw values faint, moving average on top
                ax.plot(x, y, color="tab:blue", alpha=0.25, linewidth=0.8, label="episode")
                window = max(len(y) // 50, 10)
                ax.plot(x, moving_average(y, window), color="tab:blue", label=f"mean of {window}")
                ax.legend(loc="lower right", fontsize=8)
            else:
                ax.plot(x, y, color="tab:blue", marker="o", markersize=3, linewidth=1.2)
            if curve.y == "success_rate" and validation:  # greedy validation, if logged
                epochs_per_step = x[-1] / np.asarray(table["step"])[-1]
                ax.plot(
                    np.asarray(validation["step"]) * epochs_per_step,
                    validation["success_rate"],
                    color="tab:orange",
                    marker="s",
                    markersize=3,
                    linewidth=1.2,
                    label="greedy validation",
                )
                ax.legend(loc="lower right", fontsize=8)
        ax.set_title(curve.title)
        ax.set_xlabel(curve.x)
        ax.set_ylabel(curve.ylabel)
        ax.grid(True, alpha=0.3)

    for curve in CURVES:
        fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
        draw(ax, curve)
        fig.savefig(out_dir / curve.file, dpi=120)
        plt.close(fig)

    fig, axes = plt.subplots(2, 3, figsize=(15, 8), layout="constrained")
    for ax, curve in zip(axes.flat, CURVES, strict=False):
        draw(ax, curve)
    axes.flat[-1].set_axis_off()
    fig.suptitle(f"Training: {run_dir.name}")
    combined = out_dir / "training.png"
    fig.savefig(combined, dpi=110)
    plt.close(fig)
    return combined
