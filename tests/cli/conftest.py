"""What the command-line tests share: a tiny training run made once through the real CLI,
the one-clear-line check of bad input, and file digests."""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path

import pytest

from activevision.cli import main


@pytest.fixture(autouse=True)
def _a_quiet_machine(monkeypatch):
    """The machine's load as a quiet one's: ``train`` warns on a busy machine
    (``training.cpu.busy_machine_note``), which would add a line to the output these tests
    read whenever the tests run beside other work."""
    import os

    monkeypatch.setattr(os, "getloadavg", lambda: (0.0, 0.0, 0.0))


#: A training run small enough for a test (CPU seconds), through the real CLI.
TINY_TRAIN = [
    "train",
    "--preset",
    "quickstart_ddqn",
    "--steps",
    "60",
    "--set",
    "learning_starts=20",
    "--set",
    "batch_size=8",
    "--set",
    "buffer_size=500",
    "--set",
    "epoch_steps=30",
    "--set",
    "checkpoint_interval=30",
    "--set",
    "tensorboard=false",
    "--set",
    "num_threads=1",
]


@pytest.fixture(scope="session")
def trained(tmp_path_factory) -> Path:
    """A tiny finished run; tests that change it work on a copy."""
    run = tmp_path_factory.mktemp("runs") / "tiny"
    assert main([*TINY_TRAIN, "--out", str(run)]) == 0
    return run


@pytest.fixture
def one_clear_line(capsys) -> Callable[..., str]:
    """``one_clear_line(*needles)``: stderr is one line holding every needle, and no
    traceback was printed anywhere."""

    def check(*needles: str) -> str:
        captured = capsys.readouterr()
        lines = [line for line in captured.err.splitlines() if line.strip()]
        assert len(lines) == 1, captured.err
        assert "Traceback" not in captured.err + captured.out
        for needle in needles:
            assert needle in lines[0], lines[0]
        return lines[0]

    return check


def _digests(directory: Path) -> dict[str, str]:
    return {
        str(p.relative_to(directory)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(directory.rglob("*"))
        if p.is_file()
    }


@pytest.fixture
def digests() -> Callable[[Path], dict[str, str]]:
    """``digests(directory)``: SHA-256 of every file under it, by relative path."""
    return _digests


@pytest.fixture
def tiny_train() -> list[str]:
    """The arguments of :data:`TINY_TRAIN` (add ``--out``)."""
    return list(TINY_TRAIN)


@pytest.fixture
def tiny_train_without() -> Callable[..., list[str]]:
    """``tiny_train_without(*keys)``: :data:`TINY_TRAIN` without its ``--set`` of each key,
    for a test that sets them itself (``train`` refuses a field set twice)."""

    def without(*keys: str) -> list[str]:
        argv: list[str] = []
        for word in TINY_TRAIN:
            if argv and argv[-1] == "--set" and word.partition("=")[0] in keys:
                argv.pop()
            else:
                argv.append(word)
        return argv

    return without
