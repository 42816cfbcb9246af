"""``activevision quickstart``: the README's main job (``make run``)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

from activevision.cli.args import MAX_EPISODES, MAX_MATCHES, int_in, path, positive_int, seed


def quickstart_steps(args: argparse.Namespace) -> list[list[str]]:
    """The commands the main job runs: train (or resume), evaluate, compare, episode, a short
    match comparison, report.
    A second run finds the run and redoes evaluation and figures, replacing their files."""
    from activevision.training.checkpoint import list_checkpoints

    out, run_seed, episodes = str(args.out), str(args.seed), str(args.episodes)
    if list_checkpoints(args.out):
        check_quickstart_run(args)
        steps = [["train", "--resume", out]]
    else:
        extra = ["--steps", str(args.steps)] if args.steps is not None else []
        steps = [["train", "--preset", "quickstart", "--seed", run_seed, "--out", out, *extra]]
    return [
        *steps,
        ["evaluate", "--run", out, "--episodes", episodes, "--seed", run_seed, "--overwrite"],
        ["compare", "--run", out, "--errors", "0:2:0.5", "--episodes", episodes]
        + ["--seed", run_seed, "--overwrite"],
        ["episode", "--run", out, "--seed", run_seed, "--overwrite"]
        + ["--out", str(args.out / "episode.png")],
        # a short closed-loop comparison of the head-control strategies (under a minute)
        ["match", "--matches", str(args.matches), "--ticks", str(args.match_ticks)]
        + ["--seed", run_seed]
        + ["--out", str(args.out / "match"), "--overwrite"],
        ["report", out, "--overwrite"],
    ]


def check_quickstart_run(args: argparse.Namespace) -> None:
    """ValueError unless the run in ``args.out`` is this quickstart's (the preset, seed and
    steps asked for): resuming another would run and overwrite that run's evaluations."""
    from activevision.training import load_config, preset
    from activevision.training.presets import scaled_intervals

    base = preset("quickstart")
    want = base.replace(seed=args.seed)
    if args.steps is not None:  # as train --steps does: the intervals scaled with the run
        want = want.replace(total_timesteps=args.steps)
        want = want.replace(**scaled_intervals(base, want))
    have = load_config(args.out / "config.json")
    if replace(have, run=replace(have.run, progress_bar=want.run.progress_bar)) != want:
        steps = f", {args.steps} steps" if args.steps is not None else ""
        raise ValueError(
            f"{args.out} holds another training run than this quickstart's (preset quickstart,"
            f" seed {args.seed}{steps}): choose another --out, or run the commands by hand"
        )


def run_quickstart(args: argparse.Namespace, main: Callable[[list[str]], int]) -> int:
    """Run :func:`quickstart_steps` one after the other; stop at the first that fails."""
    for argv in quickstart_steps(args):
        print(f"\n$ activevision {' '.join(argv)}", flush=True)
        code = main(argv)
        if code:
            return code
    print(f"\n{summary_line(args.out)}")
    return 0


def summary_line(run_dir: Path) -> str:
    """One line: the learned policy against scan and random (paper's success rate and goal
    reached, 95% intervals in evaluation.csv), and where the report is."""
    import json

    rows = json.loads((run_dir / "evaluation" / "evaluation.json").read_text())["methods"]
    by_method = {row["method"]: row for row in rows}
    parts = [
        f"{name} {by_method[name]['success_rate']:.1%} success rate,"
        f" {by_method[name]['success']:.1%} goal reached"
        for name in ("learned", "scan", "random")
        if name in by_method
    ]
    return f"main job: {' | '.join(parts)}; report: {run_dir / 'report.md'}"


def add_parsers(sub: Any) -> None:
    text = "short training + evaluation + figures + report"
    p = sub.add_parser(
        "quickstart",
        help=text,
        description="the main job (make run): " + text + ", and a short match comparison, all"
        " in --out",
    )
    p.set_defaults(func=None)  # run by cli.main, which passes itself
    p.add_argument("--out", type=path, default=Path("runs/quickstart"))
    p.add_argument("--steps", type=positive_int, default=None, help="default: the preset's")
    p.add_argument("--episodes", type=int_in(1, MAX_EPISODES), default=100)
    p.add_argument("--seed", type=seed, default=0)
    p.add_argument(
        "--matches", type=int_in(1, MAX_MATCHES), default=16, help="of the match comparison"
    )
    p.add_argument(
        "--match-ticks", type=positive_int, default=300, help="ticks per match (0.32 s each)"
    )
