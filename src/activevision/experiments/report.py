"""One self-contained page per run, and the README's main job (``activevision quickstart``).

Layout of a run directory after the quickstart::

    runs/NAME/config.json, metrics.csv, ...   the training run (activevision.training)
    runs/NAME/plots/training.png              training curves
    runs/NAME/evaluation/evaluation.{csv,json} fixed-seed evaluation of every method
    runs/NAME/compare/compare.{csv,png}       success vs localisation error
    runs/NAME/episode.png, episode.gif        learned vs random from one start
    runs/NAME/episode.png.json                what played in them (``episode``, ``demo``)
    runs/NAME/match/match.csv, match_*.png    head-control strategies through whole matches
    runs/NAME/robustness/robustness.{csv,png} the policy under named perturbations
                                              (``activevision robustness --run``)
    runs/NAME/report.md                       this page

A result that records another run, or no policy of this run
(:mod:`~activevision.experiments.provenance`, :func:`_own_results`), is left out with a
warning naming it and the command that writes it again.
"""

from __future__ import annotations

import contextlib
import csv
import json
import math
import platform
import warnings
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import activevision
from activevision.experiments.provenance import (
    ANOTHER_RUN,
    Provenance,
    compare_provenance,
    episode_provenance,
    run_export,
    stale_parts,
    weights_words,
)
from activevision.io import read_csv, read_json, write_text
from activevision.text import counted
from activevision.training.checkpoint import checkpoint_step, list_checkpoints
from activevision.training.config import MATCH_ENV_ID
from activevision.training.policy_files import SCORED_RUN_COLUMNS, scored_run
from activevision.training.state import check_run_config_unchanged

#: what reporting a run whose config.json was edited after its checkpoint would do
DESCRIBING_WOULD = (
    "the report would show the edited file as the configuration the run was trained with;"
    " restore the file"
)


def _csv_rows(path: Path, columns: Sequence[str], *, rows_written: bool = True) -> list[dict]:
    """A log's rows; ValueError naming the file and line where a row has more or fewer cells
    than the header (a log cut mid-row was reported with its last cell cut: epsilon 0 for
    0.02, the columns after it left out), as ``activevision plot`` refuses it, and the file
    where it is empty, its header lacks one of ``columns``, or, for a table written whole
    (``rows_written``: a command's results, not a training log), it holds no rows: its
    section was left out as if the run had none."""
    if not path.exists():
        return []
    rows = read_csv(path, columns)
    if rows_written and not rows:
        raise ValueError(f"{path} holds no rows: it is damaged or not a file activevision wrote")
    return rows


@contextlib.contextmanager
def _reading(path: Path) -> Iterator[None]:
    """Turn what a damaged file (binary, cut, of another layout) raises while the block
    reads it into a ValueError naming it."""
    try:
        yield
    except (KeyError, TypeError, AttributeError, IndexError, ValueError, csv.Error) as error:
        raise ValueError(
            f"{path} is damaged or not a file activevision wrote ({type(error).__name__}: {error})"
        ) from None


def _table(rows: list[dict], metrics: list[str]) -> str:
    """A markdown table of ``mean [low, high]`` per metric, to 3 decimals as ``evaluate``
    prints them (an oracle's entropy regret of float noise read "[-0.000, 0.000]" here)."""
    from activevision.experiments.evaluate import fixed

    head = "| method | " + " | ".join(metrics) + " |"
    lines = [head, "|" + "---|" * (len(metrics) + 1)]
    for r in rows:
        ends = [[fixed(float(r[m + end])) for end in ("", "_low", "_high")] for m in metrics]
        cells = [f"{mean} [{low}, {high}]" for mean, low, high in ends]
        lines.append(f"| {r['method']} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _steps(run: Path, asked: object) -> str:
    """The steps the run's config asks for and, where its newest checkpoint says otherwise,
    those it played: a learner plays whole rounds of its vector env (DAgger's quickstart
    asked for 600 and played 1,161), and a run stopped early played fewer."""
    checkpoints = list_checkpoints(run)
    played = checkpoint_step(checkpoints[-1]) if checkpoints else None
    if played is None or played == asked:
        return f"{asked} steps"
    return f"{asked} steps asked, {played} played"


def write_report(run_dir: str | Path) -> Path:
    """Write ``run_dir/report.md``: configuration, training curves, evaluation table,
    comparison figure and episode figure (whichever of them the run has)."""
    run = Path(run_dir)
    if not (run / "config.json").exists():
        raise FileNotFoundError(f"{run} is not a training run (no config.json)")
    config = read_json(run / "config.json")
    if not isinstance(config, dict) or not isinstance(config.get("run", {}), dict):
        raise ValueError(f"{run / 'config.json'} must hold a training run's config object")
    # the report shows config.json as the run's configuration: one edited after the run's
    # newest checkpoint is not the one its weights were trained with (a config.json of {}
    # was reported as "training seed None", "None steps asked")
    check_run_config_unchanged(run, DESCRIBING_WOULD)
    algo = config.get("algo", "ddqn")
    env_id = config.get("env_id", "ActiveVision-v0")
    parts = [
        f"# activevision report: `{run.resolve().name}`",  # also for `report .`
        "",
        f"activevision {activevision.__version__}, Python {platform.python_version()}, "
        f"training seed {config.get('seed')}, {algo} on `{env_id}`,"
        f" {_steps(run, config.get('run', {}).get('total_timesteps'))}"
        + (" (match ticks)" if env_id == MATCH_ENV_ID else "")
        + ".",
        "",
        "## Training",
    ]
    if (run / "plots" / "training.png").exists():
        parts += ["", "![training curves](plots/training.png)"]
    # a training log: its header alone before the first epoch
    metrics = _csv_rows(run / "metrics.csv", ("epoch", "step"), rows_written=False)
    if metrics:
        parts += ["", "Last epoch: " + _last_epoch(metrics[-1], algo)]
    evaluation = run / "evaluation" / "evaluation.json"
    if evaluation.exists():
        data = read_json(evaluation)
        _check_scored(evaluation, data, run)
        with _reading(evaluation):
            latency = data.get("latency")  # where evaluations before latency.json kept it
        latency_path = evaluation.with_name("latency.json")
        if latency_path.exists():
            latency = read_json(latency_path)
            with _reading(latency_path):
                float(latency["p50_ms"]), float(latency["p99_ms"])
        with _reading(evaluation):
            parts += _evaluation_part(data, latency)
    parts += _figures_part(run)
    match_csv = run / "match" / "match.csv"
    match_rows = _csv_rows(match_csv, ("method", "matches", "seed"))
    if match_rows and _own_results(match_csv, match_rows, run, f"match --run {run} --out"):
        with _reading(match_csv):
            parts += _match_part(match_rows, run)
    robustness_csv = run / "robustness" / "robustness.csv"
    robustness_rows = _csv_rows(robustness_csv, ("method", "name", "n", "seed"))
    if (
        robustness_rows
        and _learned_suite(robustness_csv, robustness_rows, run)
        and _own_results(robustness_csv, robustness_rows, run, f"robustness --run {run} --out")
    ):
        with _reading(robustness_csv):
            parts += _robustness_part(robustness_rows, run / "robustness" / "robustness.png")
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


def _check_scored(evaluation: Path, data: Any, run: Path) -> None:
    """ValueError where ``evaluation`` (in ``run``) records another run than ``run`` as the
    one it scored: an evaluate without ``--run`` (the paper's env, no learned policy of this
    run), another run's results copied in, or this run's weights replaced since (trained
    on, retrained with ``--overwrite``). The report showed them as this run's. Files from
    before the record (no ``run`` key) are read as before."""
    if not isinstance(data, dict) or "run" not in data:
        return
    again = f"evaluate it again: activevision evaluate --run {run} --overwrite"
    if data["run"] is None:
        raise ValueError(
            f"{evaluation} was written by an evaluate without --run: its table is not this"
            f" run's; {again}"
        )
    with _reading(evaluation):
        recorded = {key: data["run"][key] for key in ("config_sha256", "weights_sha256")}
        weights = str(data["weights"])
    current = scored_run(run, weights)
    for key, what in (("config_sha256", "config.json"), ("weights_sha256", "weights")):
        if recorded[key] != current[key]:
            raise ValueError(
                f"{evaluation} scored another run's {what}, or this run's before they were"
                f" replaced (trained on or retrained): {again}"
            )


def _figures_part(run: Path) -> list[str]:
    """The report's comparison and episode sections, each where the run has its figure
    and it records (:mod:`~activevision.experiments.provenance`) that this run played, with
    what played."""
    parts = []
    compare_png = run / "compare" / "compare.png"
    if compare_png.exists():
        said = _included(compare_png, compare_provenance(compare_png, run))
        if said is not None:
            parts += ["", "## Success vs localisation error", ""]
            parts += [said, ""] if said else []
            parts += ["![comparison](compare/compare.png)"]
    episode_png = run / "episode.png"
    if episode_png.exists():
        said = _included(episode_png, episode_provenance(episode_png, run))
        if said is not None:
            parts += ["", "## One episode", ""]
            parts += [said, ""] if said else []
            parts += ["![episode](episode.png)", "", "Animated: [episode.gif](episode.gif)"]
    return parts


def _included(path: Path, provenance: Provenance) -> str | None:
    """What the report says of what the file ``path`` played (its :class:`Provenance`'s
    text; ``""`` where it records nothing), or None, with a warning naming it, why and the
    command that writes it again, where it is not the run's."""
    if provenance.own:
        return provenance.text
    _left_out(path, provenance.text, provenance.again, depth=4)
    return None


def _left_out(path: Path, why: str, again: str, depth: int) -> None:
    """Warn that ``path`` is left out of the report: ``why``, and the command (after
    ``activevision``) that writes it again; ``depth``: the calls from the caller of
    :func:`write_report` to here. The report is still written, without it."""
    warnings.warn(
        f"left {path} out of the report: {why}; write it again: activevision {again}",
        stacklevel=depth + 1,
    )


def _learned_suite(path: Path, rows: list[dict], run: Path) -> bool:
    """Whether ``robustness.csv`` (``path``, in ``run``) scored the run's learned policy:
    False, with a warning, for a suite of the shipped policy (``robustness --shipped``) or
    of another method (``--method NAME``) written into the run, which the report showed as
    the run's policy's robustness (its only sign the method's name in a sentence)."""
    methods = {row["method"] for row in rows}
    if methods == {"learned"}:
        return True
    scored = ", ".join(f"`{m}`" for m in sorted(methods))
    how = "--shipped" if methods == {"shipped"} else "--method"
    _left_out(
        path,
        f"it scored {scored} (robustness {how}), not this run's learned policy",
        f"robustness --run {run} --out {path.parent} --overwrite",
        depth=3,
    )
    return False


def _own_results(path: Path, rows: list[dict], run: Path, again: str) -> bool:
    """Whether the results ``rows`` of ``path`` (``match.csv``, ``robustness.csv`` in
    ``run``) are this run's to report: False, with a warning naming the file and how to
    write it again (``activevision {again} {path's folder} --overwrite``), where they record
    (:data:`~activevision.training.policy_files.SCORED_RUN_COLUMNS`) another run's
    ``config.json`` or weights, or this run's before they were replaced (trained on,
    retrained with ``--overwrite``): the report showed them as this run's. The report is
    still written, without them (a quickstart resumed after ``robustness --run`` ended on a
    refusal). Results that played no run (a match without ``--run``: the handwritten
    strategies, which this run's weights do not change) and files from before the record
    are reported as before."""
    recorded = {tuple(row.get(column) or "" for column in SCORED_RUN_COLUMNS) for row in rows}
    if recorded == {("", "", "")}:
        return True
    config_sha256, weights_sha256, weights = recorded.pop()
    if recorded or weights not in ("final", "best"):  # rows of two runs, or no weights named
        raise ValueError(
            f"{path} is damaged or not a file activevision wrote (its run columns"
            f" {', '.join(SCORED_RUN_COLUMNS)} are not one run's)"
        )
    recorded_digests = {"config_sha256": config_sha256, "weights_sha256": weights_sha256}
    current = {key: digest or "" for key, digest in scored_run(run, weights).items()}
    stale = stale_parts(current, recorded_digests)
    if not stale:
        return True
    best = " --weights best" if weights == "best" else ""
    _left_out(
        path,
        f"it scored another run's {' and '.join(stale)}, {ANOTHER_RUN}",
        f"{again} {path.parent}{best} --overwrite",
        depth=3,
    )
    return False


def _evaluation_part(data: dict, latency: dict | None) -> list[str]:
    """The report's evaluation section, from ``evaluation.json``'s ``data`` and the
    learned policy's measured ``latency`` (``latency.json``), if any."""
    # null: no value (an interval of one episode), as NaN in files written before 2026-12-05
    rows = [{k: "nan" if v is None else str(v) for k, v in r.items()} for r in data["methods"]]
    parts = [
        "",
        "## Evaluation",
        "",
        f"{data['episodes']} episodes, seed {data['seed']}, identical starts for every "
        f"method{_error_text(rows)}; mean [95% confidence interval]." + _weights_text(data, rows),
        "",
        _table(rows, ["success", "success_rate", "success_duration", "ball_loss_duration"]),
        "",
        "success: the share of episodes that reach the goal view; success_rate: the"
        " paper's |observed ∩ desired| / |desired| landmarks at the end; success_duration:"
        " steps to success, ball_loss_duration: steps until the ball was lost (20 if"
        " never, as the paper counts).",
        "",
        _table(rows, ["entropy_regret", "regret_within", "oscillating"]),
        "",
        "Entropy regret: the belief's entropy after the final view's landmarks minus the"
        " goal view's (nats); regret_within: the share of episodes within 0.25 nats;"
        " oscillating: unsolved episodes that end swinging between two views.",
        "",
        # head travel (degrees per episode): evaluations written before it lack it
        _table(rows, [m for m in ("reward", "score", "head_travel") if m in rows[0]]),
        "",
        "reward: the episode's total; score: the authors' release's (1 success, 0 ball"
        " lost, else success_rate); head_travel: degrees the head moved in the episode.",
    ]
    if latency:
        lat = latency
        parts += [
            "",
            f"Learned policy, batch 1 on CPU (PyTorch): p50 {lat['p50_ms']:.2f} ms, "
            f"p99 {lat['p99_ms']:.2f} ms; the paper: 2.3 ms on a GTX 1060.",
        ]
    return parts


def _match_part(match_rows: list[dict], run: Path) -> list[str]:
    """The report's section on whole matches, from ``match.csv``'s rows (of ``run``)."""
    first = match_rows[0]
    return [
        "",
        "## Head control through whole matches",
        "",
        f"`ActiveVisionMatch-v0`: {counted(first['matches'], 'match')}"
        + (f" of {counted(first['ticks'], 'tick')}" if first.get("ticks") else "")
        + f" from seed {first['seed']}, the"
        " same for every strategy; the robot walks, the ball is kicked about, the UKF"
        f" tracks every tick{_match_world_text(first)}. Mean [95% interval] over matches.",
        "",
        _table(match_rows, ["position_rmse", "heading_rmse", "lost_share"]),
        "",
        _table(match_rows, ["ball_in_view", "entropy", "head_travel"]),
        "",
        "position_rmse (m) and heading_rmse (degrees): the belief's error over every"
        " tick; lost_share, ball_in_view: shares of ticks; entropy: the belief's mean"
        " (nats); head_travel: degrees per second."
        f" {_match_policies_text(match_rows, run)}",
        "",
        "![Pareto front](match/match_pareto.png)",
        "",
        "![error over time](match/match_error.png)",
        "",
        "Animated: [match_clip.gif](match/match_clip.gif)",
    ]


def _robustness_part(rows: list[dict], figure: Path) -> list[str]:
    """The report's section on the robustness suite (``activevision robustness --run``,
    written in the run's ``robustness/``), from ``robustness.csv``'s rows."""
    first = rows[0]

    def percent(row: dict, metric: str) -> str:
        ends = (float(row[metric + end]) for end in ("", "_low", "_high"))
        mean, low, high = (f"{100 * v:.1f}" for v in ends)
        return f"{mean} [{low}, {high}]"

    def change(row: dict, metric: str) -> str:
        return f"{-float(row[f'{metric}_drop_pts']):+z.1f}"  # z: no -0.0

    lines = [
        "| perturbation | setting | in its training | success rate % | change | goal"
        " reached % | change |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        trained = "yes" if r["in_training_range"] == "True" else "no"
        lines.append(
            f"| {r['name']} | {r['setting']} | {trained} | {percent(r, 'success_rate')} |"
            f" {change(r, 'success_rate')} | {percent(r, 'goal_reached')} |"
            f" {change(r, 'goal_reached')} |"
        )
    parts = [
        "",
        "## Robustness",
        "",
        f"`{first['method']}` on {first['n']} fixed-seed episodes a row from seed"
        f" {first['seed']}, localisation error {_float_text(first['error'])}: each"
        " perturbation against the row `clean` (the policy's own training world), in"
        " points. Mean [95% interval].",
        "",
        "\n".join(lines),
    ]
    if figure.exists():
        parts += ["", "![robustness](robustness/robustness.png)"]
    return parts


def _float_text(value: str) -> str:
    return f"{float(value):g}"


def _is_number(value: str) -> bool:
    try:
        float(value)
    except (TypeError, ValueError):
        return False
    return True


#: ``metrics.csv`` columns that count something (written as integers)
_COUNTS = ("epoch", "step", "episodes", "updates")
#: the learners that write no exploration epsilon or PER beta (those columns hold 0)
_NO_EXPLORATION = ("sac", "td3", "ppo")


def _last_epoch(row: dict, algo: str) -> str:
    """``metrics.csv``'s last row as text: counts as integers, no column that was not
    measured (NaN: a match has no success), and ``epsilon`` named for what it is (a DAgger
    run's is the teacher's share; an SB3 learner's and DAgger's ``beta`` are unused 0s)."""
    cells = []
    for key, value in row.items():
        if not _is_number(value) or not math.isfinite(float(value)):
            continue
        unused = key == "beta" and algo != "ddqn"
        if unused or (key == "epsilon" and algo in _NO_EXPLORATION):
            continue
        name = "teacher's share" if key == "epsilon" and algo == "dagger" else key
        number = float(value)
        text = f"{number:.0f}" if key in _COUNTS and number.is_integer() else f"{number:.4g}"
        cells.append(f"{name} {text}")
    return ", ".join(cells)


def _weights_text(data: dict, rows: list[dict[str, str]]) -> str:
    """Which weights the run's ``learned`` row played (evaluations before the record: none
    said)."""
    if "weights" not in data or not any(r.get("method") == "learned" for r in rows):
        return ""
    return f" `learned` plays the run's {weights_words(data['weights'])} weights."


def _error_text(rows: list[dict]) -> str:
    """``", localisation error 1 m and rad"`` (the entropy methods' belief and a learned
    policy's prior pose that far off), or ``", exact localisation"``."""
    errors = {float(r["error"]) for r in rows if _is_number(r.get("error", ""))}
    if not errors:
        return ""
    if errors == {0.0}:
        return ", exact localisation (error 0)"
    return ", localisation error " + "/".join(f"{e:g}" for e in sorted(errors)) + " m and rad"


def _match_world_text(row: dict) -> str:
    """The world ``match.csv``'s row records: the head's moves, the other robots and the
    detector, then the walk, the other robots' speed, the ball... where they differ from
    the default world (``experiments.match_world.WORLD_COLUMNS``; ``""`` for a file written
    before it recorded the world, nothing more for one written before those columns)."""
    from activevision.experiments.match_world import world_differences

    if not row.get("false_detections"):
        return ""
    robots = row["robots"]
    text = (
        f"; {row['action_type']} head moves of up to {float(row['step_deg']):g} degrees a"
        f" tick, {'no' if robots == '0' else robots} other robot{'' if robots == '1' else 's'},"
        f" a landmark in view detected with probability {float(row['detect_near']):g} next"
        f" to the robot falling to {float(row['detect_far']):g} at its detection range, and"
        f" {float(row['false_detections']):g} false detections per tick"
    )
    differences = world_differences(row)
    if differences:
        text += "; unlike the default world: " + ", ".join(differences)
    return text


def _match_policies_text(rows: list[dict], run: Path) -> str:
    """What ``onnx_policy`` and ``learned`` are, and whether a training run's own network
    played (``match.csv`` records the run, :func:`_own_results` checked it is this one, and,
    with ``match --model``, which model each ``onnx_policy`` row played)."""
    methods = [r["method"] for r in rows]
    text = []
    models = [r for r in rows if r.get("model")]  # match --model: each one's file and digest
    if models:
        text += [_model_text(r, run) for r in models]
    elif any(m.startswith("onnx_policy") for m in methods):
        text.append(
            "onnx_policy: an exported policy, the package's shipped one unless `match"
            " --model` named another."
        )
    weights = rows[0].get("run_weights")
    if "learned" in methods and weights:  # recorded: this run's, as it is (_own_results)
        text.append(f"learned: this run's {weights_words(weights)} weights (`match --run`).")
    elif "learned" in methods:  # a file from before the record
        text.append("learned: the training run `match --run` named.")
    else:
        text.append(
            "There is no `learned` row: `match --run RUN` adds one (a match student or an"
            " image DDQN run); an exported policy plays as onnx_policy with `match --model"
            " RUN/policy.onnx`."
        )
    return " ".join(text)


def _model_text(row: dict, run: Path) -> str:
    """What model a ``match --model`` row played: the file as given, its digest's first 12
    digits, and whether that is ``run``'s ``policy.onnx`` as it is now (a model exported
    again since, or another's, is said to be not), exported from the run's weights as they
    are now (:func:`~activevision.experiments.provenance.run_export`: one exported before
    the run was trained on or retrained is said to be not its policy as it is now)."""
    digest = row["model_sha256"]
    export = run_export(run, digest)
    whose = "not this run's policy.onnx as it is now" if export is None else export.text()
    return f"{row['method']}: `{row['model']}` (`match --model`, SHA-256 {digest[:12]}…, {whose})."
