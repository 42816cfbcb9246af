"""The paper's comparison figure: success of every method vs the robot's localisation error,
one curve per method with its 95% band (whiskers at a single error level), read from
``compare.csv``."""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

from activevision.figures.canvas import fit_legend, new_figure, save_figure
from activevision.io import read_csv_lines

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
    ``metrics`` column of ``csv_path`` (with its ``_low`` / ``_high`` bounds) that the CSV
    has. ValueError naming the file where it has no rows, a row is cut short or a cell is
    not a number, or it has none of ``metrics`` (blank panels, or matplotlib's "Number of
    columns must be a positive integer")."""
    lines = read_csv_lines(csv_path)
    rows = [row for _, row in lines]
    if not rows:
        raise ValueError(f"{csv_path} holds no levels to draw")
    if isinstance(metrics, str):  # one name, not its letters
        metrics = [metrics]
    asked = list(metrics)
    # older CSVs lack regret
    metrics = [m for m in asked if {"error", "method", m, f"{m}_low", f"{m}_high"} <= set(rows[0])]
    if not metrics:
        raise ValueError(
            f"{csv_path} has none of the columns {', '.join(asked)} (each with its _low and"
            " _high) beside error and method"
        )
    for line, row in lines:
        for column in ("error", *(f"{m}{end}" for m in metrics for end in ("", "_low", "_high"))):
            try:
                float(row[column])
            except ValueError:
                raise ValueError(
                    f"{csv_path} line {line}: {column} is not a number: {row[column]!r}"
                ) from None
    fig = new_figure(figsize=(5.5 * len(metrics), 4))
    axes = fig.subplots(1, len(metrics), squeeze=False)
    for ax, metric in zip(axes[0], metrics, strict=False):
        for method in dict.fromkeys(r["method"] for r in rows):
            sel = sorted(
                (r for r in rows if r["method"] == method), key=lambda r: float(r["error"])
            )
            e = [float(r["error"]) for r in sel]
            mean = [float(r[metric]) for r in sel]
            (line,) = ax.plot(e, mean, "o-", ms=3, label=method)
            low = [float(r[f"{metric}_low"]) for r in sel]
            high = [float(r[f"{metric}_high"]) for r in sel]
            if len(sel) == 1:
                # a band over one error level has no width: its interval went undrawn
                ax.errorbar(
                    e,
                    mean,
                    yerr=[[mean[0] - low[0]], [high[0] - mean[0]]],
                    fmt="none",
                    ecolor=line.get_color(),
                    capsize=3,
                )
            else:
                ax.fill_between(e, low, high, facecolor=line.get_color(), alpha=0.2)
        ax.set_xlabel("localisation error e (m and rad)")
        ax.set_ylabel(Y_LABELS.get(metric, metric))
        ax.set_title(TITLES.get(metric, metric), fontsize=10)
        ax.set_ylim(-0.02, 1.02)
        ax.grid(alpha=0.3)
    # one legend for every panel, below them (inside one it covered curves), in as many
    # columns as fit the figure's width (long names ran past its edges)
    handles, labels = axes[0][0].get_legend_handles_labels()
    style: dict[str, Any] = {"loc": "lower center", "fontsize": 9, "frameon": False}
    columns = max(1, min(len(labels), 3 * len(metrics)))  # ~3 names a panel's width
    columns, labels = fit_legend(fig, handles, labels, columns, **style)
    fig.legend(handles, labels, ncol=columns, **style)
    # a name too long for one column is broken into lines (in the one column)
    legend_rows = -(-len(labels) // columns) + sum(label.count("\n") for label in labels)
    fig.tight_layout(rect=(0, 0.02 + 0.055 * legend_rows, 1, 1))
    save_figure(fig, out_png, dpi=120)
