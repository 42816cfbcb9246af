"""Score head-control methods on identical episodes, with 95% confidence intervals."""

from __future__ import annotations

import math
import time
from collections.abc import Collection, Mapping, Sequence, Set
from dataclasses import dataclass
from typing import Any

import numpy as np

from activevision.envs import ActiveVisionEnv, EnvConfig
from activevision.envs.config import check_count
from activevision.envs.seeding import EPISODES_PER_SEED, check_seed, episode_seed
from activevision.experiments.policies import HeadPolicy, HeadTarget

Z95 = 1.959963984540054  #: two-sided 95% quantile of the standard normal

#: Per-episode metrics: name -> (info key or None, kind). "proportion" gets a Wilson
#: interval, "mean" a normal-approximation interval (n >= 30 in every default use).
METRICS = {
    "success": "proportion",  #: episode ended in success
    "success_rate": "mean",  #: the paper's |observed ∩ desired| / |desired| at the end
    "success_duration": "mean",  #: steps to success, 20 if never (paper)
    "ball_loss_duration": "mean",  #: steps until the ball was lost, 20 if never (paper)
    "reward": "mean",  #: total episode reward
    "score": "mean",  #: the release's score: 1 success, 0 ball lost, else success rate
    #: belief entropy after the final view's landmarks minus the goal view's (nats)
    "entropy_regret": "mean",
    "regret_within": "proportion",  #: entropy regret <= REGRET_TOLERANCE
    "oscillating": "proportion",  #: ended, unsolved, swinging between two views
    "head_travel": "mean",  #: degrees the head moved over the episode (pan-tilt Euclidean)
}
#: The "mean" metrics that are shares of something, whose intervals stay within these bounds.
SHARE_BOUNDS = {"success_rate": (0.0, 1.0), "score": (0.0, 1.0)}
#: The "mean" metrics counted in steps, within 0 and the episode's time limit.
DURATIONS = ("success_duration", "ball_loss_duration")
#: nats: a final view this close to the goal view's entropy counts as good as the goal
REGRET_TOLERANCE = 0.25


@dataclass(frozen=True)
class Interval:
    mean: float
    low: float
    high: float


def wilson_interval(successes: int, n: int, z: float = Z95) -> Interval:
    """Wilson score interval of a binomial proportion (good also near 0 and 1). It holds the
    proportion itself: at 0 or 1 of ``n`` the end that is exactly 0 or 1 in theory comes out
    a rounding error past the proportion (0/3: low 5.6e-17; 10/10: high 1 - 1.1e-16), which
    broke every whisker drawn from the pair (matplotlib refuses negative error bars).
    ValueError unless ``n >= 0`` and ``0 <= successes <= n`` (7 of 5 was a "math domain
    error", 1 of -1 a proportion of -1)."""
    if not n >= 0:
        raise ValueError(f"wilson_interval: n expects a count (>= 0), got {n!r}")
    if not 0 <= successes <= n:
        raise ValueError(f"wilson_interval: successes expects 0 to n ({n}), got {successes!r}")
    if n == 0:
        return Interval(math.nan, math.nan, math.nan)
    p = successes / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return Interval(p, max(0.0, min(p, centre - half)), min(1.0, max(p, centre + half)))


def _check_collection(name: str, of: str, values: object) -> None:
    """TypeError naming ``name`` and the type of ``values`` unless it is a sized collection
    of ``of`` (a list, tuple, array, ...): an iterator is read once (numpy saw one object in
    a generator, :func:`summarise` saw it empty after its first metric), a set drops
    repeated values, a dict is its keys and a string its letters."""
    if not isinstance(values, Collection) or isinstance(values, str | bytes | Mapping | Set):
        raise TypeError(f"{name} expects a sequence of {of}, got {type(values).__name__}")


def mean_interval(
    values: Sequence[float],
    z: float = Z95,
    bounds: tuple[float, float] | None = None,
    *,
    vouch_when_equal: bool = True,
) -> Interval:
    """Mean +- z standard errors (sample standard deviation, ddof=1), cut to ``bounds``
    where the values cannot leave them (a share: (0, 1)). One value has no interval (NaN
    ends: one sample says nothing of the spread).

    Values all equal (an oracle's success rate of 1 in every episode, no match ever lost,
    two methods that never differ) have no spread to estimate the error from, and the normal
    approximation would claim a certain mean (a zero-width interval). With bounds, the
    interval is then what the n values can vouch for: none of them differs from the value
    ``c``, so the share of all values that do is below the Wilson upper end ``w`` of 0 out
    of n, and each lies within the bounds: ``[c - w (c - lo), c + w (hi - c)]``. At an end
    of the bounds this is the Wilson interval of n out of n (or 0 out of n) scaled to them.
    Without bounds nothing limits the spread, and the interval stays the value itself; so
    does it with ``vouch_when_equal=False`` (the match metrics: their interval is the
    spread the matches show, one rule for every value, since a share 0 in every match read
    [0, 7.1%] over 50 matches where one a match lost for a few ticks read [0, 0.2%]).

    ValueError if ``values`` is not one sequence of numbers (a table of them was read as
    one sample of every cell, n its rows), if ``bounds`` is not ``(low, high)`` with low <=
    high, or a value lies outside them (the cut interval left the mean outside it: values
    of 2 within (0, 1) read 2.0 [0.88, 1.44]) or a value is no number; TypeError naming
    the type when ``values`` is no sized collection (:func:`_check_collection`)."""
    _check_collection("mean_interval: values", "numbers", values)
    try:
        x = np.asarray(values, float)
    except (TypeError, ValueError) as error:  # "could not convert string to float: 'a'"
        raise ValueError(f"mean_interval: values expects numbers: {error}") from None
    if x.ndim != 1:
        raise ValueError(f"mean_interval: values expects a 1-D sequence, got shape {x.shape}")
    if bounds is not None:
        if not bounds[0] <= bounds[1]:
            raise ValueError(f"mean_interval: bounds expects (low, high), low <= high: {bounds}")
        outside = x[(x < bounds[0]) | (x > bounds[1])]
        if len(outside):
            raise ValueError(
                f"mean_interval: a value lies outside the bounds {bounds}: {float(outside[0])}"
            )
    if len(x) == 0:
        return Interval(math.nan, math.nan, math.nan)
    if len(x) == 1:
        return Interval(float(x[0]), math.nan, math.nan)
    finite = bounds is not None and math.isfinite(bounds[1] - bounds[0])
    if vouch_when_equal and bounds is not None and finite and np.all(x == x[0]):
        lo, hi = bounds
        c = float(x[0])
        w = wilson_interval(0, len(x), z).high
        return Interval(c, c - w * (c - lo), c + w * (hi - c))
    half = z * x.std(ddof=1) / math.sqrt(len(x))
    low, high = float(x.mean() - half), float(x.mean() + half)
    if bounds is not None:
        low, high = max(low, bounds[0]), min(high, bounds[1])
    return Interval(float(x.mean()), low, high)


def summarise(episodes: Sequence[dict], time_limit: int | None = None) -> dict[str, Interval]:
    """Mean and 95% interval of every metric over ``episodes``, each within the values it
    can take: shares within [0, 1], durations within 0 and ``time_limit`` (None: at least
    0), head travel at least 0 (the normal approximation read a ball-loss duration of
    19.75 [19.26, 20.24] in episodes of 20 steps). TypeError unless ``episodes`` is a
    sequence of dicts (a dict was "string indices must be integers"), ValueError naming the
    episode that lacks a metric (it was a bare KeyError)."""
    _check_collection("summarise: episodes", "per-episode dicts", episodes)
    for index, episode in enumerate(episodes):
        if not isinstance(episode, Mapping):
            raise TypeError(
                f"summarise: episodes[{index}] expects a dict of the episode's metrics,"
                f" got {type(episode).__name__}"
            )
        missing = [name for name in METRICS if name not in episode]
        if missing:
            raise ValueError(f"summarise: episodes[{index}] has no {', '.join(missing)}")
    bounds = {
        **SHARE_BOUNDS,
        **dict.fromkeys(DURATIONS, (0.0, math.inf if time_limit is None else float(time_limit))),
        "head_travel": (0.0, math.inf),
    }
    out = {}
    for name, kind in METRICS.items():
        values = [e[name] for e in episodes]
        if kind == "proportion":
            odd = [v for v in values if v not in (0, 1)]
            if odd:  # a NaN was "cannot convert float NaN to integer", a 2 two successes
                raise ValueError(f"{name}: expects True or False per episode, got {odd[0]!r}")
            out[name] = wilson_interval(int(sum(values)), len(values))
        else:
            try:
                out[name] = mean_interval(values, bounds=bounds.get(name))
            except ValueError as error:  # which metric
                raise ValueError(f"{name}: {error}") from None
    return out


def time_limit(env: ActiveVisionEnv) -> int:
    """``env.max_episode_steps``, the most steps an evaluated episode runs; an env made
    without a time limit (``max_episode_steps=-1``) is a ValueError."""
    if env.max_episode_steps is None:
        raise ValueError("evaluation needs an env with a time limit, got max_episode_steps=-1")
    return env.max_episode_steps


def run_episode(
    env: ActiveVisionEnv,
    policy: HeadPolicy,
    seed: int,
    max_steps: int = 20,
    latencies: list[float] | None = None,
) -> dict:
    """One episode from ``seed``; the policy's own draws come from a generator derived
    from the same seed, so results do not depend on what ran before."""
    obs, info = env.reset(seed=seed)
    policy.reset(info, np.random.default_rng([seed, 7]))
    total = 0.0
    heads = [np.array(info["head"])]
    for step in range(max_steps):
        t0 = time.perf_counter()
        action = policy.act(obs, info)
        if latencies is not None:
            latencies.append(time.perf_counter() - t0)
        try:
            if isinstance(action, HeadTarget):
                obs, reward, terminated, _, info = env.jump_head(action.pan, action.tilt)
            else:
                obs, reward, terminated, _, info = env.step(action)
        except ValueError as error:
            if isinstance(action, HeadTarget):  # jump_head refuses all but finite numbers
                problem = f"invalid action {action!r}: {error}"
            elif str(error).startswith("invalid action"):
                problem = str(error)
            else:
                raise
            # as match names the strategy and tick: which of several methods acted wrongly
            raise ValueError(f"method {policy.name}, step {step}: {problem}") from None
        total += reward
        heads.append(np.array(info["head"]))
        if terminated:
            break
    regret = env.entropy_regret()
    return {
        "seed": seed,
        "success": bool(info["success"]),
        "success_rate": float(info["success_rate"]),
        "success_duration": int(info["steps_to_success"]),
        "ball_loss_duration": int(info["ball_lost_step"]),
        "reward": total,
        "score": float(info["episode_score"]),
        "steps": int(info["step"]),
        "entropy_regret": regret,
        "regret_within": bool(regret <= REGRET_TOLERANCE),
        "oscillating": bool(not info["success"] and swinging(heads)),
        "head_travel": head_travel_deg(heads),
    }


def head_travel_deg(heads: Sequence[np.ndarray]) -> float:
    """Degrees the head moved through ``heads`` (pan, tilt rad), step by step."""
    moves = np.diff(np.asarray(heads, dtype=np.float64), axis=0)
    return float(np.degrees(np.hypot(moves[:, 0], moves[:, 1])).sum()) if len(moves) else 0.0


def swinging(heads: Sequence[np.ndarray], tol: float = 1e-9) -> bool:
    """Whether the last four head poses alternate between two distinct views (A, B, A, B):
    the policy's greedy moves undo each other."""
    if len(heads) < 4:
        return False
    a, b, c, d = heads[-4:]
    same = np.allclose(a, c, atol=tol) and np.allclose(b, d, atol=tol)
    return bool(same and not np.allclose(c, d, atol=tol))


def evaluate_policy(
    policy: HeadPolicy,
    episodes: int = 100,
    seed: int = 0,
    config: EnvConfig | None = None,
    env: ActiveVisionEnv | None = None,
    measure_latency: bool = False,
) -> tuple[list[dict], dict[str, Interval], list[float]]:
    """Run ``episodes`` fixed-seed episodes.

    Returns:
        ``(records, summary, latencies_s)``: one dict per episode, the :func:`summarise`
        intervals, and per-decision latencies (empty unless ``measure_latency``).

    ValueError unless ``episodes`` is a positive integer (-3 played none and returned NaN
    intervals) up to :data:`~activevision.envs.seeding.EPISODES_PER_SEED` (more would replay
    the next seed's episodes) and ``seed`` an integer >= 0 (-1 was Gymnasium's refusal of
    episode 0's seed, -1000003); TypeError unless ``env`` is None or an
    :class:`ActiveVisionEnv` (not one wrapped by ``gymnasium.make``).
    """
    episodes = check_count("episodes", episodes, EPISODES_PER_SEED)
    seed = check_seed(seed)  # an int: a NumPy integer's episode seeds would overflow
    if env is not None and not isinstance(env, ActiveVisionEnv):
        # gymnasium.make's env (TimeLimit and any wrapper) failed on its first episode with
        # "'TimeLimit' object has no attribute 'max_episode_steps'"; unwrapping it silently
        # would drop its wrappers (a frame stack, another time limit)
        raise TypeError(
            "evaluate_policy: env expects an ActiveVisionEnv, whose episodes it plays itself"
            " (ActiveVisionEnv(config), or gymnasium.make(...).unwrapped), got"
            f" {type(env).__name__}"
        )
    env = env or ActiveVisionEnv(config or EnvConfig())
    latencies: list[float] | None = [] if measure_latency else None
    records = [
        run_episode(env, policy, episode_seed(seed, i), time_limit(env), latencies)
        for i in range(episodes)
    ]
    return records, summarise(records, time_limit(env)), latencies or []


def paired_steps(episodes: Sequence[Mapping[str, Any]], methods: Sequence[str]) -> dict[str, Any]:
    """Steps to success of ``methods`` on the episodes (seeds) that every one of them
    solves: the count, and each method's median and mean steps and mean head travel (deg).
    ``episodes``: the records of :func:`run_episode` with a ``method`` key. Comparing only
    where all succeed keeps a method that solves the easy episodes alone from looking fast."""
    solved: dict[str, dict[int, Mapping[str, Any]]] = {m: {} for m in methods}
    for record in episodes:
        if record["method"] in solved and record["success"]:
            solved[record["method"]][int(record["seed"])] = record
    common = set.intersection(*(set(s) for s in solved.values())) if methods else set()
    out: dict[str, Any] = {"episodes": len(common)}
    for m in methods:
        steps = [int(solved[m][seed]["success_duration"]) for seed in sorted(common)]
        travel = [float(solved[m][seed].get("head_travel", math.nan)) for seed in sorted(common)]
        out[m] = {
            "median": float(np.median(steps)) if steps else math.nan,
            "mean": float(np.mean(steps)) if steps else math.nan,
            "head_travel": float(np.mean(travel)) if travel else math.nan,
        }
    return out


def latency_summary(latencies_s: Sequence[float]) -> dict[str, float]:
    """p50 / p99 per-decision latency in milliseconds."""
    ms = np.asarray(latencies_s) * 1e3
    if len(ms) == 0:
        return {}
    return {"p50_ms": float(np.percentile(ms, 50)), "p99_ms": float(np.percentile(ms, 99))}


def fixed(value: float) -> str:
    """``value`` to 3 decimals, without the sign of a value that rounds to zero (a regret of
    -1e-17, float noise, printed "-0.000")."""
    text = f"{value:.3f}"
    return text[1:] if text == "-0.000" else text


def format_table(rows: dict[str, dict[str, Interval]]) -> str:
    """A plain-text table: one row per method, ``mean [low, high]`` per metric."""
    width = max([14, *(len(method) + 2 for method in rows)])  # long names keep columns aligned
    header = f"{'method':<{width}}" + "".join(f"{m:>26}" for m in METRICS)
    lines = [header, "-" * len(header)]
    for method, summary in rows.items():
        cells = "".join(
            f"{fixed(iv.mean):>10} [{fixed(iv.low):>6},{fixed(iv.high):>6}]"
            for iv in (summary[m] for m in METRICS)
        )
        lines.append(f"{method:<{width}}{cells}")
    return "\n".join(lines)


def summary_rows(rows: dict[str, dict[str, Interval]], **extra: Any) -> list[dict]:
    """Flat CSV/JSON rows: method, then ``<metric>``, ``<metric>_low``, ``<metric>_high``."""
    out = []
    for method, summary in rows.items():
        row = {**extra, "method": method}
        for m, iv in summary.items():
            row.update({m: iv.mean, f"{m}_low": iv.low, f"{m}_high": iv.high})
        out.append(row)
    return out
