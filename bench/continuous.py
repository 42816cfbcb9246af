"""Discrete against continuous head control on the same fixed-seed episodes: success rate,
goal reached, steps to success on the episodes every policy solves, and head travel.

    python bench/continuous.py --runs runs/dagger_head runs/dagger_head_continuous \\
        runs/sac_head runs/ppo_head --episodes 1000 --figure docs/figures/continuous_steps.png

Every run is played as ``activevision evaluate --runs`` plays it (the first run's env, the
paper's discrete actions; a continuous policy moves by head targets; a run that observes
what that env does not give is refused), together with the oracle (the 3-degree greedy
moves to the true goal). Test episodes are seed 0's, which no training or validation used.
Ends with one JSON line: per policy the figures, and the median steps of the best continuous
policy over the best discrete one (the issue's target: at most 0.7, at equal or better
success rate).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import torch

from activevision.cli.args import (
    ArgumentParser,
    env_config_of_run,
    positive_int,
    refused_by,
    seed,
)
from activevision.envs import ActiveVisionEnv
from activevision.envs.observations import play_differences
from activevision.experiments.evaluate import evaluate_policy, paired_steps
from activevision.experiments.policies import LearnedPolicy, OraclePolicy
from activevision.training import load_config


def main() -> None:
    parser = ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=Path, nargs="+", required=True)
    parser.add_argument("--episodes", type=positive_int, default=1000)
    parser.add_argument("--seed", type=seed, default=0)
    parser.add_argument("--figure", type=Path, help="write the steps histogram here (PNG)")
    args = parser.parse_args()
    for run in args.runs:
        if not (run / "config.json").is_file():
            parser.error(f"--runs {run}: not a training run (no config.json)")
    names = [run.name for run in args.runs] + ["oracle"]
    if len(set(names)) < len(names):  # a policy is known by its run's folder name
        parser.error(f"--runs: two policies named alike ({', '.join(names)}): rename a folder")
    torch.set_num_threads(1)

    kinds: dict[str, str] = {}
    policies = {}
    with refused_by(parser, "--runs"):  # a config or weights file truncated, garbage...
        # the first run's env, with its discrete moves (the oracle's, a discrete run's); the
        # paper's beside a continuous run, which never reads its step_deg and action_set
        env_config = env_config_of_run(args.runs[0])
        for run in args.runs:
            other = load_config(run / "config.json").env
            continuous = other.action_type == "continuous"
            differences = play_differences(other, env_config, moves_by_target=continuous)
            if differences:  # it would fail mid-evaluation, or play another policy
                parser.error(
                    f"--runs {run} was trained on {'; '.join(differences)} in the first run's"
                    " env: compare runs trained on the same inputs, camera and moves"
                )
            kinds[run.name] = other.action_type
            policies[run.name] = LearnedPolicy.from_run(run)
    env = ActiveVisionEnv(env_config)
    policies["oracle"] = OraclePolicy(env_config)
    kinds["oracle"] = "discrete"

    episodes, summaries = [], {}
    for name, policy in policies.items():
        records, summary, _ = evaluate_policy(policy, args.episodes, args.seed, env=env)
        episodes += [{"method": name, **r} for r in records]
        summaries[name] = summary
    learned = [name for name in policies if name != "oracle"]

    def best(kind: str) -> str | None:
        names = [n for n in learned if kinds[n] == kind]
        return max(names, key=lambda n: summaries[n]["success_rate"].mean) if names else None

    # the figure: the best of each kind (and the oracle) on the episodes all three solve;
    # every policy also on the episodes it solves itself
    discrete, continuous = best("discrete"), best("continuous")
    pair = [n for n in (discrete, continuous) if n is not None] + ["oracle"]
    paired = paired_steps(episodes, pair)
    own = {name: paired_steps(episodes, [name])[name] for name in policies}

    print(f"{args.episodes} test episodes from seed {args.seed}; paired: the")
    print(f"{paired['episodes']} episodes that {', '.join(pair)} all solve")
    print(
        f"{'policy':26s} {'actions':>10s} {'success rate':>13s} {'goal reached':>13s}"
        f" {'steps, own':>11s} {'steps, paired':>14s} {'travel':>8s} {'travel, paired':>15s}"
    )
    record: dict[str, object] = {"episodes": args.episodes, "paired": paired["episodes"]}
    for name in policies:
        s, mine = summaries[name], paired.get(name, {})
        print(
            f"{name:26s} {kinds[name]:>10s} {100 * s['success_rate'].mean:12.1f}%"
            f" {100 * s['success'].mean:12.1f}% {cell(own[name]['median'], '{:11g}')}"
            f" {cell(mine.get('median', math.nan), '{:14g}')} {s['head_travel'].mean:7.1f}°"
            f" {cell(mine.get('head_travel', math.nan), '{:14.1f}°')}"
        )
        record[name] = {
            "actions": kinds[name],
            "success_rate": s["success_rate"].mean,
            "success_rate_ci": [s["success_rate"].low, s["success_rate"].high],
            "goal_reached": s["success"].mean,
            "goal_reached_ci": [s["success"].low, s["success"].high],
            "median_steps_own": own[name]["median"],
            "median_steps_paired": mine.get("median"),
            "head_travel_deg": s["head_travel"].mean,
            "head_travel_paired_deg": mine.get("head_travel"),
        }

    if discrete and continuous:
        equal_or_better = (
            summaries[continuous]["success_rate"].mean >= summaries[discrete]["success_rate"].mean
        )
        # no paired episode: no ratio (JSON null, as strict JSON has no NaN)
        ratio = (
            paired[continuous]["median"] / paired[discrete]["median"]
            if paired["episodes"]
            else None
        )
        shown = (
            f"x{ratio:.2f}"
            if ratio is not None
            else f"undefined (none that {', '.join(pair)} all solve)"
        )
        print(
            f"best continuous ({continuous}) over best discrete ({discrete}): median steps"
            f" {shown} (target <= 0.70), success rate"
            f" {'equal or better' if equal_or_better else 'lower'}"
        )
        record["steps_ratio"] = ratio
        record["target_met"] = bool(ratio is not None and ratio <= 0.7 and equal_or_better)
    if args.figure is not None:
        plot(episodes, pair, kinds, paired["episodes"], args.figure)
        print(f"wrote {args.figure}")
    print(json.dumps(finite(record), allow_nan=False))


def finite(value):
    """``value`` with every NaN (a median or mean over no episodes) as None: JSON null."""
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [finite(v) for v in value]
    if isinstance(value, float) and math.isnan(value):
        return None
    return value


def cell(value: float, spec: str) -> str:
    """A table cell: ``value`` formatted by ``spec``, or "-" as wide where it is NaN (a
    median or mean over no episodes read "nan°")."""
    text = spec.format(value)
    return f"{'-':>{len(text)}s}" if math.isnan(value) else text


def plot(episodes, names, kinds, n_paired, path: Path) -> None:
    """Steps to success on the episodes every policy solves, one histogram per policy."""
    solved = {n: {} for n in names}
    for r in episodes:
        if r["success"] and r["method"] in solved:
            solved[r["method"]][r["seed"]] = r["success_duration"]
    common = set.intersection(*(set(s) for s in solved.values()))
    fig, ax = plt.subplots(figsize=(7, 3.6))
    bins = np.arange(0.5, 21.5, 1.0)
    for name in names:
        steps = [solved[name][s] for s in common]
        style = "-" if kinds[name] == "continuous" else "--"
        ax.hist(steps, bins=bins, histtype="step", linewidth=1.8, linestyle=style, label=name)
    ax.set_xlabel("steps to the goal view")
    ax.set_ylabel("episodes")
    ax.set_title(f"steps to the goal view on the {n_paired} test episodes all three solve")
    if not common:  # three empty histograms on a y axis around 0: say why instead
        ax.set_ylim(0, 1)
        ax.text(
            0.5,
            0.5,
            f"no test episode that {', '.join(names[:-1])} and {names[-1]} all solve",
            ha="center",
            va="center",
            transform=ax.transAxes,
        )
    ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    main()
