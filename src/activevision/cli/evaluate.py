"""``activevision evaluate``, ``compare``, ``episode`` and ``report``."""

from __future__ import annotations

import argparse
import functools
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from activevision.cli.args import (
    FIGURE_AND_GIF_HELP,
    MAX_EPISODES,
    add_overwrite,
    add_weights,
    check_run,
    check_weights,
    choice_list,
    distinct,
    env_config_of_run,
    error_levels,
    figure_file,
    int_in,
    localisation_error,
    path,
    positive_int,
    seed,
)
from activevision.cli.outputs import (
    OutputError,
    check_episode_outputs,
    check_outputs,
    is_training_run,
    make_output_folder,
    removed_on_failure,
    warn_replaced_gif,
)

if TYPE_CHECKING:
    from activevision.experiments.policies import HeadPolicy


#: ``compare --ray``'s episodes a Ray task (``--chunk``)
RAY_CHUNK = 25


def _method_names() -> tuple[str, ...]:
    from activevision.experiments.methods import method_names

    return method_names()


def _compare_method_names() -> tuple[str, ...]:
    from activevision.experiments.methods import compare_method_names

    return compare_method_names()


def _policies(
    names: list[str], args: argparse.Namespace, env_config: Any, error: float = 0.0
) -> dict[str, HeadPolicy]:
    from activevision.experiments.methods import check_runs, make_policy

    check_runs(names, args.run)
    return {name: make_policy(name, error, env_config, args.run, args.weights) for name in names}


def _shipped_first(
    names: list[str], args: argparse.Namespace, env_config: Any, error: float = 0.0
) -> tuple[dict[str, HeadPolicy], Any]:
    """The shipped policy where ``names`` has it, and the env every method then plays.

    Without ``--run`` that is the shipped policy's own env (its observation, camera and
    moves), as ``demo`` plays it; with ``--run``, the run's, which the shipped policy must
    fit (ValueError naming each difference, before any episode: it was a first-step error
    naming ``OnnxPolicy.env_config()``, after every episode of the methods before it)."""
    from activevision.envs.observations import play_differences
    from activevision.experiments.compare import config_at_error
    from activevision.experiments.policies import OnnxPolicy

    if "shipped" not in names:
        return {}, env_config
    shipped = _policies(["shipped"], args, env_config, error)
    onnx = shipped["shipped"]
    if not isinstance(onnx, OnnxPolicy):  # a registry whose "shipped" is another policy
        return shipped, env_config
    own = onnx.env_config(env_config)
    if args.run is None:
        return shipped, config_at_error(own, error)
    differences = play_differences(own, env_config, moves_by_target=onnx.controller.continuous)
    if differences:
        raise ValueError(
            f"the shipped policy was trained on {'; '.join(differences)} in the env of --run"
            f" {args.run}: play shipped without --run (every method then plays its env), or"
            " beside a run trained on the same inputs, camera and moves"
        )
    return shipped, env_config


def _more_runs(args: argparse.Namespace, env_config: Any, learned: bool) -> dict[str, HeadPolicy]:
    """``--runs``: each run's learned policy, as method ``learned:NAME`` (NAME: its
    directory). Each must take what the comparison's env gives (``--run``'s, or the paper's
    image), in its camera and moves (:func:`~activevision.envs.observations.play_differences`);
    a continuous policy plays the same env, moving by head targets. ``learned``: whether
    ``--run``'s policy plays (method ``learned``), which ``--runs`` must not name again."""
    from activevision.envs.observations import play_differences
    from activevision.experiments.policies import LearnedPolicy
    from activevision.training.config import load_config

    policies: dict[str, HeadPolicy] = {}
    given: dict[Path, Path] = {}  # each run's folder -> how --runs named it first
    for run in args.runs or []:
        check_run(run, "--runs")
        if run.resolve() in given:  # the same folder twice ("rename one directory" said)
            first = given[run.resolve()]
            named = f"{run}" if first == run else f"{first} and {run}"
            raise ValueError(f"--runs names the run {named} twice: give each run once")
        if learned and args.run is not None and run.resolve() == args.run.resolve():
            # it played twice, as learned and as learned:NAME, on the same episodes
            raise ValueError(
                f"--runs {run} is --run {args.run}, whose policy plays as method learned"
                " already: give it once"
            )
        given[run.resolve()] = run
        # every run plays in the comparison's env (--run's, or the shipped policy's where
        # it plays): an image of another size or stack was a traceback in the first step,
        # another camera or other moves a silently different policy
        continuous = load_config(run / "config.json").env.action_type == "continuous"
        differences = play_differences(
            env_config_of_run(run), env_config, moves_by_target=continuous
        )
        if differences:
            raise ValueError(
                f"--runs {run} was trained on {'; '.join(differences)} in the comparison's"
                " env (from --run, or the shipped policy's where it plays): compare runs"
                " trained on the same inputs, camera and moves"
            )
        name = f"learned:{run.resolve().name}"  # the folder's name, however it was given
        if name in policies:
            raise ValueError(f"--runs names two runs {run.resolve().name!r}: rename one directory")
        policy = LearnedPolicy.from_run(run, weights=args.weights)
        policy.name = name
        policies[name] = policy
    return policies


def _user_methods(
    args: argparse.Namespace, env_config: Any, taken: Any
) -> dict[str, Callable[[float], HeadPolicy]]:
    """``--strategy FILE.py:NAME``: each user's method as a factory of the error level,
    under its label (not one of ``taken``)."""
    from activevision.experiments.methods import MethodContext, MethodFactory, user_method

    methods: dict[str, Callable[[float], HeadPolicy]] = {}
    for spec in args.strategy or ():  # each once: the parser refuses one named twice
        label, factory = user_method(spec)
        if label in taken or label in methods:
            raise ValueError(f"--strategy {spec}: a method named {label!r} plays already")

        def at_error(error: float, factory: MethodFactory = factory) -> HeadPolicy:
            return factory(MethodContext(env_config, error, args.run, args.weights))

        methods[label] = at_error
    return methods


def cmd_evaluate(args: argparse.Namespace) -> None:
    """Fixed-seed evaluation of every method: table, CSV and JSON."""
    from activevision.envs import ActiveVisionEnv
    from activevision.experiments.evaluate import (
        METRICS,
        evaluate_policy,
        format_table,
        latency_summary,
        paired_steps,
        summary_rows,
    )
    from activevision.io import nan_as_null, write_csv, write_json
    from activevision.training.policy_files import scored_run

    check_weights(args)
    check_run(args.run)  # before the outputs inside it
    out = args.out or (args.run / "evaluation" if args.run else Path("evaluation"))
    files = [out / n for n in ("evaluation.csv", "episodes.csv", "evaluation.json")]
    latency_path = out / "latency.json"  # wall clock: apart, so the others are seed-exact
    check_outputs(own=[*files, latency_path], overwrite=args.overwrite, run=args.run)
    from activevision.experiments.compare import config_at_error
    from activevision.experiments.methods import runnable_methods

    # a policy that observes a prior pose gets one --error off, as the entropy methods do
    env_config = config_at_error(env_config_of_run(args.run), args.error)
    names = args.methods or runnable_methods(_compare_method_names(), args.run)
    # settled before any other policy is built (a MethodContext, a --runs check) for that env
    shipped, env_config = _shipped_first(names, args, env_config, args.error)
    others = [name for name in names if name not in shipped]
    policies = shipped | _policies(others, args, env_config, args.error)
    policies = {name: policies[name] for name in names}  # in the order named
    policies.update(_more_runs(args, env_config, "learned" in policies))
    users = _user_methods(args, env_config, policies)
    _try_users(users, env_config, args.error, args.seed)  # before the built-in methods play
    policies.update({label: make(args.error) for label, make in users.items()})
    env = ActiveVisionEnv(env_config)
    made = make_output_folder(out, None if args.out else str(out))
    summaries, episodes = {}, []
    latency: dict[str, float] = {}
    with removed_on_failure(made):
        for name, policy in policies.items():
            records, summary, lat = evaluate_policy(
                policy,
                args.episodes,
                args.seed,
                env=env,
                # the first learned policy's (a user's "learned_..." is not one)
                measure_latency=name.startswith("learned") and name not in users and not latency,
            )
            summaries[name] = summary
            episodes += [{"method": name, **r} for r in records]
            if lat:
                latency = latency_summary(lat)
    print(format_table(summaries))
    if args.episodes == 1:
        shares = ", ".join(m for m, kind in METRICS.items() if kind == "proportion")
        # success_rate is a mean (nan): "rates keep theirs" read as if it kept its interval
        print(
            "one episode: the means' 95% intervals need 2 or more (nan above); the shares"
            f" of episodes ({shares}) keep their Wilson intervals"
        )
    if latency:
        print(
            f"learned policy per-decision latency (batch 1, CPU): "
            f"p50 {latency['p50_ms']:.2f} ms, p99 {latency['p99_ms']:.2f} ms "
            f"(paper: 2.3 ms on a GTX 1060)"
        )
    solved = paired_steps(episodes, list(summaries))
    if solved["episodes"]:
        print(
            f"steps to success on the {solved['episodes']} episodes every method solves"
            " (median): " + ", ".join(f"{name} {solved[name]['median']:g}" for name in summaries)
        )
    else:
        print("steps to success: no episode is solved by every method, so none to pair")
    rows = summary_rows(summaries, episodes=args.episodes, seed=args.seed, error=args.error)
    with removed_on_failure(made, [*files, latency_path]):  # all of its outputs, or none
        write_csv(files[0], rows)
        write_csv(files[1], episodes)
        write_json(
            files[2],
            nan_as_null(  # strict JSON: an interval of one episode is null, not NaN
                {
                    "methods": rows,
                    "steps_where_all_solve": solved,
                    "episodes": args.episodes,
                    "seed": args.seed,
                    "weights": args.weights,  # of --run's learned policy: final or best validated
                    # the run scored (its config's and weights' digests), for report's check
                    "run": None if args.run is None else scored_run(args.run, args.weights),
                }
            ),
        )
        written = "evaluation.csv, evaluation.json, episodes.csv"
        if latency:
            write_json(latency_path, {"policy": "learned", "batch": 1, "device": "cpu"} | latency)
            written += ", latency.json"
        elif latency_path.exists():
            latency_path.unlink()  # --overwrite: an earlier evaluation's, not this one's
    print(f"wrote {out}/{written}")


def cmd_compare(args: argparse.Namespace) -> None:
    """The localisation-error experiment and its figure (on Ray with ``--ray``)."""
    from activevision.experiments.methods import check_runs
    from activevision.training.run_lock import RunLock

    check_weights(args)
    _check_ray_options(args)  # before --overwrite removes a compare.csv
    check_run(args.run)  # before the outputs inside it
    out = args.out or (args.run / "compare" if args.run else Path("compare"))
    if is_training_run(out):  # its folder is the trainer's (and its lock the trainer's)
        raise OutputError(f"refusing to write into the training run {out}; choose another --out")
    # compare.csv is resumed, not replaced (outputs.py, rule 3): only rules 1 and 4 apply
    check_outputs(own=[out / "compare.csv", out / "compare.png"], overwrite=True, run=args.run)
    check_runs(args.methods or [], args.run)
    made = make_output_folder(out, None if args.out else str(out))  # rows written as played
    with removed_on_failure(made):  # a folder with rows stays, to be resumed
        # one compare per folder: two would append their rows to one compare.csv
        lock = RunLock(
            out, ("written", "let it finish (or stop it), or give this one another --out")
        )
        try:
            _compare_into(out, args)
        finally:
            lock.release(remove=True)


def _check_ray_options(args: argparse.Namespace) -> None:
    """ValueError where ``compare``'s options do not go together with or without --ray."""
    if args.ray and args.runs:
        raise ValueError("--runs plays in this process: leave out --ray")
    if args.ray and args.strategy:
        raise ValueError("--strategy plays in this process: leave out --ray")
    ray_only = [
        flag
        for flag, value in (
            ("--address", args.address),
            ("--num-cpus", args.num_cpus),
            ("--chunk", args.chunk),
            ("--verbose", args.verbose),
        )
        if value
    ]
    if ray_only and not args.ray:
        raise ValueError(f"{', '.join(ray_only)} applies to a compare on Ray: add --ray")
    if args.address is not None and args.num_cpus is not None:
        raise ValueError("--num-cpus sets a local Ray's CPUs: leave it out with --address")


def _compare_into(out: Path, args: argparse.Namespace) -> None:
    """``cmd_compare``'s work, in ``out`` (made, and locked against another compare)."""
    from activevision.figures.compare import plot_compare
    from activevision.training.policy_files import scored_run

    env_config = env_config_of_run(args.run)
    # the weights the learned method plays, recorded in compare.csv: another run's levels
    # are not resumed as this one's
    run_sha256 = None if args.run is None else scored_run(args.run, args.weights)["weights_sha256"]
    # --overwrite removes compare.csv only once every method is made and checked: a refusal
    # before the first row left the user without the old file and without a new one
    if args.ray:
        from activevision.scaleout.compare import compare_ray, default_method_names
        from activevision.scaleout.ray_session import check_reachable, require_ray

        names = default_method_names(args.run, args.methods)
        require_ray()
        if args.address is not None:
            check_reachable(args.address)
        _start_over(out, args)
        compare_ray(
            out,
            names,
            args.errors,
            args.episodes,
            args.seed,
            env_config,
            run_dir=args.run,
            weights=args.weights,
            chunk=args.chunk or RAY_CHUNK,
            address=args.address,
            num_cpus=args.num_cpus,
            verbose=args.verbose,
            run_sha256=run_sha256,
        )
    else:
        from activevision.experiments.compare import compare, default_methods
        from activevision.experiments.policies import LearnedPolicy

        learned = LearnedPolicy.from_run(args.run, weights=args.weights) if args.run else None
        methods = default_methods(env_config, learned)
        if args.methods:
            # in the order given (each once: the parser refuses one named twice)
            methods = {k: methods[k] for k in args.methods if k in methods}
        for name, policy in _more_runs(args, env_config, "learned" in methods).items():
            methods[name] = functools.partial(_same, policy)
        users = _user_methods(args, env_config, methods)
        _try_users(users, env_config, args.errors[0], args.seed)
        methods.update(users)
        _start_over(out, args)
        compare(
            out,
            methods,
            args.errors,
            args.episodes,
            args.seed,
            env_config,
            run_sha256=run_sha256,
            weights=args.weights,
        )
    plot_compare(out / "compare.csv", out / "compare.png")
    print(f"wrote {out}/compare.csv and compare.png")


def _start_over(out: Path, args: argparse.Namespace) -> None:
    """``--overwrite``: remove the compare.csv that would be resumed, and its figure (kept, a
    compare stopped before its end left the older compare's figure beside the new rows)."""
    if args.overwrite:
        (out / "compare.csv").unlink(missing_ok=True)
        (out / "compare.png").unlink(missing_ok=True)


def _try_users(
    users: dict[str, Callable[[float], HeadPolicy]], env_config: Any, error: float, seed: int
) -> None:
    """Each user's method, made afresh, plays one episode of localisation error ``error``
    before any method's episodes (as ``match`` plays a trial): a mistake in it shows in
    seconds, as one line, not after every built-in method has played."""
    from activevision.envs import ActiveVisionEnv
    from activevision.experiments.compare import config_at_error
    from activevision.experiments.evaluate import evaluate_policy

    for make in users.values():
        env = ActiveVisionEnv(config_at_error(env_config, error))
        evaluate_policy(make(error), 1, seed, env=env)


def cmd_episode(args: argparse.Namespace) -> None:
    """The paper's qualitative episode figure (and a GIF) for two methods."""
    from activevision.experiments.episode_figure import trace_episode
    from activevision.experiments.provenance import write_episode_record
    from activevision.figures.episode import animate_episode, plot_episodes
    from activevision.training.policy_files import scored_run

    check_weights(args)
    check_run(args.run)  # before the outputs inside it
    # the GIF and the record of what played, for report
    gif, record, shared = check_episode_outputs(args.out, overwrite=args.overwrite, run=args.run)
    from activevision.experiments.compare import config_at_error

    env_config = config_at_error(env_config_of_run(args.run), 0.0)
    names = args.policies or (["learned", "random"] if args.run else ["oracle", "random"])
    shipped, env_config = _shipped_first(names, args, env_config)
    others = _policies([name for name in names if name not in shipped], args, env_config)
    policies = {name: (shipped | others)[name] for name in names}  # in the order named
    # the run whose policies play, as its weights were loaded: report leaves out another's
    run = None if args.run is None else scored_run(args.run, args.weights)
    traces = [trace_episode(p, args.seed, env_config) for p in policies.values()]
    plot_episodes(traces, args.out)
    animate_episode(traces[0], gif)
    write_episode_record(
        args.out,
        gif,
        command="episode",
        policies=list(policies),
        seed=args.seed,
        run=run,
        weights=args.weights,
    )
    warn_replaced_gif(shared, gif)
    print(f"wrote {args.out}, {gif} and {record}")


def cmd_report(args: argparse.Namespace) -> None:
    from activevision.experiments.report import write_report

    check_run(args.run, option="")
    check_outputs(own=[args.run / "report.md"], overwrite=args.overwrite)
    print(f"wrote {write_report(args.run)}")


def _add_common(p: argparse.ArgumentParser, run_help: str) -> None:
    p.add_argument("--run", type=path, help=run_help)
    add_weights(p)
    p.add_argument("--seed", type=seed, default=0, help="seed of the episode starts (default 0)")


def _same(policy: HeadPolicy, error: float) -> HeadPolicy:
    """A learned policy at every error level (it reads no belief)."""
    return policy


def _add_runs(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--runs",
        nargs="+",
        type=path,
        metavar="RUN",
        help="more training runs, each scored as method learned:NAME on the same episodes"
        " (e.g. a discrete and a continuous policy side by side)",
    )
    p.add_argument(
        "--strategy",
        nargs="+",
        action=distinct("strategy"),
        metavar="FILE.py:NAME",
        help="your own methods, played beside --methods on the same episodes: NAME(context)"
        " in FILE.py (or MODULE:NAME), given an experiments.methods.MethodContext, returns a"
        " HeadPolicy (reset(info, rng), act(obs, info)); examples/centre_ball.py",
    )


def add_parsers(sub: Any) -> None:
    method = choice_list(_method_names)
    text = "score methods on fixed-seed episodes"
    p = sub.add_parser(
        "evaluate",
        help=text,
        description=text + " (the same starts for every method): the paper's success rate, goal"
        " reached and more, each with its 95% interval; writes evaluation.csv, episodes.csv and"
        " evaluation.json (and latency.json with a learned policy)",
    )
    p.set_defaults(func=cmd_evaluate)
    _add_common(p, "a training run: adds the learned policy")
    p.add_argument(
        "--methods",
        nargs="+",
        type=method,
        action=distinct("method"),
        help=" ".join(_method_names()),
    )
    _add_runs(p)
    p.add_argument("--episodes", type=int_in(1, MAX_EPISODES), default=100)
    p.add_argument(
        "--error",
        type=localisation_error,
        default=0.0,
        help="localisation error of the entropy methods' belief and of a learned policy's"
        " prior pose (m and rad)",
    )
    p.add_argument("--out", type=path)
    add_overwrite(p)

    text = "success vs localisation error, every method"
    p = sub.add_parser(
        "compare",
        help=text,
        description=text + ": each method on the same episodes at each error level of --errors"
        " (the believed pose moved e metres and turned e rad); writes compare.csv and"
        " compare.png, and resumes a compare.csv played on the same episodes",
    )
    p.set_defaults(func=cmd_compare)
    _add_common(p, "a training run: adds the learned policy")
    p.add_argument(
        "--methods",
        nargs="+",
        type=choice_list(_compare_method_names),
        action=distinct("method"),
        help=" ".join(_compare_method_names()),
    )
    _add_runs(p)
    p.add_argument(
        "--errors", type=error_levels, default="0:2:0.25", help="start:stop:step or a,b,c"
    )
    p.add_argument("--episodes", type=int_in(1, MAX_EPISODES), default=100)
    p.add_argument("--out", type=path)
    p.add_argument(
        "--overwrite", action="store_true", help="start over instead of resuming compare.csv"
    )
    p.add_argument("--ray", action="store_true", help="distribute over Ray tasks")
    p.add_argument("--address", help="with --ray: auto | ray://HEAD:10001 (default: local)")
    p.add_argument("--num-cpus", type=positive_int, help="with --ray: CPUs of the local Ray")
    p.add_argument(
        "--chunk",
        type=positive_int,
        help=f"with --ray: episodes a task (default {RAY_CHUNK})",
    )
    p.add_argument(
        "--verbose",
        action="store_true",
        help="with --ray: print the workers' output too (warnings, a worker's traceback)",
    )

    text = "episode figure (and GIF) of two methods from one start"
    p = sub.add_parser("episode", help=text, description=text)
    p.set_defaults(func=cmd_episode)
    _add_common(p, "a training run (for the learned policy)")
    p.add_argument(
        "--policies",
        nargs="+",
        type=method,
        action=distinct("policy"),
        help="default: learned random (oracle random)",
    )
    p.add_argument("--out", type=figure_file, required=True, help=FIGURE_AND_GIF_HELP)
    add_overwrite(p)

    text = "one Markdown page with a run's figures and tables"
    p = sub.add_parser("report", help=text, description=text + " (RUN/report.md)")
    p.set_defaults(func=cmd_report)
    p.add_argument("run", type=path)
    add_overwrite(p)
