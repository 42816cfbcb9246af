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
from collections.abc import Callable, Collection, Iterator, Sequence
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
    Wilson's interval; the README says so beside its table.)"""
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


def _float_text(value: str) -> str:
    return f"{float(value):g}"


@dataclass(frozen=True)
class WorldColumn:
    """A ``match.csv`` column recording one setting of the world the strategies were scored
    in: ``read`` takes it from the MatchConfig, ``meaning`` says what it is (and its unit),
    ``phrase`` words a value other than the default's for ``report.md`` (from the CSV's
    text)."""

    read: Callable[[MatchConfig], object]
    meaning: str
    phrase: Callable[[str], str]


#: ``match.csv``'s world columns after ``action_type, step_deg, robots, detect_near,
#: detect_far, false_detections`` (the head's moves, the other robots' count, the detector):
#: how our robot walks, the other robots' speed, the ball, the tick, the ball detector.
#: ``report.md`` names those that differ from ``MatchConfig()``'s.
WORLD_COLUMNS: dict[str, WorldColumn] = {
    "walk": WorldColumn(
        lambda c: c.walk.target,
        "where our robot walks: waypoints or ball (--walk; walk.target)",
        lambda v: f"our robot walking to the {v}",
    ),
    "walk_speed": WorldColumn(
        lambda c: c.walk.speed,
        "our robot's forward speed, m/s (walk.speed)",
        lambda v: f"our robot walking at {_float_text(v)} m/s",
    ),
    "turn_rate": WorldColumn(
        lambda c: c.walk.turn_rate,
        "our robot's turn rate, rad/s (walk.turn_rate)",
        lambda v: f"our robot turning at {_float_text(v)} rad/s",
    ),
    "robot_speed": WorldColumn(
        lambda c: c.others.speed,
        "the other robots' walking speed, m/s; 0: they stand (--robot-speed; others.speed)",
        lambda v: f"the other robots walking at {_float_text(v)} m/s",
    ),
    "ball_decel": WorldColumn(
        lambda c: c.ball.deceleration,
        "the ball's rolling deceleration, m/s^2 (ball.deceleration)",
        lambda v: f"the ball slowing by {_float_text(v)} m/s²",
    ),
    "kick_rate": WorldColumn(
        lambda c: c.ball.kick_rate,
        "kicks per tick (ball.kick_rate)",
        lambda v: f"{_float_text(v)} kicks per tick",
    ),
    "kick_speed": WorldColumn(
        lambda c: "-".join(f"{v:g}" for v in c.ball.kick_speed),
        "a kick's initial speed, m/s, uniform LOW-HIGH (ball.kick_speed)",
        lambda v: f"kicks of {v} m/s",
    ),
    "bounce_us": WorldColumn(
        lambda c: c.ball.bounces_off_own_robot,
        "the ball bounces off our robot too, True/False (--ball-bounces-off-us;"
        " ball.bounces_off_own_robot)",
        lambda v: (
            "the ball bouncing off our robot"
            if v == "True"
            else "the ball rolling through our robot"
        ),
    ),
    "restitution": WorldColumn(
        lambda c: c.others.ball_restitution,
        "the share of its speed towards a robot the ball keeps in a bounce"
        " (others.ball_restitution)",
        lambda v: f"the ball keeping {_float_text(v)} of its speed off a robot",
    ),
    "tick_s": WorldColumn(
        lambda c: c.tick_seconds,
        "seconds a tick (tick_seconds)",
        lambda v: f"ticks of {_float_text(v)} s",
    ),
    "ball_noise": WorldColumn(
        lambda c: c.detection.ball_noise,
        "the ball detector's noise, a fraction of the ball's range (detection.ball_noise)",
        lambda v: f"ball detections off by {_float_text(v)} of their range",
    ),
    # the camera: a run trained for a robot's own plays its matches through it
    "camera_px": WorldColumn(
        lambda c: f"{c.camera.width}x{c.camera.height}",
        "the camera's image, WIDTHxHEIGHT px (camera.width, camera.height)",
        lambda v: f"a {v} px camera",
    ),
    "hfov_deg": WorldColumn(
        lambda c: round(math.degrees(c.camera.hfov), 4),
        "the camera's horizontal field of view, degrees (camera.hfov, in rad)",
        lambda v: f"a {_float_text(v)}° field of view",
    ),
    "camera_height": WorldColumn(
        lambda c: c.camera.camera_height,
        "the camera's height above the carpet, m (camera.camera_height)",
        lambda v: f"the camera {_float_text(v)} m high",
    ),
    "head_range_deg": WorldColumn(
        lambda c: " ".join(
            f"{math.degrees(low):.4g}..{math.degrees(high):.4g}"
            for low, high in (
                (c.camera.pan_min, c.camera.pan_max),
                (c.camera.tilt_min, c.camera.tilt_max),
            )
        ),
        "the head's pan and tilt ranges, degrees, PAN_LOW..PAN_HIGH TILT_LOW..TILT_HIGH"
        " (camera.pan_min ... camera.tilt_max, in rad)",
        lambda v: f"the head panning {v.split()[0]}° and tilting {v.split()[-1]}°",
    ),
}


#: the MatchConfig fields that ``match.csv``'s other columns record (``camera.*`` and
#: ``kidnap.*`` too)
_RECORDED = frozenset(
    {
        "ticks",
        "action_type",
        "step_deg",
        "max_move_deg",
        "robots.count",
        "detection.near",
        "detection.far",
        "detection.false_rate",
        "detection.ball_noise",
        "walk.target",
        "walk.speed",
        "walk.turn_rate",
        "others.speed",
        "others.ball_restitution",
        "ball.deceleration",
        "ball.kick_rate",
        "ball.kick_speed",
        "ball.bounces_off_own_robot",
        "tick_seconds",
    }
)


def other_settings(config: MatchConfig) -> str:
    """The fields of ``config`` that differ from ``MatchConfig()``'s and that no other
    ``match.csv`` column records, as ``activevision match --set`` takes them
    (``tracker.gate=9.21 walk.reach=0.5``; values JSON); empty where there are none."""
    import json

    from activevision.typecheck import config_to_dict

    def leaves(values: dict[str, object], prefix: str = "") -> dict[str, object]:
        flat: dict[str, object] = {}
        for key, value in values.items():
            if isinstance(value, dict):
                flat.update(leaves(value, f"{prefix}{key}."))
            else:
                flat[f"{prefix}{key}"] = value
        return flat

    mine, default = leaves(config_to_dict(config)), leaves(config_to_dict(MatchConfig()))
    return " ".join(
        f"{path}={json.dumps(value, separators=(',', ':'))}"
        for path, value in mine.items()
        if value != default[path]
        and path not in _RECORDED
        and not path.startswith(("camera.", "kidnap."))
    )


def world_columns(config: MatchConfig) -> dict[str, object]:
    """``match.csv``'s world columns of ``config``: the head's moves, the other robots, the
    detector, then :data:`WORLD_COLUMNS`, then ``settings`` (:func:`other_settings`) where
    there are any (a default world's file has no such column)."""
    settings = other_settings(config)
    return {
        "action_type": config.action_type,
        "step_deg": (  # the most the head moves per tick and axis
            config.step_deg if config.action_type == "discrete" else max(config.max_move_deg)
        ),
        "robots": "-".join(str(n) for n in sorted(set(config.robots.count))),
        "detect_near": config.detection.near,
        "detect_far": config.detection.far,
        "false_detections": config.detection.false_rate,
        **{name: column.read(config) for name, column in WORLD_COLUMNS.items()},
        **({"settings": settings} if settings else {}),
        **(kidnap_columns(config) if config.kidnap.enabled else {}),
    }


def kidnap_columns(config: MatchConfig) -> dict[str, object]:
    """``match.csv``'s record of the kidnapping (``MatchConfig.kidnap``), written where it
    is on: per minute, the ticks named, how far (m, LOW-HIGH) and how much it turns (rad)."""
    kidnap = config.kidnap
    return {
        "kidnap_rate": kidnap.rate,
        "kidnap_ticks": " ".join(str(t) for t in kidnap.ticks),
        "kidnap_distance": "-".join(f"{v:g}" for v in kidnap.distance),
        "kidnap_turn": kidnap.turn,
    }


def kidnap_text(config: MatchConfig) -> str:
    """The kidnapping in words: ``"kidnapped 1/min and in tick 200, carried 1-2 m, turned up
    to 0.8 rad"``; empty where it is off."""
    kidnap = config.kidnap
    if not kidnap.enabled:
        return ""
    when = [f"{kidnap.rate:g}/min"] if kidnap.rate else []
    if kidnap.ticks:
        ticks = ", ".join(str(t) for t in kidnap.ticks)
        when.append(f"in tick{'s' if len(kidnap.ticks) > 1 else ''} {ticks}")
    low, high = kidnap.distance
    return (
        f"kidnapped {' and '.join(when)}, carried {low:g}-{high:g} m, turned up to"
        f" {kidnap.turn:g} rad"
    )


def world_differences(row: dict[str, str]) -> list[str]:
    """The phrases of a ``match.csv`` row's :data:`WORLD_COLUMNS` whose value is not the
    default world's (``MatchConfig()``), in column order; none for a file written before
    they were recorded."""
    defaults = world_columns(MatchConfig())
    phrases = []
    for name, column in WORLD_COLUMNS.items():
        value = row.get(name)
        if value is None or value == "" or _same_text(value, str(defaults[name])):
            continue
        phrases.append(column.phrase(value))
    if row.get("settings"):
        phrases.append(f"--set {row['settings']}")
    if row.get("kidnap_rate") not in (None, ""):
        ticks = row.get("kidnap_ticks") or ""
        when = [f"{_float_text(row['kidnap_rate'])}/min"] if float(row["kidnap_rate"]) else []
        when += [f"in ticks {ticks}"] if ticks else []
        phrases.append(
            f"our robot kidnapped {' and '.join(when)}, carried {row.get('kidnap_distance')} m,"
            f" turned up to {_float_text(row.get('kidnap_turn') or '0')} rad"
        )
    return phrases


def _same_text(a: str, b: str) -> bool:
    """Two CSV cells alike: equal numbers (``0.20`` and ``0.2``), else equal text."""
    try:
        return float(a) == float(b)
    except ValueError:
        return a == b


def csv_rows(
    results: Sequence[MethodResult], matches: int, seed: int, config: MatchConfig
) -> list[dict]:
    """One CSV row per method: every metric's mean, low and high, plus the run's facts and
    the world's (:func:`world_columns`: the head's move, the other robots, the detector, the
    walk, the ball: what the report names).

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
        rows.append(row)
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
    differences: dict[str, dict[str, Interval]], baseline: str, matches: int, seed: int
) -> list[dict]:
    """One CSV row per method: every metric's paired difference from ``baseline``."""
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
        rows.append(row)
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
