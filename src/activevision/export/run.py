"""Export a training run directory (``config.json`` + policy weights) to ONNX."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path
from typing import Any

import numpy as np

from activevision.export.onnx_export import ExportedPolicy, export_onnx, policy_metadata
from activevision.runtime.metadata import MODEL_FILENAME
from activevision.training.config import MATCH_ENV_ID

CONFIG_FILENAME = "config.json"


def export_run(
    run_dir: str | os.PathLike[str],
    out_path: str | os.PathLike[str] | None = None,
    weights: str = "final",
    **export_options: Any,
) -> ExportedPolicy:
    """Export a training run's policy as ``policy.onnx`` + ``policy.json``: its newest
    weights, or with ``weights="best"`` those with the best validation score.

    Reads the weights with :func:`activevision.training.load_policy`, the action table,
    head limits, camera and world (appearance ranges, other robots) from the run's
    environment settings (``config.json``'s ``env``, or ``match`` for a run trained on
    ``ActiveVisionMatch-v0``) and records the SHA-256 of ``config.json`` in the metadata.

    Args:
        run_dir: a run directory written by :mod:`activevision.training`.
        out_path: ``.onnx`` file or directory to write to; default ``run_dir/policy.onnx``.
        **export_options: passed on to :func:`export_onnx` (``opset``, ``dynamic_batch``...).
    """
    from activevision.envs.actions import ACTION_NAMES_8WAY, action_table
    from activevision.envs.observations import vector_keys
    from activevision.training import load_config, load_policy

    run_dir = Path(run_dir)
    config_path = run_dir / CONFIG_FILENAME
    try:
        config_bytes = config_path.read_bytes()
    except FileNotFoundError as error:
        raise FileNotFoundError(f"{run_dir} is not a training run: no {CONFIG_FILENAME}") from error
    config = load_config(config_path)
    network = load_policy(run_dir, weights=weights)
    if config.env_id == MATCH_ENV_ID:
        # a policy trained on the match: its world, observation and moves are the match's
        return export_onnx(
            network,
            out_path or run_dir / MODEL_FILENAME,
            _match_metadata(config, hashlib.sha256(config_bytes).hexdigest()),
            **export_options,
        )
    env = config.env
    stack = getattr(network, "stack", 1)
    if stack != env.frame_stack:
        raise ValueError(
            f"{run_dir}: the network stacks {stack} frames but the environment {env.frame_stack}"
        )
    metadata = policy_metadata(
        action_table(env.step_deg, env.action_set),
        env.camera,
        training_config_sha256=hashlib.sha256(config_bytes).hexdigest(),
        action_names=ACTION_NAMES_8WAY,
        camera=env.camera,
        world={"appearance": env.appearance, "robots": env.robots},
    )
    metadata["step_deg"] = env.step_deg
    metadata["action_set"] = env.action_set
    metadata["observation"] = env.observation
    metadata["vector_keys"] = list(vector_keys(env))
    metadata["action_history"] = env.action_history
    metadata["action_type"] = env.action_type
    if env.action_type == "continuous":
        metadata["max_move_deg"] = list(env.max_move_deg)
    if config.algo == "dagger":
        from activevision.localisation import LocalisationConfig

        grid = LocalisationConfig().grid  # the views the student's goal head names
        metadata["act_by"] = config.dagger.act_by
        metadata["goal_switch_margin"] = config.dagger.switch_margin
        metadata["goal_views_deg"] = np.degrees(grid.views).tolist()
    return export_onnx(network, out_path or run_dir / MODEL_FILENAME, metadata, **export_options)


def _match_metadata(config: Any, config_sha256: str) -> dict[str, Any]:
    """policy.json's record of a policy trained on ``ActiveVisionMatch-v0`` (``config`` a
    TrainConfig): the match's moves of ``step_deg`` (or continuous ones), camera, world and
    observation (a DDQN's image; a match student's image, head, belief and ball model)."""
    from activevision.envs.actions import ACTION_NAMES_8WAY, action_table
    from activevision.envs.match.observations import vector_keys

    match = config.match
    metadata = policy_metadata(
        action_table(match.step_deg, "8way"),
        match.camera,
        training_config_sha256=config_sha256,
        action_names=ACTION_NAMES_8WAY,
        camera=match.camera,
        world={"appearance": match.appearance, "robots": match.robots},
    )
    metadata["step_deg"] = match.step_deg
    metadata["action_set"] = "8way"
    metadata["observation"] = match.observation if config.algo == "dagger" else "image"
    metadata["vector_keys"] = list(vector_keys(match)) if config.algo == "dagger" else []
    metadata["action_type"] = match.action_type
    if match.action_type == "continuous":
        metadata["max_move_deg"] = list(match.max_move_deg)
    if config.algo == "dagger":
        metadata["act_by"] = "action"
    return metadata
