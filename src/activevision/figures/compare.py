"""The paper's comparison figure: success of every method vs the robot's localisation error,
one curve per method with its 95% band, read from ``compare.csv``."""

from __future__ import annotations

import csv
import os
from collections.abc import Sequence
from pathlib import Path

from activevision.figures.canvas import new_figure, save_figure

#: y-axis labels (the CSV's column names say less to a reader)
Y_LABELS = {
    "success_rate": "success rate (mean over episodes)",
    "success": "share of episodes (goal reached)",
    "score": "release score (mean over episodes)",
    "regret_within": "share of episodes (regret <= 0.25 nats)",
}
TITLES = {
    "success_rate": "success rate (|observed ∩ desired| / |desired|)",
    "success": "episodes reaching the goal",
    "score": "release score",
    "regret_within": "entropy regret <= 0.25 nats",
}


def plot_compare(
    csv_path: str | os.PathLike[str],
    out_png: str | os.PathLike[str],
    metrics: Sequence[str] = ("success_rate", "success", "regret_within"),
) -> None:
    """Success vs localisation error, one curve per method with its 95% band: a panel per
    ``metrics`` column of ``csv_path`` (with its ``_low`` / ``_high`` bounds)."""
    with Path(csv_path).open() as f:
        rows = list(csv.DictReader(f))
    metrics = [m for m in metrics if not rows or m in rows[0]]  # older CSVs lack regret
    fig = new_figure(figsize=(5.5 * len(metrics), 4))
    axes = fig.subplots(1, len(metrics), squeeze=False)
    for ax, metric in zip(axes[0], metrics, strict=False):
        for method in dict.fromkeys(r["method"] for r in rows):
            sel = sorted(
                (r for r in rows if r["method"] == method), key=lambda r: float(r["error"])
            )
            e = [float(r["error"]) for r in sel]
            mean = [float(r[metric]) for r in sel]
            ax.plot(e, mean, "o-", ms=3, label=method)
            ax.fill_between(
                e,
                [float(r[f"{metric}_low"]) for r in sel],
                [float(r[f"{metric}_high"]) for r in sel],
                alpha=0.2,
            )
        ax.set_xlabel("localisation error e (m and rad)")
        ax.set_ylabel(Y_LABELS.get(metric, metric))
        ax.set_title(TITLES.get(metric, metric), fontsize=10)
        ax.set_ylim(-0.02, 1.02)
        ax.grid(alpha=0.3)
    # one legend for every panel, below them: inside one it covered curves
    handles, labels = axes[0][0].get_legend_handles_labels()
    columns = max(1, min(len(labels), 3 * len(metrics)))  # ~3 names a panel's width
    legend_rows = -(-len(labels) // columns)
    fig.legend(handles, labels, loc="lower center", ncol=columns, fontsize=9, frameon=False)
    fig.tight_layout(rect=(0, 0.02 + 0.055 * legend_rows, 1, 1))
    save_figure(fig, out_png, dpi=120)
