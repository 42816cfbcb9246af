"""The one place where the commands' output paths are checked before anything is written.

Rules (what a user of a research tool expects, and what keeps a run loadable):

1. The files of a training run (``config.json``, ``metrics.csv``, ``episodes.csv``, the
   weights, ``checkpoints/``...) are written only by ``train``. No other command writes over
   them, with or without ``--overwrite``: ``evaluate --out RUN`` or ``export -o
   RUN/config.onnx`` (whose metadata would be ``RUN/config.json``) are refused.
2. A file the user named (``--out FILE.png``, ``export -o FILE.onnx``) that exists already
   is replaced only with ``--overwrite``.
3. So are the fixed-name files a command writes inside its output directory
   (``evaluation.csv``, ``report.md``, ``RUN/policy.onnx``): running it again asks for
   ``--overwrite``. (``compare`` resumes its ``compare.csv`` when it was played on the same
   episodes and seed: continuing a table is not replacing it.)
4. An output directory that exists as a file is refused before any work.
5. The results of one run's policy are not written inside another training run
   (``evaluate --run A --out B/evaluation``): ``report B`` reads its folders as B's, and
   showed A's scores as B's.
"""

from __future__ import annotations

import tempfile
import warnings
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

from activevision.io import RUN_FILES


class OutputError(ValueError):
    """An output path would destroy a file that another command produced."""


def is_training_run(directory: Path) -> bool:
    """A directory written by ``train`` (it holds the run's ``config.json`` and logs)."""
    return (directory / "config.json").is_file() and (
        (directory / "metrics.csv").is_file() or (directory / "checkpoints").is_dir()
    )


def check_outputs(
    own: Iterable[Path] = (),
    named: Iterable[Path] = (),
    *,
    overwrite: bool = False,
    run: Path | None = None,
) -> None:
    """Refuse (OutputError naming the file) any output that breaks the module's rules.

    ``own``: fixed-name files of the command (rule 3), refused where they exist unless
    ``overwrite``; ``named``: files the user named (rule 2), the same. Both are held against
    rules 1, 4 and 5 (``run``: the training run the command plays, its ``--run``).
    """
    paths = [Path(p) for p in own] + [Path(p) for p in named]
    for path in paths:
        _check_run_of(path, run)
        for folder in (path.parent, *path.parent.parents):
            if folder.exists() and not folder.is_dir():
                raise OutputError(f"{folder} is a file, not a directory: choose another --out")
        if path.name in RUN_FILES and is_training_run(path.parent):
            raise OutputError(
                f"refusing to write {path}: it is a file of the training run {path.parent};"
                " choose another output path"
            )
        for folder in path.parents:  # RUN/checkpoints/..., RUN/tensorboard/...: train's too
            if folder.name in RUN_FILES and is_training_run(folder.parent):
                raise OutputError(
                    f"refusing to write {path}: {folder} belongs to the training run"
                    f" {folder.parent}; choose another output path"
                )
        if path.is_dir():
            raise OutputError(f"{path} is a directory: choose another output path")
    for path in paths:
        if path.exists() and not overwrite:
            raise OutputError(f"{path} exists; pass --overwrite to replace it")


def _check_run_of(path: Path, run: Path | None) -> None:
    """Rule 5: OutputError where ``path`` lies inside a training run other than ``run``."""
    if run is None:
        return
    for folder in Path(path).absolute().parents:
        if is_training_run(folder):
            if folder.resolve() != Path(run).resolve():
                raise OutputError(
                    f"refusing to write {path}: results of {run} inside the training run"
                    f" {folder} would read as its own (`activevision report` shows them so);"
                    " choose another --out"
                )
            return


def check_run_directory(directory: Path, *, overwrite: bool = False) -> None:
    """Refuse a new training run in ``directory`` where it would replace files another
    command (or the user) put there: any of a run's file names (rule 1 the other way round),
    unless ``overwrite``; a ``directory`` inside another run (whose folders its own commands
    write); and a ``directory`` that is a file (rule 4)."""
    if directory.exists() and not directory.is_dir():
        raise OutputError(f"{directory} is a file, not a directory: choose another --out")
    for folder in Path(directory).absolute().parents:
        if is_training_run(folder):  # not even with --overwrite: rule 1's folder
            raise OutputError(
                f"{directory} lies inside the training run {folder}: choose an --out outside it"
            )
    if overwrite or not directory.is_dir():
        return
    clash = sorted(p.name for p in directory.iterdir() if p.name in RUN_FILES)
    if clash:
        raise OutputError(
            f"{directory} already holds {', '.join(clash)}; choose another --out, or pass"
            " --overwrite to replace them"
        )


def figure_and_gif(figure: Path) -> Path:
    """The GIF written beside the figure ``figure`` (``episode``, ``demo``): refused when
    the two would be one file."""
    gif = Path(figure).with_suffix(".gif")
    if Path(figure).suffix.lower() == ".gif":  # also .GIF: one file on case-blind disks
        raise OutputError(
            f"--out {figure}: name the figure (e.g. {gif.with_suffix('.png')}); the GIF is"
            " written beside it"
        )
    return gif


def check_episode_outputs(
    figure: Path, *, overwrite: bool = False, run: Path | None = None
) -> tuple[Path, Path, list[Path]]:
    """The GIF and the record ``episode`` and ``demo`` write beside ``figure``
    (:func:`figure_and_gif`, ``experiments.provenance.record_path``), checked as
    :func:`check_outputs` and :func:`check_figure_path` check them, and the other figures
    whose GIF it is too (``episode.svg`` beside ``episode.png``: one ``episode.gif``, which
    ``episode.png.json`` records). Drawing ``episode.svg`` then replaced ``episode.png``'s
    GIF, and from another start ``report`` left ``episode.png`` out ("episode.gif is not the
    one episode.png.json records"): refused without ``overwrite``, naming that figure and
    another name to draw to; with it, :func:`warn_replaced_gif` says so after drawing."""
    from activevision.experiments.provenance import figures_sharing_gif, record_path

    gif = figure_and_gif(figure)
    record = record_path(figure)
    outputs = [figure, gif, record]
    check_outputs(named=outputs, overwrite=True, run=run)  # the rules before what exists
    check_figure_path(figure)  # before a name of its own is offered in its format
    shared = figures_sharing_gif(figure) if gif.is_file() else []
    if shared and not overwrite:
        other, free = shared[0], figure.with_name(f"{figure.stem}-2{figure.suffix}")
        raise OutputError(
            f"{gif} is the GIF of {other} ({record_path(other).name} records it): name"
            f" another figure (--out {free} draws {free.with_suffix('.gif').name}), or pass"
            f" --overwrite to replace it (from another start, {other.name} then no longer"
            " goes with it: report leaves it out)"
        )
    check_outputs(named=outputs, overwrite=overwrite, run=run)
    return gif, record, shared


def warn_replaced_gif(shared: Sequence[Path], gif: Path) -> None:
    """After ``episode``/``demo --overwrite`` drew ``gif``: warn, for each of the ``shared``
    figures (:func:`check_episode_outputs`) whose record records another GIF, that it no
    longer goes with it (the same episode drawn again is the same bytes: no warning)."""
    from activevision.experiments.provenance import record_path, records_other_gif

    for other in shared:
        if records_other_gif(other, gif):
            warnings.warn(
                f"{gif} is no longer the GIF {record_path(other).name} records: draw {other}"
                f" again (--out {other} --overwrite) or remove it (report leaves it out)",
                stacklevel=2,
            )


def check_figure_path(figure: Path) -> None:
    """OutputError unless a figure can be written at ``figure`` in the format its suffix
    names (checked before any work)."""
    from activevision.figures.canvas import figure_format

    try:
        figure_format(figure)
    except ValueError as error:
        raise OutputError(f"--out {error}") from None


def make_output_folder(folder: Path, name: str | None = None) -> list[Path]:
    """Make ``folder`` (with its missing parents) and check that files can be written in it,
    before a command's work: one that cannot fails now, in one line naming it (``name``,
    default ``--out FOLDER``), not after minutes of work. Returns the folders it made,
    deepest first (for :func:`removed_on_failure`)."""
    made = [f for f in (folder, *folder.parents) if not f.exists()]
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as err:
        _remove_empty(made)
        raise OutputError(
            f"{name or f'--out {folder}'}: cannot create it or write in it ({err.strerror or err})"
        ) from None
    return made


@contextmanager
def removed_on_failure(made: list[Path], outputs: Sequence[Path] = ()) -> Iterator[None]:
    """When the block fails, remove the command's ``outputs`` (read when it fails: a list may
    grow) and the folders ``made`` (:func:`make_output_folder`) again: a failed or
    interrupted command leaves neither an empty folder nor a part of its set of outputs
    (a CSV without its figures). Under ``--overwrite`` the older set goes with it (the
    block is the writing: an interrupt before it leaves the older set as it was)."""
    try:
        yield
    except BaseException:
        for output in outputs:
            output.unlink(missing_ok=True)
        _remove_empty(made)
        raise


def _remove_empty(folders: list[Path]) -> None:
    """Remove ``folders`` (deepest first), each while it is empty."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:
            break
