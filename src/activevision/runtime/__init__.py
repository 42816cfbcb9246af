"""Run an exported head-control policy on a robot: NumPy + onnxruntime, no torch.

Typical use::

    from activevision.runtime import HeadController

    controller = HeadController("policy.onnx")          # reads policy.json beside it
    command = controller.act(frame, pan, tilt)          # any-size uint8 grey/RGB frame
    neck.move_to(command.target_pan, command.target_tilt)

Pass ``camera=CameraModel(...)`` (the robot's camera) to be warned
(:class:`CameraMismatchWarning`) when it differs from the one the policy was trained for.

Export a trained run with :func:`activevision.export.export_run` (needs torch and onnx).
"""

from activevision.runtime.controller import (
    CameraMismatchWarning,
    HeadAngleWarning,
    HeadCommand,
    HeadController,
    robot_session_options,
)
from activevision.runtime.metadata import (
    METADATA_FILENAME,
    MODEL_FILENAME,
    CameraModel,
    HeadLimits,
    PolicyFileError,
    PolicyMetadata,
    load_metadata,
    metadata_path_for,
)
from activevision.runtime.preprocess import BT601_LUMA_RGB, FramePreprocessor, area_weights
from activevision.runtime.pretrained import pretrained_policy_path

__all__ = [
    "BT601_LUMA_RGB",
    "METADATA_FILENAME",
    "MODEL_FILENAME",
    "CameraMismatchWarning",
    "CameraModel",
    "FramePreprocessor",
    "HeadAngleWarning",
    "HeadCommand",
    "HeadController",
    "HeadLimits",
    "PolicyFileError",
    "PolicyMetadata",
    "area_weights",
    "load_metadata",
    "metadata_path_for",
    "pretrained_policy_path",
    "robot_session_options",
]
