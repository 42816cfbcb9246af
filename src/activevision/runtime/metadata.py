"""The ``policy.json`` file that travels beside an exported ``policy.onnx``.

It tells the runtime everything the ONNX graph does not: which head move each output means,
the head limits to clip to, the frame size and stack depth, and where the model came from.
Reading it needs only the standard library and NumPy (no torch).

Example ``policy.json`` (abridged)::

    {
      "format": "activevision-policy",
      "format_version": 1,
      "package_version": "0.1.0",
      "opset": 17,
      "model_file": "policy.onnx",
      "model_sha256": "3f1c...",
      "input_name": "frames",
      "output_name": "q_values",
      "image_height": 120,
      "image_width": 160,
      "stack": 1,
      "n_actions": 9,
      "action_names": ["stay", "pan_left", ...],
      "action_table_deg": [[0.0, 0.0], [3.0, 0.0], ...],
      "head_limits_deg": {"pan_min": -90.0, "pan_max": 90.0, "tilt_min": 5.0, "tilt_max": 65.0},
      "camera": {"width_px": 160, "height_px": 120, "hfov_deg": 58.0, "camera_height_m": 0.5,
                 "pan_min_deg": -90.0, "pan_max_deg": 90.0, "tilt_min_deg": 5.0,
                 "tilt_max_deg": 65.0},
      "world": {"appearance": {"gain": [1.0, 1.0], "offset": [0.0, 0.0], ...},
                "robots": {"count": [0, 0], "height": [0.4, 1.0], "radius": 0.12, ...}},
      "training_config_sha256": "9a0b...",
      "training_weights": "final",
      "training_weights_sha256": "5d2e..."
    }

Angles are stored in degrees for people to read; :class:`PolicyMetadata` hands them out in
radians. ``action_table_deg[a] = (d_pan, d_tilt)``: pan positive to the left, tilt positive
*down* (the conventions of :mod:`activevision.geometry.camera`).

``camera`` is the camera the policy was trained with (the run's ``env.camera``; see
:class:`CameraModel`), of the input's aspect ratio (its width and height are the input's),
its field of view at least ``MIN_HFOV_DEG``. Files written before it existed lack it: the
trained camera is then unknown and :class:`~activevision.runtime.HeadController` cannot
compare the robot's with it.
``head_limits_deg`` is what the controller clips its commands to; export writes the trained
camera's pan and tilt range to both, and a file where the two differ is refused.

``world`` is the world the policy was trained in: the run's ``env.appearance`` (each
appearance factor's ``[low, high]`` range) and ``env.robots`` (other robots: ``count`` and
their size and spacing), as ``typecheck.config_to_dict`` writes them. The runtime checks only
its shape (an object of objects whose values are finite numbers or ``[low, high]`` pairs) and
hands it out as a plain dict (:attr:`PolicyMetadata.world`); ``activevision robustness`` builds
the configs from it. Files written before it existed lack it (None: unknown).

Every key a reader acts on must be present and of its type, else :class:`PolicyFileError`
names the file and the key: ``opset``, ``input_name``, ``input_dtype`` (``"uint8"``),
``output_name``, ``n_actions``, the frame size and stack (at most ``MAX_IMAGE_SIDE`` px a
side and ``MAX_STACK`` frames, a training config's bounds; the ``camera`` record's size
too), the action table and names, the head limits and ``model_sha256`` (every export has
written them), and ``vector_input_name`` and
``observation`` where ``vector_keys`` lists inputs; ``vector_keys`` must be the observation's
inputs (:data:`OBSERVATION_VECTOR_KEYS`), with ``"actions"`` last exactly when
``action_history`` > 0. Keys older files lack keep a default:
``observation`` ``"image"`` and no ``vector_keys`` (files from before vector inputs),
``camera`` and ``world`` None, ``action_type`` ``"discrete"``, ``act_by`` ``"action"``.
``step_deg`` and ``action_set`` (the env's discrete moves; ``export_onnx`` alone writes
neither) come together, and the action table must be their moves. Keys no reader acts on
(``dueling``, ``preprocessing``, ``package_version``, ``training_config_sha256``,
``training_weights``, ``training_weights_sha256``) are checked for their type where present.
``model_file``, where present, must be a bare file name (the model sits beside its
policy.json: no folder, ``..`` or absolute path). It names the model as export wrote it: a
controller loads the model it is given and the metadata of the same name beside it (a pair
renamed together, ``striker.onnx`` and ``striker.json``, still loads; the model's SHA-256
proves the two belong together), so it reads ``model_file`` for nothing else.

``training_config_sha256`` is the SHA-256 of the run's ``config.json`` the policy was exported
from, ``training_weights`` which of its weights (``"final"``: ``policy.safetensors``,
``"best"``: ``best_policy.safetensors``) and ``training_weights_sha256`` their SHA-256 (null
where the run had no such file and its newest checkpoint's were read): ``activevision report``
tells by them a run's ``policy.onnx`` exported before the run was trained on or retrained.
Files written before the weights' record lack both keys (None: unknown); ``export_onnx``
alone writes neither.

``action_type`` is ``"discrete"`` (absent in older files: the graph scores the rows of
``action_table_deg``) or ``"continuous"``: the graph's output is one move ``(pan, tilt)`` in
[-1, 1], scaled by ``max_move_deg`` (the largest move per decision on each axis, degrees).
``action_table_deg`` is kept for the discrete moves the env also defines. ``step_deg`` and
``action_set`` are a discrete policy's: ``export`` writes neither for a continuous one
(its table is then the paper's 3-degree 8-way moves); continuous files exported before
(the shipped one's) record the ``step_deg`` their run's config carried unread, which is
read and checked as before, and not acted on.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from activevision.runtime.goal_evidence import GOAL_FRAMES, GoalFrame

#: Value of the ``format`` key of every policy.json.
METADATA_FORMAT = "activevision-policy"
#: Version of the policy.json layout this code reads and writes.
METADATA_FORMAT_VERSION = 1
#: Default file names of an exported policy.
MODEL_FILENAME = "policy.onnx"
METADATA_FILENAME = "policy.json"

_HEAD_LIMIT_KEYS = ("pan_min", "pan_max", "tilt_min", "tilt_max")
#: Physical bounds of the limits (a neck that turns past +-180 deg pan is a typo).
_HEAD_LIMIT_BOUNDS_DEG = {"pan_min": 180.0, "pan_max": 180.0, "tilt_min": 90.0, "tilt_max": 90.0}
#: How far (degrees) policy.json's camera record and head_limits_deg may differ: export
#: writes the same angles to both, so only the rounding of radians to degrees.
_LIMIT_AGREEMENT_DEG = 1e-6
#: Largest head move one action may make (the env's step_deg is at most 30).
MAX_MOVE_DEG = 30.0
#: Largest continuous head move per decision (the env's max_move_deg is at most 90).
MAX_CONTINUOUS_MOVE_DEG = 90.0
#: Direction (sign of d_pan, sign of d_tilt) each named action must move: pan left +,
#: tilt down + (activevision.geometry.camera).
_ACTION_SIGNS = {
    "stay": (0.0, 0.0),
    "pan_left": (1.0, 0.0),
    "pan_right": (-1.0, 0.0),
    "tilt_up": (0.0, -1.0),
    "tilt_down": (0.0, 1.0),
    "pan_left_tilt_up": (1.0, -1.0),
    "pan_left_tilt_down": (1.0, 1.0),
    "pan_right_tilt_up": (-1.0, -1.0),
    "pan_right_tilt_down": (-1.0, 1.0),
}


#: The env's action names, in its order (activevision.envs.actions.ACTION_NAMES_8WAY).
STANDARD_ACTION_NAMES = tuple(_ACTION_SIGNS)
#: The vector inputs a policy may take, in the order the network concatenates them, and the
#: size of each (activevision.envs.observations, and envs.match.observations for "belief"
#: and "ball"; "actions" is per remembered action).
VECTOR_KEY_SIZES = {
    "head": 2,
    "pose": 4,
    "belief": 3,
    "ball": 3,
    "pose_error": 1,
    "proposal": 5,
    "actions": 1,
}
#: The vector inputs each observation gives, in the order above ("actions" follows any of
#: them when a policy remembers its moves): the episodic env's observations
#: (envs.observations) and the match env's (envs.match.observations), which build theirs
#: from this table, so that HeadController builds the same layout on the robot.
OBSERVATION_VECTOR_KEYS: dict[str, tuple[str, ...]] = {
    "image": (),
    "image+head": ("head",),
    "image+head+pose": ("head", "pose", "pose_error"),
    "image+head+pose+proposal": ("head", "pose", "pose_error", "proposal"),
    "image+head+belief": ("head", "pose", "belief", "ball"),
}
#: Every vector input is clipped to +-this, the bound of the envs' observation spaces (m,
#: rad, s): what lies beyond it (a prior pose or error scale over 10, a belief std or ball
#: age over 10) is fed as the bound, in the envs and on the robot alike.
VECTOR_BOUND = 10.0


#: Keys of policy.json's ``camera`` record -> :class:`CameraModel` field (the suffix says the
#: unit: pixels, degrees or metres).
_CAMERA_KEYS = {
    "width_px": "width",
    "height_px": "height",
    "hfov_deg": "hfov",
    "camera_height_m": "camera_height",
    "pan_min_deg": "pan_min",
    "pan_max_deg": "pan_max",
    "tilt_min_deg": "tilt_min",
    "tilt_max_deg": "tilt_max",
}
#: The narrowest field of view CameraModel.from_degrees takes (degrees): a humanoid's head
#: camera sees tens of degrees; a value below this is radians given for degrees.
MIN_HFOV_DEG = 5.0
#: The highest camera CameraModel.from_degrees takes (metres): a humanoid's head camera is
#: within two metres of the ground; a value above this is centimetres given for metres.
MAX_CAMERA_HEIGHT_M = 5.0
#: The widest and highest input image a policy may take (px): geometry.camera.MAX_IMAGE_SIDE,
#: the bound of a training config's camera (the runtime imports no geometry). A larger
#: ``image_width``, ``image_height`` or ``camera`` record was written by no export.
MAX_IMAGE_SIDE = 8192
#: The most frames a policy may stack: envs.config.MAX_FRAME_STACK, a config's bound.
MAX_STACK = 64
#: The most previous actions a policy remembers (EnvConfig.action_history's limit too; the
#: controller keeps that many, so a larger number in a file is refused, not allocated).
MAX_ACTION_HISTORY = 16
#: How far a robot's camera may differ from the trained one before HeadController warns.
CAMERA_TOLERANCES = {
    "hfov": math.radians(1.0),  #: rad
    "camera_height": 0.02,  #: m
    "angle": math.radians(1.0),  #: rad, each pan and tilt limit
    "aspect": 0.01,  #: relative difference of width / height
}


#: Rows of each discrete action set's table (activevision.envs.actions.action_table).
_ACTION_SET_SIZES = {"8way": 9, "4way": 5}


def _action_table_deg(step_deg: float, action_set: str) -> np.ndarray:
    """The env's (A, 2) moves in degrees (``activevision.envs.actions.action_table``, written
    out: the runtime imports no envs)."""
    s = step_deg
    d = math.degrees(math.radians(s) * math.sqrt(2) / 2)
    moves = [(0, 0), (s, 0), (-s, 0), (0, -s), (0, s), (d, -d), (d, d), (-d, -d), (-d, d)]
    return np.asarray(moves[: _ACTION_SET_SIZES[action_set]], dtype=np.float64)


def observation_vector_keys(observation: str, action_history: int) -> tuple[str, ...]:
    """The vector inputs of ``observation`` (a key of :data:`OBSERVATION_VECTOR_KEYS`), with
    ``"actions"`` last when the policy remembers ``action_history > 0`` moves."""
    return OBSERVATION_VECTOR_KEYS[observation] + (("actions",) if action_history else ())


def vector_key_size(key: str, n_actions: int, action_history: int) -> int:
    """Length of vector input ``key``."""
    return action_history * n_actions if key == "actions" else VECTOR_KEY_SIZES[key]


def _is_sha256(text: str) -> bool:
    return len(text) == 64 and all(c in "0123456789abcdef" for c in text)


def _real(value: Any) -> float | None:
    """``value`` as a float (inf when too large for one), None unless a real number."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        return None
    try:
        return float(value)
    except OverflowError:
        return math.inf


class PolicyFileError(ValueError):
    """An exported policy (``policy.onnx`` or ``policy.json``) is missing, unreadable, corrupt
    or inconsistent. The message names the file and the problem."""


def metadata_path_for(model_path: str | os.PathLike[str]) -> Path:
    """Where the metadata of ``model_path`` lives: the same name with a ``.json`` suffix."""
    return Path(model_path).with_suffix(".json")


@dataclass(frozen=True)
class HeadLimits:
    """Joint limits of the neck, radians (pan positive left, tilt positive down)."""

    pan_min: float
    pan_max: float
    tilt_min: float
    tilt_max: float

    def clip(self, pan: float, tilt: float) -> tuple[float, float]:
        """``(pan, tilt)`` clipped into the limits."""
        return (
            min(max(pan, self.pan_min), self.pan_max),
            min(max(tilt, self.tilt_min), self.tilt_max),
        )

    def to_degrees_dict(self) -> dict[str, float]:
        """The limits in degrees, as stored in policy.json."""
        return {key: math.degrees(getattr(self, key)) for key in _HEAD_LIMIT_KEYS}


@dataclass(frozen=True)
class CameraModel:
    """A head camera and neck: the one a policy was trained for (``policy.json``'s
    ``camera``, the run's :class:`activevision.geometry.CameraConfig`) or the robot's, to
    compare with it (``HeadController(..., camera=CameraModel(...))``).

    Same fields and units as ``CameraConfig``: pixels, radians (pan positive left, tilt
    positive down from horizontal) and metres. Torch-free; :meth:`from_degrees` takes angles
    in degrees. ValueError names a field out of range.
    """

    width: int  #: image width (px)
    height: int  #: image height (px)
    hfov: float  #: horizontal field of view (rad)
    camera_height: float  #: camera above the ground (m)
    pan_min: float  #: neck yaw limits (rad)
    pan_max: float
    tilt_min: float  #: head pitch limits, down from horizontal (rad)
    tilt_max: float

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise ValueError(f"{name} must be a positive integer (px), got {value!r}")
            object.__setattr__(self, name, int(value))
        for name in ("hfov", "camera_height", *_HEAD_LIMIT_KEYS):
            value = _real(getattr(self, name))
            if value is None or not math.isfinite(value):
                raise ValueError(f"{name} must be a finite number, got {getattr(self, name)!r}")
            object.__setattr__(self, name, value)
        if not 0 < self.hfov < math.pi:
            raise ValueError(
                f"hfov must lie in (0, 180) degrees, got {math.degrees(self.hfov):.6g}"
            )
        if not self.camera_height > 0:
            raise ValueError(f"camera_height must be positive (m), got {self.camera_height}")
        for key, bound in _HEAD_LIMIT_BOUNDS_DEG.items():
            degrees = math.degrees(getattr(self, key))
            if not -bound <= degrees <= bound:
                raise ValueError(f"{key} = {degrees:.6g} degrees lies outside +-{bound:g} degrees")
        if not (self.pan_min <= self.pan_max and self.tilt_min <= self.tilt_max):
            raise ValueError(
                "pan and tilt limits must be ordered (min <= max), got pan "
                f"{self._range_deg('pan')} and tilt {self._range_deg('tilt')} degrees"
            )

    @classmethod
    def of(cls, camera: Any) -> CameraModel:
        """``camera`` itself if it is a CameraModel, else one with its fields, read as
        attributes (an :class:`activevision.geometry.CameraConfig`) or keys."""
        if isinstance(camera, cls):
            return camera
        names = [f.name for f in fields(cls)]
        try:
            if isinstance(camera, Mapping):
                values = {name: camera[name] for name in names}
            else:
                values = {name: getattr(camera, name) for name in names}
        except (KeyError, AttributeError) as error:
            raise TypeError(
                f"a camera needs the fields {names} (a CameraModel or CameraConfig), got {camera!r}"
            ) from error
        return cls(**values)

    @classmethod
    def from_degrees(
        cls,
        width: int,
        height: int,
        hfov_deg: float,
        camera_height: float,
        pan_deg: tuple[float, float],
        tilt_deg: tuple[float, float],
    ) -> CameraModel:
        """A camera with its angles in degrees: ``pan_deg`` and ``tilt_deg`` are the
        ``(min, max)`` head limits (pan positive left, tilt positive down). ValueError for a
        field of view below ``MIN_HFOV_DEG`` (radians) or a ``camera_height`` above
        ``MAX_CAMERA_HEIGHT_M`` (centimetres)."""

        def degrees(name: str, value: Any) -> float:
            real = _real(value)
            if real is None or not math.isfinite(real):
                raise ValueError(f"{name} must be a finite number of degrees, got {value!r}")
            return real

        try:
            (pan_min, pan_max), (tilt_min, tilt_max) = pan_deg, tilt_deg
        except (TypeError, ValueError) as error:
            raise ValueError(
                f"pan_deg and tilt_deg must each be a (min, max) pair, got {pan_deg!r} and"
                f" {tilt_deg!r}"
            ) from error
        hfov = degrees("hfov_deg", hfov_deg)
        if hfov < MIN_HFOV_DEG:  # no head camera is that narrow: radians given for degrees
            raise ValueError(f"hfov_deg must be degrees, at least {MIN_HFOV_DEG:g}; got {hfov:g}")
        metres = _real(camera_height)
        if metres is not None and metres > MAX_CAMERA_HEIGHT_M:  # no head camera is that high
            raise ValueError(
                f"camera_height must be metres, at most {MAX_CAMERA_HEIGHT_M:g}; got {metres:g}"
                " (centimetres?)"
            )
        return cls(
            width=width,
            height=height,
            hfov=math.radians(hfov),
            camera_height=camera_height,
            pan_min=math.radians(degrees("pan_deg", pan_min)),
            pan_max=math.radians(degrees("pan_deg", pan_max)),
            tilt_min=math.radians(degrees("tilt_deg", tilt_min)),
            tilt_max=math.radians(degrees("tilt_deg", tilt_max)),
        )

    @property
    def aspect(self) -> float:
        """width / height."""
        return self.width / self.height

    def to_json(self) -> dict[str, int | float]:
        """The record as policy.json stores it (degrees and metres)."""
        values: dict[str, int | float] = {}
        for key, name in _CAMERA_KEYS.items():
            value = getattr(self, name)
            values[key] = math.degrees(value) if key.endswith("_deg") else value
        return values

    def differences(
        self, robot: CameraModel, tolerances: Mapping[str, float] = CAMERA_TOLERANCES
    ) -> dict[str, str]:
        """How ``robot`` differs from this (trained) camera beyond ``tolerances``: field
        (``"aspect"``, ``"hfov"``, ``"camera_height"``, ``"pan_min"``...) -> a line naming
        both values; empty for the policy's camera. Resolution alone does not count (the
        controller resizes frames to the policy's input), the aspect ratio does."""
        found = {}
        if abs(robot.aspect / self.aspect - 1) > tolerances["aspect"]:
            found["aspect"] = (
                f"aspect ratio (width/height): robot {robot.width}x{robot.height} px ="
                f" {robot.aspect:.3f}, trained {self.width}x{self.height} px ="
                f" {self.aspect:.3f} (frames are resized to the policy's input, so the image"
                " is stretched)"
            )
        if abs(robot.hfov - self.hfov) > tolerances["hfov"]:
            found["hfov"] = (
                f"hfov: robot {math.degrees(robot.hfov):.1f} deg, trained"
                f" {math.degrees(self.hfov):.1f} deg"
            )
        if abs(robot.camera_height - self.camera_height) > tolerances["camera_height"]:
            found["camera_height"] = (
                f"camera_height: robot {robot.camera_height:.3f} m, trained"
                f" {self.camera_height:.3f} m"
            )
        for name in _HEAD_LIMIT_KEYS:
            mine, theirs = getattr(self, name), getattr(robot, name)
            if abs(theirs - mine) > tolerances["angle"]:
                found[name] = (
                    f"{name}: robot {math.degrees(theirs):.1f} deg, trained"
                    f" {math.degrees(mine):.1f} deg"
                )
        return found

    def _range_deg(self, axis: str) -> str:
        low, high = getattr(self, f"{axis}_min"), getattr(self, f"{axis}_max")
        return f"{math.degrees(low):g}..{math.degrees(high):g}"


@dataclass(frozen=True)
class PolicyMetadata:
    """Parsed and validated ``policy.json`` (see the module docstring for the file layout)."""

    image_height: int
    image_width: int
    stack: int
    action_table: np.ndarray = field(repr=False)  #: (A, 2) (d_pan, d_tilt), radians
    head_limits: HeadLimits
    input_name: str = "frames"
    output_name: str = "q_values"
    opset: int = 0
    package_version: str | None = None
    model_file: str | None = None
    model_sha256: str = ""
    training_config_sha256: str | None = None
    #: which of the run's weights were exported, "final" or "best" (None: not recorded)
    training_weights: str | None = None
    #: their SHA-256 (None: not recorded, or the run had no such file)
    training_weights_sha256: str | None = None
    action_names: tuple[str, ...] = ()
    #: the observation the policy was trained on ("image", "image+head", ...)
    observation: str = "image"
    #: the vector inputs, in order (empty: the image alone)
    vector_keys: tuple[str, ...] = ()
    action_history: int = 0  #: previous actions the vector remembers
    vector_input_name: str | None = None  #: the graph's vector input (None: none)
    #: "action": the argmax of the action scores; "goal": moves towards the goal view with
    #: the most evidence (``runtime.goal_evidence``), read from output ``goal_output_name``
    act_by: str = "action"
    goal_output_name: str | None = None
    goal_views: np.ndarray | None = field(default=None, repr=False)  #: (V, 2) rad
    #: with act_by "goal": the evidence (nats) another view needs over the current goal
    goal_switch_margin: float = 0.0
    #: what the goal output names (``runtime.goal_evidence.GoalFrame``): "body", the views;
    #: "camera", offsets from the head
    goal_frame: GoalFrame = "body"
    #: "discrete": the output scores the action table's rows; "continuous": it is the move
    #: (pan, tilt) in [-1, 1], times ``max_move``
    action_type: str = "discrete"
    max_move: tuple[float, float] | None = None  #: continuous: the largest move (pan, tilt) rad
    #: the env's discrete moves the action table holds: ``step_deg`` degrees a step in
    #: ``action_set`` ("8way" or "4way"); None: a file written by ``export_onnx`` alone, or
    #: a continuous policy's (which moves by ``max_move``)
    step_deg: float | None = None
    action_set: str | None = None
    #: the camera the policy was trained with (None: a policy.json from before it was kept)
    camera: CameraModel | None = None
    #: the world the policy was trained in, ``{"appearance": {factor: [low, high], ...},
    #: "robots": {"count": [lo, hi], ...}}`` (None: a policy.json from before it was kept)
    world: dict[str, dict[str, Any]] | None = field(default=None, repr=False)
    raw: Mapping[str, Any] = field(default_factory=dict, repr=False, compare=False)

    @property
    def vector_size(self) -> int:
        """Length of the vector input (0: the policy sees the image alone)."""
        return sum(
            vector_key_size(k, self.n_actions, self.action_history) for k in self.vector_keys
        )

    @property
    def n_actions(self) -> int:
        """Number of discrete head actions (rows of the action table)."""
        return int(self.action_table.shape[0])

    @property
    def output_size(self) -> int:
        """Length of the graph's action output: one score per action, or a 2-axis move."""
        return 2 if self.action_type == "continuous" else self.n_actions

    @property
    def input_shape(self) -> tuple[int, int, int]:
        """``(stack, height, width)`` of one network input."""
        return (self.stack, self.image_height, self.image_width)

    @classmethod
    def from_dict(
        cls, values: Mapping[str, Any], source: str = "policy metadata"
    ) -> PolicyMetadata:
        """Validate a decoded policy.json; :class:`PolicyFileError` names the bad key."""
        read = _MetadataReader(values, source)
        read.check_informational()
        table_deg = read.action_table_deg()
        return cls(
            image_height=read.size("image_height", MAX_IMAGE_SIDE),
            image_width=read.size("image_width", MAX_IMAGE_SIDE),
            stack=read.size("stack", MAX_STACK),
            action_table=np.radians(table_deg),
            head_limits=read.head_limits(),
            input_name=read.name("input_name"),
            output_name=read.name("output_name"),
            opset=read.opset(),
            package_version=read.optional_str("package_version"),
            model_file=read.model_file(),
            model_sha256=read.model_sha256(),
            training_config_sha256=read.training_config_sha256(),
            training_weights=read.training_weights(),
            training_weights_sha256=read.training_weights_sha256(),
            action_names=read.action_names(table_deg),
            observation=read.observation(),
            vector_keys=read.vector_keys(),
            action_history=read.count("action_history", MAX_ACTION_HISTORY),
            vector_input_name=read.vector_input_name(),
            act_by=read.act_by(),
            goal_output_name=read.optional_str("goal_output_name"),
            goal_views=read.goal_views(),
            goal_switch_margin=read.goal_switch_margin(),
            goal_frame=read.goal_frame(),
            action_type=read.action_type(),
            max_move=read.max_move(),
            step_deg=read.step_deg(table_deg),
            action_set=read.action_set(table_deg),
            camera=read.camera(),
            world=read.world(),
            raw=dict(values),
        )


class _MetadataReader:
    """Reads one policy.json key at a time; every problem is a PolicyFileError naming it."""

    def __init__(self, values: Any, source: str) -> None:
        self.source = source
        if not isinstance(values, Mapping):
            raise self.fail(f"expected a JSON object, got {type(values).__name__}")
        self.values = values
        if values.get("format") != METADATA_FORMAT:
            raise self.fail(f"'format' must be {METADATA_FORMAT!r}, got {values.get('format')!r}")
        version, reads = values.get("format_version"), METADATA_FORMAT_VERSION
        if version is not None and (isinstance(version, bool) or not isinstance(version, int)):
            # True == 1 and 1.0 == 1: read as format 1 though no export writes them
            raise self.fail(
                f"'format_version' must be an integer (this activevision reads {reads}), got"
                f" {version!r}"
            )
        if isinstance(version, int) and version > reads:
            raise self.fail(
                f"'format_version' {version} is newer than this activevision reads ({reads}):"
                " upgrade activevision where the policy runs (pip install -U"
                " 'activevision[runtime]'), or export the run with the version installed there"
            )
        if version != reads:
            raise self.fail(
                f"unsupported 'format_version' {version!r} (this activevision reads {reads})"
            )

    def fail(self, why: str) -> PolicyFileError:
        return PolicyFileError(f"{self.source}: {why}")

    def check_informational(self) -> None:
        """``input_dtype`` (required: every export writes it, and the runtime feeds uint8),
        and keys no reader acts on: of their type where present (a file that says something
        else of its model is not one export wrote)."""
        dtype = self.values.get("input_dtype")
        if dtype != "uint8":  # HeadController feeds the graph uint8 frames
            raise self.fail(f"'input_dtype' must be 'uint8' (the frames fed), got {dtype!r}")
        dueling = self.values.get("dueling", False)
        if not isinstance(dueling, bool):
            raise self.fail(f"'dueling' must be true or false, got {dueling!r}")
        self.optional_str("preprocessing")

    def name(self, key: str) -> str:
        """A graph input's or output's name: required (every export writes it; a default
        would name another tensor than the model's)."""
        value = self.values.get(key)
        if not isinstance(value, str) or not value:
            raise self.fail(f"{key!r} must name the model's tensor (a string), got {value!r}")
        return value

    def positive_int(self, key: str) -> int:
        value = self.values.get(key)
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise self.fail(f"{key!r} must be a positive integer, got {value!r}")
        return value

    def size(self, key: str, most: int) -> int:
        """A positive integer up to ``most``: a frame size or stack, which the controller
        allocates its buffers by (a training config's bound: larger was exported by none)."""
        value = self.positive_int(key)
        if value > most:
            raise self.fail(f"{key!r} must be at most {most}, got {value!r}")
        return value

    def act_by(self) -> str:
        value = self.values.get("act_by", "action")
        if value not in ("action", "goal"):
            raise self.fail(f"'act_by' must be 'action' or 'goal', got {value!r}")
        if value == "goal" and not isinstance(self.values.get("goal_output_name"), str):
            raise self.fail("'act_by' is 'goal' but no 'goal_output_name' is given")
        return str(value)

    def goal_switch_margin(self) -> float:
        value = self.values.get("goal_switch_margin", 0.0)
        if isinstance(value, bool) or not isinstance(value, int | float) or not 0 <= value < 1e6:
            raise self.fail(f"'goal_switch_margin' must be a number >= 0, got {value!r}")
        return float(value)

    def goal_frame(self) -> GoalFrame:
        value = self.values.get("goal_frame", "body")
        if value not in GOAL_FRAMES:
            raise self.fail(f"'goal_frame' must be one of {list(GOAL_FRAMES)}, got {value!r}")
        frame: GoalFrame = value
        return frame

    def action_type(self) -> str:
        value = self.values.get("action_type", "discrete")
        if value not in ("discrete", "continuous"):
            raise self.fail(f"'action_type' must be 'discrete' or 'continuous', got {value!r}")
        return str(value)

    def max_move(self) -> tuple[float, float] | None:
        """The continuous move's scale (pan, tilt) rad; required with continuous actions."""
        value = self.values.get("max_move_deg")
        if value is None:
            if self.values.get("action_type") == "continuous":
                raise self.fail("'action_type' is 'continuous' but 'max_move_deg' is missing")
            return None
        numbers = [_real(v) for v in value] if isinstance(value, list) else []
        if len(numbers) != 2 or not all(
            n is not None and 0 < n <= MAX_CONTINUOUS_MOVE_DEG for n in numbers
        ):
            raise self.fail(
                f"'max_move_deg' must be [pan, tilt] degrees in (0, {MAX_CONTINUOUS_MOVE_DEG:g}],"
                f" got {value!r}"
            )
        return (math.radians(float(value[0])), math.radians(float(value[1])))

    def goal_views(self) -> np.ndarray | None:
        """(V, 2) candidate views in radians, required with ``act_by == "goal"``."""
        views = self.values.get("goal_views_deg")
        if views is None:
            if self.values.get("act_by") == "goal":
                raise self.fail("'act_by' is 'goal' but 'goal_views_deg' is missing")
            return None
        try:
            array = np.asarray(views, dtype=np.float64)
        except (TypeError, ValueError):
            array = np.zeros((0, 0))
        if array.ndim != 2 or array.shape[1] != 2 or not len(array) or not np.isfinite(array).all():
            raise self.fail("'goal_views_deg' must be a non-empty list of [pan, tilt] degrees")
        return np.radians(array)

    def count(self, key: str, most: int) -> int:
        """A non-negative integer up to ``most``, 0 when absent."""
        value = self.values.get(key, 0)
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= most:
            raise self.fail(f"{key!r} must be an integer in 0..{most}, got {value!r}")
        return value

    def vector_keys(self) -> tuple[str, ...]:
        keys = self.values.get("vector_keys", [])
        order = list(VECTOR_KEY_SIZES)
        if (
            not isinstance(keys, list)
            or any(k not in VECTOR_KEY_SIZES for k in keys)
            or (keys != sorted(keys, key=order.index) or len(set(keys)) != len(keys))
        ):
            raise self.fail(f"'vector_keys' must list some of {order}, in that order, got {keys!r}")
        return tuple(keys)

    def observation(self) -> str:
        """What the policy observes, a key of :data:`OBSERVATION_VECTOR_KEYS`; its vector
        inputs must be ``vector_keys`` (with ``"actions"`` where ``action_history`` > 0: an
        env builds that layout from the observation, the controller from the keys). Files
        from before vector inputs lack it (and ``vector_keys``): "image"."""
        keys = self.vector_keys()
        value = self.values.get("observation")
        if value is None:
            if keys:
                raise self.fail(f"'vector_keys' lists {list(keys)!r} but 'observation' is missing")
            return "image"
        if not isinstance(value, str) or value not in OBSERVATION_VECTOR_KEYS:
            raise self.fail(
                f"'observation' must be one of {list(OBSERVATION_VECTOR_KEYS)}, got {value!r}"
            )
        history = self.count("action_history", MAX_ACTION_HISTORY)
        if value == "image" and history:
            raise self.fail(f"'action_history' is {history} but 'observation' 'image' takes none")
        want = observation_vector_keys(value, history)
        if keys != want:
            raise self.fail(
                f"'vector_keys' {list(keys)} are not the inputs of 'observation' {value!r} with"
                f" 'action_history' {history}: {list(want)}"
            )
        return value

    def vector_input_name(self) -> str | None:
        """The graph's vector input: required where ``vector_keys`` lists inputs."""
        if not self.values.get("vector_keys"):
            return self.optional_str("vector_input_name")
        return self.name("vector_input_name")

    def training_config_sha256(self) -> str | None:
        return self.optional_sha256("training_config_sha256")

    def optional_sha256(self, key: str) -> str | None:
        digest = self.values.get(key)
        if digest is not None and not (isinstance(digest, str) and _is_sha256(digest)):
            raise self.fail(f"{key!r} must be a SHA-256 (64 hex digits) or null, got {digest!r}")
        return digest

    def training_weights(self) -> str | None:
        """Which of the run's weights were exported: "final" or "best", where recorded
        (with ``training_weights_sha256``: export writes both, or neither)."""
        value = self.values.get("training_weights")
        if value is not None and value not in ("final", "best"):
            raise self.fail(f"'training_weights' must be 'final', 'best' or null, got {value!r}")
        if ("training_weights" in self.values) != ("training_weights_sha256" in self.values):
            raise self.fail(
                "'training_weights' and 'training_weights_sha256' come together (export writes"
                " both)"
            )
        return value

    def training_weights_sha256(self) -> str | None:
        digest = self.optional_sha256("training_weights_sha256")
        if digest is not None and self.values.get("training_weights") is None:
            raise self.fail("'training_weights_sha256' is given but 'training_weights' is null")
        return digest

    def step_deg(self, table_deg: np.ndarray) -> float | None:
        """The discrete step (degrees); None when absent (``export_onnx`` alone writes
        neither it nor ``action_set``). With ``action_set``, the table must be its moves."""
        value = self.values.get("step_deg")
        if value is None:
            if "action_set" in self.values:
                raise self.fail("'action_set' is given but 'step_deg' is missing")
            return None
        step = _real(value)
        if step is None or not 0 < step <= MAX_MOVE_DEG:
            raise self.fail(
                f"'step_deg' must be a number of degrees in (0, {MAX_MOVE_DEG:g}], got {value!r}"
            )
        action_set = self.action_set(table_deg)
        if action_set is None:
            raise self.fail("'step_deg' is given but 'action_set' is missing")
        want = _action_table_deg(step, action_set)
        if want.shape != table_deg.shape or not np.allclose(table_deg, want, atol=1e-6):
            raise self.fail(
                f"'action_table_deg' is not the {action_set} moves of 'step_deg' {step:g} degrees"
            )
        return step

    def action_set(self, table_deg: np.ndarray) -> str | None:
        value = self.values.get("action_set")
        if value is not None and value not in _ACTION_SET_SIZES:
            raise self.fail(f"'action_set' must be one of {list(_ACTION_SET_SIZES)}, got {value!r}")
        return value

    def optional_str(self, key: str) -> str | None:
        value = self.values.get(key)
        if value is not None and not isinstance(value, str):
            raise self.fail(f"{key!r} must be a string, got {value!r}")
        return value

    def model_file(self) -> str | None:
        """The model's file name, where present: a bare name, as export writes it (the model
        sits beside its policy.json), never a path out of the policy's folder, absolute or
        into a subfolder."""
        value = self.optional_str("model_file")
        if value is not None and (
            value in ("", ".", "..") or any(c in value for c in ("/", "\\", "\0"))
        ):
            raise self.fail(
                "'model_file' must be the model's file name, beside policy.json (no folder,"
                f" no path), got {value!r}"
            )
        return value

    def opset(self) -> int:
        """The ONNX opset the model was written with: every export records it."""
        opset = self.values.get("opset")
        if isinstance(opset, bool) or not isinstance(opset, int) or opset < 1:
            raise self.fail(f"'opset' must be a positive integer, got {opset!r}")
        return opset

    def action_table_deg(self) -> np.ndarray:
        try:
            table = np.asarray(self.values.get("action_table_deg"), dtype=np.float64)
        except (TypeError, ValueError) as error:
            raise self.fail(f"'action_table_deg' is not a numeric table: {error}") from error
        if table.ndim != 2 or table.shape[1] != 2 or table.shape[0] < 1:
            raise self.fail(
                f"'action_table_deg' must be a list of [d_pan, d_tilt] pairs, got shape "
                f"{table.shape}"
            )
        if not np.all(np.isfinite(table)):
            raise self.fail("'action_table_deg' holds non-finite values")
        if np.abs(table).max() > MAX_MOVE_DEG:
            raise self.fail(f"'action_table_deg' moves more than {MAX_MOVE_DEG} degrees per action")
        n_actions = self.values.get("n_actions")
        if isinstance(n_actions, bool) or not isinstance(n_actions, int):
            raise self.fail(f"'n_actions' must be an integer, got {n_actions!r}")
        if n_actions != table.shape[0]:
            raise self.fail(
                f"'n_actions' is {n_actions!r} but 'action_table_deg' has {table.shape[0]} rows"
            )
        return table

    def camera(self) -> CameraModel | None:
        """The trained camera, None when the file predates the record."""
        record = self.values.get("camera")
        if record is None:
            return None
        if not isinstance(record, Mapping) or not set(_CAMERA_KEYS) <= set(record):
            raise self.fail(f"'camera' must be an object with keys {list(_CAMERA_KEYS)}")
        values: dict[str, Any] = {}
        for key, name in _CAMERA_KEYS.items():
            value = record[key]
            big = isinstance(value, int) and not isinstance(value, bool) and value > MAX_IMAGE_SIDE
            if key.endswith("_px") and big:  # as a config's camera (an export's is no larger)
                raise self.fail(
                    f"'camera' {key} must be at most {MAX_IMAGE_SIDE} px, got {value!r}"
                )
            if key.endswith("_deg"):
                degrees = _real(value)
                if degrees is None:
                    raise self.fail(f"'camera' {key} must be a number, got {value!r}")
                if key == "hfov_deg" and 0 < degrees < MIN_HFOV_DEG:  # as from_degrees
                    raise self.fail(
                        f"'camera' hfov_deg must be degrees, at least {MIN_HFOV_DEG:g}; got"
                        f" {degrees:g} (radians?)"
                    )
                value = math.radians(degrees)
            values[name] = value
        try:
            camera = CameraModel(**values)
        except ValueError as error:
            raise self.fail(f"'camera' is invalid: {error}") from error
        return self.camera_matches_head_limits(self.camera_fits_input(camera))

    def camera_matches_head_limits(self, camera: CameraModel) -> CameraModel:
        """``camera``, or PolicyFileError: its pan and tilt range is not ``head_limits_deg``
        (export writes the trained camera's range to both; a file where they differ clips
        the robot's head to limits the policy was not trained with, or was edited by hand)."""
        limits = self.head_limits()
        for key in _HEAD_LIMIT_KEYS:
            recorded, limit = math.degrees(getattr(camera, key)), math.degrees(getattr(limits, key))
            if abs(recorded - limit) > _LIMIT_AGREEMENT_DEG:
                raise self.fail(
                    f"'camera' {key}_deg = {recorded:.6g} but 'head_limits_deg' {key} ="
                    f" {limit:.6g} degrees: export writes the trained camera's range to both,"
                    " so the two must agree"
                )
        return camera

    def camera_fits_input(self, camera: CameraModel) -> CameraModel:
        """``camera``, or PolicyFileError: its aspect ratio is not the policy input's (the
        network sees the trained camera's image, so the two are the same shape)."""
        width = self.size("image_width", MAX_IMAGE_SIDE)
        height = self.size("image_height", MAX_IMAGE_SIDE)
        if abs(camera.aspect / (width / height) - 1) > CAMERA_TOLERANCES["aspect"]:
            raise self.fail(
                f"'camera' is {camera.width}x{camera.height} px (aspect {camera.aspect:.3f}) but"
                f" the policy's input is {width}x{height} px (aspect {width / height:.3f}):"
                " the record cannot be the camera the policy was trained with"
            )
        return camera

    def world(self) -> dict[str, dict[str, Any]] | None:
        """The training world (an object of objects of numbers and ``[low, high]`` pairs),
        a copy; None when the file predates the record."""
        record = self.values.get("world")
        if record is None:
            return None
        shape = "an object of objects ({'appearance': {...}, 'robots': {...}})"
        if not isinstance(record, Mapping):
            raise self.fail(f"'world' must be {shape}, got {record!r}")
        world: dict[str, dict[str, Any]] = {}
        for name, group in record.items():
            if not isinstance(name, str) or not isinstance(group, Mapping):
                raise self.fail(f"'world' must be {shape}; {name!r} is {group!r}")
            world[name] = {}
            for key, value in group.items():
                items = value if isinstance(value, list) else [value]
                numbers = [_real(v) for v in items]
                if (
                    not isinstance(key, str)
                    or len(items) != (2 if isinstance(value, list) else 1)
                    or any(n is None or not math.isfinite(n) for n in numbers)
                ):
                    raise self.fail(
                        f"'world' {name}.{key} must be a finite number or a [low, high] pair of"
                        f" them, got {value!r}"
                    )
                world[name][key] = list(value) if isinstance(value, list) else value
        return world

    def head_limits(self) -> HeadLimits:
        limits_deg = self.values.get("head_limits_deg")
        if not isinstance(limits_deg, Mapping) or not set(_HEAD_LIMIT_KEYS) <= set(limits_deg):
            raise self.fail(
                f"'head_limits_deg' must be an object with keys {list(_HEAD_LIMIT_KEYS)}"
            )
        degrees: dict[str, float] = {}
        for key, bound in _HEAD_LIMIT_BOUNDS_DEG.items():
            value = _real(limits_deg[key])
            if value is None:  # float() took "90" and true (1 degree)
                raise self.fail(
                    f"'head_limits_deg' {key} must be a number of degrees, got {limits_deg[key]!r}"
                )
            if not (math.isfinite(value) and -bound <= value <= bound):
                raise self.fail(f"'head_limits_deg' {key} = {value} lies outside +-{bound} degrees")
            degrees[key] = value
        limits = HeadLimits(*(math.radians(degrees[k]) for k in _HEAD_LIMIT_KEYS))
        if not (limits.pan_min <= limits.pan_max and limits.tilt_min <= limits.tilt_max):
            raise self.fail(f"'head_limits_deg' are not ordered (min <= max): {dict(limits_deg)}")
        return limits

    def action_names(self, table_deg: np.ndarray) -> tuple[str, ...]:
        names = self.values.get("action_names")
        if (
            not isinstance(names, list)
            or len(names) != table_deg.shape[0]
            or not all(isinstance(n, str) and n for n in names)
        ):
            raise self.fail("'action_names' must list one name per action, each a string")
        for name, row in zip(names, table_deg, strict=True):
            if name in _ACTION_SIGNS and tuple(np.sign(row)) != _ACTION_SIGNS[name]:
                raise self.fail(f"action {name!r} moves the head by {row.tolist()} degrees")
        return tuple(str(n) for n in names)

    def model_sha256(self) -> str:
        digest = self.values.get("model_sha256")
        if not (isinstance(digest, str) and _is_sha256(digest)):
            raise self.fail(
                f"'model_sha256' must be the model's SHA-256 (64 hex digits), got"
                f" {digest!r}: without it a model from another export would be accepted"
            )
        return digest


def _unique_pairs(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """``json``'s object_pairs_hook refusing a key named twice (``json.loads`` keeps the
    last value without a word: an edited policy.json's second ``"step_deg"``). The runtime
    imports nothing else of activevision, so this is ``activevision.io``'s hook again."""
    values: dict[str, Any] = {}
    for key, value in pairs:
        if key in values:
            raise PolicyFileError(f"duplicate key {key!r} (each key may appear once)")
        values[key] = value
    return values


def load_metadata(path: str | os.PathLike[str]) -> PolicyMetadata:
    """Read and validate a policy.json; :class:`PolicyFileError` if missing or invalid."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError as error:
        raise PolicyFileError(
            f"policy metadata {path} not found (export writes it beside the .onnx model)"
        ) from error
    except (OSError, UnicodeDecodeError) as error:
        raise PolicyFileError(f"cannot read policy metadata {path}: {error}") from error
    try:
        values = json.loads(text, object_pairs_hook=_unique_pairs)
    except PolicyFileError as error:
        raise PolicyFileError(f"policy metadata {path}: {error}") from None
    except (ValueError, RecursionError) as error:
        # ValueError: JSONDecodeError, or an integer of more digits than Python converts;
        # RecursionError: arrays or objects nested too deep for the decoder
        raise PolicyFileError(f"policy metadata {path} is not valid JSON: {error}") from error
    return PolicyMetadata.from_dict(values, source=str(path))
