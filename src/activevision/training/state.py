"""A trainer's checkpoint: its progress as a dataclass, and the checkpoint directory's I/O.

:class:`TrainerState` is everything besides weights, optimiser and replay buffer that a
resumed run needs (``state.json``): counters, the trainer's generator, the open epoch and
episode, how far the logs go, the best validation so far and the config's checksum.
:meth:`TrainerState.from_json` checks every field, so a ``state.json`` that is valid JSON
but wrong inside is a :class:`~activevision.training.checkpoint.CheckpointError` naming the
field, not a failure halfway through a resume.

:func:`save_checkpoint` writes a checkpoint directory (``model.safetensors``,
``optimizer.pt``, ``replay.npz``, ``state.json``, ``manifest.json``) through
:mod:`activevision.training.checkpoint`'s atomic, checksummed writers;
:func:`load_checkpoint` verifies and reads one back, :func:`restore_learning` puts its
weights, optimiser and replay buffer into a freshly built learner.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, cast

import numpy as np
import torch

from activevision.agents.ddqn import DDQNLearner
from activevision.agents.replay.prioritized import PrioritizedReplayBuffer
from activevision.io import file_sha256, loads_json
from activevision.training import checkpoint as ckpt
from activevision.training.loggers import LogPosition
from activevision.training.metrics import EPISODE_FIELDS, EpochAccumulator

STATE_FILE = "state.json"
CONFIG_FILE = "config.json"
_SHA256 = re.compile(r"[0-9a-f]{64}")


@dataclass(frozen=True)
class TrainerState:
    """A trainer's progress at a checkpoint (the fields of ``state.json``, in its order)."""

    step: int  #: environment steps taken
    episode: int  #: episodes finished
    rng: dict[str, Any]  #: the trainer's numpy generator (``bit_generator.state``, PCG64)
    epoch_log: EpochAccumulator  #: episodes and losses of the unfinished epoch (a copy)
    episode_open: bool  #: whether an episode is under way
    episode_seed: int  #: the reset seed of the current (or last) episode
    episode_actions: tuple[int, ...]  #: its actions so far
    episode_reward: float  #: its reward so far
    obs_sha256: str | None  #: digest of the current observation (None between episodes)
    metrics_rows: int  #: epoch rows logged
    episodes_rows: int  #: episode rows logged
    best_eval: float | None  #: best validation success rate (None: no best weights)
    best_step: int  #: the step of the best weights
    evaluations_rows: int  #: validation rows logged
    config_sha256: str  #: SHA-256 of the run's config.json

    @property
    def log_position(self) -> LogPosition:
        """How far the run's logs went at this checkpoint."""
        return LogPosition(self.step, self.metrics_rows, self.episodes_rows, self.evaluations_rows)

    def to_json(self) -> str:
        """The ``state.json`` text: one JSON object, fields in declaration order."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        values["epoch_log"] = self.epoch_log.to_dict()
        values["episode_actions"] = list(self.episode_actions)
        return json.dumps(values)

    @classmethod
    def from_json(cls, text: str, source: str = STATE_FILE) -> TrainerState:
        """Parse and check ``state.json``; CheckpointError naming ``source`` and the field."""
        try:
            values = loads_json(text)
        except ValueError as error:  # not JSON, or a key named twice
            raise ckpt.CheckpointError(f"cannot read {source}: {error}") from error
        if not isinstance(values, dict):
            raise ckpt.CheckpointError(f"{source} must hold a JSON object")
        if "config_sha256" not in values:
            raise ckpt.CheckpointError(
                f"checkpoint state {source} does not record its config's checksum (written by"
                " an older activevision); start a new run"
            )
        names = [f.name for f in fields(cls)]
        missing = [name for name in names if name not in values]
        if missing:
            raise ckpt.CheckpointError(
                f"checkpoint state {source} lacks the field(s) {', '.join(missing)}"
            )
        extra = sorted(set(values) - set(names))
        if extra:
            raise ckpt.CheckpointError(
                f"checkpoint state {source} has unexpected field(s) {', '.join(extra)}"
            )
        checked = {}
        for name in names:
            try:
                checked[name] = _FIELD_CHECKS[name](values[name])
            except (TypeError, ValueError, KeyError) as error:
                raise ckpt.CheckpointError(
                    f"checkpoint state {source}: field {name!r} {error}"
                ) from None
        state = cls(**checked)
        if (state.obs_sha256 is None) == state.episode_open:
            raise ckpt.CheckpointError(
                f"checkpoint state {source}: field 'obs_sha256' must be a digest exactly when"
                f" 'episode_open' is true (episode_open={state.episode_open})"
            )
        return state


# ---------------------------------------------------------------------- field checks
def _count(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(f"must be a non-negative integer, got {value!r}")
    return value


def _seed(value: Any) -> int:
    if _count(value) >= 2**31:
        raise ValueError(f"must be below 2**31, got {value!r}")
    return int(value)


def _number(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"must be a number, got {value!r}")
    return float(value)


def _finite_or_none(value: Any) -> float | None:
    if value is not None and not math.isfinite(_number(value)):
        raise ValueError(f"must be a finite number or null, got {value!r}")
    return None if value is None else float(value)


def _flag(value: Any) -> bool:
    if not isinstance(value, bool):
        raise ValueError(f"must be true or false, got {value!r}")
    return value


def _digest_or_none(value: Any) -> str | None:
    return None if value is None else _digest_text(value)


def _digest_text(value: Any) -> str:
    if not isinstance(value, str) or not _SHA256.fullmatch(value):
        raise ValueError(f"must be a SHA-256 hex digest, got {value!r}")
    return value


def _actions(value: Any) -> tuple[int, ...]:
    if not isinstance(value, list):
        raise ValueError(f"must be a list of actions, got {type(value).__name__}")
    try:
        return tuple(_count(a) for a in value)
    except ValueError as error:
        raise ValueError(f"must hold actions (non-negative integers): {error}") from None


def _generator_state(value: Any) -> dict[str, Any]:
    """A PCG64 state, checked by loading it into a throwaway generator."""
    if not isinstance(value, dict):
        raise ValueError(f"must be a generator state object, got {type(value).__name__}")
    try:
        np.random.PCG64().state = cast(Any, value)
    except (TypeError, ValueError, KeyError, OverflowError) as error:
        raise ValueError(f"is not a PCG64 generator state ({error})") from None
    copy: dict[str, Any] = json.loads(json.dumps(value))  # a copy
    return copy


def _epoch_log(value: Any) -> EpochAccumulator:
    if not isinstance(value, dict) or sorted(value) != ["episodes", "losses"]:
        raise ValueError("must be an object with exactly 'episodes' and 'losses'")
    episodes, losses = value["episodes"], value["losses"]
    if not isinstance(episodes, list) or not isinstance(losses, list):
        raise ValueError("must hold lists 'episodes' and 'losses'")
    for record in episodes:
        if not isinstance(record, dict) or sorted(record) != sorted(EPISODE_FIELDS):
            raise ValueError(f"episodes must be records with the fields {list(EPISODE_FIELDS)}")
        for number in record.values():
            _number(number)
    for loss in losses:
        _number(loss)
    return EpochAccumulator.from_dict(json.loads(json.dumps(value)))


_FIELD_CHECKS: dict[str, Callable[[Any], Any]] = {
    "step": _count,
    "episode": _count,
    "rng": _generator_state,
    "epoch_log": _epoch_log,
    "episode_open": _flag,
    "episode_seed": _seed,
    "episode_actions": _actions,
    "episode_reward": _number,
    "obs_sha256": _digest_or_none,
    "metrics_rows": _count,
    "episodes_rows": _count,
    "best_eval": _finite_or_none,
    "best_step": _count,
    "evaluations_rows": _count,
    "config_sha256": _digest_text,
}


# ---------------------------------------------------------------------- digests
def obs_digest(obs: np.ndarray | None) -> str | None:
    """SHA-256 of an observation's bytes (None for None): how resuming checks its replay."""
    return None if obs is None else hashlib.sha256(np.ascontiguousarray(obs).tobytes()).hexdigest()


def config_digest(run_dir: Path) -> str:
    """SHA-256 of the run's ``config.json``."""
    return file_sha256(run_dir / CONFIG_FILE)


# ---------------------------------------------------------------------- the directory
def save_checkpoint(
    run_dir: Path,
    state: TrainerState,
    learner: DDQNLearner,
    buffer: PrioritizedReplayBuffer,
    best_weights: Mapping[str, torch.Tensor] | None,
    metadata: Mapping[str, Any],
    keep: int,
) -> Path:
    """Write checkpoint ``state.step`` of ``run_dir`` atomically, keeping the ``keep`` newest.

    ``model.safetensors`` holds the online, target and (with validation) best weights under
    the prefixes ``online.``, ``target.``, ``best.``, with the network's ``metadata``.
    """
    tensors = {f"online.{k}": v for k, v in learner.online.state_dict().items()}
    tensors.update({f"target.{k}": v for k, v in learner.target.state_dict().items()})
    if best_weights is not None:
        tensors.update({f"best.{k}": v for k, v in best_weights.items()})

    def write_files(directory: Path) -> None:
        ckpt.save_tensors(directory / "model.safetensors", tensors, metadata)
        ckpt.save_torch_state(directory / "optimizer.pt", learner.optimizer.state_dict())
        ckpt.save_arrays(directory / "replay.npz", buffer.state_dict())
        (directory / STATE_FILE).write_text(state.to_json())

    return ckpt.write_checkpoint(run_dir, state.step, write_files, keep)


@dataclass(frozen=True)
class LoadedCheckpoint:
    """A verified checkpoint directory's contents."""

    path: Path
    state: TrainerState
    tensors: dict[str, torch.Tensor]
    optimizer: dict[str, Any]
    replay: dict[str, np.ndarray]

    def weights(self, prefix: str) -> dict[str, torch.Tensor]:
        """The state dict stored under ``prefix`` (``online``, ``target`` or ``best``)."""
        start = f"{prefix}."
        return {k.removeprefix(start): v for k, v in self.tensors.items() if k.startswith(start)}


def load_checkpoint(run_dir: Path, checkpoint: Path | None = None) -> LoadedCheckpoint:
    """Verify and read ``checkpoint`` (default: the run's newest); CheckpointError if it is
    missing, corrupt, or was taken under another ``config.json``."""
    path = checkpoint if checkpoint is not None else ckpt.latest_checkpoint(run_dir)
    ckpt.verify_checkpoint(path)
    tensors, _ = ckpt.load_tensors(path / "model.safetensors")
    optimizer = ckpt.load_torch_state(path / "optimizer.pt")
    replay = ckpt.load_arrays(path / "replay.npz")
    try:
        text = (path / STATE_FILE).read_text()
    except OSError as error:
        raise ckpt.CheckpointError(f"cannot read {path / STATE_FILE}: {error}") from error
    state = TrainerState.from_json(text, str(path / STATE_FILE))
    check_config_unchanged(run_dir, path, state.config_sha256)
    return LoadedCheckpoint(path, state, tensors, optimizer, replay)


def restore_learning(
    loaded: LoadedCheckpoint, learner: DDQNLearner, fresh_buffer: PrioritizedReplayBuffer
) -> PrioritizedReplayBuffer:
    """Load the checkpoint's weights and optimiser state into ``learner``; return its replay
    buffer, which must be one the run's config builds (``fresh_buffer``)."""
    learner.online.load_state_dict(loaded.weights("online"))
    learner.target.load_state_dict(loaded.weights("target"))
    learner.optimizer.load_state_dict(loaded.optimizer)
    try:
        buffer = PrioritizedReplayBuffer.from_state_dict(loaded.replay)
    except KeyError as error:
        raise ckpt.CheckpointError(
            f"the checkpoint's replay buffer lacks {error} (written by an older activevision?)"
        ) from error
    for name in ("capacity", "obs_shape", "alpha", "eps", "n_step", "gamma", "aux_dim"):
        if getattr(buffer, name) != getattr(fresh_buffer, name):
            raise ckpt.CheckpointError(
                f"the checkpoint's replay buffer has {name}={getattr(buffer, name)!r}, the run's"
                f" config gives {getattr(fresh_buffer, name)!r}"
            )
    return buffer


#: what resuming from a checkpoint under a changed config.json would do
RESUMING_WOULD = (
    "resuming would mix two configurations: restore the file, or start a new run with the new"
    " config"
)
#: what playing a run's network under a config.json edited after training would do
PLAYING_WOULD = (
    "playing its network would read the edited world, moves and observation, not those it was"
    " trained with; restore the file"
)


def check_config_unchanged(
    run_dir: Path, checkpoint: Path, saved: str | None, consequence: str = RESUMING_WOULD
) -> None:
    """CheckpointError unless ``run_dir``'s config.json is the file (SHA-256 ``saved``, from
    the checkpoint's state) that ``checkpoint`` was taken under; ``consequence`` says what
    going on regardless would do (a resume, an export)."""
    try:
        current = config_digest(run_dir)
    except OSError as error:
        raise ckpt.CheckpointError(f"cannot read {run_dir / CONFIG_FILE}: {error}") from error
    if current != saved:
        raise ckpt.CheckpointError(
            f"{run_dir / CONFIG_FILE} was changed after checkpoint {checkpoint.name}: {consequence}"
        )


def check_run_config_unchanged(run_dir: Path, consequence: str) -> None:
    """CheckpointError unless ``run_dir``'s config.json is the file its newest checkpoint was
    taken under (SHA-256 in the checkpoint's state.json): the run's weights were learnt in
    the world and with the moves of that file, so reading them with an edited one (to
    export, evaluate or play them) would pair the network with another world.
    ``consequence`` says what going on regardless would do. No checkpoint, an unreadable one
    or one from before the digest was kept: nothing to compare (loading the weights reports
    a corrupt checkpoint). The policy files do not record the digest: every checkpoint
    rewrites policy.safetensors, and a resume refuses an edited config.json, so the newest
    checkpoint's digest is that of every weights file of the run."""
    checkpoints = ckpt.list_checkpoints(run_dir)
    if not checkpoints:
        return
    try:
        saved = json.loads((checkpoints[-1] / STATE_FILE).read_text()).get("config_sha256")
    except (OSError, ValueError, AttributeError):
        return
    if saved is not None:
        check_config_unchanged(run_dir, checkpoints[-1], saved, consequence)


__all__ = [
    "LoadedCheckpoint",
    "TrainerState",
    "check_config_unchanged",
    "check_run_config_unchanged",
    "config_digest",
    "load_checkpoint",
    "obs_digest",
    "restore_learning",
    "save_checkpoint",
]
