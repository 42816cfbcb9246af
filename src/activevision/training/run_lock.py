"""One trainer at a time per run directory.

Two processes training into one run directory (a second ``train --resume`` in another
terminal, a duplicated job) would interleave their logs and checkpoints, and the second's
start would delete the first's checkpoint half-written at that moment. A trainer therefore
holds an exclusive advisory lock (``flock``) on ``RUN/.lock`` from before its first write
until :meth:`RunLock.release` (the trainer's ``close``). The operating system drops the lock
when the process ends, however it ends, so a killed run leaves no stale lock to clear; the
file itself stays, naming the last holder. Where ``fcntl`` does not exist (Windows), runs
are not locked.
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


class RunInUseError(RuntimeError):
    """Another process is training into the run directory."""


class RunLock:
    """The exclusive lock on ``run_dir`` (created if need be); RunInUseError naming the
    holder's pid when another process holds it."""

    def __init__(self, run_dir: str | os.PathLike[str]) -> None:
        self.path = Path(run_dir) / LOCK_FILE
        self._file: IO[str] | None = None
        if fcntl is None:
            return
        self.path.parent.mkdir(parents=True, exist_ok=True)
        file = self.path.open("a+", encoding="utf-8")
        try:
            fcntl.flock(file.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            file.seek(0)
            holder = file.read().strip() or "unknown pid"
            file.close()
            raise RunInUseError(
                f"{self.path.parent} is being trained by another process ({holder}): let it"
                " finish (or stop it) before resuming, or train into another --out"
            ) from None
        file.seek(0)
        file.truncate()
        file.write(f"pid {os.getpid()}\n")
        file.flush()
        self._file = file

    def release(self) -> None:
        """Let another trainer take the run (idempotent)."""
        if self._file is not None:
            self._file.close()  # closing the descriptor drops the flock
            self._file = None


__all__ = ["LOCK_FILE", "RunInUseError", "RunLock"]
