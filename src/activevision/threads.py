"""numba's thread pool next to PyTorch.

numba's OpenMP threading layer and PyTorch share one ``libgomp``; when numba starts its
pool (the first ``numba.get_num_threads()`` or parallel kernel call) it resets the OpenMP
thread count, so a PyTorch that was set to one thread silently runs on all cores, and two
such processes on a small machine spin against each other. Every threaded kernel of this
package asks for the thread count through :func:`numba_threads`, which keeps PyTorch's
setting. Single environments and single frames never start the pool at all.
"""

from __future__ import annotations

import sys

import numba


def numba_threads() -> int:
    """``numba.get_num_threads()``, leaving PyTorch's thread count as it was (PyTorch is not
    imported here: only adjusted when the process already uses it)."""
    torch = sys.modules.get("torch")
    if torch is None:
        return int(numba.get_num_threads())
    before = torch.get_num_threads()
    threads = int(numba.get_num_threads())
    if torch.get_num_threads() != before:
        torch.set_num_threads(before)
    return threads
