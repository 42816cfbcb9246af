"""Benchmark: are training runs of the same seed bitwise identical across processes?

Trains the same short DDQN run (``quickstart_ddqn`` preset, 900 steps, 600 updates, seed 0) in
``--repeats`` fresh processes, with 2 threads, 1 thread, and 1 thread with oneDNN (mkldnn)
off, and reports how many distinct final weights each produced and the time per run. Within
one process runs are identical (tests/training); across processes they are not always.

Usage: python bench/reproducibility.py [--repeats 4]
The last printed line is one JSON object.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

from activevision.cli.args import ArgumentParser, positive_int

RUN = """
import hashlib, sys, tempfile
import torch
from activevision.training import Trainer, preset
torch.backends.mkldnn.enabled = sys.argv[2] != "1"
config = preset("quickstart_ddqn").replace(
    total_timesteps=900, learning_starts=300, num_threads=int(sys.argv[1]),
    progress_bar=False, tensorboard=False, checkpoint_interval=0, seed=0)
with tempfile.TemporaryDirectory() as run_dir:  # the run's files, removed after it
    trainer = Trainer(config, run_dir)
    try:
        trainer.train()
    finally:
        trainer.close()
weights = b"".join(p.detach().cpu().numpy().tobytes() for p in trainer.learner.online.parameters())
print(hashlib.sha256(weights).hexdigest())
"""


def runs(threads: int, onednn_off: bool, repeats: int) -> tuple[int, float]:
    """(distinct weight hashes, mean seconds per run) of ``repeats`` fresh processes."""
    hashes, seconds = set(), []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = subprocess.run(
            [sys.executable, "-c", RUN, str(threads), "1" if onednn_off else "0"],
            capture_output=True,
            text=True,
            check=True,
        )
        seconds.append(time.perf_counter() - t0)
        hashes.add(out.stdout.split()[-1])
    return len(hashes), sum(seconds) / len(seconds)


def main() -> None:
    parser = ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=positive_int, default=4, help="processes per setting")
    args = parser.parse_args()
    results = {}
    for name, threads, onednn_off in (
        ("default_2_threads", 2, False),
        ("default_1_thread", 1, False),
        ("onednn_off_1_thread", 1, True),
    ):
        distinct, seconds = runs(threads, onednn_off, args.repeats)
        results[f"{name}_distinct_results"] = distinct
        results[f"{name}_s_per_run"] = round(seconds, 1)
        print(
            f"{name:18s}: {distinct} distinct result(s) in {args.repeats} processes, "
            f"{seconds:.1f} s per run"
        )
    results["repeats"] = args.repeats
    results["onednn_off_slowdown_vs_1_thread"] = round(
        results["onednn_off_1_thread_s_per_run"] / results["default_1_thread_s_per_run"], 2
    )
    print(json.dumps(results))


if __name__ == "__main__":
    main()
