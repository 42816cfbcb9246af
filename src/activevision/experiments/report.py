"""One self-contained page per run, and the README's main job (``activevision quickstart``).

Layout of a run directory after the quickstart::

    runs/NAME/config.json, metrics.csv, ...   the training run (activevision.training)
    runs/NAME/plots/training.png              training curves
    runs/NAME/evaluation/evaluation.{csv,json} fixed-seed evaluation of every method
    runs/NAME/compare/compare.{csv,png}       success vs localisation error
    runs/NAME/episode.png, episode.gif        learned vs random from one start
    runs/NAME/match/match.csv, match_*.png    head-control strategies through whole matches
    runs/NAME/report.md                       this page
"""

from __future__ import annotations

import csv
import json
import platform
from pathlib import Path

import activevision
from activevision.io import read_json, write_text


def _csv_rows(path: Path) -> list[dict]:
    if not path.exists():
        return []
    with path.open() as f:
        return list(csv.DictReader(f))


def _table(rows: list[dict], metrics: list[str]) -> str:
    head = "| method | " + " | ".join(metrics) + " |"
    lines = [head, "|" + "---|" * (len(metrics) + 1)]
    for r in rows:
        cells = [
            f"{float(r[m]):.3f} [{float(r[m + '_low']):.3f}, {float(r[m + '_high']):.3f}]"
            for m in metrics
        ]
        lines.append(f"| {r['method']} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def write_report(run_dir: str | Path) -> Path:
    """Write ``run_dir/report.md``: configuration, training curves, evaluation table,
    comparison figure and episode figure (whichever of them the run has)."""
    run = Path(run_dir)
    if not (run / "config.json").exists():
        raise FileNotFoundError(f"{run} is not a training run (no config.json)")
    config = read_json(run / "config.json")
    parts = [
        f"# activevision report: `{run.name}`",
        "",
        f"activevision {activevision.__version__}, Python {platform.python_version()}, "
        f"training seed {config.get('seed')}, {config.get('algo', 'ddqn')},"
        f" {config.get('run', {}).get('total_timesteps')} steps.",
        "",
        "## Training",
    ]
    if (run / "plots" / "training.png").exists():
        parts += ["", "![training curves](plots/training.png)"]
    metrics = _csv_rows(run / "metrics.csv")
    if metrics:
        last = metrics[-1]
        parts += [
            "",
            "Last epoch: "
            + ", ".join(f"{k} {float(v):.4g}" for k, v in last.items() if _is_number(v)),
        ]
    evaluation = run / "evaluation" / "evaluation.json"
    if evaluation.exists():
        data = read_json(evaluation)
        rows = [{k: str(v) for k, v in r.items()} for r in data["methods"]]
        parts += [
            "",
            "## Evaluation",
            "",
            f"{data['episodes']} episodes, seed {data['seed']}, identical starts for every "
            "method; mean [95% confidence interval].",
            "",
            _table(rows, ["success", "success_rate", "success_duration", "ball_loss_duration"]),
            "",
            _table(rows, ["entropy_regret", "regret_within", "oscillating"]),
            "",
            "Entropy regret: the belief's entropy after the final view's landmarks minus the"
            " goal view's (nats); regret_within: the share of episodes within 0.25 nats;"
            " oscillating: unsolved episodes that end swinging between two views.",
            "",
            # head travel (degrees per episode): evaluations written before it lack it
            _table(rows, [m for m in ("reward", "score", "head_travel") if m in rows[0]]),
        ]
        if data.get("latency"):
            lat = data["latency"]
            parts += [
                "",
                f"Learned policy, batch 1 on CPU (PyTorch): p50 {lat['p50_ms']:.2f} ms, "
                f"p99 {lat['p99_ms']:.2f} ms; the paper: 2.3 ms on a GTX 1060.",
            ]
    if (run / "compare" / "compare.png").exists():
        parts += ["", "## Success vs localisation error", "", "![comparison](compare/compare.png)"]
    if (run / "episode.png").exists():
        parts += [
            "",
            "## One episode",
            "",
            "![episode](episode.png)",
            "",
            "Animated: [episode.gif](episode.gif)",
        ]
    match_rows = _csv_rows(run / "match" / "match.csv")
    if match_rows:
        first = match_rows[0]
        parts += [
            "",
            "## Head control through whole matches",
            "",
            f"`ActiveVisionMatch-v0`: {first['matches']} matches from seed {first['seed']}, the"
            " same for every strategy; the robot walks, the ball is kicked about, the UKF"
            " tracks every tick. Mean [95% interval] over matches.",
            "",
            _table(match_rows, ["position_rmse", "heading_rmse", "lost_share"]),
            "",
            _table(match_rows, ["ball_in_view", "entropy", "head_travel"]),
            "",
            "![Pareto front](match/match_pareto.png)",
            "",
            "![error over time](match/match_error.png)",
            "",
            "Animated: [match_clip.gif](match/match_clip.gif)",
        ]
    parts += [
        "",
        "## Configuration",
        "",
        "```json",
        json.dumps(config, indent=2),
        "```",
        "",
    ]
    out = run / "report.md"
    write_text(out, "\n".join(parts))
    return out


def _is_number(value: str) -> bool:
    try:
        float(value)
    except (TypeError, ValueError):
        return False
    return True
