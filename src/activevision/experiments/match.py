"""Play head-control strategies through whole matches on the same seeds and measure what a
RoboCup team cares about (``activevision match``).

Per match (:mod:`activevision.envs.match.scores`), then mean and 95% interval over
matches: position and heading RMSE, the share of ticks lost (error above 0.5 m) and with the
ball in view, the mean entropy and the head's travel; every interval, shares' too, is the
normal approximation from the spread over matches (:func:`match_interval`).

Match ``i`` of every method is reset with seed ``seed + i``: the same start, ball and walk
draws. Strategies only change where the head looks, and so what is detected. So two methods
are best compared match by match: :func:`paired_differences` gives each metric's mean
difference from a baseline with the 95% interval of the per-match differences, which is
far narrower than either method's own interval when the matches' difficulty varies more
than the methods do.
"""

from __future__ import annotations

import contextlib
import math
import numbers
import time
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from activevision.envs.config import MAX_VECTOR_ENVS, check_count
from activevision.envs.match.config import MatchConfig
from activevision.envs.match.scores import LOST_M, KidnapEvents, MatchScores
from activevision.envs.match.vector import ActiveVisionMatchVectorEnv
from activevision.envs.seeding import check_seed
from activevision.experiments.evaluate import Interval, mean_interval, wilson_interval
from activevision.experiments.match_methods import (
    USER_STRATEGY,
    StrategyFactory,
    StrategyOptions,
    make_match_policy,
    user_errors,
)
from activevision.experiments.match_world import world_columns
from activevision.io import file_sha256

#: per-match metrics, in table order: name -> (column header, format)
MATCH_METRICS = {
    "position_rmse": ("pos RMSE m", "{:.3f}"),
    "heading_rmse": ("head. RMSE deg", "{:.2f}"),
    "lost_share": ("lost", "{:.1%}"),
    "ball_in_view": ("ball in view", "{:.1%}"),
    "entropy": ("entropy", "{:.2f}"),
    "head_travel": ("travel deg/s", "{:.1f}"),
}
SHARES = ("lost_share", "ball_in_view")
#: the values each per-match metric can take (entropy has no bound: a differential entropy
#: goes below 0); a metric's interval stays within them
METRIC_BOUNDS: dict[str, tuple[float, float] | None] = {
    "position_rmse": (0.0, math.inf),
    "heading_rmse": (0.0, math.inf),
    **dict.fromkeys(SHARES, (0.0, 1.0)),
    "entropy": None,
    "head_travel": (0.0, math.inf),
}


@dataclass
class MatchClip:
    """One match tick by tick, for the clip: true pose, belief, head, ball and the other
    robots."""

    pose: list[np.ndarray] = field(default_factory=list)
    mean: list[np.ndarray] = field(default_factory=list)
    cov: list[np.ndarray] = field(default_factory=list)
    head: list[np.ndarray] = field(default_factory=list)
    ball: list[np.ndarray] = field(default_factory=list)
    ball_in_view: list[bool] = field(default_factory=list)
    robots: list[np.ndarray] = field(default_factory=list)

    def add(self, info: dict[str, np.ndarray], i: int) -> None:
        self.pose.append(info["pose"][i].copy())
        self.mean.append(info["belief_mean"][i].copy())
        self.cov.append(info["belief_cov"][i].copy())
        self.head.append(info["head"][i].copy())
        self.ball.append(info["ball"][i].copy())
        self.ball_in_view.append(bool(info["ball_in_view"][i]))
        self.robots.append(info["robots"][i].copy())


@dataclass(frozen=True)
class MethodResult:
    """One method over every match."""

    method: str
    per_match: dict[str, np.ndarray]  #: metric -> (M,)
    error_curve: np.ndarray  #: (ticks, M) position error per tick and match
    clip: MatchClip
    seconds: float
    #: every kidnap and what followed it (``MatchConfig.kidnap`` on; None: off)
    kidnaps: KidnapEvents | None = None

    def summary(self) -> dict[str, Interval]:
        """Mean and 95% interval over matches of every metric (:func:`match_interval`)."""
        return {
            name: match_interval(values, METRIC_BOUNDS[name])
            for name, values in self.per_match.items()
        }


def match_interval(values: np.ndarray, bounds: tuple[float, float] | None) -> Interval:
    """The mean of per-match ``values`` and its 95% interval, by one rule for every metric,
    share or not: the normal approximation from the spread over matches, cut to ``bounds``
    (:data:`METRIC_BOUNDS`: two matches' heading RMSEs of 0.2 and 5.7 deg read [-0.05,
    5.97] unbounded). Values the same in every match (a robot never lost) show no spread:
    their interval is the value itself. (Until 2026-12-05 a share 0 in every match took the
    Wilson interval of 0 out of the matches, [0, 7.1%] over 50, while a share 0 in all but
    one took the normal one, [0, 0.2%] for a few ticks lost: more loss, a narrower
    interval. How many matches a never-lost robot vouches for is a statement about
    matches, not ticks: none of 50 lost puts the share of matches ever lost below 7.1%, by
    Wilson's interval; docs/match.md says so beside its table.)"""
    return mean_interval(values.tolist(), bounds=bounds, vouch_when_equal=False)


def play_matches(
    method: str,
    config: MatchConfig,
    matches: int,
    seed: int,
    options: StrategyOptions | None = None,
    clip_match: int = 0,
    label: str | None = None,
) -> MethodResult:
    """Play ``matches`` matches of ``config`` with strategy ``method`` in lock-step
    (``options``: its model, run or margin); the result is named ``label`` (default:
    ``method``); match ``clip_match`` is recorded tick by tick. Bad counts are refused
    before playing (:func:`check_play_arguments`; ``clip_match`` past the matches was
    numpy's IndexError)."""
    check_play_arguments(config, matches, seed)
    if (
        isinstance(clip_match, bool)
        or not isinstance(clip_match, numbers.Integral)
        or not 0 <= clip_match < matches
    ):
        raise ValueError(
            f"clip_match: expects a match's index, 0 to {matches - 1}, got {clip_match!r}"
        )
    start = time.perf_counter()
    policy = make_match_policy(method, config, options)
    env = ActiveVisionMatchVectorEnv(matches, config)
    obs, info = env.reset(seed=seed)
    name = label or method
    with users_code(method, f"strategy {name}: reset"):
        policy.reset(matches, np.random.default_rng(seed))
    scores = MatchScores(config.ticks, matches, config.tick_seconds)
    clip = MatchClip()
    clip.add(info, clip_match)
    for tick in range(config.ticks):
        with users_code(method, f"strategy {name}, tick {tick}: act"):
            actions = policy.act(obs, info)
        try:
            obs, reward, _, _, info = env.step(actions)
        except ValueError as error:
            if not str(error).startswith("invalid action"):
                raise
            raise ValueError(f"strategy {name}, tick {tick}: {error}") from None
        scores.add(info, reward)
        clip.add(info, clip_match)
    env.close()
    seconds = time.perf_counter() - start
    return MethodResult(name, scores.per_match(), scores.position, clip, seconds, scores.kidnaps())


@contextlib.contextmanager
def users_code(method: str, what: str) -> Iterator[None]:
    """Exceptions a user's strategy raises inside the block, as one line naming ``what``
    and the line of their code (:func:`user_code_error`); the package's own strategies'
    propagate as they are (a bug there deserves its traceback)."""
    if method != USER_STRATEGY:
        yield
        return
    with user_errors(what):
        yield


def model_labels(models: Sequence[Path]) -> list[str]:
    """What each exported policy plays as: ``onnx_policy`` for one model, else
    ``onnx_policy[NAME]`` with NAME its training run's folder (``runs/NAME/policy.onnx``) or
    its file name's stem, numbered where two coincide (the folder's own name, however the
    path was given: ``policy.onnx`` in the run's folder is named after it too)."""
    if len(models) <= 1:
        return ["onnx_policy"]
    folders = [Path(m).resolve().parent.name for m in models]
    names = [
        f if m.stem == "policy" and f else m.stem for m, f in zip(models, folders, strict=True)
    ]
    labels = []
    for i, name in enumerate(names):
        if names.count(name) > 1:
            name = f"{name}-{names[: i + 1].count(name)}"
        labels.append(f"onnx_policy[{name}]")
    return labels


def expand_methods(
    methods: Sequence[str],
    models: Sequence[Path] = (),
    margins: Sequence[float] = (),
    run: Path | None = None,
    weights: str = "final",
    strategies: Sequence[tuple[str, StrategyFactory]] = (),
) -> list[tuple[str, str, StrategyOptions]]:
    """``(label, method, options)`` for every result to play: ``onnx_policy`` once per
    model (:func:`model_labels`; the shipped policy when there is none), ``entropy_track``
    once per margin (``entropy_track[10deg]`` where there are several), the others once
    (``learned``: ``run``'s ``weights``), then each ``(label, factory)`` of the user's
    ``strategies`` (:func:`~activevision.experiments.match_methods.load_strategy`).
    ValueError if two results would share a label."""
    entries: list[tuple[str, str, StrategyOptions]] = []
    for name in methods:
        if name == "onnx_policy" and models:
            for label, model in zip(model_labels(models), models, strict=True):
                entries.append((label, name, StrategyOptions(model=model)))
        elif name == "entropy_track" and margins:
            for margin in margins:
                label = name if len(margins) == 1 else f"{name}[{margin:g}deg]"
                entries.append((label, name, StrategyOptions(track_margin_deg=margin)))
        else:
            entries.append((name, name, StrategyOptions(run=run, weights=weights)))
    for label, factory in strategies:
        entries.append((label, USER_STRATEGY, StrategyOptions(factory=factory)))
    check_labels(entries)
    return entries


#: the columns of ``match.csv`` that record the exported model each ``onnx_policy`` row played
#: (``match --model``): the file as given and its SHA-256, empty in the other rows. Absent
#: without ``--model``: the shipped policy plays, and those files keep their bytes.
MODEL_COLUMNS = ("model", "model_sha256")


def model_columns(
    entries: Sequence[tuple[str, str, StrategyOptions]],
) -> dict[str, dict[str, str]]:
    """:data:`MODEL_COLUMNS` per label of ``entries`` (:func:`expand_methods`), for
    :func:`csv_rows`: each model file's path as given and SHA-256 as it is now (read once
    the strategies were made, before the matches), ``""`` for the labels that play none;
    ``{}`` where no entry names a model (the shipped policy, or no ``onnx_policy``)."""
    if not any(options.model is not None for _, _, options in entries):
        return {}
    columns = {}
    for label, _, options in entries:
        model = options.model
        columns[label] = {
            "model": "" if model is None else str(model),
            "model_sha256": "" if model is None else file_sha256(model),
        }
    return columns


def check_labels(entries: Sequence[tuple[str, str, StrategyOptions]]) -> None:
    """ValueError if two results would share a label (the CSV, the tables and the figures
    tell results apart by it)."""
    labels = [label for label, _, _ in entries]
    twice = sorted({label for label in labels if labels.count(label) > 1})
    if twice:
        raise ValueError(f"two strategies are named {', '.join(twice)}: rename one")


def check_play_arguments(config: MatchConfig, matches: int, seed: int) -> None:
    """TypeError unless ``config`` is a MatchConfig (which checks its own ticks), ValueError
    naming ``matches`` unless it is a positive integer up to :data:`MAX_VECTOR_ENVS` (the
    env's own limit, by which it was refused as ``num_envs``), or ``seed`` unless it is an
    integer >= 0 (or None: fresh draws, other matches for each strategy)."""
    if not isinstance(config, MatchConfig):
        raise TypeError(f"config: expects a MatchConfig, got {type(config).__name__}")
    check_count("matches", matches, MAX_VECTOR_ENVS)
    if seed is not None:
        check_seed(seed)


#: Ticks a user's strategy plays as a trial before any strategy's matches (compare_matches).
TRIAL_TICKS = 3


def compare_matches(
    entries: Sequence[tuple[str, str, StrategyOptions]],
    config: MatchConfig,
    matches: int,
    seed: int,
    progress: Callable[[MethodResult], None] | None = None,
) -> list[MethodResult]:
    """:func:`play_matches` for each ``(label, method, options)`` of
    :func:`expand_methods`, on the same seeds. The user's strategies first play
    :data:`TRIAL_TICKS` ticks of the same matches: one that fails fails before the others
    have played (which can take minutes), not after. ValueError if two entries share a
    label (both were played, and the figures drew one of them), or for bad counts
    (:func:`check_play_arguments`), before any strategy plays."""
    check_play_arguments(config, matches, seed)
    check_labels(entries)
    trial = config.replace(ticks=min(config.ticks, TRIAL_TICKS))
    for label, name, options in entries:
        if name == USER_STRATEGY:
            play_matches(name, trial, matches, seed, options, label=label)
    results = []
    for label, name, options in entries:
        result = play_matches(name, config, matches, seed, options, label=label)
        results.append(result)
        if progress is not None:
            progress(result)
    return results


NAME_WIDTH = 18  #: the method column's width, unless a name needs more

#: what follows the kidnaps (``--kidnap``), over the kidnaps that left the robot lost: name
#: -> (column header, format)
KIDNAP_METRICS = {
    "kidnap_detected": ("lost alarm", "{:.0%}"),
    "kidnap_recovered": (f"back < {LOST_M:g} m", "{:.0%}"),
    "recovery_s": ("seconds to it", "{:.1f}"),
}


def kidnap_summary(events: KidnapEvents, tick_seconds: float) -> dict[str, Interval]:
    """What followed the kidnaps that left the robot lost (its error at least
    :data:`~activevision.envs.match.scores.LOST_M` at the end of the kidnap's tick), each
    followed until the match's next kidnap or its end: the share after which the lost
    detector fired (``kidnap_detected``) and the share after which the error came back
    under the threshold (``kidnap_recovered``), each with its 95% Wilson interval over those
    kidnaps (each counted as one trial, wherever it happened), and the seconds until it did
    (``recovery_s``, over the recovered ones: the others are left out, so a strategy that
    recovers less often can read faster; mean and normal 95% interval, at least 0). NaN
    where no kidnap left the robot lost."""
    lost = events.lost
    n = int(lost.sum())
    back = events.recovery_ticks[lost & events.recovered]
    return {
        "kidnap_detected": wilson_interval(int((events.detected & lost).sum()), n),
        "kidnap_recovered": wilson_interval(len(back), n),
        "recovery_s": mean_interval((back * tick_seconds).tolist(), bounds=(0.0, math.inf)),
    }


def kidnap_header(width: int = NAME_WIDTH) -> str:
    cols = "".join(f"{header:>22}" for header, _ in KIDNAP_METRICS.values())
    return f"{'method':<{width}}{'kidnaps (lost)':>16}{cols}"


def format_kidnaps(result: MethodResult, tick_seconds: float, width: int = NAME_WIDTH) -> str:
    """One row of the kidnap table: the kidnaps (those that left the robot lost) and each
    of :data:`KIDNAP_METRICS` with its 95% interval."""
    events = result.kidnaps
    if events is None:
        raise ValueError(f"{result.method}: its matches had no kidnapping")
    summary = kidnap_summary(events, tick_seconds)
    cells = []
    for name, (_, fmt) in KIDNAP_METRICS.items():
        iv = summary[name]
        cells.append(f"{fmt.format(iv.mean)} [{fmt.format(iv.low)},{fmt.format(iv.high)}]")
    count = f"{len(events.tick)} ({int(events.lost.sum())})"
    return f"{result.method:<{width}}{count:>16}" + _cells(cells)


def table_header(width: int = NAME_WIDTH) -> str:
    cols = "".join(f"{header:>22}" for header, _ in MATCH_METRICS.values())
    return f"{'method':<{width}}{cols}"


def _cells(cells: Sequence[str]) -> str:
    """The table's cells, each right-aligned in 22 characters and at least one space after
    the one before (a 22-character share difference ran into its neighbour:
    ``+0.0% [-39.0%,39.0%]-43.3% [-65.4%,-21.3%]``)."""
    return "".join(f" {c:>21}" for c in cells)


def format_result(result: MethodResult, width: int = NAME_WIDTH) -> str:
    """One table row: each metric's mean and 95% interval."""
    summary = result.summary()
    cells = []
    for name, (_, fmt) in MATCH_METRICS.items():
        iv = summary[name]
        cells.append(f"{fmt.format(iv.mean)} [{fmt.format(iv.low)},{fmt.format(iv.high)}]")
    return f"{result.method:<{width}}" + _cells(cells)


def csv_rows(
    results: Sequence[MethodResult],
    matches: int,
    seed: int,
    config: MatchConfig,
    scored: dict[str, str] | None = None,
    models: Mapping[str, Mapping[str, str]] | None = None,
) -> list[dict]:
    """One CSV row per method: every metric's mean, low and high, plus the run's facts and
    the world's (:func:`world_columns`: the head's move, the other robots, the detector, the
    walk, the ball: what the report names), and last, for matches that played a training
    run (``match --run``), ``scored``: its digests
    (:func:`~activevision.training.policy_files.scored_run_columns`, which ``report``
    checks against the run it reports); before them, where ``match --model`` named
    exported models, ``models``: each row's :data:`MODEL_COLUMNS` (:func:`model_columns`;
    none without, whose files keep their bytes).

    No wall-clock time: the same seed writes the same bytes (the console prints the time)."""
    rows = []
    world = world_columns(config)
    for r in results:
        ticks = r.error_curve.shape[0]
        row: dict[str, object] = {
            "method": r.method,
            "matches": matches,
            "ticks": ticks,
            "seed": seed,
            **world,
        }
        for name, iv in r.summary().items():
            row[name] = iv.mean
            row[f"{name}_low"] = iv.low
            row[f"{name}_high"] = iv.high
        if r.kidnaps is not None:  # kidnapping on: what followed (none of it otherwise)
            row["kidnaps"] = len(r.kidnaps.tick)
            row["kidnaps_lost"] = int(r.kidnaps.lost.sum())
            for name, iv in kidnap_summary(r.kidnaps, config.tick_seconds).items():
                row[name] = iv.mean
                row[f"{name}_low"] = iv.low
                row[f"{name}_high"] = iv.high
        if models:
            row |= models.get(r.method, dict.fromkeys(MODEL_COLUMNS, ""))
        rows.append(row | (scored or {}))
    return rows


def paired_differences(
    results: Sequence[MethodResult], baseline: str
) -> dict[str, dict[str, Interval]]:
    """Per method other than ``baseline``: each metric's mean difference ``method -
    baseline`` over the same matches, with the 95% interval of the per-match differences
    (:func:`match_interval`; a share's differences lie within [-1, 1]; two methods that
    never differ on it read 0 [0, 0], as two that never differ on any other metric)."""
    base = next((r for r in results if r.method == baseline), None)
    if base is None:
        raise ValueError(f"the baseline {baseline!r} is not among the methods played")
    return {
        r.method: {
            name: match_interval(
                values - base.per_match[name], (-1.0, 1.0) if name in SHARES else None
            )
            for name, values in r.per_match.items()
        }
        for r in results
        if r.method != baseline
    }


def format_difference(
    method: str, differences: dict[str, Interval], width: int = NAME_WIDTH
) -> str:
    """One row of the paired table: each metric's difference and its 95% interval."""
    cells = []
    for name, (_, fmt) in MATCH_METRICS.items():
        iv = differences[name]
        # "z": a difference that rounds to zero reads 0, not -0.000
        signed, bound = fmt.replace("{:", "{:+z"), fmt.replace("{:", "{:z")
        cells.append(f"{signed.format(iv.mean)} [{bound.format(iv.low)},{bound.format(iv.high)}]")
    return f"{method:<{width}}" + _cells(cells)


def paired_rows(
    differences: dict[str, dict[str, Interval]],
    baseline: str,
    matches: int,
    seed: int,
    models: Mapping[str, Mapping[str, str]] | None = None,
    scored: dict[str, str] | None = None,
) -> list[dict]:
    """One CSV row per method: every metric's paired difference from ``baseline``; then,
    where ``match --model`` named exported models, ``models`` (:func:`model_columns`): the
    row's :data:`MODEL_COLUMNS` and the baseline's (``baseline_model``,
    ``baseline_model_sha256``); and last, for matches that played a training run, ``scored``:
    its digests. Each as ``match.csv`` records them (none without, whose files keep their
    bytes)."""
    none = dict.fromkeys(MODEL_COLUMNS, "")
    rows = []
    for method, metrics in differences.items():
        row: dict[str, object] = {
            "method": method,
            "baseline": baseline,
            "matches": matches,
            "seed": seed,
        }
        for name, iv in metrics.items():
            row[f"{name}_diff"] = iv.mean
            row[f"{name}_diff_low"] = iv.low
            row[f"{name}_diff_high"] = iv.high
        if models:
            row |= models.get(method, none)
            row |= {f"baseline_{k}": v for k, v in models.get(baseline, none).items()}
        rows.append(row | (scored or {}))
    return rows


def pareto_front(results: Sequence[MethodResult], references: Collection[str] = ()) -> list[str]:
    """The methods no other beats on both position RMSE (lower) and ball in view (higher);
    ``references`` (privileged methods) neither join nor beat anyone."""
    points = {
        r.method: (r.per_match["position_rmse"].mean(), r.per_match["ball_in_view"].mean())
        for r in results
        if r.method not in references
    }
    front = []
    for name, (rmse, ball) in points.items():
        dominated = any(
            (o_rmse <= rmse and o_ball >= ball) and (o_rmse < rmse or o_ball > ball)
            for other, (o_rmse, o_ball) in points.items()
            if other != name
        )
        if not dominated:
            front.append(name)
    return front
