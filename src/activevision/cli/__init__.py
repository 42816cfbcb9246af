"""The ``activevision`` command line: ``main`` and ``build_parser``; one module per command
group (``train``, ``evaluate``, ``robustness``, ``match``, ``deploy``, ``scene``,
``quickstart``), shared argument types in :mod:`activevision.cli.args` and the output-path check in
:mod:`activevision.cli.outputs`.

Heavy imports (torch, matplotlib) happen inside the command that needs them, so
``activevision --help`` is instant. The command is the only place a matplotlib backend is
chosen: :func:`main` sets ``MPLBACKEND=Agg`` (unless the user set one) before any command
imports matplotlib; the library's figures (:mod:`activevision.figures`) draw on their own
Agg canvas and never choose one."""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import warnings
from collections.abc import Callable, Iterator
from types import FrameType
from typing import Any

from activevision.cli import deploy, evaluate, match, quickstart, robustness, scene, train
from activevision.cli.args import ArgumentParser, error_text, is_refusal

_COMMAND_GROUPS = (train, evaluate, robustness, match, deploy, quickstart, scene)


def build_parser() -> ArgumentParser:
    parser = ArgumentParser(
        prog="activevision",
        description="Teach a humanoid soccer robot where to look: train head controllers (the"
        " paper's DDQN + PER, DAgger, SB3), score them against the entropy method and RoboCup"
        " teams' head control, in episodes and whole matches, and export them to ONNX.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    for group in _COMMAND_GROUPS:
        group.add_parsers(sub)
    return parser


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, a job scheduler's stop), raised in the main thread as Ctrl-C's
    KeyboardInterrupt is: a command stops as on Ctrl-C (its clean-up, its one line), with
    the shell's exit status for SIGTERM (128 + 15) instead of 130."""


class _Sigterm:
    """Whether SIGTERM arrived: code that catches the :class:`Terminated` and raises a
    KeyboardInterrupt of its own (Ray's ``ray.get`` does) would otherwise hide it."""

    received = False


def _unsafe_to_raise(frame: FrameType | None) -> bool:
    """Whether an exception raised in ``frame`` would crash the process: the Python code a
    numba-compiled function calls while it boxes its result (``_numba_unpickle`` of a type,
    a namedtuple's ``__new__``) is not expected to raise, and a KeyboardInterrupt raised
    there was a segmentation fault (a namedtuple result: the viewpoint search, every tick
    of a match's entropy_track and glance_track) or a SystemError. (A namedtuple or a
    dataclass that Python code makes, its ``__new__`` or ``__init__`` compiled from
    ``<string>`` as well, just waits until it returns.)"""
    depth = 0
    while frame is not None and depth < 8:
        code = frame.f_code
        if code.co_name == "_numba_unpickle" and "numba" in code.co_filename:
            return True
        if depth == 0 and code.co_filename == "<string>":
            return True
        frame, depth = frame.f_back, depth + 1
    return False


class _RaiseWhenSafe:
    """A profile function (``sys.setprofile``) that raises ``error`` at the first call or
    return in code where that is safe (:func:`_unsafe_to_raise`), then gives the profile
    back to ``previous``."""

    def __init__(self, error: BaseException, previous: Any) -> None:
        self.error, self.previous = error, previous

    def __call__(self, frame: FrameType, event: str, arg: object) -> None:
        if _unsafe_to_raise(frame):
            return
        sys.setprofile(self.previous)
        raise self.error


def _raise_when_safe(error: BaseException, frame: FrameType | None) -> None:
    """Raise ``error`` from a signal handler's ``frame``, or where that would crash the
    process (:func:`_unsafe_to_raise`) at the first call or return in safe code after it."""
    waiting = sys.getprofile()
    if isinstance(waiting, _RaiseWhenSafe):  # an earlier interrupt waits: this one instead
        sys.setprofile(waiting.previous)
    if not _unsafe_to_raise(frame):
        raise error
    sys.setprofile(_RaiseWhenSafe(error, sys.getprofile()))


@contextlib.contextmanager
def _sigterm_as_interrupt() -> Iterator[_Sigterm]:
    """While the block runs, SIGTERM raises :class:`Terminated` (once: a second SIGTERM
    ends the process at once, as it did before), and Ctrl-C its KeyboardInterrupt (where
    SIGINT has Python's default handler), each where raising it cannot crash the process
    (:func:`_raise_when_safe`). Outside the main thread, where Python cannot set signal
    handlers, nothing changes."""
    sigterm = _Sigterm()
    if threading.current_thread() is not threading.main_thread():
        yield sigterm
        return

    def terminate(signum: int, frame: FrameType | None) -> None:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        sigterm.received = True
        _raise_when_safe(Terminated(), frame)

    def interrupt(signum: int, frame: FrameType | None) -> None:
        _raise_when_safe(KeyboardInterrupt(), frame)

    previous = signal.signal(signal.SIGTERM, terminate)
    previous_int = signal.getsignal(signal.SIGINT)
    if previous_int is signal.default_int_handler:  # not where SIGINT is ignored
        signal.signal(signal.SIGINT, interrupt)
    try:
        yield sigterm
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL if previous is None else previous)
        if previous_int is signal.default_int_handler:
            signal.signal(signal.SIGINT, previous_int)
        waiting = sys.getprofile()
        if isinstance(waiting, _RaiseWhenSafe):  # never raised: the block ended first
            sys.setprofile(waiting.previous)


def main(argv: list[str] | None = None) -> int:
    """Run one command; returns the exit code (0 done, 2 bad input, a refused file or a failure
    such as a sweep's failed trials, 130 interrupted by Ctrl-C, 143 stopped by SIGTERM)."""
    # Headless by default; an environment variable, so --help needs no matplotlib import.
    os.environ.setdefault("MPLBACKEND", "Agg")
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exit_:  # --help (0) or a bad argument (2, one line already printed)
        return exit_.code if isinstance(exit_.code, int) else 2
    # warnings on one line each, like errors (not Python's "file:line: Category" and source)
    formatwarning = warnings.formatwarning
    warnings.formatwarning = _one_line_warning(args.command)
    sigterm = _Sigterm()
    try:
        with _sigterm_as_interrupt() as sigterm:
            if args.command == "quickstart":
                return quickstart.run_quickstart(args, main)
            args.func(args)
    except KeyboardInterrupt as interrupt:
        # Ctrl-C or SIGTERM: one line, with what to do next where the command knows, and the
        # shell's exit status for SIGINT (128 + 2) or SIGTERM (128 + 15)
        note = args.interrupted(args) if getattr(args, "interrupted", None) else ""
        if isinstance(interrupt, Terminated) or sigterm.received:
            print(f"activevision {args.command}: stopped by SIGTERM{note}", file=sys.stderr)
            return 143
        print(f"activevision {args.command}: interrupted{note}", file=sys.stderr)
        return 130
    except Exception as err:
        # Our own errors and bad input get one clear line; anything else is a bug: traceback.
        if not is_refusal(err):
            raise
        print(f"activevision {args.command}: error: {error_text(err)}", file=sys.stderr)
        return 2
    finally:
        warnings.formatwarning = formatwarning
    return 0


def _one_line_warning(command: str) -> Callable[..., str]:
    def format_warning(message: Warning | str, category: type[Warning], *_: object) -> str:
        text = " ".join(str(message).split())
        return f"activevision {command}: warning: {text}\n"

    return format_warning
