"""Export a trained :class:`~activevision.agents.q_network.QNetwork` to ONNX for the robot.

Writes two files side by side, each atomically (temporary file + ``os.replace``):

* ``policy.onnx`` — the network with a **uint8** ``(1, stack, H, W)`` input named ``frames``
  and float32 ``(1, n_actions)`` output ``q_values``. The ``/ 255`` scaling of the network is
  inside the graph, folded into the first convolution's weights (``conv(x / 255) ==
  conv'(x)`` with ``w' = w / 255``; identical up to float rounding), so the graph is
  ``Cast -> Conv -> MaxPool -> Relu -> Conv -> Relu -> Conv -> Relu -> Flatten -> Gemm ->
  Relu -> Gemm``.
* ``policy.json`` — what the runtime needs besides the graph (see
  :mod:`activevision.runtime.metadata`): input size and stack, the action table in degrees,
  head limits, the camera and world (appearance ranges, other robots) the policy was trained
  with, SHA-256 of the model and of the run's ``config.json``, package version, opset.

Needs torch and onnx (``pip install activevision[export]``); onnxruntime, when installed, is
used to check the exported graph against PyTorch.
"""

from __future__ import annotations

import copy
import hashlib
import io
import json
import math
import os
import typing
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import torch
from torch import nn

import activevision
from activevision.agents.q_network import QNetwork
from activevision.agents.student import StudentNetwork
from activevision.io import write_bytes, write_text
from activevision.runtime.metadata import (
    METADATA_FORMAT,
    METADATA_FORMAT_VERSION,
    MODEL_FILENAME,
    STANDARD_ACTION_NAMES,
    CameraModel,
    PolicyMetadata,
    metadata_path_for,
)
from activevision.typecheck import config_to_dict

#: ONNX opset of exported policies (onnxruntime >= 1.14 runs it).
DEFAULT_OPSET = 17
#: Opsets export accepts: from the first with the uint8 ops the graph uses in their current
#: form (13) to the newest the TorchScript exporter writes (20).
SUPPORTED_OPSETS = range(13, 21)


def check_opset(opset: int) -> int:
    """``opset`` if export can write it, else ValueError naming the supported range."""
    if isinstance(opset, bool) or not isinstance(opset, int) or opset not in SUPPORTED_OPSETS:
        raise ValueError(
            f"ONNX opset must be an integer from {SUPPORTED_OPSETS.start} to"
            f" {SUPPORTED_OPSETS.stop - 1}, got {opset!r}"
        )
    return opset


INPUT_NAME = "frames"
OUTPUT_NAME = "q_values"
#: A DAgger student's second input (the Dict observation's vectors) and its output.
VECTOR_INPUT_NAME = "vector"
LOGITS_NAME = "logits"
GOAL_LOGITS_NAME = "goal_logits"
#: Largest |Q_onnx - Q_torch| accepted by the post-export check.
VERIFY_ATOL = 1e-4

#: Keys export_onnx derives from the network itself (a caller's value must agree).
_DERIVED_KEYS = ("image_height", "image_width", "stack", "n_actions")


class ExportedPolicy(NamedTuple):
    """Paths written by an export."""

    model_path: Path
    metadata_path: Path


class _Uint8Policy(nn.Module):
    """uint8 frames -> Q-values, with the input scaling folded into conv1 (or kept as a Mul)."""

    def __init__(self, network: QNetwork, fold_scaling: bool) -> None:
        super().__init__()
        self.network = copy.deepcopy(network).cpu().float().eval()
        for parameter in self.network.parameters():  # drop channels-last strides
            parameter.data = parameter.data.contiguous()
        self.fold_scaling = fold_scaling
        if fold_scaling:
            with torch.no_grad():
                self.network.conv1.weight.mul_(1.0 / 255.0)

    def forward(self, frames: torch.Tensor) -> torch.Tensor:
        x = frames.float()  # a float input skips QNetwork's own / 255
        if not self.fold_scaling:
            x = x * (1.0 / 255.0)
        q: torch.Tensor = self.network(x)  # nn.Module calls are typed as returning Any
        return q


class _Uint8Student(nn.Module):
    """uint8 frames (and the float32 vector) -> action logits of a StudentNetwork."""

    def __init__(self, network: StudentNetwork) -> None:
        super().__init__()
        self.network = copy.deepcopy(network).cpu().float().eval()

    def forward(
        self, frames: torch.Tensor, vector: torch.Tensor | None = None
    ) -> torch.Tensor | tuple[torch.Tensor, torch.Tensor]:
        logits, goal = self.network.forward_with_goal(frames.float() * (1.0 / 255.0), vector)
        return logits if goal is None else (logits, goal)


def policy_metadata(
    action_table: np.ndarray,
    head_limits: Mapping[str, float] | Any,
    training_config_sha256: str | None = None,
    action_names: Sequence[str] | None = None,
    camera: Any | None = None,
    world: Mapping[str, Any] | None = None,
    training_weights: str | None = None,
    training_weights_sha256: str | None = None,
) -> dict[str, Any]:
    """The caller's part of policy.json, from radians.

    Args:
        action_table: (A, 2) head moves ``(d_pan, d_tilt)`` in radians, as
            :func:`activevision.envs.actions.action_table` returns.
        head_limits: a :class:`activevision.geometry.CameraConfig` (or anything with
            ``pan_min``, ``pan_max``, ``tilt_min``, ``tilt_max`` attributes or keys), radians.
        training_config_sha256: SHA-256 of the training run's ``config.json``, if any.
        action_names: name per action; default: the env's (``ACTION_NAMES_8WAY``, cut to the
            table's length). The runtime checks each row moves the way its name says.
        camera: the camera the policy was trained with (the run's ``env.camera``, a
            :class:`activevision.geometry.CameraConfig` or
            :class:`activevision.runtime.CameraModel`), recorded as policy.json's ``camera``
            so that ``HeadController(..., camera=...)`` can compare a robot's camera with it.
            None: not recorded.
        world: the world the policy was trained in, recorded as policy.json's ``world``:
            record name -> config dataclass or its dict (``{"appearance": env.appearance,
            "robots": env.robots}``, stored as ``typecheck.config_to_dict`` writes them).
            None: not recorded.
        training_weights: which of the run's weights are exported, "final" or "best",
            recorded with ``training_weights_sha256``, their SHA-256 (None where unknown),
            so that ``activevision report`` can tell an export from weights the run has
            replaced since. None: neither is recorded.
    """
    table = np.asarray(action_table, dtype=np.float64)
    if table.ndim != 2 or table.shape[1] != 2:
        raise ValueError(f"action_table must have shape (A, 2), got {table.shape}")

    def limit(key: str) -> float:
        value = head_limits[key] if isinstance(head_limits, Mapping) else getattr(head_limits, key)
        return math.degrees(float(value))

    values: dict[str, Any] = {
        "action_table_deg": np.degrees(table).tolist(),
        "head_limits_deg": {k: limit(k) for k in ("pan_min", "pan_max", "tilt_min", "tilt_max")},
    }
    if camera is not None:
        values["camera"] = CameraModel.of(camera).to_json()
    if world is not None:
        values["world"] = {name: config_to_dict(record) for name, record in world.items()}
    values["training_config_sha256"] = training_config_sha256
    if training_weights is not None:
        values["training_weights"] = training_weights
        values["training_weights_sha256"] = training_weights_sha256
    values["action_names"] = list((action_names or STANDARD_ACTION_NAMES)[: len(table)])
    return values


def export_onnx(
    q_network: QNetwork | StudentNetwork,
    out_path: str | os.PathLike[str],
    metadata: Mapping[str, Any],
    *,
    opset: int = DEFAULT_OPSET,
    dynamic_batch: bool = False,
    fold_scaling: bool = True,
    verify: bool = True,
) -> ExportedPolicy:
    """Write ``q_network`` as ONNX to ``out_path`` and its metadata JSON beside it.

    Args:
        q_network: the policy network (any device; exported from a CPU copy).
        out_path: the ``.onnx`` file to write, or a directory to write ``policy.onnx`` into.
            The metadata goes to the same path with a ``.json`` suffix.
        metadata: at least ``action_table_deg`` and ``head_limits_deg`` (build it with
            :func:`policy_metadata`); extra JSON keys are kept. Keys derived from the network
            (image size, stack, number of actions) may be given but must agree.
        opset: ONNX opset version.
        dynamic_batch: give the input a symbolic batch dimension instead of a fixed 1 (the
            robot decides one frame at a time; fixed 1 is as fast and simpler to check).
        fold_scaling: fold the ``/ 255`` input scaling into conv1's weights (default) instead
            of exporting a Mul node.
        verify: check the written graph with ``onnx.checker`` and, when onnxruntime is
            installed, its Q-values against PyTorch on random frames (``VERIFY_ATOL``).

    Returns:
        The paths written. Raises ValueError if the metadata does not fit the network.
    """
    check_opset(opset)
    model_path = model_path_of(out_path)
    model_path.parent.mkdir(parents=True, exist_ok=True)
    stack, (height, width) = _stack(q_network), q_network.image_shape
    vector_size = getattr(q_network, "vector_size", 0)
    module: nn.Module
    if isinstance(q_network, StudentNetwork):
        module = _Uint8Student(q_network)
    else:
        module = _Uint8Policy(q_network, fold_scaling)
    model_bytes = _onnx_bytes(module, (1, stack, height, width), opset, dynamic_batch, vector_size)
    document = _metadata_document(q_network, metadata, model_path.name, model_bytes, opset)
    PolicyMetadata.from_dict(document, source="exported metadata")  # the runtime must accept it
    if verify:
        _verify(q_network, model_bytes, (stack, height, width), vector_size)

    metadata_path = metadata_path_for(model_path)
    text = json.dumps(document, indent=2) + "\n"
    write_bytes(model_path, model_bytes)
    write_text(metadata_path, text)
    return ExportedPolicy(model_path, metadata_path)


def model_path_of(out_path: str | os.PathLike[str]) -> Path:
    """The model file export writes for ``out_path``: itself if it ends in ``.onnx``, else
    ``out_path/policy.onnx`` (a directory)."""
    path = Path(out_path)
    if path.is_dir() or path.suffix.lower() != ".onnx":
        return path / MODEL_FILENAME
    return path


# ---------------------------------------------------------------------- helpers
def _stack(network: QNetwork | StudentNetwork) -> int:
    return int(getattr(network, "stack", 1))  # a student sees one frame


def _onnx_bytes(
    module: nn.Module,
    input_shape: tuple[int, ...],
    opset: int,
    dynamic_batch: bool,
    vector_size: int = 0,
) -> bytes:
    example: tuple[torch.Tensor, ...] = (torch.zeros(input_shape, dtype=torch.uint8),)
    input_names = [INPUT_NAME]
    output_names = [LOGITS_NAME] if isinstance(module, _Uint8Student) else [OUTPUT_NAME]
    if isinstance(module, _Uint8Student) and module.network.n_goals:
        output_names.append(GOAL_LOGITS_NAME)
    if vector_size:
        example += (torch.zeros((1, vector_size), dtype=torch.float32),)
        input_names.append(VECTOR_INPUT_NAME)
    buffer = io.BytesIO()
    dynamic_axes = (
        {name: {0: "batch"} for name in input_names + output_names} if dynamic_batch else None
    )
    with warnings.catch_warnings(), torch.inference_mode(False), torch.no_grad():
        # The TorchScript exporter is deprecated in favour of torch.export + onnxscript, which
        # is a heavier dependency; for this plain CNN both write the same graph.
        warnings.simplefilter("ignore", category=DeprecationWarning)
        warnings.simplefilter("ignore", category=FutureWarning)
        torch.onnx.export(
            module,
            example,
            typing.cast(Any, buffer),  # a file-like object, which its annotation omits
            input_names=input_names,
            output_names=output_names,
            dynamic_axes=dynamic_axes,
            opset_version=opset,
            do_constant_folding=True,
            dynamo=False,
        )
    return buffer.getvalue()


def _metadata_document(
    network: QNetwork | StudentNetwork,
    metadata: Mapping[str, Any],
    model_file: str,
    model_bytes: bytes,
    opset: int,
) -> dict[str, Any]:
    continuous = bool(getattr(network, "continuous", False))
    derived = {
        "image_height": int(network.image_shape[0]),
        "image_width": int(network.image_shape[1]),
        "stack": _stack(network),
        # a continuous policy outputs a move; its n_actions are the env's discrete table's
        "n_actions": len(metadata.get("action_table_deg", ())) if continuous else network.n_actions,
    }
    if continuous and (
        metadata.get("action_type") != "continuous" or "max_move_deg" not in metadata
    ):
        raise ValueError(
            "the network outputs continuous moves: metadata needs action_type='continuous'"
            " and max_move_deg"
        )
    for key in _DERIVED_KEYS:
        if key in metadata and metadata[key] != derived[key]:
            raise ValueError(
                f"metadata[{key!r}] = {metadata[key]!r} but the network has {derived[key]!r}"
            )
    for key in ("action_table_deg", "head_limits_deg"):
        if key not in metadata:
            raise ValueError(f"metadata needs {key!r} (build it with policy_metadata())")
    rows = len(metadata["action_table_deg"])
    if not continuous and rows != network.n_actions:
        raise ValueError(
            f"the action table has {rows} rows but the network has {network.n_actions} outputs"
        )
    document: dict[str, Any] = {
        "format": METADATA_FORMAT,
        "format_version": METADATA_FORMAT_VERSION,
        "package_version": activevision.__version__,
        "opset": int(opset),
        "model_file": model_file,
        "model_sha256": hashlib.sha256(model_bytes).hexdigest(),
        "input_name": INPUT_NAME,
        "input_dtype": "uint8",
        "output_name": LOGITS_NAME if isinstance(network, StudentNetwork) else OUTPUT_NAME,
        **derived,
        "dueling": bool(getattr(network, "dueling", False)),
        "preprocessing": "grey (ITU-R BT.601 luma), area-average resize to image_width x "
        "image_height, round half up to uint8; the graph scales by 1/255 itself",
    }
    for key, value in metadata.items():
        document.setdefault(key, value)
    document.setdefault("training_config_sha256", None)
    if isinstance(network, StudentNetwork):
        if network.vector_size != sum(_vector_sizes(document)):
            raise ValueError(
                f"metadata's vector_keys {document.get('vector_keys')} do not add up to the"
                f" network's vector input of {network.vector_size}"
            )
        if network.vector_size:
            document["vector_input_name"] = VECTOR_INPUT_NAME
        if network.n_goals:
            document["goal_output_name"] = GOAL_LOGITS_NAME
    return document


def _vector_sizes(document: Mapping[str, Any]) -> list[int]:
    from activevision.runtime.metadata import vector_key_size

    keys = document.get("vector_keys", [])
    return [
        vector_key_size(k, int(document["n_actions"]), int(document.get("action_history", 0)))
        for k in keys
    ]


def _verify(
    network: QNetwork | StudentNetwork,
    model_bytes: bytes,
    input_shape: tuple[int, int, int],
    vector_size: int = 0,
) -> None:
    import onnx

    onnx.checker.check_model(onnx.load_model_from_string(model_bytes))
    try:
        import onnxruntime as ort
    except ImportError:
        return
    rng = np.random.default_rng(0)
    frames = rng.integers(0, 256, (1, *input_shape), dtype=np.uint8)
    session = ort.InferenceSession(model_bytes, providers=["CPUExecutionProvider"])
    feed: dict[str, np.ndarray] = {INPUT_NAME: frames}
    reference = copy.deepcopy(network).cpu().eval()
    with torch.inference_mode():
        if isinstance(reference, StudentNetwork):
            vector = rng.uniform(-1, 1, (1, vector_size)).astype(np.float32)
            if vector_size:
                feed[VECTOR_INPUT_NAME] = vector
            want = reference(torch.from_numpy(frames), torch.from_numpy(vector)).numpy()
        else:
            want = reference(torch.from_numpy(frames)).numpy()
    got = session.run([session.get_outputs()[0].name], feed)[0]  # the action scores
    error = float(np.abs(got - want).max())
    if not error <= VERIFY_ATOL:
        raise RuntimeError(f"exported ONNX differs from PyTorch by {error:.3g} > {VERIFY_ATOL}")
