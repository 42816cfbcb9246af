"""Crash-safe checkpoints that never execute code when loaded.

A checkpoint is a directory ``checkpoints/step_00003000/`` holding

* ``model.safetensors`` — online and target weights (safetensors: plain tensors, no pickle),
  with the network's shape in its metadata;
* ``optimizer.pt`` — the Adam state, read back with ``torch.load(weights_only=True)``;
* ``replay.npz`` — the replay buffer as plain arrays, read back with ``allow_pickle=False``;
* ``state.json`` — counters and generator states;
* ``manifest.json`` — size and SHA-256 of every file above.

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
from typing import Any

import numpy as np
import torch
from safetensors import SafetensorError
from safetensors.torch import load_file, safe_open, save_file

from activevision.io import fsync_path

CHECKPOINTS_DIR = "checkpoints"
MANIFEST = "manifest.json"
_PREFIX = "step_"


class CheckpointError(RuntimeError):
    """A checkpoint is missing, incomplete or corrupt."""


def checkpoint_name(step: int) -> str:
    """Directory name of the checkpoint taken after ``step`` environment steps."""
    return f"{_PREFIX}{step:09d}"


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
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    for old in list_checkpoints(run_dir)[:-keep]:
        shutil.rmtree(old, ignore_errors=True)
    return final


def verify_checkpoint(path: str | os.PathLike[str]) -> None:
    """Check every file against the manifest; CheckpointError on any difference."""
    path = Path(path)
    try:
        manifest = json.loads((path / MANIFEST).read_text())
    except (OSError, json.JSONDecodeError) as error:
        raise CheckpointError(f"checkpoint {path} has no readable manifest: {error}") from error
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
    """Save tensors with safetensors; metadata values are stored as JSON strings."""
    plain = {name: t.detach().cpu().contiguous() for name, t in tensors.items()}
    save_file(plain, str(path), metadata={k: json.dumps(v) for k, v in metadata.items()})


def load_tensors(path: Path) -> tuple[dict[str, torch.Tensor], dict[str, Any]]:
    """Tensors and metadata written by :func:`save_tensors` (CheckpointError if unreadable)."""
    try:
        tensors = load_file(str(path))
        with safe_open(str(path), framework="pt") as file:
            metadata = {k: json.loads(v) for k, v in (file.metadata() or {}).items()}
    except (OSError, SafetensorError, json.JSONDecodeError) as error:
        raise CheckpointError(f"cannot read weights from {path}: {error}") from error
    return tensors, metadata


def save_torch_state(path: Path, state: Mapping[str, Any]) -> None:
    """Save an optimiser state dict (tensors and plain Python values only)."""
    torch.save(dict(state), path)


def load_torch_state(path: Path) -> dict[str, Any]:
    """Load with ``weights_only=True``: tensors and plain containers, never arbitrary code."""
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except Exception as error:  # torch raises several types for damaged files
        raise CheckpointError(f"cannot read {path}: {error}") from error


def save_arrays(path: Path, arrays: Mapping[str, np.ndarray]) -> None:
    """Save plain numpy arrays as an uncompressed .npz (fast; images are uint8 already)."""
    with open(path, "wb") as file:
        np.savez(file, **arrays)


def load_arrays(path: Path) -> dict[str, np.ndarray]:
    """Load an .npz with ``allow_pickle=False`` into memory."""
    try:
        with np.load(path, allow_pickle=False) as archive:
            return {name: archive[name] for name in archive.files}
    except (OSError, ValueError, KeyError, EOFError) as error:
        raise CheckpointError(f"cannot read arrays from {path}: {error}") from error


# ---------------------------------------------------------------------- helpers
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
