"""Export a training run directory (``config.json`` + policy weights) to ONNX."""

from __future__ import annotations

import hashlib
import os
from collections.abc import Mapping, Sequence
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
    ``ActiveVisionMatch-v0``) and records the SHA-256 of ``config.json`` in the metadata, and
    which weights were exported and theirs (``training_weights``,
    ``training_weights_sha256``), taken as they were read.

    Args:
        run_dir: a run directory written by :mod:`activevision.training`.
        out_path: ``.onnx`` file or directory to write to; default ``run_dir/policy.onnx``.
        **export_options: passed on to :func:`export_onnx` (``opset``, ``dynamic_batch``...).
    """
    from activevision.envs.observations import vector_keys
    from activevision.training import load_config, load_policy
    from activevision.training.policy_files import scored_run
    from activevision.training.state import check_run_config_unchanged

    run_dir = Path(run_dir)
    config_path = run_dir / CONFIG_FILENAME
    try:
        config_bytes = config_path.read_bytes()
    except FileNotFoundError as error:
        raise FileNotFoundError(f"{run_dir} is not a training run: no {CONFIG_FILENAME}") from error
    config = load_config(config_path)
    sha256 = hashlib.sha256(config_bytes).hexdigest()
    check_run_config_unchanged(
        run_dir,
        "policy.json would record the edited camera and moves, not those the policy was"
        " trained with; restore the file",
    )
    # the weights exported, as they are read: report tells an export of weights the run
    # has replaced since (trained on, retrained) from its policy as it is
    source = {
        "training_weights": weights,
        "training_weights_sha256": scored_run(run_dir, weights)["weights_sha256"],
    }
    network = load_policy(run_dir, weights=weights)
    if config.env_id == MATCH_ENV_ID:
        # a policy trained on the match: its world, observation and moves are the match's
        from activevision.envs.match.observations import vector_keys as match_keys

        match = config.match
        student = config.algo == "dagger"
        metadata = _world_metadata(
            match,
            "8way",
            match.observation if student else "image",
            match_keys(match) if student else (),
            sha256,
            source,
        )
        if student:
            metadata["act_by"] = "action"
        return export_onnx(
            network, out_path or run_dir / MODEL_FILENAME, metadata, **export_options
        )
    env = config.env
    stack = getattr(network, "stack", 1)
    if stack != env.frame_stack:
        raise ValueError(
            f"{run_dir}: the network stacks {stack} frames but the environment {env.frame_stack}"
        )
    metadata = _world_metadata(
        env, env.action_set, env.observation, vector_keys(env), sha256, source
    )
    metadata["action_history"] = env.action_history
    if config.algo == "dagger":
        from activevision.localisation import LocalisationConfig

        # the views the student's goal head names: those the trainer's env searched
        grid = LocalisationConfig.for_camera(env.camera).grid
        metadata["act_by"] = config.dagger.act_by
        metadata["goal_switch_margin"] = config.dagger.switch_margin
        metadata["goal_frame"] = config.dagger.goal_frame
        metadata["goal_views_deg"] = np.degrees(grid.views).tolist()
    return export_onnx(network, out_path or run_dir / MODEL_FILENAME, metadata, **export_options)


def _world_metadata(
    world: Any,
    action_set: str,
    observation: str,
    keys: Sequence[str],
    config_sha256: str,
    source: Mapping[str, Any],
) -> dict[str, Any]:
    """policy.json's record of the world a policy was trained in (``world`` an ``EnvConfig``
    or a ``MatchConfig``): its moves, camera, appearance and robots, and the observation;
    and of the run's files it was exported from (``config_sha256``, ``source``: the
    weights', :func:`policy_metadata`'s ``training_weights`` and
    ``training_weights_sha256``).

    A discrete policy's moves are ``step_deg`` in ``action_set`` (its actions index their
    table); a continuous one's are ``max_move_deg``, and it records no ``step_deg`` nor
    ``action_set``: a continuous run never reads them, and the value its config carried
    (the default, or one a ``--config`` file held) was written as if it moved by it. Its
    ``action_table_deg`` (a key every policy.json has) holds the paper's discrete moves, those
    the other methods make beside it (``cli.args.env_config_of_run``)."""
    from activevision.envs import EnvConfig
    from activevision.envs.actions import ACTION_NAMES_8WAY, action_table

    discrete = world.action_type == "discrete"
    moves = (world.step_deg, action_set) if discrete else (EnvConfig().step_deg, "8way")
    metadata = policy_metadata(
        action_table(*moves),
        world.camera,
        training_config_sha256=config_sha256,
        action_names=ACTION_NAMES_8WAY,
        camera=world.camera,
        world={"appearance": world.appearance, "robots": world.robots},
        **source,
    )
    if discrete:
        metadata["step_deg"] = world.step_deg
        metadata["action_set"] = action_set
    metadata["observation"] = observation
    metadata["vector_keys"] = list(keys)
    metadata["action_type"] = world.action_type
    if not discrete:
        metadata["max_move_deg"] = list(world.max_move_deg)
    return metadata
