"""A sweep's figure: success rate (a sweep of match runs: reward per match) vs environment
step, one mean curve with a +-std band per grid point (``activevision.scaleout.plot_sweep``
groups ``sweep.csv``'s rows into curves)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from activevision.figures.canvas import new_figure, save_figure

#: the y-axis label of each metric a sweep's figure draws
SWEEP_METRIC_LABELS = {"success_rate": "success rate", "episode_reward": "reward per match"}


def plot_sweep_curves(
    curves: Mapping[str, Sequence[Mapping[str, Any]]],
    out_png: str | os.PathLike[str],
    metric: str = "success_rate",
) -> None:
    """One curve per label: its rows' ``<metric>_mean`` (+- ``<metric>_std``) vs ``step``,
    labelled with the largest ``seeds`` count; ``metric`` is a key of
    :data:`SWEEP_METRIC_LABELS`."""
    fig = new_figure(figsize=(7, 4.5))
    ax = fig.subplots()
    for label, sel in curves.items():
        sel = sorted(sel, key=lambda r: r["step"])
        step = np.array([r["step"] for r in sel], float)
        mean = np.array([r[f"{metric}_mean"] for r in sel], float)
        std = np.array([r[f"{metric}_std"] for r in sel], float)
        (line,) = ax.plot(
            step, mean, "o-", ms=3, label=f"{label} (n={max(r['seeds'] for r in sel)})"
        )
        ax.fill_between(step, mean - std, mean + std, alpha=0.2, color=line.get_color())
        if len(step) == 1:  # a band over one step has no width: a bar instead
            ax.errorbar(step, mean, yerr=std, fmt="none", capsize=4, color=line.get_color())
    ax.set_xlabel("environment step")
    ax.set_ylabel(f"{SWEEP_METRIC_LABELS[metric]} (mean ± std over seeds)")
    if metric == "success_rate":
        ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    save_figure(fig, out_png, dpi=120)
