"""numba's thread pool next to PyTorch.

numba's OpenMP threading layer and PyTorch share one ``libgomp``; when numba starts its
pool (the first ``numba.get_num_threads()`` or parallel kernel call) it resets the OpenMP
thread count, so a PyTorch that was set to one thread silently runs on all cores, and two
such processes on a small machine spin against each other. Every threaded kernel of this
package asks for the thread count through :func:`numba_threads`, which keeps PyTorch's
setting. Single environments and single frames never start the pool at all.

GNU OpenMP's pool does not survive a ``fork``: a process forked from one whose pool had
started (``multiprocessing``'s default start method on Linux before Python 3.14: a
``Pool`` of workers that each step a native vector env, after the parent stepped one) was
terminated by numba at its first threaded kernel ("fork() called from a process already
using GNU OpenMP, this is unsafe"), and a ``Pool`` waited for it for ever. There
:func:`numba_threads` answers 1, so every kernel runs its serial twin, to the same bytes.
"""

from __future__ import annotations

import os
import sys

import numba

#: the process whose threaded kernels started numba's pool (None: none yet)
_pool_pid: int | None = None


def numba_threads() -> int:
    """``numba.get_num_threads()``, leaving PyTorch's thread count as it was (PyTorch is not
    imported here: only adjusted when the process already uses it); 1, without asking
    numba, in a process forked from one whose OpenMP pool had started."""
    global _pool_pid
    if _pool_pid is not None and _pool_pid != os.getpid() and _inherited_openmp():
        return 1
    _pool_pid = os.getpid()
    torch = sys.modules.get("torch")
    if torch is None:
        return int(numba.get_num_threads())
    before = torch.get_num_threads()
    threads = int(numba.get_num_threads())
    if torch.get_num_threads() != before:
        torch.set_num_threads(before)
    return threads


def _inherited_openmp() -> bool:
    """Whether the pool this forked process inherited runs on OpenMP (numba's ``omp``
    layer), which a fork leaves unusable; TBB and numba's workqueue survive one."""
    try:
        return bool(numba.threading_layer() == "omp")
    except ValueError:  # no threading layer was ever started
        return False
