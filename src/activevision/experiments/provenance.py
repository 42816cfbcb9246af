"""What a run's comparison figure and episode figure record of what played, and whether
``activevision report`` shows them as the run's (:func:`compare_provenance`,
:func:`episode_provenance`).

``compare.csv`` records the digest of the weights its ``learned`` method played
(``run_sha256``, :mod:`activevision.experiments.compare`). ``episode`` and ``demo`` write,
beside their figure and GIF, a record (the figure's name and ``.json``, ``episode.png.json``:
:func:`write_episode_record`): the
policies, the start's seed, the run whose policy played (the digests of its ``config.json``
and weights, as ``evaluation.json`` records them) or the exported model, and the digests of
the figure and GIF it describes. Files written before these records are reported as before.

A model ``demo --policy`` or ``match --model`` played is the run's own where it is
``RUN/policy.onnx`` as it is now and the ``policy.json`` beside it records that it was
exported from the run's ``config.json`` and weights as they are now (:func:`run_export`): an
export from before the run was trained on or retrained is not the run's policy.
"""

from __future__ import annotations

import glob
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from activevision.io import file_sha256, read_csv, read_json, write_json
from activevision.runtime.metadata import MODEL_FILENAME, load_metadata, metadata_path_for
from activevision.training.policy_files import scored_run

#: what ``episode`` and ``demo`` record beside their figure: ``episode.png`` ->
#: ``episode.png.json``, the whole name (``episode.svg`` beside it has its own,
#: ``episode.svg.json``; ``episode.json`` was both's, and ``--out RUN/policy.png`` would
#: have written over the exported policy's ``policy.json``)
RECORD_SUFFIX = ".json"
#: the record's keys, each always written (null where it does not apply)
RECORD_KEYS = ("command", "policies", "seed", "run", "weights", "model", "model_sha256", "files")


@dataclass(frozen=True)
class Provenance:
    """Whether a result file is the run's to report: ``own``, with ``text`` saying what
    played (``""``: nothing recorded, a file from before the record); or not, with ``text``
    saying why and ``again`` the command (after ``activevision``) that writes it again."""

    own: bool
    text: str = ""
    again: str = ""


def record_path(figure: str | Path) -> Path:
    """The record ``episode`` and ``demo`` write beside ``figure``: its name and
    :data:`RECORD_SUFFIX`, one per figure."""
    figure = Path(figure)
    return figure.with_name(figure.name + RECORD_SUFFIX)


def figures_sharing_gif(figure: str | Path) -> list[Path]:
    """The other figures beside ``figure`` whose records (:func:`record_path`) record the
    GIF ``figure``'s would be (``episode.svg`` beside ``episode.png``: one name without its
    suffix, one ``episode.gif``), those that exist, by name. A record that does not read is
    passed over (``report`` names it)."""
    figure = Path(figure)
    gif = figure.with_suffix(".gif")
    shared = []
    for record in sorted(figure.parent.glob(f"{glob.escape(gif.stem)}.*{RECORD_SUFFIX}")):
        other = record.with_name(record.name.removesuffix(RECORD_SUFFIX))
        if other.name == figure.name or other.with_suffix(".gif") != gif or not other.is_file():
            continue
        if gif.name in _recorded_files(record):
            shared.append(other)
    return shared


def records_other_gif(figure: str | Path, gif: str | Path) -> bool:
    """Whether ``figure``'s record records a GIF of ``gif``'s name other than ``gif`` as it
    is now (one drawn since for another figure of its name: ``report`` leaves ``figure``
    out)."""
    recorded = _recorded_files(record_path(figure)).get(Path(gif).name)
    return recorded is not None and recorded != file_sha256(gif)


def _recorded_files(record: Path) -> dict[str, str]:
    """The ``files`` a record holds (name -> SHA-256); none where it does not read."""
    try:
        files = read_json(record)["files"]
        return {str(k): str(v) for k, v in dict(files).items()}
    except (OSError, ValueError, TypeError, KeyError):
        return {}


def write_episode_record(
    figure: Path,
    gif: Path,
    *,
    command: str,
    policies: Sequence[str],
    seed: int,
    run: dict[str, str | None] | None = None,
    weights: str | None = None,
    model: str | None = None,
    model_sha256: str | None = None,
) -> Path:
    """Write :func:`record_path` of ``figure`` (drawn with ``gif`` by ``command``): the
    ``policies`` in their rows' order, the start's ``seed``, ``run``: the digests of the run
    whose ``weights`` played (:func:`~activevision.training.policy_files.scored_run`, taken
    as they were loaded; None: no run), ``model``/``model_sha256``: the exported model
    ``demo`` played (its path as given, None for the shipped one), and the digests of the
    figure and the GIF as written. The same seed writes the same bytes."""
    path = record_path(figure)
    record: dict[str, Any] = {
        "command": command,
        "policies": list(policies),
        "seed": seed,
        "run": run,
        "weights": weights if run is not None else None,
        "model": model,
        "model_sha256": model_sha256,
        "files": {p.name: file_sha256(p) for p in (figure, gif)},
    }
    write_json(path, record)
    return path


def _damaged(path: Path, why: str) -> ValueError:
    return ValueError(f"{path} is damaged or not a file activevision wrote ({why})")


def weights_words(weights: str | None) -> str:
    """How a page names a run's weights: "best validated" or "final"."""
    return "best validated" if weights == "best" else "final"


def stale_parts(current: Mapping[str, str | None], recorded: Mapping[str, str | None]) -> list[str]:
    """What of a run (``config.json``, ``weights``: those ``current`` holds) a record's
    digests do not match."""
    return [
        what
        for key, what in (("config_sha256", "config.json"), ("weights_sha256", "weights"))
        if key in current and current[key] != recorded.get(key)
    ]


#: why a result of another run's files, or of this run's before they changed, is left out
ANOTHER_RUN = "or this run's before they were replaced (trained on or retrained)"


@dataclass(frozen=True)
class RunExport:
    """A model that is a run's ``policy.onnx`` as it is now (:func:`run_export`): ``why``
    it is not the run's policy as it is now (``""``: it is), and the ``weights`` it was
    exported from, ``"final"`` or ``"best"`` (None: its ``policy.json`` does not say)."""

    why: str = ""
    weights: str | None = None

    def text(self) -> str:
        """``this run's policy.onnx`` and, where recorded, which weights it was exported
        from, or why it is not the run's policy as it is now."""
        if self.why:
            return f"this run's policy.onnx, {self.why}"
        if self.weights is None:
            return "this run's policy.onnx"
        which = weights_words(self.weights)
        return f"this run's policy.onnx, exported from its {which} weights"


def run_export(run: Path, model_sha256: str) -> RunExport | None:
    """What the exported model of SHA-256 ``model_sha256`` is of ``run``: None where it is
    not ``RUN/policy.onnx`` as it is now; else, by the ``policy.json`` beside it, whether it
    was exported from the run's ``config.json`` and weights as they are now (``export``
    records their digests): not where its ``policy.json`` describes another model or
    records another run's files or this run's before they were replaced (an export before
    the run was trained on or retrained). A ``policy.json`` from before the weights' record
    is checked for its ``config.json`` alone, one that is missing not at all, as before.
    :class:`~activevision.runtime.PolicyFileError` (a ValueError) naming a damaged one."""
    exported = run / MODEL_FILENAME
    if not exported.is_file() or file_sha256(exported) != model_sha256:
        return None
    path = metadata_path_for(exported)
    if not path.is_file():
        return RunExport()
    meta = load_metadata(path)
    if meta.model_sha256 != model_sha256:
        return RunExport(f"whose {path.name} describes another model (its model_sha256)")
    recorded = {"config_sha256": meta.training_config_sha256}
    weights = meta.training_weights
    current = scored_run(run, weights or "final")
    if weights is None:  # a policy.json from before the weights' record
        current = {"config_sha256": current["config_sha256"]}
    else:
        recorded["weights_sha256"] = meta.training_weights_sha256
    stale = stale_parts(current, recorded)
    if stale:
        return RunExport(f"exported from another run's {' and '.join(stale)}, {ANOTHER_RUN}")
    return RunExport(weights=weights)


def episode_provenance(figure: Path, run: Path) -> Provenance:
    """Whether ``figure`` (``RUN/episode.png``) is ``run``'s episode, by its record
    (:func:`write_episode_record`): not where the figure or its GIF is not the one recorded
    (replaced since), where it played another run's ``config.json`` or weights or this
    run's before they were replaced, or where it played no policy of this run (``demo`` of
    the shipped policy or of another model, ``episode`` without ``--run``; ``demo --policy
    RUN/policy.onnx`` of this run's exported policy as it is now is this run's, where it
    was exported from the run's files as they are now, :func:`run_export`). A figure
    without a record (written before it) is the run's, as before. ValueError naming the
    record where it is damaged."""
    path = record_path(figure)
    again = f"episode --run {run} --out {figure} --overwrite"
    if not path.is_file():
        return Provenance(True)
    data = read_json(path)
    if not isinstance(data, dict) or not set(RECORD_KEYS) <= set(data):
        raise _damaged(path, f"it must hold an object with the keys {', '.join(RECORD_KEYS)}")
    try:
        policies = [str(p) for p in data["policies"]]
        seed = int(data["seed"])
        files = {str(k): str(v) for k, v in dict(data["files"]).items()}
        recorded = None if data["run"] is None else dict(data["run"])
    except (TypeError, ValueError) as error:
        raise _damaged(path, f"{type(error).__name__}: {error}") from None
    # by digest, not name: a figure and record renamed together (ep.png to episode.png)
    # are still each other's
    for drawn in (figure, figure.with_suffix(".gif")):
        if drawn.is_file() and file_sha256(drawn) not in files.values():
            why = f"{drawn.name} is not the one {path.name} records (replaced since)"
            return Provenance(False, why, again)
    played = " and ".join(f"`{p}`" for p in policies) + f" from the start of seed {seed}"
    if recorded is None:
        export = run_export(run, str(data["model_sha256"])) if data["model_sha256"] else None
        if export is not None and not export.why:
            return Provenance(True, f"{played}; `{policies[0]}` is {export.text()}.")
        if export is not None:
            why = f"it played {export.text()}"
        elif data["command"] == "demo":
            what = "another exported model" if data["model"] else "the shipped policy"
            why = f"it played {what} (demo), not this run's policy"
        else:
            why = "it played no policy of this run (an episode without --run)"
        return Provenance(False, why, again)
    weights = "best" if data["weights"] == "best" else "final"
    stale = stale_parts(scored_run(run, weights), recorded)
    if stale:
        best = " --weights best" if weights == "best" else ""
        why = f"it played another run's {' and '.join(stale)}, {ANOTHER_RUN}"
        return Provenance(False, why, f"episode --run {run}{best} --out {figure} --overwrite")
    if "learned" in policies:
        played += f"; `learned` plays this run's {weights_words(weights)} weights"
    return Provenance(True, played + ".")


def compare_provenance(figure: Path, run: Path) -> Provenance:
    """Whether ``figure`` (``RUN/compare/compare.png``) is ``run``'s comparison, by the
    ``run_sha256`` its ``compare.csv`` records, of the run's weights ``run_weights`` names
    (a CSV from before that column: either): not where it played another run's weights
    or this run's before they were replaced, or no run (a compare without ``--run``: no
    learned policy of this run, in the paper's env). A figure without a CSV, or a CSV from
    before the columns, is the run's, as before. ValueError naming the CSV where it is
    damaged or its rows record two runs."""
    from activevision.experiments.compare import RESUME_COLUMNS, RUN_COLUMN, WEIGHTS_COLUMN

    csv_path = figure.with_name("compare.csv")
    again = f"compare --run {run} --out {figure.parent} --overwrite"
    if not csv_path.is_file():
        return Provenance(True)
    rows = read_csv(csv_path, RESUME_COLUMNS)
    if not rows:
        raise _damaged(csv_path, "it holds no rows")
    if RUN_COLUMN not in rows[0]:
        return Provenance(True)
    recorded = {(row[RUN_COLUMN], row.get(WEIGHTS_COLUMN)) for row in rows}
    (digest, weights), *others = recorded
    if others or weights not in (None, "final", "best") or (weights and not digest):
        raise _damaged(csv_path, f"its rows' {RUN_COLUMN} and {WEIGHTS_COLUMN} are not one run's")
    if not digest:
        return Provenance(False, "it played no run (a compare without --run)", again)
    for played, which in (("final", "final"), ("best", "best validated")):
        if weights in (None, played) and scored_run(run, played)["weights_sha256"] == digest:
            # said only where learned played (--methods may leave it out: the others in
            # the run's env)
            learned = any(row["method"] == "learned" for row in rows)
            said = f"`learned` plays this run's {which} weights." if learned else ""
            return Provenance(True, said)
    why = f"it played another run's weights, {ANOTHER_RUN}"
    if weights == "best":
        again = f"compare --run {run} --weights best --out {figure.parent} --overwrite"
    return Provenance(False, why, again)
