"""Argument types and helpers shared by the ``activevision`` commands.

Every value a user types is checked here, at the boundary, so a bad one ends in one line
that names it (argparse's ``error: argument --episodes: ...``) instead of a traceback or a
silently wrong result further down."""

from __future__ import annotations

import argparse
import contextlib
import math
import os
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, TypeVar

if TYPE_CHECKING:
    from activevision.envs import EnvConfig


#: the namespace attribute where :class:`ArgumentParser` keeps, while it parses, the options
#: given so far (each destination -> how it was given); removed before the namespace returns
_GIVEN = "_activevision_given"


def _shown(option: str | None, values: object) -> str:
    """An option as typed: ``--steps 5``, ``--runs a b``, ``--overwrite``."""
    if values is None or isinstance(values, bool):
        words: list[str] = []
    elif isinstance(values, list | tuple):
        words = [str(v) for v in values]
    else:
        words = [str(values)]
    return " ".join([option or "", *words]).strip()


def _once(base: type[argparse.Action]) -> type[argparse.Action]:
    """``base`` (a store action) that refuses a second value for its destination: argparse
    kept the last one silently (``--steps 5 --steps 6`` trained 6 steps, ``--runs A --runs
    B`` scored B alone)."""

    class Once(base):  # type: ignore[misc,valid-type]
        def __call__(
            self,
            parser: argparse.ArgumentParser,
            namespace: argparse.Namespace,
            values: object,
            option_string: str | None = None,
        ) -> None:
            given: dict[str, str] = vars(namespace).setdefault(_GIVEN, {})
            now = _shown(option_string, values)
            if self.dest in given:
                raise argparse.ArgumentError(
                    self, f"given twice ({given[self.dest]}, then {now}): give it once"
                )
            given[self.dest] = now
            super().__call__(parser, namespace, values, option_string)

    Once.__name__ = Once.__qualname__ = f"{base.__name__.lstrip('_')}Once"
    return Once


#: argparse's actions that keep one value, each as one refusing a second (:func:`_once`);
#: ``append`` (``--set``, ``--grid``), ``count``, ``help`` and ``version`` are left as they are
_ONCE_ACTIONS = {
    name: _once(base)
    for name, base in {
        None: argparse._StoreAction,
        "store": argparse._StoreAction,
        "store_const": argparse._StoreConstAction,
        "store_true": argparse._StoreTrueAction,
        "store_false": argparse._StoreFalseAction,
    }.items()
}


def distinct(noun: str) -> type[argparse.Action]:
    """The action of a list option (``nargs="+"``) that refuses a value given twice, naming
    it: ``--methods random random`` (``names the method random twice: give each method
    once``) played random once, the repeat dropped silently. Its list is given once, as
    every option that keeps one value (:func:`_once`)."""

    class Distinct(argparse._StoreAction):
        def __call__(
            self,
            parser: argparse.ArgumentParser,
            namespace: argparse.Namespace,
            values: str | Sequence[Any] | None,
            option_string: str | None = None,
        ) -> None:
            seen: list[object] = []
            for value in values if isinstance(values, list) else [values]:
                if value in seen:  # by value: --track-margin 5 5.0 is one margin twice
                    shown = f"{value:g}" if isinstance(value, float) else str(value)
                    raise argparse.ArgumentError(
                        self, f"names the {noun} {shown} twice: give each {noun} once"
                    )
                seen.append(value)
            super().__call__(parser, namespace, values, option_string)

    return _once(Distinct)


class ArgumentParser(argparse.ArgumentParser):
    """argparse with a one-line error: ``activevision CMD: error: ...`` and exit code 2; an
    option that keeps one value (not ``--set``'s kind, which collects them) given twice is
    refused, naming it (argparse kept the last silently)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        for name, action in _ONCE_ACTIONS.items():
            self.register("action", name, action)

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        parsed, extras = super().parse_known_args(args, namespace)
        vars(parsed).pop(_GIVEN, None)
        return parsed, extras

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


#: an argument's number type (int or float)
Number = TypeVar("Number", int, float)


def _integer(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer, got {text!r}") from None


def is_refusal(error: BaseException) -> bool:
    """Whether ``error`` is bad input or a refused file, told in one line (a ValueError, an
    OSError, an ImportError, a MemoryError: sizes within the config's bounds that this
    machine cannot hold, such as images of 8192 x 8192 px, or an error of activevision's
    own: a run's weights that fail their checksum, a policy file that does not match its
    metadata...), not a bug, which keeps its traceback."""
    return isinstance(error, ValueError | OSError | ImportError | MemoryError) or type(
        error
    ).__module__.startswith("activevision")


def error_text(error: BaseException) -> str:
    """A refusal's line: its message, and what a MemoryError is (numpy's says only "Unable
    to allocate 74.5 GiB for an array...", Python's nothing)."""
    if isinstance(error, MemoryError):
        return f"out of memory: {error}" if str(error) else "out of memory"
    return str(error)


@contextlib.contextmanager
def refused_by(parser: argparse.ArgumentParser, option: str) -> Iterator[None]:
    """Read what ``option`` names (a run, a policy file) inside: an error :func:`is_refusal`
    takes for a refusal (its weights file truncated, garbage bytes...) ends as
    ``parser.error`` (``PROG: error: OPTION: why``, exit code 2); any other keeps its
    traceback. For the scripts that build their own parser (``bench/``)."""
    try:
        yield
    except Exception as error:
        if not is_refusal(error):
            raise
        parser.error(f"{option}: {error_text(error)}")


#: ``--out`` of the picture commands (their ``--help`` said nothing of it)
FIGURE_HELP = "the figure's file, in the format its suffix names (.png, .pdf, .svg, ...)"
#: ``--out`` of ``episode`` and ``demo``: the record is
#: :func:`activevision.experiments.provenance.record_path`'s
FIGURE_AND_GIF_HELP = (
    FIGURE_HELP + "; the first policy's GIF is written beside it (its name without the"
    " suffix + .gif: episode.gif, one for episode.png and episode.svg; another figure's"
    " is replaced only with --overwrite), and a record of what played in them (the"
    " figure's name + .json: episode.png.json), which report reads"
)


def figure_file(text: str) -> Path:
    """A figure's file (``--out view.png``): a path that ends in a separator names a folder,
    which ``Path`` would silently make a file of that name (``--out figs/`` wrote a PNG
    called ``figs``); a name that is a suffix alone (``--out figs/.png``) has no suffix to
    Python and was written as a PNG called ``.png``; a name without a suffix names no format
    (``--out demo``, read as ``demo``'s folder, wrote a PNG file called ``demo``)."""
    if text.endswith(("/", os.sep)) or not text:
        raise argparse.ArgumentTypeError(
            f"name the figure's file, not a folder: got {text!r} (e.g. {text or './'}view.png)"
        )
    path = Path(text)
    if path.name.startswith(".") and path.name.count(".") == 1:  # ".png": no name, no suffix
        raise argparse.ArgumentTypeError(
            f"name the figure's file: {path.name!r} is a suffix alone (e.g."
            f" {path.with_name('view' + path.name)})"
        )
    if not path.suffix:
        raise argparse.ArgumentTypeError(
            f"name the figure's file with its format's suffix: {text!r} has no suffix (e.g."
            f" {path.with_name(path.name + '.png')}, or {path / 'view.png'} in that folder)"
        )
    return path


def path(text: str) -> Path:
    """A file or folder argument: not empty. ``Path("")`` is the current folder, so ``--out
    ""`` (a shell variable left unset: ``--out "$RUN"``) trained into whatever folder the
    command ran in."""
    if not text:
        raise argparse.ArgumentTypeError("must not be empty (the current folder is '.')")
    if not text.strip():  # ``--out " "`` wrote into a folder named by spaces
        raise argparse.ArgumentTypeError(f"must not be blank, got {text!r}")
    return Path(text)


def name(text: str) -> str:
    """A strategy's name (``--clip-method``, ``--baseline``): not empty nor blank. An empty
    one (a shell variable left unset: ``--clip-method "$M"``) was taken as no option, and the
    default played silently in its place."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"expects a strategy's name, got {text!r}")
    return text


def positive_int(text: str) -> int:
    """An integer >= 1 (episodes, steps, chunk sizes)."""
    value = _integer(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}")
    return value


def seed(text: str) -> int:
    """A seed: an integer in [0, 2**31) (NumPy's generators take no negative seed)."""
    value = _integer(text)
    if not 0 <= value < 2**31:
        raise argparse.ArgumentTypeError(f"must be an integer in [0, 2**31), got {text!r}")
    return value


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return value


#: The largest localisation error the commands take (m and rad): beyond the field's size in
#: metres, and past a full turn in radians, a larger error means nothing more.
MAX_ERROR = 10.0


def localisation_error(text: str) -> float:
    """A localisation error: a finite number in ``[0, MAX_ERROR]`` (metres and radians)."""
    value = _finite(text)
    if not 0 <= value <= MAX_ERROR:
        raise argparse.ArgumentTypeError(
            f"must lie in [0, {MAX_ERROR:g}] (m and rad), got {text!r}"
        )
    return value


def positive_float(text: str) -> float:
    """A finite number > 0."""
    value = _finite(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return value


def _bounded(
    convert: Callable[[str], Number], low: float, high: float, wanted: str
) -> Callable[[str], Number]:
    """An argument type: ``convert(text)`` checked to lie in ``[low, high]`` (``wanted``
    says what, in the error)."""

    def parse(text: str) -> Number:
        value = convert(text)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{wanted}, got {text!r}")
        return value

    return parse


def float_in(low: float, high: float, unit: str = "") -> Callable[[str], float]:
    """An argument type: a number in ``[low, high]`` (``unit`` named in the error)."""
    return _bounded(_finite, low, high, f"must lie in [{low:g}, {high:g}] {unit}".rstrip())


#: The most matches one command plays: they are played together, one native vector env of
#: that many sub-environments (envs.config.MAX_VECTOR_ENVS; the parser imports no envs)
MAX_MATCHES = 65_536
#: The most episodes of one fixed-seed set (``--episodes``): past it, the set of ``--seed s``
#: replays the first episodes of ``--seed s+1`` (envs.seeding.EPISODES_PER_SEED); 10**12
#: ran, unrefused, for years
MAX_EPISODES = 1_000_003


def int_in(low: int, high: int) -> Callable[[str], int]:
    """An argument type: an integer in ``[low, high]``."""
    return _bounded(_integer, low, high, f"must be an integer from {low} to {high}")


def error_levels(text: str) -> list[float]:
    """``0:2:0.25`` (start:stop:step, stop included) or ``0,0.5,1``: finite levels >= 0."""
    import numpy as np

    with _naming(text):
        if ":" in text:
            parts = text.split(":")
            if len(parts) != 3:
                raise argparse.ArgumentTypeError("expects start:stop:step")
            start, stop, step = (localisation_error(v) for v in parts)
            if step <= 0:
                raise argparse.ArgumentTypeError("step must be positive")
            if stop < start:
                raise argparse.ArgumentTypeError("stop is below start")
            return [round(float(v), 6) for v in np.arange(start, stop + step / 2, step)]
        levels = [localisation_error(v) for v in text.split(",")]
        if len(set(levels)) != len(levels):
            raise argparse.ArgumentTypeError("repeats a level")
        return levels


def seed_list(text: str) -> list[int]:
    """``0..9`` (both ends included), ``0,3,7`` or ``5``."""
    with _naming(text):
        if ".." in text:
            start, _, stop = text.partition("..")
            first, last = seed(start), seed(stop)
            if last < first:
                raise argparse.ArgumentTypeError("the end is before the start")
            return list(range(first, last + 1))
        seeds = [seed(v) for v in text.split(",")]
        if len(set(seeds)) != len(seeds):
            raise argparse.ArgumentTypeError("repeats a seed")
        return seeds


@contextlib.contextmanager
def _naming(text: str) -> Iterator[None]:
    """Add the whole value to an error about one of its parts."""
    try:
        yield
    except argparse.ArgumentTypeError as error:
        raise argparse.ArgumentTypeError(f"{error} (in {text!r})") from None


def grid_item(text: str) -> tuple[str, list[str]]:
    """``learning_rate=5e-4,1e-3``: a config key and its values (as text, parsed like
    ``--set`` when each trial's config is built)."""
    key, sep, values = text.partition("=")
    if not sep or not key.strip() or not values.strip():
        raise argparse.ArgumentTypeError(f"expects KEY=V1,V2,..., got {text!r}")
    return key.strip(), [v.strip() for v in values.split(",")]


def choice_list(choices: Callable[[], tuple[str, ...]]) -> Callable[[str], str]:
    """An argument type accepting one of ``choices()`` (looked up when parsing)."""

    def parse(text: str) -> str:
        known = choices()
        if text not in known:
            raise argparse.ArgumentTypeError(f"unknown {text!r}; choose from {', '.join(known)}")
        return text

    return parse


def add_weights(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--weights",
        choices=("final", "best"),
        default="final",
        help="the run's final weights or its best validated ones (eval_interval)",
    )


def check_weights(args: argparse.Namespace) -> None:
    """``--weights best`` names the best validated weights of a training run: refused where
    no run is given (``--run``, or ``--runs`` where the command has it)."""
    if args.weights != "final" and args.run is None and not getattr(args, "runs", None):
        raise ValueError(f"--weights {args.weights} picks a training run's weights: give --run")


def add_overwrite(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="replace output files that exist already (never a training run's own files)",
    )


def check_run(run_dir: Path | None, option: str = "--run") -> None:
    """ValueError naming ``option`` (``""`` for a positional RUN) unless ``run_dir`` (where
    given) holds a run's config.json: checked before the outputs a command puts inside the
    run, so a run that is a file is named as the run it is, not as an ``--out`` nobody
    typed."""
    if run_dir is not None and not (run_dir / "config.json").is_file():
        raise ValueError(not_a_run(run_dir, option))


def not_a_run(run_dir: Path, option: str = "--run") -> str:
    """The line for ``run_dir``, named by ``option`` (``""`` for a positional RUN), that
    holds no run's config.json; a file of a run named for the run (``RUN/config.json``,
    ``RUN/policy.onnx``) says so, and which run it is in ("RUN/config.json: not a training
    run (no config.json)" left the user looking for a config.json beside it)."""
    named = f"{option} {run_dir}" if option else str(run_dir)
    if run_dir.is_file() and (run_dir.parent / "config.json").is_file():
        return (
            f"{named}: a file of the training run {run_dir.parent}, not a run: name the run's"
            " folder"
        )
    return f"{named}: not a training run (no config.json)"


def env_config_of_run(run_dir: Path | None) -> EnvConfig:
    """The EnvConfig a run trained on (its config.json), else the paper's default. Its
    actions are discrete: a continuous policy moves by head targets (``HeadTarget``), so
    every method plays the same env. A run trained on the match (``match_ddqn``) plays
    episodes through the match's camera, with its moves: the image its network takes and
    the moves its actions are (its config's ``env`` is the unused default).

    The discrete moves the other methods (scan, random, oracle, entropy_steps...) make are
    the run's own where its actions are discrete; beside a run of continuous moves, which
    never reads ``step_deg`` or ``action_set``, they are the paper's (3 degrees, 8 ways):
    its config's values were read here, and one it carried unread (from a ``--config``
    file, or a run trained before ``--set`` refused them) made the baselines' moves
    silently other than the paper's, and refused discrete ``--runs`` of the paper's."""
    from activevision.envs import EnvConfig

    if run_dir is None:
        return EnvConfig()
    from activevision.envs.match.config import MATCH_ACTION_SET
    from activevision.training.config import MATCH_ENV_ID, load_config

    check_run(run_dir)
    config = load_config(run_dir / "config.json")
    world = config.match if config.env_id == MATCH_ENV_ID else config.env
    env = config.env.replace(action_type="discrete")
    if config.env_id == MATCH_ENV_ID:
        match = config.match
        moves = {"step_deg": match.step_deg, "action_set": MATCH_ACTION_SET}
        env = env.through_camera(match.camera).replace(**moves)
    if world.action_type == "continuous":  # its step_deg and action_set are unread
        paper = EnvConfig()
        env = env.replace(step_deg=paper.step_deg, action_set=paper.action_set)
    return env
