"""numba's thread pool across a fork (``activevision.threads``)."""

import multiprocessing
import subprocess
import sys
import textwrap

import pytest

# The parent steps a native vector env of 4 sub-environments (renders and searches on
# numba's threads), then a forked child steps one of its own and sends its observations'
# digest back. Run in a fresh interpreter: the pool must be the parent's own.
SCRIPT = textwrap.dedent(
    """
    import hashlib, multiprocessing, queue
    import gymnasium as gym, numpy as np
    import activevision

    def rollout():
        envs = gym.make_vec("ActiveVision-v0", 4, vectorization_mode="vector_entry_point")
        digest = hashlib.sha256(envs.reset(seed=3)[0].tobytes())
        for action in range(9):
            digest.update(envs.step(np.full(4, action))[0].tobytes())
        return digest.hexdigest()

    def child(out):
        out.put(rollout())

    if __name__ == "__main__":
        mine = rollout()
        import numba
        layer = numba.threading_layer()
        context = multiprocessing.get_context("fork")
        out = context.Queue()
        process = context.Process(target=child, args=(out,))
        process.start()
        while True:  # its digest, or "none" once it died without one
            try:
                theirs = out.get(timeout=1)
                break
            except queue.Empty:
                if not process.is_alive():
                    theirs = "none"
                    break
        process.join(30)
        print(layer, process.exitcode, theirs == mine)
    """
)


@pytest.mark.skipif(
    "fork" not in multiprocessing.get_all_start_methods(), reason="no fork on this platform"
)
def test_a_process_forked_after_the_pool_started_steps_a_vector_env_to_the_same_bytes():
    # GNU OpenMP's pool does not survive a fork: numba terminated such a child at its first
    # threaded kernel ("fork() called from a process already using GNU OpenMP"), so a
    # multiprocessing Pool of workers stepping native vector envs waited for ever
    out = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=400
    )
    assert out.returncode == 0, out.stderr
    layer, exitcode, same = out.stdout.split()
    assert (exitcode, same) == ("0", "True"), (layer, out.stderr[-2000:])
