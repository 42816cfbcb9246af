"""``activevision robustness``: a policy on fixed-seed episodes under named perturbations
(:mod:`activevision.experiments.robustness`)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from activevision.cli.args import (
    MAX_EPISODES,
    add_overwrite,
    add_weights,
    check_run,
    check_weights,
    choice_list,
    distinct,
    env_config_of_run,
    int_in,
    localisation_error,
    path,
    seed,
)
from activevision.cli.outputs import (
    OutputError,
    check_outputs,
    is_training_run,
    make_output_folder,
    removed_on_failure,
)

if TYPE_CHECKING:
    from activevision.envs import EnvConfig
    from activevision.experiments.policies import HeadPolicy


def _perturbation_names() -> tuple[str, ...]:
    from activevision.experiments.robustness import perturbation_names

    return perturbation_names()


def _method_names() -> tuple[str, ...]:
    from activevision.experiments.methods import method_names

    return method_names()


def _method(args: argparse.Namespace) -> str:
    """The policy to score: ``--method``, ``--shipped``, or the learned one of ``--run``."""
    if args.shipped and args.method not in (None, "shipped"):
        raise ValueError(f"--shipped and --method {args.method} name two policies; pick one")
    if (args.shipped or args.method == "shipped") and args.run is not None:
        raise ValueError(
            f"--shipped and --run {args.run} name two policies (the shipped one plays in its own"
            " training world); pick one"
        )
    name: str | None = "shipped" if args.shipped else args.method
    if name is None:
        if args.run is None:
            raise ValueError("name the policy: --run runs/NAME, --shipped or --method NAME")
        name = "learned"
    return name


def _policy(name: str, args: argparse.Namespace) -> tuple[HeadPolicy, EnvConfig]:
    """The policy and the env it was trained on, as ``evaluate`` plays it (a policy that
    observes a prior pose gets one ``--error`` off), in the world it was trained in: an
    exported policy's is its policy.json's ``world``, a run's its config.json's ``env``."""
    from activevision.experiments.compare import config_at_error
    from activevision.experiments.methods import make_policy
    from activevision.experiments.policies import OnnxPolicy

    check_weights(args)
    clean = config_at_error(env_config_of_run(args.run), args.error)
    policy = make_policy(name, args.error, clean, args.run, args.weights)
    if isinstance(policy, OnnxPolicy) and args.run is None:
        # the packaged policy's observation and training world (appearance ranges, other
        # robots): its clean row is played there, and in_training_range compares with it
        clean = config_at_error(policy.env_config(clean, trained_world=True), args.error)
    return policy, clean


def _blind(method: str, policy: HeadPolicy) -> str | None:
    """``method`` where its policy does not see the camera image, else None."""
    from activevision.experiments.robustness import sees_image

    return None if sees_image(policy) else method


def _outputs(args: argparse.Namespace, method: str) -> tuple[Path, Path]:
    out = args.out or (args.run / "robustness" if args.run else Path(f"robustness-{method}"))
    if is_training_run(out):
        raise OutputError(f"refusing to write into the training run {out}; choose another --out")
    files = (out / "robustness.csv", out / "robustness.png")
    check_outputs(named=files, overwrite=args.overwrite, run=args.run)
    return files


def cmd_robustness(args: argparse.Namespace) -> None:
    """Score one policy under every (or the chosen) perturbation: table, CSV, figure."""
    from activevision.experiments.robustness import list_table

    if args.list:
        # with a policy named: the rows it would play, on its world, with its training range
        named = args.run is not None or args.shipped or args.method is not None
        if named:
            check_run(args.run)
        if named:
            method = _method(args)
            policy, clean = _policy(method, args)
            print(list_table(clean, args.perturbations, _blind(method, policy)))
        else:
            print(list_table(None, args.perturbations))
        return
    method = _method(args)
    check_run(args.run)  # before RUN/robustness/..., which names a bad --run as an --out
    csv_path, png_path = _outputs(args, method)
    from activevision.experiments.robustness import (
        format_row,
        perturbations,
        score_perturbations,
        table_header,
        worst_drops,
    )
    from activevision.figures.robustness import plot_robustness
    from activevision.io import write_csv
    from activevision.training.policy_files import scored_run_columns

    policy, clean = _policy(method, args)
    # the run scored, as its weights were loaded: robustness.csv's last columns, for report,
    # which leaves out another run's suite
    run = {} if args.run is None else scored_run_columns(args.run, args.weights)
    blind = _blind(method, policy)
    rows = perturbations(clean, args.perturbations, blind)
    made = make_output_folder(csv_path.parent, None if args.out else str(csv_path.parent))
    what = f"{method} ({args.run})" if args.run else method
    print(
        f"robustness of {what}: {len(rows)} rows x {args.episodes} episodes"
        f" from seed {args.seed}, localisation error {args.error:g}"
    )
    if blind is not None and not args.perturbations:
        print(
            f"{blind} does not see the camera image: the rows that change only the image"
            " (appearance, camera mount, all-mild) are left out"
        )
    print(table_header(), flush=True)
    with removed_on_failure(made):
        scored = score_perturbations(
            policy,
            clean,
            rows,
            args.episodes,
            args.seed,
            progress=lambda row: print(format_row(row), flush=True),
        )
    print(worst_drops(scored))
    with removed_on_failure(made, [csv_path, png_path]):  # both, or neither
        write_csv(csv_path, [{"method": method, "error": args.error, **r, **run} for r in scored])
        # the run by its folder's name, not the path given: the same figure from any directory
        named = f"{method} ({args.run.resolve().name})" if args.run else method
        plot_robustness(
            scored,
            png_path,
            title=f"{named}: {args.episodes} episode{'s' * (args.episodes != 1)} a row,"
            f" seed {args.seed}, localisation error {args.error:g}",
        )
    print(f"wrote {csv_path} and {png_path}")


def add_parsers(sub: Any) -> None:
    p = sub.add_parser(
        "robustness",
        help="score a policy under named appearance, robot and camera-mount perturbations",
        description="Score one policy on the same fixed-seed episodes under each named"
        " perturbation of its training env (see --list); writes robustness.csv and"
        " robustness.png.",
    )
    p.set_defaults(func=cmd_robustness)
    p.add_argument("--run", type=path, help="a training run: scores its learned policy")
    p.add_argument("--shipped", action="store_true", help="score the policy shipped in the package")
    p.add_argument(
        "--method",
        type=choice_list(_method_names),
        help="score another method instead (" + " ".join(_method_names()) + ")",
    )
    add_weights(p)
    p.add_argument(
        "--perturbations",
        nargs="+",
        type=choice_list(_perturbation_names),
        action=distinct("perturbation"),
        metavar="NAME",
        help="play only these (clean is always played); default: all (see --list)",
    )
    p.add_argument("--episodes", type=int_in(1, MAX_EPISODES), default=200)
    p.add_argument("--seed", type=seed, default=0)
    p.add_argument(
        "--error",
        type=localisation_error,
        default=0.0,
        help="localisation error of a policy's prior pose (and of the entropy methods'"
        " belief), m and rad, in every row",
    )
    p.add_argument(
        "--out",
        type=path,
        help="output directory (default: RUN/robustness, or ./robustness-METHOD)",
    )
    add_overwrite(p)
    p.add_argument(
        "--list",
        action="store_true",
        help="print the perturbation table and exit (with a policy named: the rows it would"
        " play, on its training world, with whether each lies within its training ranges)",
    )
