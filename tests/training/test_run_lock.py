"""One trainer at a time per run directory (``training.run_lock``): a second trainer, of any
learner, fresh or resuming, is refused while the first holds the run, naming its pid; the
run is free again once the first closes or its process dies, however it dies."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import textwrap
from collections.abc import Iterator

import pytest

from activevision.training.dagger import DaggerTrainer
from activevision.training.run_lock import LOCK_FILE, RunInUseError, RunLock
from activevision.training.runs import reopen_run
from activevision.training.trainer import Trainer

from .test_dagger import tiny
from .test_trainer import tiny_config


def test_a_second_ddqn_trainer_is_refused_until_the_first_closes(tmp_path, fake_env_factory):
    run = tmp_path / "run"
    first = Trainer(tiny_config(), run, fake_env_factory, loggers=[])
    first.train(60)  # a checkpoint: the run can be resumed
    holder = rf"{run} is being trained by this process \(pid {os.getpid()}\)"
    with pytest.raises(RunInUseError, match=holder):
        reopen_run(run, fake_env_factory, loggers=[])
    first.close()
    second = reopen_run(run, fake_env_factory, loggers=[])
    assert second.step == 60
    second.train()
    second.close()


def test_a_resumed_dagger_run_in_use_is_said_to_be_in_use_not_a_bad_checkpoint(tmp_path):
    run = tmp_path / "run"
    first = DaggerTrainer(tiny(steps=200), run, loggers=[])
    first.train(100)  # whole rollouts: a little more
    first.save_checkpoint()
    with pytest.raises(RunInUseError, match="is being trained by this process"):
        reopen_run(run, loggers=[])
    first.close()
    first.close()  # closing twice is harmless
    second = reopen_run(run, loggers=[])
    assert second.step == first.step > 0
    second.close()


class FailingLogger:
    """A logger whose start fails: a trainer's construction fails after taking the lock."""

    def start(self, position):
        raise RuntimeError("the log cannot start")

    def close(self):
        pass


def test_a_trainer_that_fails_to_start_lets_the_run_go(tmp_path, fake_env_factory):
    run = tmp_path / "run"
    with pytest.raises(RuntimeError, match="the log cannot start"):
        Trainer(tiny_config(), run, fake_env_factory, loggers=[FailingLogger()])
    with pytest.raises(RuntimeError, match="the log cannot start"):
        DaggerTrainer(tiny(steps=200), tmp_path / "dagger", loggers=[FailingLogger()])
    for folder in (run, tmp_path / "dagger"):
        RunLock(folder).release()  # free: no "this process" holds it


HOLD = """
import sys, time
from activevision.training.run_lock import RunLock
lock = RunLock(sys.argv[1])
print("held", flush=True)
time.sleep(60)
"""


@contextlib.contextmanager
def held_by_another_process(folder) -> Iterator[int]:
    """``folder``'s run lock held by a child process (its pid) until the block ends, when
    the child is killed."""
    holder = subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(HOLD), str(folder)],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        yield holder.pid
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait()


def test_a_lock_dies_with_its_process(tmp_path):
    """A killed trainer leaves no stale lock: the operating system drops it."""
    with held_by_another_process(tmp_path) as pid:
        with pytest.raises(RunInUseError, match=f"another process \\(pid {pid}\\)"):
            RunLock(tmp_path)
    lock = RunLock(tmp_path)  # free again
    assert (tmp_path / LOCK_FILE).read_text() == f"pid {os.getpid()}\n"
    lock.release()
