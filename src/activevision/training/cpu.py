"""Process-wide PyTorch settings that make CPU training fast (measured in ``bench/train.py``).

These change process state (thread count, allocator thresholds), so the trainer applies them
once when it starts rather than at import time.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os

import torch

# glibc mallopt parameters (malloc.h)
_M_TRIM_THRESHOLD = -1
_M_TOP_PAD = -2
_M_MMAP_THRESHOLD = -3


def resolve_device(name: str) -> torch.device:
    """ "auto" means cuda when available, else cpu. ValueError for a device this machine
    does not have (``cuda`` without a GPU, ``cuda:3`` with one)."""
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    try:
        device = torch.device(name)
    except RuntimeError as error:
        raise ValueError(f"device {name!r} is not a torch device: {error}") from None
    if device.type == "cuda":
        count = torch.cuda.device_count() if torch.cuda.is_available() else 0
        if count == 0 or (device.index or 0) >= count:
            raise ValueError(
                f"device {name!r} requested but this machine has {count} CUDA device(s);"
                " use device=auto or cpu"
            )
    if device.type == "mps" and not torch.backends.mps.is_available():
        raise ValueError(f"device {name!r} requested but MPS is not available here")
    return device


def training_device(name: str) -> torch.device:
    """:func:`resolve_device`, and on a GPU deterministic kernels: the same seed gives the
    same weights there too, and a resumed run ends as an uninterrupted one (cuDNN's default
    convolution gradients accumulate in a varying order)."""
    device = resolve_device(name)
    if device.type == "cuda":
        deterministic_cuda()
    return device


def deterministic_cuda() -> None:
    """cuDNN's and cuBLAS's deterministic algorithms, process-wide (a few percent slower).
    cuBLAS reads ``CUBLAS_WORKSPACE_CONFIG`` when it starts: set here unless already set."""
    os.environ.setdefault("CUBLAS_WORKSPACE_CONFIG", ":4096:8")
    torch.backends.cudnn.deterministic = True
    torch.backends.cudnn.benchmark = False
    torch.use_deterministic_algorithms(True, warn_only=True)


def resolve_num_threads(num_threads: int) -> int:
    """0 means one thread per core."""
    return num_threads if num_threads > 0 else (os.cpu_count() or 1)


#: How many more runnable processes than cores (the 1-minute load average) make a machine
#: busy for a run with a thread per core: beyond it, numba's and PyTorch's thread teams wait
#: on cores the other processes hold. Measured on 2 cores at load 6-7 (docs/benchmarks.md):
#: 2.8-3.2 steps/s with two threads, 11.5-13.3 with one.
BUSY_LOAD_MARGIN = 1.0


def busy_machine_note(
    num_threads: int,
    load: float | None = None,
    cores: int | None = None,
    *,
    resuming: bool = False,
) -> str | None:
    """One line for a run about to train with a thread per core (``num_threads`` 0) on a
    machine whose 1-minute load average ``load`` (read here when None) is more than
    :data:`BUSY_LOAD_MARGIN` above its ``cores``; None where it is not, or the user chose
    the thread count. ``resuming``: a run that continues keeps its ``config.json``'s
    threads (``--resume`` takes no ``--set``), so the line says what a new run would set."""
    cores = cores or os.cpu_count() or 1
    if num_threads != 0 or cores < 2:
        return None
    if load is None:
        try:
            load = os.getloadavg()[0]
        except OSError:  # where the OS keeps no load average
            return None
    if load <= cores + BUSY_LOAD_MARGIN:
        return None
    busy = f"this machine is busy (load {load:.1f} on {cores} cores): a thread per core"
    if resuming:
        return (
            f"{busy}, this run's setting (its config.json: run.num_threads 0), trains 4x"
            " slower on such a machine than one thread; a resumed run keeps its threads, a"
            " new run started with --set run.num_threads=1 uses one (docs/benchmarks.md)"
        )
    return (
        f"{busy}, the default, trained 4x slower on such a machine than --set"
        " run.num_threads=1 (docs/benchmarks.md)"
    )


def keep_freed_memory_mapped() -> bool:
    """Ask glibc to reuse freed heap memory instead of returning it to the OS.

    Every update allocates and frees activations of ~18 MB (32 x 32 x 58 x 78 floats). By
    default glibc serves such blocks with ``mmap`` and unmaps them on free, so each update pays
    thousands of page faults to touch fresh zeroed pages again; on a 2-core CPU that was about a
    third of the update time. Raising the mmap and trim thresholds keeps the pages. Returns
    False where glibc is not available (then nothing changes).
    """
    name = ctypes.util.find_library("c")
    if name is None:
        return False
    try:
        libc = ctypes.CDLL(name)
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    ok = mallopt(_M_MMAP_THRESHOLD, 32 << 20)  # glibc's maximum
    ok &= mallopt(_M_TRIM_THRESHOLD, 512 << 20)
    ok &= mallopt(_M_TOP_PAD, 64 << 20)
    return bool(ok)


def configure_torch_cpu(num_threads: int) -> None:
    """Thread count, flushing of denormals, and the allocator setting above."""
    torch.set_num_threads(resolve_num_threads(num_threads))
    torch.set_flush_denormal(True)
    keep_freed_memory_mapped()
