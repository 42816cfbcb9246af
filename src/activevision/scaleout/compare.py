"""The localisation-error experiment (:func:`activevision.experiments.compare.compare`) as
Ray tasks: one task per (error level, method, chunk of episodes).

Methods travel by name and every task builds its own environment and policy, so nothing
that may not pickle (lambdas, torch modules) crosses process boundaries. The result is
identical to the local run: :func:`~activevision.experiments.evaluate.run_episode` resets the
environment with the episode's seed and gives the policy a generator derived from it, so an
episode does not depend on what ran before it in the same process.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from activevision.envs import EnvConfig
from activevision.experiments.methods import (
    check_runs,
    compare_method_names,
    make_policy,
    runnable_methods,
)


def evaluate_chunk(
    method: str,
    error: float,
    base_seed: int,
    episode_indices: Sequence[int],
    config: EnvConfig,
    run_dir: str | Path | None = None,
    weights: str = "final",
) -> list[dict[str, Any]]:
    """Episode records of ``method`` for ``episode_indices`` of the level seeded ``base_seed``
    (what :func:`~activevision.experiments.evaluate.evaluate_policy` computes for them)."""
    from activevision.envs import ActiveVisionEnv
    from activevision.envs.seeding import episode_seed
    from activevision.experiments.compare import config_at_error
    from activevision.experiments.evaluate import run_episode, time_limit

    env = ActiveVisionEnv(config_at_error(config, error))
    policy = make_policy(method, error, config, run_dir, weights)
    try:
        return [
            run_episode(env, policy, episode_seed(base_seed, i), time_limit(env))
            for i in episode_indices
        ]
    finally:
        env.close()


def compare_ray(
    out_dir: str | Path,
    method_names: Sequence[str],
    errors: Sequence[float],
    episodes: int = 100,
    seed: int = 0,
    config: EnvConfig | None = None,
    run_dir: str | Path | None = None,
    weights: str = "final",
    chunk: int = 25,
    address: str | None = None,
    num_cpus: int | None = None,
    verbose: bool = False,
    run_sha256: str | None = None,
) -> list[dict]:
    """Run the experiment on Ray into ``out_dir/compare.csv`` (same file as the local run).

    Every (level, method, ``chunk`` episodes) is one Ray task using one CPU. Levels and
    methods already in the CSV are skipped, and the CSV is rewritten (atomically) as each
    level completes, in level order, so an interrupted run loses only unfinished levels.
    ``weights``: the run's "final" or "best" weights; ``run_sha256``: their digest, recorded
    in each row and checked against those resumed (as the local run's).
    ``address``/``num_cpus``: see :func:`~activevision.scaleout.ray_session.ray_session`.
    ``verbose``: the workers' output (warnings, a worker's traceback) is printed too (where
    this call starts Ray: a Ray already initialised in the process keeps its own setting).
    """
    from activevision.envs import ActiveVisionEnv
    from activevision.experiments.compare import check_resumable, done_levels, with_run
    from activevision.experiments.evaluate import summarise, summary_rows, time_limit
    from activevision.io import write_csv
    from activevision.scaleout.ray_session import ray_session

    if chunk < 1:
        raise ValueError(f"chunk must be positive, got {chunk}")
    check_runs(method_names, run_dir)  # also names the choices for an unknown method
    config = config or EnvConfig()
    csv_path = Path(out_dir) / "compare.csv"
    rows = done_levels(csv_path)
    check_resumable(csv_path, rows, episodes, seed, errors, run_sha256, weights)
    resumed = list(rows)
    done = {(float(r["error"]), r["method"]) for r in rows}
    run = str(run_dir) if run_dir is not None else None
    starts = list(range(0, episodes, chunk))
    limit = time_limit(ActiveVisionEnv(config))  # the tasks' envs', for the durations' bounds

    # quiet, as sweep: no INFO line of Ray's start ("Started a local Ray instance") and no
    # worker's output; a chunk's error reaches ray.get as an exception, and an idle worker
    # that Ray's shutdown stops with SIGTERM may print a traceback ("SystemExit: 1")
    quiet_logs = {} if verbose else {"logging_level": logging.WARNING}
    with ray_session(address, num_cpus, log_to_driver=verbose, **quiet_logs) as ray:
        task = ray.remote(num_cpus=1)(evaluate_chunk)
        config_ref = ray.put(config)
        pending: list[tuple[int, float, dict[str, list[Any]]]] = []
        for level, e in enumerate(errors):
            refs = {
                name: [
                    task.remote(
                        name,
                        float(e),
                        seed + level,
                        range(s, min(s + chunk, episodes)),
                        config_ref,
                        run,
                        weights,
                    )
                    for s in starts
                ]
                for name in method_names
                if (float(e), name) not in done
            }
            if refs:
                pending.append((level, float(e), refs))
        for level, e, refs in pending:  # in level order, so the CSV matches the local run's
            for name, chunk_refs in refs.items():
                records = [r for part in _get(ray, chunk_refs) for r in part]
                level_rows = summary_rows(
                    {name: summarise(records, limit)},
                    error=e,
                    episodes=episodes,
                    seed=seed,
                    level_seed=seed + level,
                )
                rows += with_run(level_rows, resumed, run_sha256, weights)
            write_csv(csv_path, rows)
    return rows


def _get(ray: Any, refs: list[Any]) -> list[Any]:
    """``ray.get(refs)``; a task's own error (a missing weights file, a bad run) is raised as
    itself, as the local run raises it, not wrapped in Ray's RayTaskError with the worker's
    traceback."""
    try:
        return list(ray.get(refs))
    except ray.exceptions.RayTaskError as error:
        cause = getattr(error, "cause", None)
        if isinstance(cause, Exception):
            raise cause from None
        raise


def default_method_names(run_dir: str | Path | None, selected: Sequence[str] | None) -> list[str]:
    """The methods ``activevision compare`` runs: ``selected`` in its order, each once, less
    those not runnable without a run (``--methods`` as the local CLI reads it); without
    ``selected``, the default order."""
    names = runnable_methods(compare_method_names(), run_dir)
    if not selected:
        return names
    return [m for m in dict.fromkeys(selected) if m in names]
