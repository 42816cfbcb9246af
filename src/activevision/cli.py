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


def _env_config(run_dir: Path | None):
    """The EnvConfig a run trained on (its config.json's env_kwargs), else the default."""
    from activevision.envs import EnvConfig

    if run_dir is None:
        return EnvConfig()
    from activevision.export import env_config_of
    from activevision.training import load_config

    return env_config_of(load_config(run_dir / "config.json").env_kwargs)


def cmd_train(args: argparse.Namespace) -> None:
    """Train (or resume) a DDQN + PER run."""
    from activevision.training import (
        apply_overrides,
        load_config,
        plot_run,
        preset,
        resume,
        train,
    )

    if args.resume is not None:
        resume(args.resume, steps=args.steps)
        run_dir = args.resume
    else:
        if args.out is None:
            raise ValueError("--out runs/NAME is required (or --resume runs/NAME)")
        config = load_config(args.config) if args.config else preset(args.preset)
        overrides = list(args.set or [])
        if args.steps is not None:
            overrides.append(f"total_timesteps={args.steps}")
        if args.seed is not None:
            overrides.append(f"seed={args.seed}")
        train(apply_overrides(config, overrides), args.out)
        run_dir = args.out
    print(f"figures: {plot_run(run_dir)}")


def cmd_plot(args: argparse.Namespace) -> None:
    from activevision.training import plot_run

    print(f"wrote {plot_run(args.run)}")


def _methods(names: list[str], args: argparse.Namespace, env_config, error: float = 0.0):
    from activevision.experiments.policies import make_policy

    return {name: make_policy(name, error, env_config, args.run, args.weights) for name in names}


def cmd_evaluate(args: argparse.Namespace) -> None:
    """Fixed-seed evaluation of every method: table, CSV and JSON."""
    from activevision.envs import ActiveVisionEnv
    from activevision.experiments.evaluate import (
        evaluate_policy,
        format_table,
        latency_summary,
        summary_rows,
    )
    from activevision.experiments.policies import DEFAULT_ORDER
    from activevision.io import write_csv, write_json

    env_config = _env_config(args.run)
    names = args.methods or [m for m in DEFAULT_ORDER if m != "learned" or args.run]
    policies = _methods(names, args, env_config, args.error)
    env = ActiveVisionEnv(env_config)
    summaries, episodes, latency = {}, [], {}
    for name, policy in policies.items():
        records, summary, lat = evaluate_policy(
            policy, args.episodes, args.seed, env=env, measure_latency=name == "learned"
        )
        summaries[name] = summary
        episodes += [{"method": name, **r} for r in records]
        if lat:
            latency = latency_summary(lat)
    print(format_table(summaries))
    if latency:
        print(
            f"learned policy per-decision latency (batch 1, CPU): "
            f"p50 {latency['p50_ms']:.2f} ms, p99 {latency['p99_ms']:.2f} ms "
            f"(paper: 2.3 ms on a GTX 1060)"
        )
    out = args.out or (args.run / "evaluation" if args.run else Path("evaluation"))
    rows = summary_rows(summaries, episodes=args.episodes, seed=args.seed, error=args.error)
    write_csv(out / "evaluation.csv", rows)
    write_csv(out / "episodes.csv", episodes)
    write_json(
        out / "evaluation.json",
        {"methods": rows, "latency": latency, "episodes": args.episodes, "seed": args.seed},
    )
    print(f"wrote {out}/evaluation.csv, evaluation.json, episodes.csv")


def _parse_errors(text: str) -> list[float]:
    """``0:2:0.25`` (start:stop:step, stop included) or ``0,0.5,1``."""
    if ":" in text:
        start, stop, step = (float(v) for v in text.split(":"))
        if step <= 0:
            raise ValueError(f"--errors step must be positive, got {step}")
        return [round(v, 6) for v in np.arange(start, stop + step / 2, step)]
    return [float(v) for v in text.split(",")]


def cmd_compare(args: argparse.Namespace) -> None:
    """The localisation-error experiment and its figure (on Ray with ``--ray``)."""
    if getattr(args, "ray", False):
        from activevision.scaleout.cli import cmd_compare_ray

        return cmd_compare_ray(args)
    from activevision.experiments.compare import compare, default_methods, plot_compare
    from activevision.experiments.policies import LearnedPolicy

    env_config = _env_config(args.run)
    learned = LearnedPolicy.from_run(args.run, weights=args.weights) if args.run else None
    methods = default_methods(env_config, learned)
    if args.methods:
        methods = {k: v for k, v in methods.items() if k in args.methods}
    out = args.out or (args.run / "compare" if args.run else Path("compare"))
    compare(out, methods, _parse_errors(args.errors), args.episodes, args.seed, env_config)
    plot_compare(out / "compare.csv", out / "compare.png")
    print(f"wrote {out}/compare.csv and compare.png")


def cmd_episode(args: argparse.Namespace) -> None:
    """The paper's qualitative episode figure (and a GIF) for two methods."""
    from activevision.experiments.episode_figure import (
        animate_episode,
        plot_episodes,
        trace_episode,
    )

    env_config = _env_config(args.run)
    names = args.policies or (["learned", "random"] if args.run else ["oracle", "random"])
    policies = _methods(names, args, env_config)
    traces = [trace_episode(p, args.seed, env_config) for p in policies.values()]
    plot_episodes(traces, args.out, config=env_config)
    gif = args.out.with_suffix(".gif")
    animate_episode(traces[0], gif, env_config)
    print(f"wrote {args.out} and {gif}")


def cmd_report(args: argparse.Namespace) -> None:
    from activevision.experiments.report import write_report

    print(f"wrote {write_report(args.run)}")


def cmd_export(args: argparse.Namespace) -> None:
    """ONNX model + metadata for the torch-free HeadController."""
    from activevision.export import export_run

    exported = export_run(args.run, args.out, weights=args.weights, opset=args.opset)
    print(f"wrote {exported.model_path} and {exported.metadata_path}")


def cmd_demo(args: argparse.Namespace) -> None:
    """Episode figure and GIF of the shipped (or a given) ONNX policy against random."""
    from activevision.experiments.episode_figure import (
        animate_episode,
        plot_episodes,
        trace_episode,
    )
    from activevision.experiments.policies import OnnxPolicy, RandomPolicy
    from activevision.runtime import pretrained_policy_path

    policy = OnnxPolicy(args.policy or pretrained_policy_path())
    traces = [trace_episode(p, args.seed) for p in (policy, RandomPolicy())]
    plot_episodes(traces, args.out)
    gif = args.out.with_suffix(".gif")
    animate_episode(traces[0], gif)
    print(f"wrote {args.out} and {gif}")


def cmd_quickstart(args: argparse.Namespace) -> None:
    """The README's main job: short training (resumed if interrupted), evaluation of every
    method, a coarse localisation-error comparison, the episode figure and the report."""
    from activevision.training.checkpoint import list_checkpoints

    out, seed = args.out, str(args.seed)
    if list_checkpoints(out):
        steps = [["train", "--resume", str(out)]]
    else:
        extra = ["--steps", str(args.steps)] if args.steps is not None else []
        steps = [["train", "--preset", "quickstart", "--seed", seed, "--out", str(out), *extra]]
    episodes = str(args.episodes)
    steps += [
        ["evaluate", "--run", str(out), "--episodes", episodes, "--seed", seed],
        [
            "compare",
            "--run",
            str(out),
            "--errors",
            "0:2:0.5",
            "--episodes",
            episodes,
            "--seed",
            seed,
        ],
        ["episode", "--run", str(out), "--seed", seed, "--out", str(out / "episode.png")],
        ["report", str(out)],
    ]
    for argv in steps:
        print(f"\n$ activevision {' '.join(argv)}", flush=True)
        if main(argv):
            raise RuntimeError(f"activevision {argv[0]} failed")


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

    def add_weights(p: argparse.ArgumentParser) -> None:
        p.add_argument(
            "--weights",
            choices=("final", "best"),
            default="final",
            help="the run's final weights or its best validated ones (eval_interval)",
        )

    p = add("train", cmd_train, "train a DDQN + PER head controller")
    p.add_argument("--config", type=Path, help="TrainConfig JSON file")
    # spelled out: importing training.config here would load torch for every command
    p.add_argument(
        "--preset", default="paper", help="paper | release | drq_aux | data4x | data8x | quickstart"
    )
    p.add_argument("--steps", type=int, help="total environment steps (resume: steps to add)")
    p.add_argument("--seed", type=int)
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a config key")
    p.add_argument("--out", type=Path, help="run directory, e.g. runs/NAME")
    p.add_argument("--resume", type=Path, metavar="RUN", help="continue runs/NAME")

    p = add("plot", cmd_plot, "draw a run's training figures")
    p.add_argument("run", type=Path)

    p = add("evaluate", cmd_evaluate, "score methods on fixed-seed episodes")
    p.add_argument("--run", type=Path, help="a training run: adds the learned policy")
    add_weights(p)
    p.add_argument(
        "--methods", nargs="+", help="learned shipped entropy_jump entropy_steps oracle scan random"
    )
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--error", type=float, default=0.0, help="localisation error of the entropy methods"
    )
    p.add_argument("--out", type=Path)

    p = add("compare", cmd_compare, "success vs localisation error, every method")
    p.add_argument("--run", type=Path, help="a training run: adds the learned policy")
    add_weights(p)
    p.add_argument("--methods", nargs="+")
    p.add_argument("--errors", default="0:2:0.25", help="start:stop:step or a,b,c")
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=Path)
    from activevision.scaleout.cli import add_compare_ray_arguments, add_sweep_parser

    add_compare_ray_arguments(p)  # --ray, --address, --num-cpus, --chunk
    add_sweep_parser(sub)  # `activevision sweep`

    p = add("episode", cmd_episode, "episode figure (and GIF) of two methods from one start")
    p.add_argument("--run", type=Path, help="a training run (for the learned policy)")
    add_weights(p)
    p.add_argument("--policies", nargs="+", help="default: learned random (oracle random)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=Path, required=True)

    p = add("report", cmd_report, "one Markdown page with a run's figures and tables")
    p.add_argument("run", type=Path)

    p = add("export", cmd_export, "export a run's policy to ONNX (+ policy.json)")
    p.add_argument("run", type=Path)
    p.add_argument("--out", "-o", type=Path, help="default: RUN/policy.onnx")
    add_weights(p)
    p.add_argument("--opset", type=int, default=17)

    p = add("demo", cmd_demo, "episode figure + GIF of the shipped policy (no training needed)")
    p.add_argument("--policy", type=Path, help="an exported policy.onnx (default: the shipped one)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=Path, default=Path("demo/episode.png"))

    p = add("quickstart", cmd_quickstart, "short training + evaluation + figures + report")
    p.add_argument("--out", type=Path, default=Path("runs/quickstart"))
    p.add_argument("--steps", type=int, default=None, help="default: the quickstart preset")
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--seed", type=int, default=0)

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
    except Exception as err:
        # Our own errors and bad input get one clear line; anything else is a bug: traceback.
        if not isinstance(err, ValueError | OSError | ImportError) and not type(
            err
        ).__module__.startswith("activevision"):
            raise
        print(f"activevision {args.command}: error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
