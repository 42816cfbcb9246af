"""``activevision render`` and ``viewpoints``: pictures of a random episode start."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from activevision.cli.args import FIGURE_HELP, add_overwrite, choice_list, figure_file, seed
from activevision.cli.outputs import check_figure_path, check_outputs


def _field_names() -> tuple[str, ...]:
    from activevision.geometry.field import FIELD_PRESETS

    return tuple(FIELD_PRESETS)


def _random_episode(episode_seed: int, field: str) -> Any:
    """A fresh episode start of ActiveVision-v0 (the env's own start distribution)."""
    from activevision.envs import EnvConfig
    from activevision.envs.simulation import EpisodeBatch
    from activevision.geometry import field_preset

    sim = EpisodeBatch(EnvConfig(field=field_preset(field)), 1)
    sim.reset(np.zeros(1, dtype=np.int64), [np.random.default_rng(episode_seed)])
    return sim


def cmd_render(args: argparse.Namespace) -> None:
    """Camera image beside the top view for a random episode start."""
    from activevision.envs.view import episode_panel
    from activevision.figures.canvas import save_rgb

    check_outputs(named=[args.out], overwrite=args.overwrite)
    check_figure_path(args.out)
    sim = _random_episode(args.seed, args.field)
    save_rgb(episode_panel(sim, 0, sim.render()[0]), args.out)
    print(f"wrote {args.out}")


def cmd_viewpoints(args: argparse.Namespace) -> None:
    """Every candidate viewpoint's footprint shaded by its entropy; the best in red."""
    from activevision.envs.view import viewpoint_search
    from activevision.figures.scene import plot_viewpoint_search

    check_outputs(named=[args.out], overwrite=args.overwrite)
    check_figure_path(args.out)
    sim = _random_episode(args.seed, args.field)
    plot_viewpoint_search(viewpoint_search(sim, 0), args.out)
    print(f"wrote {args.out}")


def add_parsers(sub: Any) -> None:
    for name, func, text in [
        ("render", cmd_render, "render a random view: camera image beside the top view"),
        ("viewpoints", cmd_viewpoints, "plot the best-viewpoint search of a random start"),
    ]:
        p = sub.add_parser(name, help=text, description=text)
        p.set_defaults(func=func)
        p.add_argument("--seed", type=seed, default=0, help="seed of the start (default 0)")
        p.add_argument(
            "--field",
            type=choice_list(_field_names),
            default="kidsize",
            help="field preset: kidsize | paper2019",
        )
        p.add_argument("--out", type=figure_file, required=True, help=FIGURE_HELP)
        add_overwrite(p)
