"""A run's policy files and :func:`load_policy`, their reader.

A run directory holds

* ``policy.safetensors`` — the newest online weights, rewritten with every checkpoint;
* ``best_policy.safetensors`` — with ``eval_interval``: the weights with the best greedy
  validation score so far (metadata ``step`` and ``validation_success_rate``, a match
  run's ``validation_episode_reward``).

Both are written atomically with :func:`activevision.training.checkpoint.save_tensors`
(checksummed) and carry the network's shape in their metadata, so :func:`load_policy` builds
the :class:`QNetwork` from the file alone and never executes code.
"""

from __future__ import annotations

import math
import os
import sys
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch

from activevision.agents.q_network import QNetwork
from activevision.agents.student import StudentNetwork
from activevision.io import atomic_path, file_sha256
from activevision.training import checkpoint as ckpt

POLICY_FILE = "policy.safetensors"  #: the newest online weights
BEST_POLICY_FILE = "best_policy.safetensors"  #: best greedy validation score (eval_interval)


def network_metadata(network: torch.nn.Module, step: int) -> dict[str, Any]:
    """What :func:`load_policy` needs to rebuild ``network`` (a QNetwork), and the step of
    its weights. (A StudentNetwork's come from ``DaggerTrainer.metadata``.)"""
    if not isinstance(network, QNetwork):
        raise TypeError(f"policy files hold QNetwork weights, got a {type(network).__name__}")
    return {
        "n_actions": network.n_actions,
        "stack": network.stack,
        "image_shape": list(network.image_shape),
        "dueling": network.dueling,
        "aux_outputs": network.aux_outputs,
        "step": step,
    }


def write_policy(
    run_dir: Path, weights: Mapping[str, torch.Tensor], metadata: Mapping[str, Any]
) -> Path:
    """Write (atomically) ``policy.safetensors``: the run's newest online weights."""
    path = run_dir / POLICY_FILE
    with atomic_path(path) as tmp:
        ckpt.save_tensors(tmp, weights, metadata)
    return path


def write_best_policy(
    run_dir: Path,
    weights: Mapping[str, torch.Tensor],
    metadata: Mapping[str, Any],
    step: int,
    score: float,
    score_name: str = "success_rate",
) -> Path:
    """Write (atomically) ``best_policy.safetensors``: weights of ``step`` that scored the
    best validation ``score`` (metadata ``validation_<score_name>``)."""
    path = run_dir / BEST_POLICY_FILE
    full = {**metadata, "step": step, f"validation_{score_name}": score}
    with atomic_path(path) as tmp:
        ckpt.save_tensors(tmp, weights, full)
    return path


@dataclass
class BestWeights:
    """The weights with the best greedy validation score so far (SB3 ``EvalCallback``)."""

    #: the validation score: success rate; a match run's mean reward (-inf: none yet)
    score: float = -math.inf
    step: int = 0  #: the step the weights are of
    weights: dict[str, torch.Tensor] | None = None  #: a copy of the network's state dict

    def keep(self, network: torch.nn.Module, step: int, score: float) -> None:
        """Take a copy of ``network``'s weights as the best, scoring ``score`` at ``step``."""
        self.keep_weights(network.state_dict(), step, score)

    def keep_weights(self, weights: Mapping[str, torch.Tensor], step: int, score: float) -> None:
        """Take a copy of ``weights`` (a state dict) as the best."""
        self.weights = {k: v.detach().clone() for k, v in weights.items()}
        self.step, self.score = step, score

    def write(
        self, run_dir: Path, metadata: Mapping[str, Any], score_name: str = "success_rate"
    ) -> Path:
        """Write ``best_policy.safetensors`` (``metadata``: :func:`network_metadata`)."""
        if self.weights is None:
            raise ValueError("no best weights to write: nothing was validated yet")
        return write_best_policy(run_dir, self.weights, metadata, self.step, self.score, score_name)


def load_policy(
    path: str | os.PathLike[str], device: str = "cpu", weights: str = "final"
) -> QNetwork | StudentNetwork:
    """A trained network in eval mode (a QNetwork, or a DAgger run's StudentNetwork), from a
    run directory, a checkpoint, or a weights file.

    Reads safetensors only (no code is executed). A run directory's ``policy.safetensors``
    holds its newest online weights (``weights="final"``), ``best_policy.safetensors`` those
    with the best validation score (``weights="best"``, runs with ``eval_interval``).
    """
    return load_policy_and_metadata(path, device, weights)[0]


def load_policy_and_metadata(
    path: str | os.PathLike[str], device: str = "cpu", weights: str = "final"
) -> tuple[QNetwork | StudentNetwork, dict[str, Any]]:
    """:func:`load_policy`, and the metadata its file carries (what the run's trainer wrote:
    the network's shape, the step, the observation)."""
    path = _weights_file(Path(path), weights)
    tensors, meta = ckpt.load_tensors(path)
    if any(k.startswith("online.") for k in tensors):
        tensors = {
            k.removeprefix("online."): v for k, v in tensors.items() if k.startswith("online.")
        }
    network: QNetwork | StudentNetwork
    try:
        if meta.get("network") == "student":
            network = StudentNetwork.from_metadata(meta)
            network.load_state_dict(tensors)
            return network.to(device).eval(), meta
        network = QNetwork(
            meta["n_actions"],
            meta["stack"],
            tuple(meta["image_shape"]),
            meta["dueling"],
            aux_outputs=meta.get("aux_outputs", 0),
        )
        network.load_state_dict(tensors)
    except (KeyError, RuntimeError, TypeError, ValueError) as error:
        raise ckpt.CheckpointError(f"{path} does not hold policy weights: {error}") from error
    return network.to(device).eval(), meta


def scored_run(run_dir: str | os.PathLike[str], weights: str = "final") -> dict[str, str | None]:
    """What an evaluation records of the run it scored: the SHA-256 of its ``config.json``
    and of its weights file ``weights`` names (None where absent), so that ``report`` can
    tell results written for another run, or for weights the run has since replaced
    (trained on, retrained with ``--overwrite``), from its own. Digests, not the folder's
    name: a run moved or renamed stays itself, and the same seed still gives the same
    bytes."""
    run = Path(run_dir)
    files = {
        "config_sha256": run / "config.json",
        "weights_sha256": run / (BEST_POLICY_FILE if weights == "best" else POLICY_FILE),
    }
    return {key: file_sha256(path) if path.is_file() else None for key, path in files.items()}


#: the columns a table of results (``match.csv``, ``robustness.csv``) records the training
#: run it scored in (``--run``; absent without): :func:`scored_run`'s digests and which of its
#: weights played, for ``report`` to tell another run's results from its own
SCORED_RUN_COLUMNS = ("run_config_sha256", "run_weights_sha256", "run_weights")


def scored_run_columns(run_dir: str | os.PathLike[str], weights: str = "final") -> dict[str, str]:
    """:data:`SCORED_RUN_COLUMNS` of a table that scored run ``run_dir``'s ``weights``
    ("final" or "best"); a file that is absent has an empty digest."""
    digests = scored_run(run_dir, weights)
    return {
        "run_config_sha256": digests["config_sha256"] or "",
        "run_weights_sha256": digests["weights_sha256"] or "",
        "run_weights": weights,
    }


def _caller_level() -> int:
    """The ``stacklevel`` of the first caller outside this module, for a warning issued by
    the function that calls this one (whichever public function the caller used)."""
    frame = sys._getframe(1)
    level = 1
    while frame.f_back is not None and frame.f_code.co_filename == __file__:
        frame = frame.f_back
        level += 1
    return level


def _weights_file(path: Path, weights: str) -> Path:
    """The weights file that ``load_policy(path, weights=weights)`` reads."""
    if weights not in ("final", "best"):
        raise ValueError(f"weights must be 'final' or 'best', got {weights!r}")
    if path.is_dir() and weights == "best":
        path = path / BEST_POLICY_FILE
        if not path.exists():
            raise ckpt.CheckpointError(
                f"no {path.name} in {path.parent}: no validation has run (a run keeps one from"
                " its first validation, every eval_interval steps when that is > 0)"
            )
    elif path.is_dir():
        for name in (POLICY_FILE, "model.safetensors"):  # a run's, a checkpoint's
            if (path / name).exists():
                return path / name
        checkpoints = ckpt.list_checkpoints(path)
        if checkpoints:
            # policy.safetensors is rewritten with every checkpoint, so the newest
            # checkpoint holds the same weights
            newest = checkpoints[-1] / "model.safetensors"
            warnings.warn(
                f"{path} has no {POLICY_FILE} (deleted?): reading its newest checkpoint's"
                f" weights, {newest}",
                stacklevel=_caller_level(),
            )
            return newest
        raise ckpt.CheckpointError(
            f"no policy weights in {path}: neither {POLICY_FILE} (a run writes it with each"
            " checkpoint; this run has none yet, or it was deleted) nor a checkpoint's"
            " model.safetensors"
        )
    if not path.exists():
        raise ckpt.CheckpointError(f"no policy weights at {path}")
    return path


__all__ = [
    "BEST_POLICY_FILE",
    "POLICY_FILE",
    "SCORED_RUN_COLUMNS",
    "BestWeights",
    "load_policy",
    "load_policy_and_metadata",
    "network_metadata",
    "scored_run",
    "scored_run_columns",
    "write_best_policy",
    "write_policy",
]
