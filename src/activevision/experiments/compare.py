"""The paper's localisation-error experiment: success of every method as the robot's
self-localisation error grows; :mod:`activevision.figures.compare` draws the figure.

At error level ``e`` the entropy-based head control searches its goal from the true pose
moved ``e`` m in a random direction and turned by ``+-e`` rad, and is scored against the
true goal with the true pose. The paper's learned policy never sees the belief; one trained
on a prior pose (``EnvConfig.observation`` with "pose") gets a prior just as far off.
Within a level every method plays the same episodes; each level draws its own episodes, so
the spread of a method that ignores the error is the sampling noise the confidence band
shows.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from activevision.envs import ActiveVisionEnv, EnvConfig
from activevision.experiments.evaluate import evaluate_policy, summary_rows
from activevision.experiments.methods import compare_method_names, make_policy
from activevision.experiments.policies import HeadPolicy
from activevision.io import read_csv, write_csv

DEFAULT_ERRORS = tuple(np.round(np.arange(0.0, 2.01, 0.25), 2))

#: Methods as factories of the error level (only the entropy methods use it).
MethodFactory = Callable[[float], HeadPolicy]


def default_methods(
    config: EnvConfig, learned: HeadPolicy | None = None
) -> dict[str, MethodFactory]:
    """Every method as a factory of the error level; ``learned`` first when given."""
    methods: dict[str, MethodFactory] = {}
    if learned is not None:
        methods["learned"] = lambda e: learned
    for name in compare_method_names():
        if name != "learned":
            methods[name] = functools.partial(_make_at_error, name, config)
    return methods


def _make_at_error(name: str, config: EnvConfig, error: float) -> HeadPolicy:
    return make_policy(name, error, config)


def config_at_error(config: EnvConfig, error: float) -> EnvConfig:
    """The env of error level ``error``: a policy that observes a prior pose gets one
    ``error`` m and rad off, as the entropy methods' belief is."""
    if not config.observes_prior:
        return config
    return config.replace(prior_error_range=(error, error), prior_exact_share=0.0)


def done_levels(csv_path: Path) -> list[dict]:
    """The rows of ``compare.csv`` already played; ValueError naming the line of a row cut
    short (its method was taken as played and written back with its numbers empty), or the
    file where it is empty or lacks a column a level is known by (it was taken for a CSV of
    no levels and replaced without ``--overwrite``)."""
    return read_csv(csv_path, RESUME_COLUMNS) if csv_path.exists() else []


#: the columns of ``compare.csv`` that say which level a row is, and on which episodes
RESUME_COLUMNS = ("method", "error", "episodes", "seed")
#: the column of ``compare.csv`` that says which run's weights played (empty: no run)
RUN_COLUMN = "run_sha256"
#: the column after it that says which of the run's weights they are, ``final`` or ``best``
#: (``--weights``), for ``report``'s command that writes the comparison again; only where a
#: run played (``compare --run``: a compare without keeps its bytes), absent in CSVs from
#: before it
WEIGHTS_COLUMN = "run_weights"


def with_run(
    new: list[dict], done: list[dict], run_sha256: str | None, weights: str = "final"
) -> list[dict]:
    """``new`` rows with :data:`RUN_COLUMN`, last, where the CSV has it (or is new), and,
    where a run played (``run_sha256``, the digest of its ``weights``, "final" or "best"),
    :data:`WEIGHTS_COLUMN` after it: the rows resumed from a CSV from before a column keep
    its layout."""
    if done and RUN_COLUMN not in done[0]:
        return new
    columns = {RUN_COLUMN: run_sha256 or ""}
    if run_sha256 and not (done and WEIGHTS_COLUMN not in done[0]):
        columns[WEIGHTS_COLUMN] = weights
    return [{**row, **columns} for row in new]


def check_resumable(
    csv_path: Path,
    rows: list[dict],
    episodes: int,
    seed: int,
    errors: Sequence[float],
    run_sha256: str | None = None,
    weights: str = "final",
) -> None:
    """Levels already in the CSV are kept only if they were played on the same episodes: the
    same count and seed, and for each error level the episodes its place in ``errors``
    gives (level ``i`` plays seed ``seed + i``'s: a level moved in the list would keep
    another level's episodes); and by the same run: ``run_sha256``, the digest of the
    weights its learned policy plays (None: no run), against each row's, and the run's
    ``weights`` ("final" or "best") against each row's :data:`WEIGHTS_COLUMN` (rows from
    before a column are kept as before). Another run's levels were resumed as this run's (an
    interrupted ``compare --run A --out C``, then ``--run B --out C``), and levels of the
    final weights as the best's where the two files were one copy (report then read the
    CSV's two names for the weights as damaged)."""
    places = {float(e): i for i, e in enumerate(errors)}
    for row in rows:
        if RUN_COLUMN in row and (row[RUN_COLUMN] or None) != run_sha256:
            other = "another run's weights" if row[RUN_COLUMN] else "a compare without --run"
            raise ValueError(
                f"{csv_path} holds levels played by {other}: resume with the same --run and"
                " --weights, or pass --overwrite to start over"
            )
        if run_sha256 and row.get(WEIGHTS_COLUMN, weights) != weights:
            raise ValueError(
                f"{csv_path} holds levels played by the run's {row[WEIGHTS_COLUMN]} weights,"
                f" not its {weights}: resume with --weights {row[WEIGHTS_COLUMN]}, or pass"
                " --overwrite to start over"
            )
        if (row.get("episodes"), row.get("seed")) != (str(episodes), str(seed)):
            raise ValueError(
                f"{csv_path} holds levels of {row.get('episodes')} episodes from seed"
                f" {row.get('seed')}, not {episodes} from seed {seed}: resume with those, or"
                " pass --overwrite to start over"
            )
        error = float(row["error"])
        if error not in places:
            continue
        want = str(seed + places[error])
        if row.get("level_seed") != want:
            played = row.get("level_seed") or "unknown (a CSV from before level_seed)"
            raise ValueError(
                f"{csv_path} holds error {error:g} played on the episodes of seed {played};"
                f" in --errors {','.join(f'{e:g}' for e in errors)} it is played on seed"
                f" {want}'s: resume with the same --errors in the same order, or pass"
                " --overwrite to start over"
            )


def compare(
    out_dir: str | Path,
    methods: dict[str, MethodFactory],
    errors: Sequence[float] = DEFAULT_ERRORS,
    episodes: int = 100,
    seed: int = 0,
    config: EnvConfig | None = None,
    progress: bool = True,
    run_sha256: str | None = None,
    weights: str = "final",
) -> list[dict]:
    """Run the experiment into ``out_dir/compare.csv``, one error level at a time.

    The CSV is rewritten (atomically) after every level, and levels already in it are
    skipped: an interrupted run loses at most the level in progress. Level ``i`` of
    ``errors`` plays the episodes of seed ``seed + i`` (its ``level_seed`` column); a
    resume with the levels in other places is refused (:func:`check_resumable`), as one
    of levels another run played (``run_sha256``: the digest of the weights the learned
    method plays, the run's ``weights``, "final" or "best": recorded in each row).
    ``progress``: a bar on stderr, where that is a terminal.
    """
    out_dir = Path(out_dir)
    csv_path = out_dir / "compare.csv"
    rows = done_levels(csv_path)
    check_resumable(csv_path, rows, episodes, seed, errors, run_sha256, weights)
    resumed = list(rows)
    done = {(float(r["error"]), r["method"]) for r in rows}
    config = config or EnvConfig()
    env = ActiveVisionEnv(config)
    todo = [
        (li, e) for li, e in enumerate(errors) if any((float(e), m) not in done for m in methods)
    ]
    bar = None
    if progress and sys.stderr.isatty():  # as a training run's: a log gets no redraws
        from tqdm import tqdm

        bar = tqdm(total=len(todo) * len(methods), desc="compare", unit="method")
    try:
        for level, e in todo:
            if config.observes_prior:  # the learned policy's prior is as wrong as the belief
                env = ActiveVisionEnv(config_at_error(config, float(e)))
            for name, factory in methods.items():
                if (float(e), name) in done:
                    continue
                _, summary, _ = evaluate_policy(
                    factory(float(e)), episodes, seed=seed + level, env=env
                )
                level_rows = summary_rows(
                    {name: summary},
                    error=float(e),
                    episodes=episodes,
                    seed=seed,
                    level_seed=seed + level,
                )
                rows += with_run(level_rows, resumed, run_sha256, weights)
                if bar is not None:
                    bar.update()
                    bar.set_postfix(error=e, method=name, success=f"{summary['success'].mean:.2f}")
            write_csv(csv_path, rows)
    finally:  # an error's line comes after the bar's, not glued to it
        if bar is not None:
            bar.close()
    return rows
