"""``activevision export`` and ``demo``: the policy a robot runs."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from activevision.cli.args import (
    FIGURE_AND_GIF_HELP,
    add_overwrite,
    add_weights,
    check_run,
    figure_file,
    path,
    seed,
)
from activevision.cli.outputs import check_episode_outputs, check_outputs, warn_replaced_gif


def _opset(text: str) -> int:
    from activevision.export.onnx_export import check_opset

    try:
        return check_opset(int(text))
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def cmd_export(args: argparse.Namespace) -> None:
    """ONNX model + metadata for the torch-free HeadController."""
    from activevision.export import export_run
    from activevision.export.onnx_export import model_path_of
    from activevision.runtime.metadata import metadata_path_for

    if (
        args.out is not None
        and not args.out.is_dir()
        and args.out.suffix.lower() not in ("", ".onnx")
    ):
        raise ValueError(f"--out {args.out}: name a .onnx file or a directory")
    check_run(args.run, option="")  # before the outputs inside it
    model = model_path_of(args.out or args.run)
    outputs = [model, metadata_path_for(model)]
    if args.out is None:
        check_outputs(own=outputs, overwrite=args.overwrite, run=args.run)
    else:
        check_outputs(named=outputs, overwrite=args.overwrite, run=args.run)
    exported = export_run(args.run, model, weights=args.weights, opset=args.opset)
    print(f"wrote {exported.model_path} and {exported.metadata_path}")


def cmd_demo(args: argparse.Namespace) -> None:
    """Episode figure and GIF of the shipped (or a given) ONNX policy against random."""
    from activevision.experiments.episode_figure import trace_episode
    from activevision.experiments.policies import OnnxPolicy, RandomPolicy
    from activevision.experiments.provenance import write_episode_record
    from activevision.figures.episode import animate_episode, plot_episodes
    from activevision.io import file_sha256
    from activevision.runtime import pretrained_policy_path

    # the GIF and the record of what played, for report (no run's policy: demo's)
    gif, record, shared = check_episode_outputs(args.out, overwrite=args.overwrite)
    model = args.policy or pretrained_policy_path()
    policy = OnnxPolicy(model)
    # as loaded: the file the controller read (--policy may name the run or export folder
    # that holds policy.onnx, as HeadController takes it)
    model_sha256 = file_sha256(policy.controller.model_path)
    # the figure's row says whose policy it is (the class's name, "onnx", said neither): the
    # file's name, or its run's folder for an exported policy.onnx (that read: --policy may
    # name its folder, "." in it)
    if args.policy is None:
        policy.name = "shipped"
    else:
        read = Path(policy.controller.model_path)
        policy.name = read.resolve().parent.name if read.stem == "policy" else read.stem
    config = policy.env_config()  # the observation the policy takes; an exact prior pose
    traces = [trace_episode(p, args.seed, config) for p in (policy, RandomPolicy(config))]
    plot_episodes(traces, args.out)
    animate_episode(traces[0], gif)
    write_episode_record(
        args.out,
        gif,
        command="demo",
        policies=[trace.policy for trace in traces],
        seed=args.seed,
        model=None if args.policy is None else str(args.policy),
        model_sha256=model_sha256,
    )
    warn_replaced_gif(shared, gif)
    print(f"wrote {args.out}, {gif} and {record}")


def add_parsers(sub: Any) -> None:
    text = "export a run's policy to ONNX (+ policy.json)"
    p = sub.add_parser(
        "export",
        help=text,
        description=text + ": the model and the file that describes it (inputs, moves, camera,"
        " training world), what activevision.runtime.HeadController loads on a robot",
    )
    p.set_defaults(func=cmd_export)
    p.add_argument("run", type=path)
    p.add_argument("--out", "-o", type=path, help="default: RUN/policy.onnx")
    add_weights(p)
    p.add_argument("--opset", type=_opset, default=17, help="ONNX opset (default 17)")
    add_overwrite(p)

    text = "episode figure + GIF of the shipped policy (no training needed)"
    p = sub.add_parser("demo", help=text, description=text + ", beside random head moves")
    p.set_defaults(func=cmd_demo)
    p.add_argument("--policy", type=path, help="an exported policy.onnx (default: the shipped one)")
    p.add_argument("--seed", type=seed, default=0, help="seed of the episode's start (default 0)")
    p.add_argument(
        "--out",
        type=figure_file,
        default=Path("demo/episode.png"),
        help=FIGURE_AND_GIF_HELP + " (default: demo/episode.png)",
    )
    add_overwrite(p)
