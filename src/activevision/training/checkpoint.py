"""Crash-safe checkpoints that never execute code when loaded.

A checkpoint is a directory ``checkpoints/step_00003000/`` holding

* ``model.safetensors`` — online and target weights (safetensors: plain tensors, no pickle),
  with the network's shape in its metadata;
* ``optimizer.pt`` — the Adam state, read back with ``torch.load(weights_only=True)``;
* ``replay.npz`` — the replay buffer as plain arrays, read back with ``allow_pickle=False``;
* ``state.json`` — counters and generator states;
* ``manifest.json`` — size and SHA-256 of every file above.

Every weights file the package writes (a checkpoint's ``model.safetensors``, a run's
``policy.safetensors`` and ``best_policy.safetensors``) also carries the SHA-256 of its
tensors and metadata in its own header, and :func:`load_tensors`, the one reader of them all,
refuses a file whose content does not match it.

It is written into a hidden temporary directory that is renamed into place only once complete
(a rename is atomic), so a crash mid-save leaves the previous checkpoint untouched; older
checkpoints are deleted only after the new one exists. Loading checks the manifest, so a
truncated or altered file raises :class:`CheckpointError` instead of resuming from garbage.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, cast

import numpy as np
import torch
from safetensors import SafetensorError
from safetensors.torch import load_file, safe_open
from safetensors.torch import save as serialise_tensors

from activevision.io import fsync_path, loads_json

CHECKPOINTS_DIR = "checkpoints"
MANIFEST = "manifest.json"
#: The files of every checkpoint (besides the manifest); verification requires exactly these.
CHECKPOINT_FILES = ("model.safetensors", "optimizer.pt", "replay.npz", "state.json")
_PREFIX = "step_"
_CHECKSUM_KEY = "content_sha256"  #: safetensors metadata key of the weights' own checksum
#: the weights files a trainer writes into its run (training.policy_files), atomically through
#: a hidden ``.NAME.*.tmp`` file beside each
_RUN_WEIGHTS = ("policy.safetensors", "best_policy.safetensors")
#: what the other commands write into a run by default (``plot``, ``report``, ``export``,
#: ``evaluate``, ``compare``, ``match``, ``robustness``, ``quickstart``'s episode figure):
#: ``report`` shows them as the run's, ``demo``/``match`` play its policy.onnx
RUN_OUTPUTS = (
    "plots",
    "report.md",
    "policy.onnx",
    "policy.json",
    "evaluation",
    "compare",
    "episode.png",
    "episode.gif",
    "episode.png.json",
    "match",
    "robustness",
)


class CheckpointError(RuntimeError):
    """A checkpoint is missing, incomplete or corrupt."""


def checkpoint_name(step: int) -> str:
    """Directory name of the checkpoint taken after ``step`` environment steps."""
    return f"{_PREFIX}{step:09d}"


def checkpoint_step(checkpoint: str | os.PathLike[str]) -> int:
    """The environment steps a checkpoint was taken after (:func:`checkpoint_name`'s)."""
    return int(Path(checkpoint).name.removeprefix(_PREFIX))


def list_checkpoints(run_dir: str | os.PathLike[str]) -> list[Path]:
    """Complete checkpoints of a run, oldest first (temporary directories are ignored)."""
    directory = Path(run_dir) / CHECKPOINTS_DIR
    if not directory.is_dir():
        return []
    found = [p for p in directory.iterdir() if p.is_dir() and p.name.startswith(_PREFIX)]
    return sorted(found, key=lambda p: p.name)


def latest_checkpoint(run_dir: str | os.PathLike[str]) -> Path:
    """The newest checkpoint of a run; CheckpointError if there is none."""
    checkpoints = list_checkpoints(run_dir)
    if not checkpoints:
        raise CheckpointError(f"no checkpoint in {Path(run_dir) / CHECKPOINTS_DIR}")
    return checkpoints[-1]


def write_checkpoint(
    run_dir: str | os.PathLike[str],
    step: int,
    write_files: Callable[[Path], None],
    keep: int = 2,
) -> Path:
    """Create checkpoint ``step`` atomically; ``write_files(tmp_dir)`` writes its contents.

    Keeps the ``keep`` newest checkpoints. Returns the checkpoint's directory.
    """
    directory = Path(run_dir) / CHECKPOINTS_DIR
    directory.mkdir(parents=True, exist_ok=True)
    remove_stale_writes(run_dir)
    final = directory / checkpoint_name(step)
    tmp = Path(tempfile.mkdtemp(dir=directory, prefix=f".{final.name}.", suffix=".tmp"))
    try:
        write_files(tmp)
        manifest = {p.name: _file_digest(p) for p in sorted(tmp.iterdir()) if p.is_file()}
        (tmp / MANIFEST).write_text(json.dumps(manifest, indent=2) + "\n")
        _fsync_dir_files(tmp)
        if final.exists():  # the same step saved again: replace it only now that tmp is whole
            shutil.rmtree(final)
        os.replace(tmp, final)
        fsync_path(directory)
    except OSError as error:
        shutil.rmtree(tmp, ignore_errors=True)
        if error.filename is not None or error.errno is None:
            raise
        # a full disk: "[Errno 28] No space left on device" named neither file nor run
        raise type(error)(error.errno, f"cannot write {final}: {error.strerror}") from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    for old in list_checkpoints(run_dir)[:-keep]:
        shutil.rmtree(old, ignore_errors=True)
    return final


def remove_stale_writes(run_dir: str | os.PathLike[str]) -> list[Path]:
    """Delete the hidden ``.step_*.tmp`` directories that a killed checkpoint write left
    behind (each as large as the replay buffer), and the run's ``.policy.safetensors.*.tmp``
    and ``.best_policy.safetensors.*.tmp`` files of a killed weights write (one a kill,
    never removed before); returns what was removed. Call it only while no other process
    writes checkpoints of this run (the trainer's files only: a ``report`` or ``export``
    may be writing its own into the run at the same time)."""
    run = Path(run_dir)
    directory = run / CHECKPOINTS_DIR
    stale = []
    if directory.is_dir():
        stale = [
            p
            for p in directory.iterdir()
            if p.is_dir() and p.name.startswith(f".{_PREFIX}") and p.name.endswith(".tmp")
        ]
    for path in stale:
        shutil.rmtree(path, ignore_errors=True)
    weights = [p for name in _RUN_WEIGHTS for p in run.glob(f".{name}.*.tmp") if p.is_file()]
    for path in weights:
        path.unlink(missing_ok=True)
    return stale + weights


def remove_earlier_outputs(run_dir: str | os.PathLike[str]) -> list[Path]:
    """Delete :data:`RUN_OUTPUTS` from ``run_dir`` where it holds an earlier attempt of a
    run (its ``config.json`` and ``metrics.csv``: ``train --out RUN --overwrite`` over one
    that stopped before its first checkpoint), before a fresh run starts there: its
    figures, report, exported policy and results were the earlier attempt's, and ``report``,
    ``demo`` and ``match`` read them as the new run's. A folder that held no run keeps them
    (the user's own files). Returns what was removed. Call it while holding the run's lock."""
    run = Path(run_dir)
    if not ((run / "config.json").is_file() and (run / "metrics.csv").is_file()):
        return []
    removed = [run / name for name in RUN_OUTPUTS if (run / name).exists()]
    for path in removed:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink()
    return removed


def remove_earlier_weights(run_dir: str | os.PathLike[str]) -> list[Path]:
    """Delete the run's ``policy.safetensors`` and ``best_policy.safetensors`` before a
    fresh run starts in ``run_dir`` (``train --out RUN --overwrite`` over an attempt that
    stopped before its first checkpoint): they are the earlier attempt's weights, which
    ``export``, ``evaluate`` and ``--weights best`` would read as this run's. Returns what
    was removed."""
    removed = [Path(run_dir) / name for name in _RUN_WEIGHTS]
    removed = [path for path in removed if path.is_file()]
    for path in removed:
        path.unlink(missing_ok=True)
    return removed


def verify_checkpoint(
    path: str | os.PathLike[str], expected_files: tuple[str, ...] = CHECKPOINT_FILES
) -> None:
    """Check that the manifest lists exactly ``expected_files``, that the directory holds
    nothing else, and every file against its size and SHA-256; CheckpointError otherwise."""
    path = Path(path)
    try:
        manifest = loads_json((path / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError) as error:
        # ValueError: not JSON, or not UTF-8 text (a binary file was a bare "'utf-8' codec
        # can't decode byte", naming no file); RecursionError: nested too deep
        raise CheckpointError(f"checkpoint {path} has no readable manifest: {error}") from error
    if not isinstance(manifest, dict) or sorted(manifest) != sorted(expected_files):
        listed = sorted(manifest) if isinstance(manifest, dict) else manifest
        raise CheckpointError(
            f"checkpoint {path}: the manifest must list {sorted(expected_files)}, it lists"
            f" {listed!r}"
        )
    present = {p.name for p in path.iterdir() if p.name != MANIFEST}
    missing, extra = sorted(set(expected_files) - present), sorted(present - set(expected_files))
    if missing:
        raise CheckpointError(f"checkpoint {path} is missing {', '.join(missing)}")
    if extra:
        raise CheckpointError(f"checkpoint {path} holds unexpected files {extra}")
    for name, expected in manifest.items():
        file = path / name
        if not file.is_file():
            raise CheckpointError(f"checkpoint {path} is missing {name}")
        if _file_digest(file) != expected:
            raise CheckpointError(f"checkpoint file {file} is corrupt (size or SHA-256 differs)")


# ---------------------------------------------------------------------- file formats
def save_tensors(
    path: Path, tensors: Mapping[str, torch.Tensor], metadata: Mapping[str, Any]
) -> None:
    """Save tensors with safetensors; metadata values are stored as JSON strings, beside the
    SHA-256 of both (checked by :func:`load_tensors`)."""
    if _CHECKSUM_KEY in metadata:
        raise ValueError(f"metadata key {_CHECKSUM_KEY!r} is reserved for the checksum")
    plain = {name: t.detach().cpu().contiguous() for name, t in tensors.items()}
    header = {k: json.dumps(v) for k, v in metadata.items()}
    header[_CHECKSUM_KEY] = _content_digest(plain, header)
    Path(path).write_bytes(_sorted_header(serialise_tensors(plain, metadata=header)))


def _sorted_header(data: bytes) -> bytes:
    """safetensors writes its metadata in hash-map order, which changes from process to
    process; the same metadata in sorted order makes the same weights the same bytes. (The
    header is JSON padded with spaces to a multiple of 8 bytes; tensor offsets count from
    its end, so its length may change.)"""
    size = int.from_bytes(data[:8], "little")
    header = json.loads(data[8 : 8 + size])
    header["__metadata__"] = dict(sorted(header["__metadata__"].items()))
    text = json.dumps(header, separators=(",", ":"), ensure_ascii=False).encode()
    text = text.ljust(-(-len(text) // 8) * 8)
    return len(text).to_bytes(8, "little") + text + data[8 + size :]


def load_tensors(path: Path) -> tuple[dict[str, torch.Tensor], dict[str, Any]]:
    """Tensors and metadata written by :func:`save_tensors`; CheckpointError if the file is
    missing, unreadable, carries no checksum or does not match it."""
    try:
        tensors = load_file(str(path))
        with safe_open(str(path), framework="pt") as file:
            header = dict(file.metadata() or {})
        stored = header.pop(_CHECKSUM_KEY, None)
        metadata = {k: json.loads(v) for k, v in header.items()}
    except (OSError, SafetensorError, json.JSONDecodeError) as error:
        raise CheckpointError(f"cannot read weights from {path}: {error}") from error
    if stored is None:
        raise CheckpointError(
            f"{path} carries no checksum (written by an older activevision), so it cannot be"
            " verified; retrain the run or resume it from a verified checkpoint"
        )
    if _content_digest(tensors, header) != stored:
        raise CheckpointError(f"{path} is corrupt: its tensors or metadata fail the checksum")
    return tensors, metadata


def save_torch_state(path: Path, state: Mapping[str, Any]) -> None:
    """Save an optimiser state dict (tensors and plain Python values only)."""
    torch.save(dict(state), path)


def load_torch_state(path: Path) -> dict[str, Any]:
    """Load with ``weights_only=True``: tensors and plain containers, never arbitrary code."""
    try:
        state: dict[str, Any] = torch.load(path, map_location="cpu", weights_only=True)
        return state
    except Exception as error:  # torch raises several types for damaged files
        raise CheckpointError(f"cannot read {path}: {error}") from error


def save_arrays(path: Path, arrays: Mapping[str, np.ndarray]) -> None:
    """Save plain numpy arrays as an uncompressed .npz (fast; images are uint8 already)."""
    with open(path, "wb") as file:
        np.savez(file, **cast(dict[str, Any], arrays))  # names, not savez's own keywords


def load_arrays(path: Path) -> dict[str, np.ndarray]:
    """Load an .npz with ``allow_pickle=False`` into memory."""
    try:
        with np.load(path, allow_pickle=False) as archive:
            return {name: archive[name] for name in archive.files}
    except (OSError, ValueError, KeyError, EOFError) as error:
        raise CheckpointError(f"cannot read arrays from {path}: {error}") from error


# ---------------------------------------------------------------------- helpers
def _content_digest(tensors: Mapping[str, torch.Tensor], header: Mapping[str, str]) -> str:
    """SHA-256 over the metadata strings and every tensor's name, dtype, shape and bytes."""
    sha = hashlib.sha256(json.dumps(dict(header), sort_keys=True).encode())
    for name in sorted(tensors):
        tensor = tensors[name].contiguous()
        sha.update(f"{name}|{tensor.dtype}|{tuple(tensor.shape)}|".encode())
        sha.update(tensor.reshape(-1).view(torch.uint8).numpy().tobytes())
    return sha.hexdigest()


def _file_digest(path: Path) -> dict[str, Any]:
    sha = hashlib.sha256()
    with open(path, "rb") as file:
        for block in iter(lambda: file.read(1 << 22), b""):
            sha.update(block)
    return {"bytes": path.stat().st_size, "sha256": sha.hexdigest()}


def _fsync_dir_files(directory: Path) -> None:
    for file in directory.iterdir():
        fsync_path(file)
    fsync_path(directory)
