"""The one place where the commands' output paths are checked before anything is written.

Rules (what a user of a research tool expects, and what keeps a run loadable):

1. The files of a training run (``config.json``, ``metrics.csv``, ``episodes.csv``, the
   weights, ``checkpoints/``...) are written only by ``train``. No other command writes over
   them, with or without ``--overwrite``: ``evaluate --out RUN`` or ``export -o
   RUN/config.onnx`` (whose metadata would be ``RUN/config.json``) are refused.
2. A file the user named (``--out FILE.png``, ``export -o FILE.onnx``) that exists already
   is replaced only with ``--overwrite``.
3. The fixed-name files a command writes inside its output directory (``evaluation.csv``,
   ``compare.csv``, ``report.md``, ``plots/*.png``) are that command's own: running it again
   refreshes them.
"""

from __future__ import annotations

from collections.abc import Iterable
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
    own: Iterable[Path] = (), named: Iterable[Path] = (), *, overwrite: bool = False
) -> None:
    """Refuse (OutputError naming the file) any output that breaks the module's rules.

    ``own``: fixed-name files of the command (rule 3); ``named``: files the user named
    (rule 2). Both are held against rule 1.
    """
    own, named = [Path(p) for p in own], [Path(p) for p in named]
    for path in own + named:
        if path.name in RUN_FILES and is_training_run(path.parent):
            raise OutputError(
                f"refusing to write {path}: it is a file of the training run {path.parent};"
                " choose another output path"
            )
    for path in named:
        if path.exists() and not overwrite:
            raise OutputError(f"{path} exists; pass --overwrite to replace it")
