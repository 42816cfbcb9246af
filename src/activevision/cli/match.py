"""``activevision match``: head-control strategies through whole matches on the same seeds
(:mod:`activevision.experiments.match`): a table, a CSV and three figures."""

from __future__ import annotations

import argparse
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from activevision.cli.args import (
    MAX_MATCHES,
    add_overwrite,
    add_weights,
    check_weights,
    choice_list,
    float_in,
    int_in,
    not_a_run,
    path,
    positive_int,
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
    from activevision.envs.match.config import DetectionConfig, MatchConfig
    from activevision.experiments.match_methods import StrategyOptions
    from activevision.geometry import CameraConfig

OUTPUT_FILES = ("match.csv", "match_pareto.png", "match_error.png", "match_clip.gif")
PAIRED_FILE = "match_paired.csv"  #: with --baseline


def _method_names() -> tuple[str, ...]:
    from activevision.experiments.match_methods import match_method_names

    return match_method_names()


def _count(n: int, noun: str) -> str:
    """``n`` and the noun, plural unless one ("1 match", "2 matches"; it read "1 matches")."""
    return f"{n} {noun}" + ("" if n == 1 else "es" if noun.endswith("ch") else "s")


def _world_text(args: argparse.Namespace, config: MatchConfig, run: str | None = None) -> str:
    """What differs from the default world: ``", 4 other robots walking at 0.2 m/s,
    detector 0.6/0.15/0.2"``, or nothing; ``run`` names the run a detector came from
    (default: ``--run`` as given)."""
    from activevision.envs.match.config import DetectionConfig

    text = ""
    if args.robots:
        moving = f"walking at {args.robot_speed:g} m/s" if args.robot_speed else "standing"
        text += f", {args.robots} other robot{'s' if args.robots > 1 else ''} {moving}"
    if config.detection != DetectionConfig():
        text += f", detector {detector_text(config.detection)}"
        if args.detection is None:
            text += f" (the one {args.run if run is None else run} was trained with)"
    camera = config.camera.differences()
    if camera:  # only a run's: the command line names no camera
        text += f", camera {camera} (the one {args.run if run is None else run} was trained with)"
    if args.ball_bounces_off_us:
        text += ", the ball bouncing off our robot"
    return text


def detector_text(detection: DetectionConfig) -> str:
    """``"0.6/0.15/0.2"`` (near/far/false per tick), with the ball detector's noise when it
    is not the default's."""
    from activevision.envs.match.config import DetectionConfig

    text = f"{detection.near:g}/{detection.far:g}/{detection.false_rate:g}"
    if detection.ball_noise != DetectionConfig().ball_noise:
        text += f", ball noise {detection.ball_noise:g} of its range"
    return text


def _run_world(run: Path | None) -> tuple[DetectionConfig | None, CameraConfig | None]:
    """The detector a training run on the match was trained with, and the camera of any
    run (its network sees that camera's image; None: no run, or not one)."""
    from activevision.training import load_config
    from activevision.training.config import MATCH_ENV_ID

    if run is None or not (run / "config.json").is_file():
        return None, None  # no run, or not one: _strategies says so
    run_config = load_config(run / "config.json")
    if run_config.env_id == MATCH_ENV_ID:
        return run_config.match.detection, run_config.match.camera
    return None, run_config.env.camera


def _match_config(args: argparse.Namespace) -> MatchConfig:
    """The matches the command line asks for."""
    from activevision.envs.match.config import (
        BallConfig,
        DetectionConfig,
        MatchConfig,
        OthersConfig,
        WalkConfig,
    )
    from activevision.envs.robots import RobotsConfig
    from activevision.geometry import CameraConfig

    if args.robot_speed and not args.robots:
        raise ValueError("--robot-speed moves the other robots: give --robots N (1-8) too")
    # a run plays the world it was trained for: its camera (the image its network takes)
    # and, trained on the match, its detector
    trained, camera = _run_world(args.run)
    if args.detection:
        detection = DetectionConfig(*args.detection)
        if trained is not None and trained != detection:
            print(
                f"note: {args.run} was trained with detector {detector_text(trained)};"
                f" these matches use {detector_text(detection)} (--detection)"
            )
    else:  # a run on the match plays the world it was trained for
        detection = trained or DetectionConfig()
    return MatchConfig(
        ticks=args.ticks,
        step_deg=args.step_deg,
        action_type=args.action_type,
        max_move_deg=(args.step_deg, args.step_deg),
        walk=WalkConfig(target=args.walk),
        robots=RobotsConfig(count=(args.robots, args.robots)),
        others=OthersConfig(speed=args.robot_speed),
        ball=BallConfig(bounces_off_own_robot=args.ball_bounces_off_us),
        detection=detection,
        camera=camera or CameraConfig(),
    )


def _strategies(
    args: argparse.Namespace, config: MatchConfig
) -> list[tuple[str, str, StrategyOptions]]:
    """``(label, method, options)`` of every result to play, each checked before any plays:
    the files exist, the options name strategies that are played, and every strategy can
    be made for ``config`` (a run's moves fit the match)."""
    import numpy as np

    from activevision.experiments.match import expand_methods, users_code
    from activevision.experiments.match_methods import (
        MATCH_METHODS,
        default_match_methods,
        load_strategy,
        make_match_policy,
    )

    models: list[Path] = list(dict.fromkeys(args.model or ()))
    for model in models:
        if model.is_dir():  # was "no such file"
            raise ValueError(
                f"--model {model} is a directory: name the .onnx model in it"
                f" (e.g. {model / 'policy.onnx'})"
            )
        if not model.is_file():
            raise ValueError(f"--model {model}: no such file")
    if args.run is not None and not (args.run / "config.json").is_file():
        raise ValueError(not_a_run(args.run))
    methods = list(dict.fromkeys(args.methods or default_match_methods(args.run)))
    margins = list(dict.fromkeys(args.track_margin or ()))
    if margins and "entropy_track" not in methods:
        raise ValueError("--track-margin sets entropy_track's margin: add it to --methods")
    if models and "onnx_policy" not in methods:
        raise ValueError("--model is played by onnx_policy: add it to --methods")
    if args.run is not None and "learned" not in methods:
        raise ValueError("--run is played by learned: add it to --methods")
    check_weights(args)
    strategies = []
    for spec in dict.fromkeys(args.strategy or ()):
        label, factory = load_strategy(spec)
        # a row of that name is read as the built-in's: privileged, a run's, the shipped
        # policy (report.md says so), whether or not the built-in plays too
        if label.partition("[")[0] in MATCH_METHODS:
            raise ValueError(
                f"--strategy {spec}: its label {label!r} is a built-in strategy's; give NAME"
                " a name attribute of its own"
            )
        strategies.append((label, factory))
    entries = expand_methods(methods, models, margins, args.run, args.weights, strategies)
    for label, method, options in entries:  # loads each run and model once: errors first
        policy = make_match_policy(method, config, options)
        with users_code(method, f"strategy {label}: reset"):
            policy.reset(1, np.random.default_rng(0))
    return entries


@contextmanager
def _unmade_when_failing(made: list[Path], args: argparse.Namespace) -> Iterator[None]:
    """:func:`~activevision.cli.outputs.removed_on_failure`, and running out of memory for
    the per-tick scores of every match as one line naming ``--ticks`` and ``--matches``."""
    try:
        with removed_on_failure(made):
            yield
    except MemoryError as err:
        raise ValueError(
            f"--ticks {args.ticks} x --matches {args.matches}: out of memory ({err}); ask for fewer"
        ) from None


def cmd_match(args: argparse.Namespace) -> None:
    """Play every chosen strategy through the same matches; print, write and plot."""
    out: Path = args.out
    if is_training_run(out):
        raise OutputError(f"refusing to write into the training run {out}; choose another --out")
    files = [out / name for name in OUTPUT_FILES]
    paired_path = out / PAIRED_FILE
    check_outputs(
        named=files + ([paired_path] if args.baseline else []),
        overwrite=args.overwrite,
        run=args.run,
    )
    config = _match_config(args)
    entries = _strategies(args, config)
    methods = list(dict.fromkeys(method for _, method, _ in entries))
    labels = [label for label, _, _ in entries]
    clip_method = args.clip_method or labels[0]
    if clip_method not in labels:
        raise ValueError(f"--clip-method {clip_method} is not among: {', '.join(labels)}")
    if args.baseline is not None and args.baseline not in labels:
        raise ValueError(f"--baseline {args.baseline} is not among: {', '.join(labels)}")
    if args.baseline is not None and len(labels) < 2:
        raise ValueError("--baseline needs at least one other method to compare with")
    made = make_output_folder(out)  # before the matches: one that cannot be made fails now
    import numpy as np

    from activevision.experiments.match import (
        NAME_WIDTH,
        compare_matches,
        csv_rows,
        format_difference,
        format_result,
        paired_differences,
        paired_rows,
        pareto_front,
        table_header,
    )
    from activevision.experiments.match_methods import privileged_methods
    from activevision.figures.match import clip_frames, plot_error_over_time, plot_pareto, save_gif
    from activevision.io import write_csv
    from activevision.runtime.controller import CameraMismatchWarning

    seconds = args.ticks * config.tick_seconds
    play = f"{seconds / 60:.1f} min" if seconds >= 60 else f"{seconds:.3g} s"
    head = f"{args.step_deg:g} deg" + (" per axis" if args.action_type == "continuous" else "")
    print(
        f"{_count(len(labels), 'method')} x {_count(args.matches, 'match')}"
        f" of {_count(args.ticks, 'tick')}"
        f" ({play} of play), seeds {args.seed}..{args.seed + args.matches - 1},"
        f" {args.action_type} head moves of up to {head} per {config.tick_seconds:g} s,"
        f" walking to {args.walk}{_world_text(args, config)}"
    )
    if args.matches == 1:
        print("one match gives no 95% intervals (they need 2 or more matches): nan below")
    width = max(NAME_WIDTH, max(len(label) for label in labels) + 2)
    print(table_header(width), flush=True)
    with _unmade_when_failing(made, args), warnings.catch_warnings():
        # each strategy was made once already, to check it (_strategies): a policy of another
        # camera than the matches' has said so, and says it once
        warnings.simplefilter("ignore", CameraMismatchWarning)
        results = compare_matches(
            entries,
            config,
            args.matches,
            args.seed,
            progress=lambda r: print(
                f"{format_result(r, width)}   ({r.seconds:.0f} s)", flush=True
            ),
        )
    references = privileged_methods() & set(methods)
    front = pareto_front(results, references)
    print(f"Pareto front (position RMSE vs ball in view): {', '.join(front)}")
    if references:
        print(
            f"privileged references (read the simulator's truth): {', '.join(sorted(references))}"
        )
    # all of its outputs, or none: an older paired CSV too (it was left beside the
    # removed set when a write before it failed under --overwrite)
    outputs = files + ([paired_path] if args.baseline is not None else [])
    with removed_on_failure(made, outputs):
        csv_path, pareto_path, error_path, clip_path = files
        write_csv(csv_path, csv_rows(results, args.matches, args.seed, config))
        if args.baseline is None and args.overwrite and paired_path.exists():
            paired_path.unlink()  # --overwrite (match.csv was there): not this run's pairs
        if args.baseline is not None:
            differences = paired_differences(results, args.baseline)
            print(f"paired differences from {args.baseline}, match by match (mean [95% interval]):")
            print(table_header(width))
            for method, metrics in differences.items():
                print(format_difference(method, metrics, width))
            pairs = paired_rows(differences, args.baseline, args.matches, args.seed)
            write_csv(paired_path, pairs)
        # the run by its folder's name, not by the path given: the figures are the same bytes
        # whatever the current directory and wherever the run lies
        run_name = None if args.run is None else args.run.resolve().name
        world = _world_text(args, config, run_name)
        # the console's first line names the walk; the figures, which travel alone, did not
        # (a striker walking to the ball sees it three times as often)
        walk = "" if args.walk == "waypoints" else f", walking to the {args.walk}"
        title = (
            f"{_count(args.matches, 'match')} x {play}, seed {args.seed},"
            f" {args.action_type} head {args.step_deg:g} deg/tick{walk}{world}"
        )
        points = {
            r.method: {k: (iv.mean, iv.low, iv.high) for k, iv in r.summary().items()}
            for r in results
        }
        plot_pareto(points, front, pareto_path, title, references)
        plot_error_over_time(
            {r.method: r.error_curve for r in results}, config.tick_seconds, error_path, title
        )
        clip = next(r for r in results if r.method == clip_method).clip
        frames = clip_frames(
            np.array(clip.pose),
            np.array(clip.mean),
            np.array(clip.cov),
            np.array(clip.head),
            np.array(clip.ball),
            np.array(clip.ball_in_view),
            config.field,
            config.camera,
            f"{clip_method}, match seed {args.seed}",
            config.tick_seconds,
            every=max(1, args.ticks // 150),
            robots=np.array(clip.robots),
            robot_radius=config.robots.radius,
        )
        save_gif(frames, clip_path, fps=10)
    print(f"wrote {', '.join(str(f) for f in outputs)}")


def add_parsers(sub: Any) -> None:
    p = sub.add_parser(
        "match",
        help="compare head-control strategies through whole matches (ActiveVisionMatch-v0)",
        description="Play each strategy through the same seeded matches of"
        " ActiveVisionMatch-v0 (the robot walking, the ball kicked about, the UKF tracking"
        " every tick) and report position and heading RMSE, time lost, ball in view, entropy"
        " and head travel with 95% intervals; writes match.csv, match_pareto.png,"
        " match_error.png and match_clip.gif.",
    )
    p.set_defaults(func=cmd_match)
    p.add_argument(
        "--methods",
        nargs="+",
        type=choice_list(_method_names),
        metavar="NAME",
        help="strategies to play (default: all; learned with --run): " + " ".join(_method_names()),
    )
    p.add_argument("--matches", type=int_in(1, MAX_MATCHES), default=50)
    p.add_argument("--ticks", type=positive_int, default=600, help="ticks per match (0.32 s each)")
    p.add_argument("--seed", type=seed, default=0, help="match i plays seed SEED + i")
    p.add_argument(
        "--step-deg",
        type=float_in(0.1, 30, "degrees"),
        default=3.0,
        help="head move per tick (paper: 3 degrees)",
    )
    p.add_argument(
        "--action-type",
        choices=("discrete", "continuous"),
        default="discrete",
        help="discrete: the 9 moves of --step-deg (the paper's); continuous: any move of up to"
        " --step-deg per axis (every strategy moves straight to its target; an exported"
        " policy's command is followed at that speed)",
    )
    p.add_argument(
        "--walk",
        choices=("waypoints", "ball"),
        default="waypoints",
        help="our robot walks to random waypoints, or to the ball",
    )
    p.add_argument(
        "--robots",
        type=int_in(0, 8),
        default=0,
        help="other robots on the field (0-8), occluding landmarks and the ball, which"
        " bounces off them",
    )
    p.add_argument(
        "--robot-speed",
        type=float_in(0, 1, "m/s"),
        default=0.0,
        help="m/s the other robots walk at between random waypoints (0: they stand; KidSize"
        " robots walk 0.1-0.3)",
    )
    p.add_argument(
        "--ball-bounces-off-us",
        action="store_true",
        help="the ball bounces off our robot's body, as off the others' (default: it rolls"
        " through our robot, as in the README's figures)",
    )
    p.add_argument(
        "--detection",
        nargs=3,
        type=float_in(0, 1),
        metavar=("NEAR", "FAR", "FALSE"),
        help="the landmark detector: probability of detecting a landmark in view at the robot"
        " and at its detection range, and false detections per tick (default 0.95 0.5 0.05;"
        " with --run, the detector that run was trained with)",
    )
    p.add_argument(
        "--model",
        type=path,
        nargs="+",
        help="exported policies (policy.onnx) for onnx_policy (default: the shipped one);"
        " with several, onnx_policy plays each, named onnx_policy[RUN] after its run folder",
    )
    p.add_argument(
        "--strategy",
        nargs="+",
        metavar="FILE.py:NAME",
        help="your own strategies, played beside --methods: NAME(config) in FILE.py (or"
        " MODULE:NAME) returns an object with reset(n, rng) and act(obs, info)"
        " (examples/uncertainty_glance.py)",
    )
    p.add_argument("--run", type=path, help="a training run for the learned strategy")
    add_weights(p)
    p.add_argument(
        "--track-margin",
        type=float_in(0, 22, "degrees"),
        nargs="+",
        metavar="DEG",
        help="how far inside the image entropy_track keeps the ball (default 5; 22, half"
        " the camera's vertical view, is ball tracking); with several, entropy_track plays"
        " each, named entropy_track[DEGdeg]",
    )
    p.add_argument(
        "--clip-method", help="the strategy shown in match_clip.gif (default: the first)"
    )
    p.add_argument(
        "--baseline",
        metavar="NAME",
        help="also print and write (match_paired.csv) every other strategy's difference from"
        " this one, match by match on the same seeds, with 95%% intervals",
    )
    p.add_argument("--out", type=path, default=Path("match-results"), help="output directory")
    add_overwrite(p)
