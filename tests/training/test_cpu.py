"""Devices: "auto" and named devices, and deterministic kernels on a GPU (same seed, same
weights; a resumed run ends as an uninterrupted one). The GPU half was checked on an H200
(2026-12-04): without them the resume tests failed there, with them they pass."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest
import torch

from activevision.training.cpu import resolve_device, training_device


def test_a_cpu_device_changes_no_global_setting():
    before = (torch.are_deterministic_algorithms_enabled(), torch.backends.cudnn.deterministic)
    assert training_device("cpu") == torch.device("cpu")
    after = (torch.are_deterministic_algorithms_enabled(), torch.backends.cudnn.deterministic)
    assert after == before


def test_a_gpu_device_gets_deterministic_kernels():
    """What training_device does on a GPU, run in a fresh process (it is process-wide)."""
    code = textwrap.dedent("""
        import os, torch
        from activevision.training.cpu import deterministic_cuda
        os.environ.pop("CUBLAS_WORKSPACE_CONFIG", None)
        deterministic_cuda()
        assert torch.are_deterministic_algorithms_enabled()
        assert torch.is_deterministic_algorithms_warn_only_enabled()
        assert torch.backends.cudnn.deterministic and not torch.backends.cudnn.benchmark
        assert os.environ["CUBLAS_WORKSPACE_CONFIG"] == ":4096:8"
        print("ok")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["ok"]


@pytest.mark.skipif(torch.cuda.is_available(), reason="a machine without a GPU")
def test_a_gpu_that_is_not_there_is_refused():
    with pytest.raises(ValueError, match="CUDA device"):
        resolve_device("cuda")
    assert resolve_device("auto") == torch.device("cpu")


def test_busy_machine_note_only_for_a_thread_per_core_on_a_busy_machine():
    from activevision.training.cpu import busy_machine_note

    note = busy_machine_note(0, load=6.5, cores=2)
    assert note is not None and "load 6.5 on 2 cores" in note and "num_threads=1" in note
    assert busy_machine_note(0, load=3.0, cores=2) is None  # at the margin: not busy
    assert busy_machine_note(0, load=3.1, cores=2) is not None
    assert busy_machine_note(2, load=9.0, cores=2) is None  # the user chose the threads
    assert busy_machine_note(1, load=9.0, cores=2) is None
    assert busy_machine_note(0, load=9.0, cores=1) is None  # one thread already


def test_the_busy_machine_note_of_a_resumed_run_gives_no_advice_resume_refuses():
    """``train --resume`` on a busy machine advised ``--set run.num_threads=1``, which
    ``--resume`` refuses: its line names the run's own setting and what a new run sets."""
    from activevision.training.cpu import busy_machine_note

    note = busy_machine_note(0, load=6.5, cores=2, resuming=True)
    assert note is not None and "load 6.5 on 2 cores" in note
    assert "this run's setting" in note and "a resumed run keeps its threads" in note
    assert "new run started with --set run.num_threads=1" in note
