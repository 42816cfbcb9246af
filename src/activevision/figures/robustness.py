"""The robustness suite's figure: success rate and goal reached per perturbation, as
horizontal bars with their 95% intervals, the clean value as a vertical line, and the
perturbations outside the policy's training ranges hatched (``activevision robustness``)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from activevision.figures.canvas import new_figure, save_figure

#: each panel's metric and axis label, in lines short enough that the two labels stay apart
#: when long row names narrow the panels (a blind method's all-mild+robots-4)
PANELS = (
    (
        "success_rate",
        "success rate: mean share of the goal view's"
        "\nlandmarks seen at the end (%; whiskers: 95% interval,"
        "\nnormal approximation; Wilson's where all are 0 or 100)",
    ),
    (
        "goal_reached",
        "goal reached: share of episodes that end"
        "\nat the goal view"
        "\n(%; whiskers: 95% Wilson interval)",
    ),
)
#: the dashed line: the ``clean`` row, the policy's own training world (randomised for a
#: policy trained so; the paper's clean world is the ``paper-clean`` row)
CLEAN_LABEL = "clean: the policy's training world (every change is against it)"
#: the same for a method that was not trained (no training world, no training ranges)
CLEAN_LABEL_UNTRAINED = "clean: the env's own world (every change is against it)"
#: bar colours by level ("clean"/"paper-clean" rows, mild, strong, robots, camera mount)
COLOURS = {
    "trained": "#555555",
    "neutral": "#999999",
    "mild": "#9ecae1",
    "strong": "#2171b5",
    "robots": "#fd8d3c",
    "mount": "#807dba",
}


def _truth(value: Any) -> bool:
    """A boolean column as written by the code (bool) or read back from a CSV (text)."""
    return value if isinstance(value, bool) else str(value).strip().lower() in ("true", "1", "yes")


def _colour(row: Mapping[str, Any]) -> str:
    factor = str(row["factor"])
    if factor == "robots":
        return COLOURS["robots"]
    if factor.startswith("mount"):
        return COLOURS["mount"]
    return COLOURS.get(str(row["level"]), COLOURS["strong"])


def _label(row: Mapping[str, Any]) -> str:
    """The row's name, with its setting where the name does not say it already."""
    factor = str(row["factor"])
    if factor == "none" or factor == "robots" or factor.startswith("mount"):
        return str(row["name"])
    return f"{row['name']}  ({row['setting']})"


def plot_robustness(
    rows: Sequence[Mapping[str, Any]], out_png: str | os.PathLike[str], title: str = ""
) -> None:
    """One bar per row (top to bottom in ``rows`` order) in each panel of :data:`PANELS`:
    ``<metric>`` with whiskers to ``<metric>_low`` / ``<metric>_high`` (proportions, drawn
    in percent) and its value beside; the row named ``clean`` as a dashed line; rows whose
    ``in_training_range`` is false hatched (none for a method that was not trained: None,
    or empty as read from the CSV); a thin rule between factors. ValueError where there are
    no rows (it drew two empty panels)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    if not rows:
        raise ValueError("plot_robustness: no rows to draw")
    n = len(rows)
    y = np.arange(n)
    colours = [_colour(r) for r in rows]
    # a method that was not trained has no training range (None, or empty in the CSV)
    trained = all(r["in_training_range"] not in (None, "") for r in rows)
    outside = [trained and not _truth(r["in_training_range"]) for r in rows]
    factors = [str(r["factor"]) for r in rows]
    breaks = [i - 0.5 for i in range(1, n) if factors[i] != factors[i - 1]]
    clean = next((r for r in rows if r["name"] == "clean"), None)
    fig = new_figure(figsize=(12, 2.0 + 0.24 * n))
    axes = fig.subplots(1, len(PANELS), sharey=True)
    for ax, (metric, label) in zip(axes, PANELS, strict=True):
        mean = 100 * np.array([float(r[metric]) for r in rows])
        low = 100 * np.array([float(r[f"{metric}_low"]) for r in rows])
        high = 100 * np.array([float(r[f"{metric}_high"]) for r in rows])
        bars = ax.barh(y, mean, height=0.7, color=colours, linewidth=0)
        for bar, hatch in zip(bars, outside, strict=True):
            if hatch:
                bar.set_hatch("//")
                bar.set_edgecolor("white")
                bar.set_hatch_linewidth(0.6)
        ax.errorbar(
            mean,
            y,
            xerr=np.vstack([mean - low, high - mean]),
            fmt="none",
            ecolor="black",
            elinewidth=0.8,
            capsize=2,
        )
        if clean is not None:
            ax.axvline(100 * float(clean[metric]), color="black", ls="--", lw=1, zorder=3)
        for b in breaks:
            ax.axhline(b, color="#bbbbbb", lw=0.5)
        for yi, m in zip(y, mean, strict=True):  # as the table prints them: 72.5, not "72"
            ax.text(102.5, yi, f"{m:.1f}", va="center", ha="left", fontsize=7)
        ax.set_xlim(-2, 111)  # the axis off 0: a clean line at 0% would hide in it
        ax.set_xticks(range(0, 101, 20))
        ax.set_xlabel(label)
        ax.grid(axis="x", alpha=0.3)
        ax.set_axisbelow(True)
        ax.spines[["top", "right"]].set_visible(False)
    axes[0].set_yticks(y, [_label(r) for r in rows], fontsize=8)
    axes[0].tick_params(axis="y", length=0)
    axes[1].tick_params(axis="y", length=0)
    axes[0].set_ylim(n - 0.5, -0.5)  # the table's first row on top
    hatched = Patch(facecolor="#999999", hatch="//", edgecolor="white")
    hatched.set_hatch_linewidth(0.6)
    hatched.set_label("outside this policy's training ranges")
    # only the kinds of bar drawn (a --perturbations of a few rows listed other robots and
    # a camera mount it never played)
    shown = set(colours)
    beyond = "them" if COLOURS["mild"] in shown else "the robust training ranges"
    kinds = [
        ("mild", "mild (inside the robust training ranges)"),
        ("strong", f"strong (beyond {beyond})"),
        ("robots", "other robots"),
        ("mount", "camera mounted off the model"),
    ]
    handles = [
        *(Patch(color=COLOURS[k], label=text) for k, text in kinds if COLOURS[k] in shown),
        *([hatched] if any(outside) else []),
        Line2D(
            [],
            [],
            color="black",
            ls="--",
            lw=1,
            label=CLEAN_LABEL if trained else CLEAN_LABEL_UNTRAINED,
        ),
    ]
    fig.legend(
        handles=handles,
        loc="lower center",
        bbox_to_anchor=(0.5, 0.0),
        ncol=3,
        fontsize=8,
        frameon=False,
    )
    if title:
        fig.suptitle(title, fontsize=10)
    # 0.6 inches for the legend below; tight_layout leaves room for the title itself (more
    # room in the rect left a band as tall as the title under it)
    fig.tight_layout(rect=(0, 0.6 / fig.get_figheight(), 1, 1))
    save_figure(fig, out_png, dpi=120)
