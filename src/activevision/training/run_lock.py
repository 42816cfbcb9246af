"""One trainer at a time per run directory (and one ``compare`` per output folder).

Two processes training into one run directory (a second ``train --resume`` in another
terminal, a duplicated job) would interleave their logs and checkpoints, and the second's
start would delete the first's checkpoint half-written at that moment. A trainer therefore
holds an exclusive advisory lock (``flock``) on ``RUN/.lock`` from before its first write
until :meth:`RunLock.release` (the trainer's ``close``). The operating system drops the lock
when the process ends, however it ends, so a killed run leaves no stale lock to clear; the
file itself stays, naming the last holder. A resume takes the lock before it reads the
checkpoint (another trainer may be replacing it) and hands it to the trainer it builds. Where
``fcntl`` does not exist (Windows), runs are not locked.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import IO

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX
    fcntl = None  # type: ignore[assignment]

LOCK_FILE = ".lock"  #: in the run directory; holds "pid N" of the trainer holding it


class RunInUseError(Exception):
    """Another trainer holds the run directory. (Not a RuntimeError: the resume paths turn
    those into "checkpoint does not fit" errors.)"""


#: what the lock's holder does to the folder, and what to do instead (the refusal's words)
TRAINING = ("trained", "let it finish (or stop it) before resuming, or train into another --out")


class RunLock:
    """The exclusive lock on ``run_dir`` (created if need be); RunInUseError naming the
    holder's pid when another process holds it. ``work`` is ``(what the holder does,
    what to do instead)``: a trainer's by default; ``compare`` locks its folder too."""

    def __init__(self, run_dir: str | os.PathLike[str], work: tuple[str, str] = TRAINING) -> None:
        done, advice = work
        self.path = Path(run_dir) / LOCK_FILE
        self._file: IO[str] | None = None
        if fcntl is None:
            return
        self.path.parent.mkdir(parents=True, exist_ok=True)
        # read-write without truncating (the holder's pid must stay readable) or appending
        file = os.fdopen(os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644), "r+", encoding="utf-8")
        try:
            fcntl.flock(file.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            file.seek(0)
            holder = file.read().strip() or "unknown pid"
            file.close()
            if holder == _holder():
                raise RunInUseError(
                    f"{self.path.parent} is being {done} by this process ({holder}): release"
                    " the lock that holds it first (a trainer's close())"
                ) from None
            raise RunInUseError(
                f"{self.path.parent} is being {done} by another process ({holder}): {advice}"
            ) from None
        # written over the old holder, then cut: a reader never finds the file empty
        file.seek(0)
        file.write(_holder() + "\n")
        file.truncate()
        file.flush()
        self._file = file

    def release(self, remove: bool = False) -> None:
        """Let another trainer take the run (idempotent). With ``remove``, the lock file
        goes too (removed while still held, so no other process can hold it by then)."""
        if self._file is not None:
            if remove:
                self.path.unlink(missing_ok=True)
            self._file.close()  # closing the descriptor drops the flock
            self._file = None


def _holder() -> str:
    return f"pid {os.getpid()}"


__all__ = ["LOCK_FILE", "TRAINING", "RunInUseError", "RunLock"]
