"""``activevision sweep`` and ``activevision compare --ray``: argparse wiring for
:mod:`activevision.cli`, which adds them with::

    from activevision.scaleout.cli import add_compare_ray_arguments, add_sweep_parser
    add_sweep_parser(sub)                    # in build_parser(), beside the other commands
    add_compare_ray_arguments(p)             # on the compare parser
    if args.ray: return cmd_compare_ray(args)   # first line of cmd_compare

Nothing here imports Ray until a command runs.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any


def parse_seeds(text: str) -> list[int]:
    """``0..9`` (both ends included), ``0,3,7`` or ``5``."""
    if ".." in text:
        start, stop = (int(v) for v in text.split(".."))
        if stop < start:
            raise ValueError(f"--seeds {text}: the end is before the start")
        return list(range(start, stop + 1))
    return [int(v) for v in text.split(",")]


def parse_grid(items: list[str] | None) -> dict[str, list[str]]:
    """``["learning_rate=5e-4,1e-3", "dueling=true,false"]`` -> key -> values (as text,
    parsed like ``--set`` when each trial's config is built)."""
    grid: dict[str, list[str]] = {}
    for item in items or []:
        key, sep, values = item.partition("=")
        if not sep or not key or not values:
            raise ValueError(f"--grid expects KEY=V1,V2,..., got {item!r}")
        grid[key.strip()] = [v.strip() for v in values.split(",")]
    return grid


def add_sweep_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``sweep`` to the CLI's subparsers (sets ``func=cmd_sweep``)."""
    text = "seed x grid sweep of training runs on Ray Tune (pip install activevision[ray])"
    p = subparsers.add_parser("sweep", help=text, description=text)
    p.set_defaults(func=cmd_sweep)
    p.add_argument("--seeds", default="0..4", help="0..9 (inclusive) or 0,1,2 (default 0..4)")
    p.add_argument(
        "--grid", action="append", metavar="KEY=V1,V2", help="sweep a config key (repeatable)"
    )
    p.add_argument("--config", type=Path, help="TrainConfig JSON file (instead of --preset)")
    p.add_argument("--preset", default="paper", help="paper | release | quickstart")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a config key")
    p.add_argument("--out", type=Path, required=True, help="sweep directory, e.g. runs/SWEEP")
    p.add_argument("--address", help="join a Ray cluster: auto | ray://HEAD:10001")
    p.add_argument("--num-cpus", type=int, help="CPUs of the local Ray instance (default: all)")
    p.add_argument("--cpus-per-trial", type=float, default=1.0)
    p.add_argument("--max-failures", type=int, default=2, help="restarts of a failed trial")
    return p


def cmd_sweep(args: argparse.Namespace) -> None:
    """Run the sweep; print where its outputs went."""
    from activevision.scaleout.sweep import sweep
    from activevision.training import apply_overrides, load_config, preset

    config = load_config(args.config) if args.config else preset(args.preset)
    config = apply_overrides(config, list(args.set or []))
    rows = sweep(
        config,
        parse_seeds(args.seeds),
        parse_grid(args.grid),
        args.out,
        address=args.address,
        num_cpus=args.num_cpus,
        max_failures=args.max_failures,
        cpus_per_trial=args.cpus_per_trial,
    )
    print(f"{len(rows)} aggregated rows")
    print(f"wrote {args.out}/trials.csv, sweep.csv and sweep.png")


def add_compare_ray_arguments(p: argparse.ArgumentParser) -> None:
    """``--ray``, ``--address``, ``--num-cpus``, ``--chunk`` on the ``compare`` parser."""
    p.add_argument("--ray", action="store_true", help="distribute over Ray tasks")
    p.add_argument("--address", help="with --ray: auto | ray://HEAD:10001 (default: local)")
    p.add_argument("--num-cpus", type=int, help="with --ray: CPUs of the local Ray instance")
    p.add_argument("--chunk", type=int, default=25, help="with --ray: episodes per task")


def cmd_compare_ray(args: argparse.Namespace) -> None:
    """``activevision compare --ray``: same CSV and figure as the local command."""
    from activevision.cli import _env_config, _parse_errors
    from activevision.experiments.compare import plot_compare
    from activevision.scaleout.compare import compare_ray, default_method_names

    env_config = _env_config(args.run)
    out = args.out or (args.run / "compare" if args.run else Path("compare"))
    compare_ray(
        out,
        default_method_names(args.run, args.methods),
        _parse_errors(args.errors),
        args.episodes,
        args.seed,
        env_config,
        run_dir=args.run,
        weights=args.weights,
        chunk=args.chunk,
        address=args.address,
        num_cpus=args.num_cpus,
    )
    plot_compare(out / "compare.csv", out / "compare.png")
    print(f"wrote {out}/compare.csv and compare.png")
