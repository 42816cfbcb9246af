"""Benchmark: Ray Tune overhead and scaling of a local 2-trial training sweep.

Runs the same 2-seed sweep of a small config twice on a local Ray instance: with 1 CPU
(the trials run one after the other) and with 2 CPUs (side by side), one CPU and one torch
thread per trial. Each trial measures its own run time inside the trainable (imports,
trainer construction, training, checkpoints; ``trials.csv``'s ``elapsed_s``). Ray's overhead
is the sweep's wall time (Ray start, the ``sweep()`` call with its scheduling, worker start,
reporting, Tune checkpoints, aggregation and figure, Ray shutdown) beyond the trials' own
time, as a fraction of it: sequential ``(wall - sum) / sum``, parallel ``(wall - max) / max``;
``overhead_fraction_excl_ray_start_stop`` leaves out starting and stopping Ray (a
once-per-session cost, nil when joining a running cluster).

Usage: python bench/sweep.py [--steps 900]
The last printed line is one JSON object.
"""

from __future__ import annotations

import csv
import json
import os
import platform
import tempfile
import time
from pathlib import Path
from typing import Any

from activevision.cli.args import ArgumentParser, positive_int


def run_sweep(steps: int, num_cpus: int, out_dir: Path) -> dict[str, Any]:
    from activevision.scaleout import sweep
    from activevision.training import apply_overrides, preset

    config = apply_overrides(
        preset("paper"),
        [
            f"total_timesteps={steps}",
            "learning_starts=100",
            "buffer_size=2000",
            "batch_size=8",
            "checkpoint_interval=300",
            "num_threads=1",
            "target_update_interval=100",
            "tensorboard=false",
            "progress_bar=false",
        ],
    )
    import ray

    t0 = time.perf_counter()
    # Ray's session folder (logs, sockets, spilled objects) in out_dir's temporary folder,
    # not a new /tmp/ray/session_* left behind at every run
    ray_dir = out_dir.parent / "ray"
    ray.init(
        num_cpus=num_cpus, include_dashboard=False, log_to_driver=False, _temp_dir=str(ray_dir)
    )
    t1 = time.perf_counter()
    sweep(config, [0, 1], {}, out_dir, verbose=0)  # joins the instance started above
    t2 = time.perf_counter()
    ray.shutdown()
    wall = time.perf_counter() - t0
    tune_wall = t2 - t1
    with (out_dir / "trials.csv").open() as f:
        trials = list(csv.DictReader(f))
    if any(t["status"] != "TERMINATED" for t in trials):
        raise RuntimeError(f"a trial failed: {trials}")
    own = [float(t["elapsed_s"]) for t in trials]
    ideal = sum(own) if num_cpus == 1 else max(own)
    return {
        "num_cpus": num_cpus,
        "wall_s": round(wall, 2),
        "trial_own_s": [round(t, 2) for t in own],
        "ideal_s": round(ideal, 2),
        "overhead_s": round(wall - ideal, 2),
        "overhead_fraction": round((wall - ideal) / ideal, 4),
        "ray_start_stop_s": round(wall - tune_wall, 2),
        "sweep_call_s": round(tune_wall, 2),
        "overhead_fraction_excl_ray_start_stop": round((tune_wall - ideal) / ideal, 4),
        "trials_per_hour": round(len(trials) * 3600 / wall, 1),
    }


def main() -> None:
    parser = ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--steps", type=positive_int, default=900, help="environment steps per trial"
    )
    args = parser.parse_args()
    import ray

    results = {}
    # (Ray's processes may still be writing logs as they end: their leftovers must not stop
    # the folder's removal)
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as tmp:
        for n in (1, 2):
            results[n] = run_sweep(args.steps, n, Path(tmp) / f"cpus{n}")
            print(f"{n} worker(s): {json.dumps(results[n])}", flush=True)
    one, two = results[1], results[2]
    summary = {
        "steps_per_trial": args.steps,
        "trials": 2,
        "trials_per_hour_1_worker": one["trials_per_hour"],
        "trials_per_hour_2_workers": two["trials_per_hour"],
        "scaling_ratio": round(two["trials_per_hour"] / one["trials_per_hour"], 3),
        "overhead_fraction": two["overhead_fraction"],
        "overhead_fraction_1_worker": one["overhead_fraction"],
        "overhead_s_1_worker": one["overhead_s"],
        "overhead_s_2_workers": two["overhead_s"],
        "overhead_fraction_excl_ray_start_stop": two["overhead_fraction_excl_ray_start_stop"],
        "ray_start_stop_s_2_workers": two["ray_start_stop_s"],
        "ray": ray.__version__,
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
    }
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
