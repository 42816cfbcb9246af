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
    distinct,
    float_in,
    int_in,
    name,
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
from activevision.text import counted

if TYPE_CHECKING:
    from activevision.envs.match.config import DetectionConfig, MatchConfig
    from activevision.experiments.match_methods import StrategyOptions
    from activevision.geometry import CameraConfig

OUTPUT_FILES = ("match.csv", "match_pareto.png", "match_error.png", "match_clip.gif")
PAIRED_FILE = "match_paired.csv"  #: with --baseline


def _method_names() -> tuple[str, ...]:
    from activevision.experiments.match_methods import match_method_names

    return match_method_names()


def _world_text(args: argparse.Namespace, config: MatchConfig, run: str | None = None) -> str:
    """What differs from the default world: ``", 4 other robots walking at 0.2 m/s,
    detector 0.6/0.15/0.2"``, or nothing; ``run`` names the run a detector came from
    (default: ``--run`` as given)."""
    from activevision.envs.match.config import DetectionConfig
    from activevision.experiments.match_world import kidnap_text

    text = ""
    if args.robots:
        moving = f"walking at {args.robot_speed:g} m/s" if args.robot_speed else "standing"
        text += f", {args.robots} other robot{'s' if args.robots > 1 else ''} {moving}"
    if config.detection != DetectionConfig():
        text += f", detector {detector_text(config.detection)}"
        if args.detection is None and args.run is not None:  # else --set's, named below
            text += f" (the one {args.run if run is None else run} was trained with)"
    camera = config.camera.differences()
    if camera and trained_camera(args):  # a run's (--set camera... is refused beside --run)
        text += f", camera {camera} (the one {args.run if run is None else run} was trained with)"
    if args.ball_bounces_off_us:
        text += ", the ball bouncing off our robot"
    if args.set:  # each as given: the camera, the tick, the tracker...
        text += ", --set " + " ".join(args.set)
    kidnap = kidnap_text(config)
    if kidnap:
        text += f", {kidnap}"
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


#: the match's settings an option of its own sets: ``--set`` refuses them, naming it
OPTION_PATHS = {
    "ticks": "--ticks",
    "step_deg": "--step-deg",
    "max_move_deg": "--step-deg",
    "action_type": "--action-type",
    "walk.target": "--walk",
    "walk": "--walk (and --set walk.FIELD=VALUE for the others)",
    "robots.count": "--robots",
    "others.speed": "--robot-speed",
    "ball.bounces_off_own_robot": "--ball-bounces-off-us",
    "detection.near": "--detection",
    "detection.far": "--detection",
    "detection.false_rate": "--detection",
    "detection": "--detection (and --set detection.ball_noise=VALUE)",
    "robots": "--robots (and --set robots.FIELD=VALUE for the others)",
    "others": "--robot-speed (and --set others.FIELD=VALUE for the others)",
    "ball": "--ball-bounces-off-us (and --set ball.FIELD=VALUE for the others)",
    "kidnap.rate": "--kidnap",
    "kidnap.ticks": "--kidnap-ticks",
    "kidnap": "--kidnap or --kidnap-ticks (and --set kidnap.distance=[LOW,HIGH], kidnap.turn=RAD)",
}
#: the settings ``match`` reads nothing of: why ``--set`` refuses them
UNREAD_PATHS = {
    "reward": "activevision match scores no reward (what a head is scored by is its table);"
    " the reward is what a training run learns: activevision train --set match.reward.FIELD=...",
    "observation": "every strategy takes the image and the info it needs whatever the"
    " observation; it is what a training run's network takes (activevision train --set"
    " match.observation=...)",
}


def match_settings(items: list[str] | None) -> dict[str, Any]:
    """``--set KEY=VALUE`` items as ``{path: value}`` (a leading ``match.`` dropped; values
    JSON where they parse, as ``train --set``). ValueError for an item that is no KEY=VALUE,
    a path set twice (``camera.hfov`` and ``match.camera.hfov``), or a key that an option
    sets (:data:`OPTION_PATHS`) or that ``match`` never reads (:data:`UNREAD_PATHS`)."""
    from activevision.training.config import parse_overrides

    settings: dict[str, Any] = {}
    try:
        changes = parse_overrides(items or [], lambda key: key.removeprefix("match."))
    except ValueError as error:
        raise ValueError(f"--set: {error}") from None
    for key, value in changes.items():
        path = key.removeprefix("match.")
        first = path.split(".")[0]
        if path in OPTION_PATHS:
            raise ValueError(f"--set {key}: give it with {OPTION_PATHS[path]}")
        if first in UNREAD_PATHS:
            raise ValueError(f"--set {key}: {UNREAD_PATHS[first]}")
        settings[path] = value
    return settings


def _match_config(args: argparse.Namespace) -> MatchConfig:
    """The matches the command line asks for: its options, then ``--set``."""
    from activevision.envs.match.config import (
        BallConfig,
        DetectionConfig,
        KidnapConfig,
        MatchConfig,
        OthersConfig,
        WalkConfig,
        with_paths,
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
    settings = match_settings(args.set)
    kidnap = KidnapConfig(rate=args.kidnap, ticks=tuple(args.kidnap_ticks or ()))
    late = [t for t in kidnap.ticks if t > args.ticks]
    if late:
        raise ValueError(f"--kidnap-ticks {late[0]}: past the match's {args.ticks} ticks (--ticks)")
    if not kidnap.enabled and any(p.split(".")[0] == "kidnap" for p in settings):
        raise ValueError("--set kidnap...: says how a kidnap goes; give --kidnap or --kidnap-ticks")
    if trained_camera(args) and any(p.split(".")[0] == "camera" for p in settings):
        raise ValueError(
            f"--set camera...: --run {args.run} plays through the camera it was trained for"
            " (its network takes that camera's image)"
        )
    config = MatchConfig(
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
        kidnap=kidnap,
    )
    if not settings:
        return config
    try:
        return with_paths(config, settings)
    except ValueError as error:
        raise ValueError(f"--set {error}") from None


def trained_camera(args: argparse.Namespace) -> bool:
    """Whether ``--run`` names a training run, whose camera the matches play through."""
    return args.run is not None and (args.run / "config.json").is_file()


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

    models = _models(args.model or [])
    if args.run is not None and not (args.run / "config.json").is_file():
        raise ValueError(not_a_run(args.run))
    # each once: the parser refuses a method or margin named twice
    methods = list(args.methods or default_match_methods(args.run))
    margins = list(args.track_margin or ())
    if margins and "entropy_track" not in methods:
        raise ValueError("--track-margin sets entropy_track's margin: add it to --methods")
    if models and "onnx_policy" not in methods:
        raise ValueError("--model is played by onnx_policy: add it to --methods")
    if args.run is not None and "learned" not in methods:
        raise ValueError("--run is played by learned: add it to --methods")
    check_weights(args)
    strategies = []
    for spec in args.strategy or ():
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


def _models(named: list[Path]) -> list[Path]:
    """``--model``'s files, each checked to be one, and each once: one named twice (however
    the path was written) played twice, as ``onnx_policy[NAME-1]`` and ``[NAME-2]``."""
    given: dict[Path, Path] = {}  # each model's file -> how --model named it first
    for model in named:
        if model.resolve() in given:
            first = given[model.resolve()]
            twice = f"{model}" if first == model else f"{first} and {model}"
            raise ValueError(f"--model names the policy {twice} twice: give each once")
        given[model.resolve()] = model
        if model.is_dir():  # was "no such file"
            raise ValueError(
                f"--model {model} is a directory: name the .onnx model in it"
                f" (e.g. {model / 'policy.onnx'})"
            )
        if not model.is_file():
            raise ValueError(f"--model {model}: no such file")
    return list(named)


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
    from activevision.experiments.match import model_columns
    from activevision.training.policy_files import scored_run_columns

    config = _match_config(args)
    entries = _strategies(args, config)
    # the run the learned strategy plays, as its weights are now (they were loaded to be
    # checked): recorded in match.csv for report, which leaves out another run's matches
    scored = None if args.run is None else scored_run_columns(args.run, args.weights)
    models = model_columns(entries)  # --model's files, as played: which model each row is
    methods = list(dict.fromkeys(method for _, method, _ in entries))
    labels = [label for label, _, _ in entries]
    clip_method = labels[0] if args.clip_method is None else args.clip_method
    if clip_method not in labels:
        raise ValueError(f"--clip-method {clip_method} is not among: {', '.join(labels)}")
    if args.baseline is not None and args.baseline not in labels:
        raise ValueError(f"--baseline {args.baseline} is not among: {', '.join(labels)}")
    if args.baseline is not None and len(labels) < 2:
        raise ValueError("--baseline needs at least one other method to compare with")
    made = make_output_folder(out)  # before the matches: one that cannot be made fails now
    import numpy as np

    from activevision.envs.match.scores import LOST_M
    from activevision.experiments.match import (
        NAME_WIDTH,
        compare_matches,
        csv_rows,
        format_difference,
        format_kidnaps,
        format_result,
        kidnap_header,
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
        f"{counted(len(labels), 'method')} x {counted(args.matches, 'match')}"
        f" of {counted(args.ticks, 'tick')}"
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
    if config.kidnap.enabled:
        print(
            f"after each kidnap that left the robot lost (error >= {LOST_M:g} m), until the"
            " next or the match's end: the lost detector fired, the error back under"
            f" {LOST_M:g} m, and the seconds it took (mean over those back) [95% intervals]:"
        )
        print(kidnap_header(width))
        for result in results:
            print(format_kidnaps(result, config.tick_seconds, width))
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
        write_csv(csv_path, csv_rows(results, args.matches, args.seed, config, scored, models))
        if args.baseline is None and args.overwrite and paired_path.exists():
            paired_path.unlink()  # --overwrite (match.csv was there): not this run's pairs
        if args.baseline is not None:
            differences = paired_differences(results, args.baseline)
            print(f"paired differences from {args.baseline}, match by match (mean [95% interval]):")
            print(table_header(width))
            for method, metrics in differences.items():
                print(format_difference(method, metrics, width))
            pairs = paired_rows(differences, args.baseline, args.matches, args.seed, models, scored)
            write_csv(paired_path, pairs)
        # the run by its folder's name, not by the path given: the figures are the same bytes
        # whatever the current directory and wherever the run lies
        run_name = None if args.run is None else args.run.resolve().name
        world = _world_text(args, config, run_name)
        # the console's first line names the walk; the figures, which travel alone, did not
        # (a striker walking to the ball sees it three times as often)
        walk = "" if args.walk == "waypoints" else f", walking to the {args.walk}"
        title = (
            f"{counted(args.matches, 'match')} x {play}, seed {args.seed},"
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
        action=distinct("method"),
        metavar="NAME",
        help="strategies to play (default: all; learned with --run): " + " ".join(_method_names()),
    )
    p.add_argument("--matches", type=int_in(1, MAX_MATCHES), default=50)
    p.add_argument(
        "--ticks",
        type=positive_int,
        default=600,
        help="ticks per match (0.32 s each; --set tick_seconds=S for another tick)",
    )
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
        " through our robot, as in docs/match.md's figures)",
    )
    p.add_argument(
        "--kidnap",
        type=float_in(0, 60, "per minute"),
        default=0.0,
        metavar="PER_MIN",
        help="kidnap our robot at random, seeded ticks, PER_MIN times per minute of play on"
        " average: carried 1-2 m and turned up to 0.8 rad, its belief told nothing (--set"
        " kidnap.distance=[LOW,HIGH] kidnap.turn=RAD); a table follows of what came after:"
        " the lost alarm, the error back under 0.5 m and how soon",
    )
    p.add_argument(
        "--kidnap-ticks",
        type=positive_int,
        nargs="+",
        action=distinct("tick"),
        metavar="TICK",
        help="kidnap our robot in these ticks of every match too (1: the first)",
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
        action=distinct("strategy"),
        metavar="FILE.py:NAME",
        help="your own strategies, played beside --methods: NAME(config) in FILE.py (or"
        " MODULE:NAME) returns an object with reset(n, rng) and act(obs, info)"
        " (examples/uncertainty_glance.py)",
    )
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="set any other field of the matches' MatchConfig by its path, as train --set"
        " match.KEY does: tick_seconds=0.16, camera.hfov=1.2, walk.speed=0.3,"
        " tracker.gate=9.21, detection.ball_noise=0.1; values are JSON. Those an option sets"
        " (--ticks, --step-deg, --detection...) are refused, naming it",
    )
    p.add_argument("--run", type=path, help="a training run for the learned strategy")
    add_weights(p)
    p.add_argument(
        "--track-margin",
        type=float_in(0, 22, "degrees"),
        nargs="+",
        action=distinct("margin"),
        metavar="DEG",
        help="how far inside the image entropy_track keeps the ball (default 5; 22, half"
        " the camera's vertical view, is ball tracking); with several, entropy_track plays"
        " each, named entropy_track[DEGdeg]",
    )
    p.add_argument(
        "--clip-method",
        type=name,
        metavar="NAME",
        help="the strategy shown in match_clip.gif (default: the first)",
    )
    p.add_argument(
        "--baseline",
        type=name,
        metavar="NAME",
        help="also print and write (match_paired.csv) every other strategy's difference from"
        " this one, match by match on the same seeds, with 95%% intervals",
    )
    p.add_argument("--out", type=path, default=Path("match-results"), help="output directory")
    add_overwrite(p)
