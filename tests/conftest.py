"""Shared by every test."""

import hashlib
import os
import shutil
import sys
from pathlib import Path

import pytest


def _source_numba_cache() -> Path:
    """The numba cache of this state of the sources, as ``make test`` names it: numba checks
    a cached kernel against its own file only, not the files of the kernels it calls, so
    after an edit to one of those a plain ``pytest`` ran the old code from the default cache
    beside the sources."""
    root = Path(__file__).resolve().parent.parent
    sources = sorted((root / "src").rglob("*.py"), key=lambda p: os.fsencode(p.relative_to(root)))
    digest = hashlib.sha1(b"".join(p.read_bytes() for p in sources)).hexdigest()[:16]
    return root / ".numba_cache" / digest


def _prune_other_numba_caches(current: Path) -> None:
    """Remove the caches of earlier states of the sources, as ``make`` does: each edit left
    one more folder of compiled kernels behind."""
    if current.parent.is_dir():
        for other in current.parent.iterdir():
            if other != current:
                shutil.rmtree(other, ignore_errors=True)


# before numba is imported (it reads the variable once); make test and the user's own win
if "NUMBA_CACHE_DIR" not in os.environ and "numba" not in sys.modules:
    os.environ["NUMBA_CACHE_DIR"] = str(_source_numba_cache())
    _prune_other_numba_caches(Path(os.environ["NUMBA_CACHE_DIR"]))


@pytest.fixture(autouse=True)
def _sb3_logs_in_tmp_path(tmp_path_factory, monkeypatch):
    """Stable-Baselines3 used outside the package's trainers (as a user would) logs to a
    new ``SB3-<time>`` folder in the temporary directory at every ``learn``: give it a
    folder of the test session's instead, so the tests leave none behind."""
    monkeypatch.setenv("SB3_LOGDIR", str(tmp_path_factory.getbasetemp() / "sb3"))
