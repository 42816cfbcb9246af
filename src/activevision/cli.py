"""The ``activevision`` command line. Heavy imports (torch, matplotlib) happen inside the
subcommand that needs them, so ``activevision --help`` is instant."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def _random_episode(seed: int, field: str):
    """A fresh episode start of ActiveVision-v0 (the env's own start distribution)."""
    from activevision.envs import EnvConfig
    from activevision.envs.simulation import EpisodeBatch
    from activevision.geometry import field_preset

    sim = EpisodeBatch(EnvConfig(field=field_preset(field)), 1)
    sim.reset(np.zeros(1, dtype=np.int64), [np.random.default_rng(seed)])
    return sim


def cmd_render(args: argparse.Namespace) -> None:
    """Camera image beside the top view for a random episode start."""
    from activevision.rendering.topview import episode_panel, save_rgb

    sim = _random_episode(args.seed, args.field)
    save_rgb(episode_panel(sim, 0, sim.render()[0]), args.out)
    print(f"wrote {args.out}")


def cmd_viewpoints(args: argparse.Namespace) -> None:
    """Every candidate viewpoint's footprint shaded by its entropy; the best in red."""
    from activevision.rendering.viewpoints_plot import plot_viewpoint_search

    sim = _random_episode(args.seed, args.field)
    plot_viewpoint_search(sim, 0, args.out)
    print(f"wrote {args.out}")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="activevision",
        description="Learn where a humanoid soccer robot should look (DDQN + PER).",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    def add(name: str, func, help_text: str) -> argparse.ArgumentParser:
        p = sub.add_parser(name, help=help_text, description=help_text)
        p.set_defaults(func=func)
        return p

    for name, func, text in [
        ("render", cmd_render, "render a random view: camera image beside the top view"),
        ("viewpoints", cmd_viewpoints, "plot the best-viewpoint search of a random start"),
    ]:
        p = add(name, func, text)
        p.add_argument("--seed", type=int, default=0)
        p.add_argument("--field", default="kidsize", help="field preset: kidsize | paper2019")
        p.add_argument("--out", type=Path, required=True)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        args.func(args)
    except (ValueError, FileNotFoundError) as err:
        print(f"activevision {args.command}: error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
