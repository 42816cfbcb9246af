"""One trainer at a time per run directory (``training.run_lock``): a second trainer, of any
learner, fresh or resuming, is refused while the first holds the run, naming its pid; the
run is free again once the first closes or its process dies, however it dies."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap

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
    holder = rf"{run} is being trained by another process \(pid {os.getpid()}\)"
    with pytest.raises(RunInUseError, match=holder):
        reopen_run(run, fake_env_factory, loggers=[])
    with pytest.raises(RunInUseError):  # nor a trainer that would write over it
        Trainer(tiny_config(), run, fake_env_factory, loggers=[], _resuming=True)
    first.close()
    second = reopen_run(run, fake_env_factory, loggers=[])
    assert second.step == 60
    second.train()
    second.close()


def test_a_second_dagger_trainer_is_refused_until_the_first_closes(tmp_path):
    run = tmp_path / "run"
    first = DaggerTrainer(tiny(steps=200), run, loggers=[])
    with pytest.raises(RunInUseError, match="is being trained by another process"):
        DaggerTrainer(tiny(steps=200), run, loggers=[], _resuming=True)
    first.close()
    first.close()  # closing twice is harmless
    DaggerTrainer(tiny(steps=200), run, loggers=[], _resuming=True).close()


HOLD = """
import sys, time
from activevision.training.run_lock import RunLock
lock = RunLock(sys.argv[1])
print("held", flush=True)
time.sleep(60)
"""


def test_a_lock_dies_with_its_process(tmp_path):
    """A killed trainer leaves no stale lock: the operating system drops it."""
    holder = subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(HOLD), str(tmp_path)],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        with pytest.raises(RunInUseError, match=f"pid {holder.pid}"):
            RunLock(tmp_path)
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait()
    lock = RunLock(tmp_path)  # free again
    assert (tmp_path / LOCK_FILE).read_text() == f"pid {os.getpid()}\n"
    lock.release()
