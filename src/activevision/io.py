"""Crash-safe file writing: write a temporary file beside the target, flush it to disk, then
rename it over the target (atomic on POSIX), so a crash never leaves a half-written file and
never destroys the previous version."""

from __future__ import annotations

import contextlib
import csv
import errno
import hashlib
import io
import json
import math
import os
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any


def fsync_path(path: Path) -> None:
    """Flush a file (or a directory's entries) to disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` to write; when the block succeeds it is
    flushed and renamed over ``path``, when it fails it is removed."""
    path = Path(path)
    if path.is_dir():  # refused before the block's work; the rename named the temporary
        raise IsADirectoryError(errno.EISDIR, f"cannot write {path}: it is a directory")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as error:  # name the file asked for, not the temporary one
        raise type(error)(error.errno, f"cannot write {path}: {error.strerror}") from None
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        fsync_path(tmp)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except OSError as error:
        if error.filename not in (None, name) or error.errno is None:
            raise  # another file's error, which names it
        # a full disk or a failed write: "[Errno 28] No space left on device" named no file
        raise type(error)(error.errno, f"cannot write {path}: {error.strerror}") from None
    finally:
        tmp.unlink(missing_ok=True)


def file_sha256(path: str | os.PathLike) -> str:
    """The SHA-256 of a file's bytes, hex: what result files record of the files they used."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def write_bytes(path: str | os.PathLike, data: bytes) -> None:
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def write_text(path: str | os.PathLike, text: str) -> None:
    write_bytes(path, text.encode("utf-8"))


def write_json(path: str | os.PathLike, data: Any) -> None:
    write_text(path, json.dumps(data, indent=2) + "\n")


def nan_as_null(data: Any) -> Any:
    """``data`` (JSON-like: dicts, lists, tuples, scalars) with every float NaN as None, so
    that it is written as ``null``: Python writes NaN as a bare ``NaN``, which strict JSON
    readers (jq, JavaScript, most languages' parsers) refuse. For results, where NaN means
    "no value" (an interval of one episode); a file read back by this package turns the
    nulls into NaN again where it needs numbers."""
    if isinstance(data, float) and math.isnan(data):
        return None
    if isinstance(data, dict):
        return {key: nan_as_null(value) for key, value in data.items()}
    if isinstance(data, (list, tuple)):
        return [nan_as_null(value) for value in data]
    return data


def write_csv(path: str | os.PathLike, rows: Sequence[dict]) -> None:
    """Rows of dicts with the same keys (the first row's keys are the header), as UTF-8 (as
    :func:`read_csv` reads them, whatever the locale)."""
    with atomic_path(path) as tmp, tmp.open("w", encoding="utf-8", newline="") as f:
        if rows:
            writer = csv.DictWriter(f, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)


def read_csv(
    path: str | os.PathLike, columns: Sequence[str] = (), *, live: bool = False
) -> list[dict[str, str]]:
    """A CSV file's rows as dicts keyed by its header (:func:`read_csv_lines`)."""
    return [row for _, row in read_csv_lines(path, columns, live=live)]


class CutLineError(ValueError):
    """A CSV file whose last line has no end of line: it was cut inside that line."""


def read_csv_text(path: str | os.PathLike, *, live: bool = False) -> tuple[str, bool]:
    """A CSV file's text (UTF-8, newlines kept) and whether an unterminated last line was
    dropped from it. Every CSV this package writes ends each row with an end of line
    (csv's ``\r\n``; :class:`~activevision.training.metrics.CsvLog` appends whole rows),
    so a last line without one was cut: by a crash, a full disk, a copy stopped midway, or,
    for a log still being written (``live``), a row not written to its end yet. A row cut
    inside its last cell still has all its cells (``0.12`` of ``0.1234``), so counting
    cells does not find it. CutLineError naming the file where not ``live``; ``live`` drops
    that line (the caller says so). UnicodeDecodeError where it is no UTF-8 text."""
    text = Path(path).read_bytes().decode("utf-8")
    if not text or text.endswith("\n"):
        return text, False
    if not live:
        line = text.count("\n") + 1
        raise CutLineError(
            f"{path} line {line} has no end of line: the file was cut inside its last row;"
            " it is damaged or not a file activevision wrote"
        )
    return text[: text.rfind("\n") + 1], True


def read_csv_lines(
    path: str | os.PathLike, columns: Sequence[str] = (), *, live: bool = False
) -> list[tuple[int, dict[str, str]]]:
    """A CSV file's rows as dicts keyed by its header, each with the line it ends on;
    ValueError naming the file: where it has no header row (empty: every CSV this package
    writes has one, so a file of 0 bytes was read as a table of no rows), its header lacks
    one of ``columns`` (another file's table, whose rows were then skipped as not played
    or not there), a row has more or fewer cells than the header (a file cut mid-row:
    DictReader fills the missing cells with None, which were read on as values), its last
    line has no end of line (cut inside its last row, :func:`read_csv_text`; dropped where
    ``live``) or the file is not CSV text."""
    rows = []
    try:
        text, _ = read_csv_text(path, live=live)
        with io.StringIO(text, newline="") as f:
            reader = csv.DictReader(f)
            header = reader.fieldnames or []  # None for an empty file; [] for blank lines
            # the reader's line, not a count of rows: it skips blank lines, and a quoted
            # cell may hold several
            rows = [(reader.line_num, row) for row in reader]
    except (UnicodeDecodeError, csv.Error) as error:  # binary, a NUL, a field past the limit
        raise ValueError(
            f"{path} is damaged or not a file activevision wrote ({type(error).__name__}: {error})"
        ) from None
    if not any(header):
        raise ValueError(
            f"{path} is empty (no header row): it is damaged or not a file activevision wrote"
        )
    missing = [column for column in columns if column not in header]
    if missing:
        raise ValueError(
            f"{path} has no {missing[0]!r} column: it is damaged or not a file activevision wrote"
        )
    for line, row in rows:
        if None in row or None in row.values():  # DictReader's marks of a row cut or run on
            raise ValueError(
                f"{path} line {line} has {'more' if None in row else 'fewer'} cells than its"
                " header: it is damaged or not a file activevision wrote"
            )
    return rows


class DuplicateKeyError(ValueError):
    """A JSON object that names one key twice (:func:`loads_json`)."""


def _unique_pairs(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """``json``'s object_pairs_hook refusing a key named twice: ``json.loads`` keeps the
    last value and drops the first without a word (a config's ``"seed": 1`` written over by
    a forgotten ``"seed": 2`` further down)."""
    values: dict[str, Any] = {}
    for key, value in pairs:
        if key in values:
            raise DuplicateKeyError(f"duplicate key {key!r}")
        values[key] = value
    return values


def loads_json(text: str | bytes) -> Any:
    """``json.loads`` that refuses an object with a key named twice (DuplicateKeyError, a
    ValueError naming the key), for every JSON file a user could write or edit."""
    return json.loads(text, object_pairs_hook=_unique_pairs)


def read_json(path: str | os.PathLike) -> Any:
    """A JSON file's value; ValueError naming the file if it is not valid JSON (or names a
    key twice in one object)."""
    try:
        return loads_json(Path(path).read_text(encoding="utf-8"))
    except DuplicateKeyError as error:
        raise ValueError(f"{path}: {error} (each key may appear once)") from None
    except (ValueError, RecursionError) as error:
        # ValueError: JSONDecodeError, UnicodeDecodeError, or an integer of more digits than
        # Python converts; RecursionError: arrays or objects nested too deep for the decoder
        raise ValueError(f"{path} is not valid JSON: {error}") from None


#: Files and directories of a training run directory, written only by training (the CLI's
#: output check refuses every other command's write to them).
RUN_FILES = frozenset(
    {
        "config.json",
        "metrics.csv",
        "episodes.csv",
        "evaluations.csv",
        "policy.safetensors",
        "best_policy.safetensors",
        "tensorboard",
        "checkpoints",
    }
)
