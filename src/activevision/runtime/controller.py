"""Real-time head control on a robot: camera frame + head angles in, head command out.

Needs only NumPy and onnxruntime (``pip install activevision[runtime]``); nothing here
imports torch or gymnasium.
"""

from __future__ import annotations

import hashlib
import math
import numbers
import os
import sys
import warnings
from collections.abc import Mapping
from pathlib import Path
from types import FrameType
from typing import Any, NamedTuple

import numpy as np

from activevision.runtime.decision import (
    OneHeadGoal,
    clipped_move,
    continuous_move,
    greedy_action,
)
from activevision.runtime.goal_evidence import GoalEvidence, goal_output_count
from activevision.runtime.metadata import (
    CAMERA_TOLERANCES,
    VECTOR_BOUND,
    CameraModel,
    HeadLimits,
    PolicyFileError,
    PolicyMetadata,
    load_metadata,
    metadata_path_for,
)
from activevision.runtime.preprocess import ColorOrder, FramePreprocessor, luma_weights


class CameraMismatchWarning(UserWarning):
    """The robot's camera (``HeadController(..., camera=...)``) differs from the one the
    policy was trained for: the policy may not transfer."""


class HeadAngleWarning(UserWarning):
    """A head angle (or a proposal) given to :meth:`HeadController.act` lies well outside the
    head limits the policy was trained within (:data:`HEAD_LIMIT_MARGIN` beyond): most often
    a sign convention that is not the policy's (tilt positive up). Once per controller."""


#: How far beyond the policy's head limits (rad) a head angle given to ``act`` may lie
#: before a :class:`HeadAngleWarning`: a head resting level below a 5-degree tilt limit, or a
#: joint overshooting its limit, is no sign of a wrong convention.
HEAD_LIMIT_MARGIN = math.radians(5.0)


class HeadCommand(NamedTuple):
    """One decision of the policy. Angles in radians; pan positive left, tilt positive down."""

    #: index of the chosen discrete action (row of the action table); -1 for a continuous
    #: policy, whose move is ``(d_pan, d_tilt)``
    action: int
    d_pan: float  #: the action's pan step
    d_tilt: float  #: the action's tilt step
    #: current pan + d_pan, clipped to the policy's head limits (and to the robot's, given
    #: ``HeadController(..., camera=...)``)
    target_pan: float
    target_tilt: float  #: current tilt + d_tilt, clipped the same way


def robot_session_options(num_threads: int = 1) -> Any:  # onnxruntime.SessionOptions (untyped)
    """onnxruntime settings for a small robot CPU that also runs vision, walking and so on.

    * ``intra_op_num_threads = num_threads`` (default 1) and ``inter_op_num_threads = 1``: a
      1.8 M-parameter CNN is too small to gain from splitting across cores, and one thread
      leaves the other cores to the rest of the robot.
    * ``session.intra_op.allow_spinning = "0"``: idle worker threads sleep instead of
      busy-waiting for the next request (spinning burns a core between decisions).
    * ``execution_mode = ORT_SEQUENTIAL``: the graph is a chain; parallel branches buy nothing.
    * ``graph_optimization_level = ORT_ENABLE_ALL``: constant folding, Conv+ReLU fusion and
      the CPU-specific layout optimisations.
    """
    import onnxruntime as ort

    threads = _thread_count(num_threads)
    options = ort.SessionOptions()
    options.intra_op_num_threads = threads
    options.inter_op_num_threads = 1
    options.add_session_config_entry("session.intra_op.allow_spinning", "0")
    options.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    options.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    return options


#: The most onnxruntime threads a controller may ask for: more than any CPU has cores (as
#: training's ``MAX_THREADS``). 100,000 hung the constructor starting threads, and 2**40 was
#: a PolicyFileError calling the model invalid.
MAX_THREADS = 1024


def _thread_count(num_threads: object) -> int:
    """``num_threads`` as an int in ``1..MAX_THREADS`` (NumPy integers too); a bool, a float,
    a string or a number out of range is a ValueError naming it. (Not the envs' own
    ``check_count``: the robot runtime imports nothing else of activevision.)"""
    if (
        isinstance(num_threads, bool | np.bool_)
        or not isinstance(num_threads, numbers.Integral)
        or not 1 <= int(num_threads) <= MAX_THREADS
    ):
        raise ValueError(
            f"num_threads must be a positive integer up to {MAX_THREADS}, got {num_threads!r}"
        )
    return int(num_threads)


#: the inputs of :meth:`HeadController.act` a policy may need, besides frame and head angles
_OPTIONAL_INPUTS = ("pose", "pose_error", "proposal", "belief", "ball")


class HeadController:
    """Greedy head control with an exported Q-network (``policy.onnx`` + ``policy.json``).

    Each :meth:`act` converts the camera frame to grey (ITU-R BT.601), resizes it to the
    policy's input size by area averaging (:mod:`activevision.runtime.preprocess`), pushes it
    onto the frame stack, runs the network and returns the head move with the highest
    Q-value, plus the resulting joint targets clipped to the head limits. A continuous policy
    (policy.json's ``action_type``) outputs the move itself, a fraction of ``max_move`` on
    each axis.

    Args:
        model_path: the exported ``policy.onnx`` (or the folder holding it); its metadata
            is read from the ``.json`` file of the same name beside it.
        num_threads: onnxruntime intra-op threads, 1 to :data:`MAX_THREADS` (1 suits a
            small robot CPU; see :func:`robot_session_options` for all session settings).
        color_order: channel order of 3-channel frames, ``"rgb"`` or ``"bgr"`` (OpenCV).
        verify_checksum: check the model file against the SHA-256 in the metadata, so a
            model and a metadata file from different exports are caught at load time.
        camera: the robot's camera, a :class:`~activevision.runtime.CameraModel` (or an
            ``activevision.geometry.CameraConfig``). If its field of view, height, pan or tilt
            range, or aspect ratio differs from the camera the policy was trained for
            (:attr:`trained_camera`) beyond :data:`~activevision.runtime.metadata.
            CAMERA_TOLERANCES`, one :class:`CameraMismatchWarning` names each difference
            and how to retrain. Resolution alone does not matter: frames are resized. No
            check when the policy.json predates the camera record (``trained_camera`` None).
            Every command's targets stay within its pan and tilt limits too.
            With or without ``camera``, the frames' aspect ratio is checked against the
            policy input's, whenever their size changes, until the first that differs (one
            CameraMismatchWarning: frames would be stretched).

    Raises:
        PolicyFileError: (a ValueError) the model or metadata is missing, unreadable,
            corrupt or the two do not match.
        ImportError: onnxruntime is not installed.

    Not thread-safe: use one controller per thread (each holds its own frame stack).
    """

    def __init__(
        self,
        model_path: str | os.PathLike[str],
        num_threads: int = 1,
        color_order: ColorOrder = "rgb",
        verify_checksum: bool = True,
        camera: CameraModel | Any | None = None,
    ) -> None:
        luma_weights(color_order)  # validates color_order
        self.robot_camera = None if camera is None else CameraModel.of(camera)
        num_threads = _thread_count(num_threads)
        self.color_order: ColorOrder = color_order
        if not isinstance(model_path, str | os.PathLike):
            # Path(None) is "expected str, bytes or os.PathLike object, not NoneType"
            raise PolicyFileError(
                "model_path: expects the path of a policy.onnx or of a run or export folder,"
                f" got {model_path!r}"
            )
        self.model_path = Path(model_path)
        if self.model_path.is_dir():  # a run or export folder: its policy.onnx
            self.model_path = self.model_path / "policy.onnx"
        self.metadata_path = metadata_path_for(self.model_path)
        if self.model_path == self.metadata_path:  # policy.json given for policy.onnx
            raise PolicyFileError(
                f"{self.model_path} is the policy's metadata; pass the ONNX model beside it,"
                f" {self.model_path.with_suffix('.onnx')}"
            )
        if not self.model_path.is_file():
            raise PolicyFileError(
                f"policy model {self.model_path} not found"
                + (
                    " (export the run first: activevision export RUN_DIR)"
                    if Path(model_path).is_dir()
                    else ""
                )
            )
        if self.model_path.suffix.lower() != ".onnx":
            # export writes only .onnx models: a CSV or PNG passed here was "policy metadata
            # f.json not found", naming a file the user never meant
            raise PolicyFileError(
                f"{self.model_path} is not a policy file: pass an exported .onnx model (with"
                " its .json beside it) or the run or export folder that holds policy.onnx"
            )
        self.metadata: PolicyMetadata = load_metadata(self.metadata_path)
        model_bytes = _read_model(self.model_path)
        if verify_checksum:
            digest = hashlib.sha256(model_bytes).hexdigest()
            if digest != self.metadata.model_sha256:
                raise PolicyFileError(
                    f"policy model {self.model_path} does not match its metadata "
                    f"{self.metadata_path} (SHA-256 {digest[:12]}... != "
                    f"{self.metadata.model_sha256[:12]}...): the files come from different "
                    "exports or the model is corrupt"
                )
        self._session = _open_session(self.model_path, model_bytes, num_threads)
        self._check_signature()
        self._check_camera()

        meta = self.metadata
        self._preprocess = FramePreprocessor(meta.image_height, meta.image_width)
        self._frames = np.zeros((1, *meta.input_shape), dtype=np.uint8)
        self._stack_empty = True
        self._feed: dict[str, np.ndarray] = {meta.input_name: self._frames}
        self._vector = np.zeros((1, meta.vector_size), dtype=np.float32)
        if meta.vector_size:
            assert meta.vector_input_name is not None  # _check_signature
            self._feed[meta.vector_input_name] = self._vector
        self._history = np.full(meta.action_history, -1, dtype=np.int64)
        self._outputs = [meta.output_name]
        self._evidence: GoalEvidence | None = None
        self._goal: OneHeadGoal | None = None
        if meta.act_by == "goal":
            assert meta.goal_output_name is not None and meta.goal_views is not None
            self._outputs.append(meta.goal_output_name)
            self._evidence = GoalEvidence(
                1, meta.goal_views, meta.action_table, meta.goal_switch_margin, meta.goal_frame
            )
            self._goal = OneHeadGoal(self._evidence)
        self._table = [(float(dp), float(dt)) for dp, dt in meta.action_table]
        # policy.json's reader requires max_move_deg with continuous actions
        continuous = meta.action_type == "continuous"
        self._max_move = np.asarray(meta.max_move) if continuous else None
        self._reach: tuple[float, float] | None = None
        if self._max_move is not None:
            self._reach = (float(self._max_move[0]), float(self._max_move[1]))
        # the inputs act takes (pose, ...) and, for each, whether this policy needs it
        self._needs = {name: name in meta.vector_keys for name in _OPTIONAL_INPUTS}
        self.last_q_values: np.ndarray | None = None
        self.last_goal_logits: np.ndarray | None = None
        # the frame size last checked against the policy's aspect ratio, None once warned
        self._frame_size: tuple[int, int] | None = (0, 0)
        self._angles_warned = False  # a HeadAngleWarning was given
        limits = meta.head_limits
        # the head angles beyond which a HeadAngleWarning is given (_check_head_angles)
        self._angle_bounds = (
            limits.pan_min - HEAD_LIMIT_MARGIN,
            limits.pan_max + HEAD_LIMIT_MARGIN,
            limits.tilt_min - HEAD_LIMIT_MARGIN,
            limits.tilt_max + HEAD_LIMIT_MARGIN,
        )
        robot = self.robot_camera
        # the robot's neck limits (camera=), which bound the targets beside the policy's
        self._robot_limits = (
            None
            if robot is None
            else HeadLimits(robot.pan_min, robot.pan_max, robot.tilt_min, robot.tilt_max)
        )

    @property
    def trained_camera(self) -> CameraModel | None:
        """The camera the policy was trained with (policy.json's ``camera``), or None for a
        policy exported before the record existed."""
        return self.metadata.camera

    @property
    def inputs(self) -> tuple[str, ...]:
        """What :meth:`act` needs besides the frame and head angles: some of ``"pose"``,
        ``"pose_error"`` and ``"proposal"`` (episodic policies; none for the paper's
        image-only one), or ``"pose"``, ``"belief"`` and ``"ball"`` (a match student)."""
        keys = ("pose", "belief", "ball", "pose_error", "proposal")
        return tuple(k for k in self.metadata.vector_keys if k in keys)

    # ------------------------------------------------------------------ public API
    @property
    def n_actions(self) -> int:
        """Number of discrete head actions (of the action table; a continuous policy
        outputs a move instead)."""
        return self.metadata.n_actions

    @property
    def continuous(self) -> bool:
        """Whether the policy outputs a continuous move rather than an action index."""
        return self._max_move is not None

    def reset(self) -> None:
        """Forget the frame stack and the remembered actions (call when the head was moved by
        something else, or at the start of a new search). The next frame fills every slot of
        the stack."""
        self._stack_empty = True
        self._history[:] = -1
        if self._evidence is not None:
            self._evidence.reset()

    def observe(self, frame: np.ndarray, color_order: ColorOrder | None = None) -> np.ndarray:
        """Preprocess ``frame`` and push it onto the frame stack; returns the (stack, H, W)
        uint8 network input (a view, valid until the next call)."""
        frames: np.ndarray = self._frames[0]
        order = self.color_order if color_order is None else color_order
        if self._stack_empty or frames.shape[0] == 1:
            self._preprocess(frame, order, out=frames[-1])  # validates before writing
            frames[:-1] = frames[-1]
            self._stack_empty = False
        else:
            newest = self._preprocess(frame, order)  # validate before shifting the stack
            frames[:-1] = frames[1:]
            frames[-1] = newest
        height, width = frame.shape[0], frame.shape[1]
        if self._frame_size is not None and (height, width) != self._frame_size:
            self._frame_size = (height, width)  # a new size (a camera's is fixed): check it
            self._check_frame_aspect(width, height)
        return frames

    def q_values(self, frame: np.ndarray, color_order: ColorOrder | None = None) -> np.ndarray:
        """Push ``frame`` onto the stack and return the policy's Q-values (a DAgger policy's
        action logits; a continuous policy's move in [-1, 1]), shape (A,) or (2,), with the
        vector input of the last :meth:`act`."""
        self.observe(frame, color_order)
        outputs = self._session.run(self._outputs, self._feed)
        q: np.ndarray = outputs[0][0]
        self.last_q_values = q
        self.last_goal_logits = outputs[1][0] if len(outputs) > 1 else None
        return q

    def act(
        self,
        frame: np.ndarray,
        pan: float,
        tilt: float,
        pose: tuple[float, float, float] | None = None,
        proposal: tuple[float, float] | None = None,
        color_order: ColorOrder | None = None,
        pose_error: float | None = None,
        belief: tuple[float, float, float] | None = None,
        ball: tuple[float, float, float] | None = None,
    ) -> HeadCommand:
        """The greedy head command for a camera ``frame`` taken at head angles ``(pan, tilt)``.

        Args:
            frame: camera image, uint8, (H, W) or (H, W, 1) grey or (H, W, 3) colour, any size.
            pan, tilt: current head joint angles, radians (pan positive left, tilt positive
                down).
            pose: the robot's believed pose ``(x m, y m, theta rad)`` on the field, for a
                policy whose :attr:`inputs` include ``"pose"``.
            pose_error: with ``pose``: how far off the belief may be (m and rad; e.g. the
                filter's position standard deviation). Policies trained across errors learn
                from it when to trust the pose.
            proposal: ``(pan, tilt)`` rad of the view the entropy method proposes from that
                pose (``activevision.localisation.best_viewpoint``), or ``(nan, nan)`` when
                no view shows the ball; for a policy whose :attr:`inputs` include it.
            color_order: overrides the controller's ``color_order`` for this frame.
            belief: the belief's standard deviations ``(x m, y m, theta rad)``, for a match
                student (whose :attr:`inputs` include ``"belief"``; with ``pose``).
            ball: the robot's ball model ``(x m, y m, seconds since seen)``, x forward and
                y left of the robot, for a match student.

        Raises:
            ValueError: an input the policy needs is missing, or one it does not take is given.

        Warns:
            HeadAngleWarning: once, for a head angle or a proposal more than
                :data:`HEAD_LIMIT_MARGIN` outside the policy's head limits (a convention that
                is not the policy's).
        """
        pan, tilt = _finite_angle("pan", pan), _finite_angle("tilt", tilt)
        if not self._angles_warned:
            self._check_head_angles(pan, tilt)
        self._fill_vector(pan, tilt, pose, proposal, pose_error, belief, ball)
        scores = self.q_values(frame, color_order)
        # the argmax action or the continuous move; with goal evidence, the move towards
        # the goal view with the most evidence so far: policy_actions' numbers for one head
        # (activevision.runtime.decision)
        goal = None
        if self._goal is not None:
            assert self.last_goal_logits is not None  # an output of every goal policy
            goal = self._goal.target(self.last_goal_logits, pan, tilt)
        if self._reach is not None:
            action = -1
            if goal is None:
                move = clipped_move(scores)
            else:
                move = continuous_move(pan, tilt, goal, self._reach)
            d_pan, d_tilt = move[0] * self._reach[0], move[1] * self._reach[1]
        else:
            if goal is None:
                action = int(np.argmax(scores))
            else:
                assert self._evidence is not None
                action = greedy_action(pan, tilt, goal, self._evidence.table)
            if len(self._history):
                self._history[:-1] = self._history[1:]
                self._history[-1] = action
            d_pan, d_tilt = self._table[action]
        target_pan, target_tilt = self.metadata.head_limits.clip(pan + d_pan, tilt + d_tilt)
        if self._robot_limits is not None:  # and where the robot's neck reaches
            target_pan, target_tilt = self._robot_limits.clip(target_pan, target_tilt)
        return HeadCommand(action, d_pan, d_tilt, target_pan, target_tilt)

    def _fill_vector(
        self,
        pan: float,
        tilt: float,
        pose: tuple[float, float, float] | None,
        proposal: tuple[float, float] | None,
        pose_error: float | None,
        belief: tuple[float, float, float] | None = None,
        ball: tuple[float, float, float] | None = None,
    ) -> None:
        """The vector input, laid out as ``activevision.envs.observations`` (and
        ``envs.match.observations``) build it."""
        self._check_given(
            pose=pose, pose_error=pose_error, proposal=proposal, belief=belief, ball=ball
        )
        # Python floats, not small arrays: the same numbers (each is copied or comes from
        # one IEEE operation) at a fraction of the time
        values: list[float] = []
        for key in self.metadata.vector_keys:
            if key == "head":
                values += (pan, tilt)
            elif key == "pose":
                x, y, theta = _on_the_field("pose", _finite_numbers("pose", pose, 3))
                values += (x, y, math.cos(theta), math.sin(theta))
            elif key == "pose_error":
                values += _non_negative("pose_error", _finite_numbers(key, pose_error, 1))
            elif key in ("belief", "ball"):
                # the match env's bound on its vectors (stds, ball age in seconds)
                known = _finite_numbers(key, belief if key == "belief" else ball, 3)
                if key == "belief":
                    _non_negative("belief", known)
                else:
                    _on_the_field("ball", known)
                values += known
            elif key == "proposal":
                values += self._proposal(proposal, pan, tilt)
            else:
                values += self._onehot_history()
        if values:
            # the envs' observation bound on every entry (envs.observations and
            # envs.match.observations clip theirs the same way), as np.clip
            self._vector[0] = [min(max(v, -VECTOR_BOUND), VECTOR_BOUND) for v in values]

    # ------------------------------------------------------------------ internals
    def _check_given(self, **given: object) -> None:
        """ValueError for an input (``pose=...``) the policy needs and was not given, or
        was given and does not take (in the order of act's arguments)."""
        for name, value in given.items():
            if self._needs[name] and value is None:
                raise ValueError(
                    f"this policy ({self.metadata.observation!r}) needs {name}=...; see"
                    " HeadController.act"
                )
            if not self._needs[name] and value is not None:
                keys = self.metadata.vector_keys
                raise ValueError(
                    f"this policy ({self.metadata.observation!r}) takes no {name}; it was"
                    f" trained on {', '.join(('image', *keys))}"
                )

    def _onehot_history(self) -> list[float]:
        """The remembered actions, one-hot, oldest first (none yet: all 0)."""
        onehot = [0.0] * (len(self._history) * self.n_actions)
        for slot, action in enumerate(self._history.tolist()):
            if action >= 0:
                onehot[slot * self.n_actions + action] = 1.0
        return onehot

    def _proposal(self, proposal: Any, pan: float, tilt: float) -> tuple[float, ...]:
        """The proposal's part of the vector; one found well outside the head limits warns
        (once, as the head angles do)."""
        vector = _proposal_vector(proposal, pan, tilt)
        if vector[4] and not self._angles_warned:
            self._check_head_angles(vector[0], vector[1], "proposal")
        return vector

    def _check_camera(self) -> None:
        """One CameraMismatchWarning when the robot's camera is not the trained one."""
        trained, robot = self.trained_camera, self.robot_camera
        if trained is None or robot is None:
            return
        differences = trained.differences(robot)
        if differences:
            warnings.warn(
                camera_mismatch_message(
                    self.model_path, robot, differences, self.metadata.image_width
                ),
                CameraMismatchWarning,
                stacklevel=3,  # the caller of HeadController(...)
            )

    def _check_frame_aspect(self, width: int, height: int) -> None:
        """One CameraMismatchWarning when the frames' aspect ratio is not the policy
        input's: resizing stretches them. Not again after it."""
        meta = self.metadata
        trained = meta.image_width / meta.image_height
        if abs((width / height) / trained - 1) > CAMERA_TOLERANCES["aspect"]:
            self._frame_size = None
            warnings.warn(
                f"frames of {width}x{height} px (aspect {width / height:.3f}) are stretched to"
                f" the policy's {meta.image_width}x{meta.image_height} input (aspect"
                f" {trained:.3f}): the policy may not transfer. Crop the frames to that aspect"
                " ratio, or train for the robot's camera (docs/robot.md)",
                CameraMismatchWarning,
                stacklevel=_caller_level(),  # the caller of act, q_values or observe
            )

    def _check_head_angles(self, pan: float, tilt: float, what: str = "head angle") -> None:
        """One HeadAngleWarning for a head angle (or the proposal's, ``what``) more than
        HEAD_LIMIT_MARGIN outside the policy's head limits (the first such; none after it)."""
        low_pan, high_pan, low_tilt, high_tilt = self._angle_bounds
        if low_pan <= pan <= high_pan and low_tilt <= tilt <= high_tilt:  # the usual case
            return
        limits = self.metadata.head_limits
        for name, angle in (("pan", pan), ("tilt", tilt)):
            low, high = getattr(limits, f"{name}_min"), getattr(limits, f"{name}_max")
            if low - HEAD_LIMIT_MARGIN <= angle <= high + HEAD_LIMIT_MARGIN:
                continue
            self._angles_warned = True
            warnings.warn(
                f"{what} {name} {math.degrees(angle):.1f} deg lies outside the {name}"
                f" limits the policy was trained within, {math.degrees(low):.3g} to"
                f" {math.degrees(high):.3g} deg: check the convention act expects (radians,"
                " pan positive left, tilt positive down from horizontal) and the neck's"
                " zero. The command is clipped into the limits; this is said once",
                HeadAngleWarning,
                stacklevel=_caller_level(),  # the caller of act
            )
            return

    def _check_signature(self) -> None:
        """The ONNX graph's input and output must agree with the metadata."""
        meta = self.metadata
        inputs = {i.name: i for i in self._session.get_inputs()}
        outputs = {o.name: o for o in self._session.get_outputs()}

        def mismatch(why: str) -> PolicyFileError:
            return PolicyFileError(
                f"policy model {self.model_path} does not match its metadata "
                f"{self.metadata_path}: {why}"
            )

        if meta.input_name not in inputs:
            raise mismatch(f"no input {meta.input_name!r} (model inputs: {list(inputs)})")
        if meta.output_name not in outputs:
            raise mismatch(f"no output {meta.output_name!r} (model outputs: {list(outputs)})")
        graph_input = inputs[meta.input_name]
        if graph_input.type != "tensor(uint8)":
            raise mismatch(f"input {meta.input_name!r} is {graph_input.type}, need tensor(uint8)")
        shape = list(graph_input.shape)
        batch_ok = len(shape) == 4 and (shape[0] in (1, None) or isinstance(shape[0], str))
        if not batch_ok or tuple(shape[1:]) != meta.input_shape:
            raise mismatch(
                f"input shape {shape} but metadata says (batch, stack, H, W) = "
                f"(1, {meta.stack}, {meta.image_height}, {meta.image_width})"
            )
        if meta.vector_size:
            vector = inputs.get(meta.vector_input_name or "")
            if vector is None or list(vector.shape)[-1] != meta.vector_size:
                raise mismatch(
                    f"metadata's vector_keys {list(meta.vector_keys)} need a float32 input"
                    f" {meta.vector_input_name!r} of {meta.vector_size}; model inputs:"
                    f" {[(i.name, i.shape) for i in inputs.values()]}"
                )
        elif len(inputs) != 1:
            raise mismatch(f"the model takes {list(inputs)} but the metadata lists no vector")
        out_shape = list(outputs[meta.output_name].shape)
        if len(out_shape) != 2 or out_shape[1] != meta.output_size:
            what = (
                "a continuous 2-axis move"
                if meta.action_type == "continuous"
                else f"{meta.n_actions} actions"
            )
            raise mismatch(f"output shape {out_shape} but metadata says {what}")
        if meta.act_by == "goal" and meta.goal_views is not None:
            goal = outputs.get(meta.goal_output_name or "")
            frame = meta.goal_frame
            need = goal_output_count(meta.goal_views, frame)
            if goal is None or list(goal.shape)[-1] != need:
                raise mismatch(
                    f"goal_frame {frame!r} over {len(meta.goal_views)} goal_views_deg needs an"
                    f" output {meta.goal_output_name!r} of {need} logits; model outputs:"
                    f" {[(o.name, o.shape) for o in outputs.values()]}"
                )


def camera_mismatch_message(
    model_path: Path,
    robot: CameraModel,
    differences: Mapping[str, str],
    input_width: int = 160,
) -> str:
    """The warning for a robot whose camera differs (``CameraModel.differences``): each
    difference, and the ``activevision train`` settings of the robot's whole camera (a
    retrain starts from its preset's camera, so every field is given, not only those that
    differ): its angles and height, and an image ``input_width`` wide (the policy's) at the
    robot's aspect ratio (training renders at the network's input size, not the camera's)."""
    height = max(1, round(input_width / robot.aspect))
    values: dict[str, float] = {"width": input_width, "height": height}
    values |= {name: getattr(robot, name) for name in ("hfov", "camera_height")}
    values |= {name: _trainable_limit(name, getattr(robot, name)) for name in _HEAD_LIMITS}
    fixed = [axis for axis in ("pan", "tilt") if values[f"{axis}_min"] == values[f"{axis}_max"]]
    for axis in fixed:  # training's camera needs min < max: the narrowest range around it
        middle = values[f"{axis}_min"]
        values[f"{axis}_min"] = _trainable_limit(axis, middle - FIXED_AXIS_HALF_RANGE)
        values[f"{axis}_max"] = _trainable_limit(axis, middle + FIXED_AXIS_HALF_RANGE)
    settings = " ".join(f"--set env.camera.{name}={value:.9g}" for name, value in values.items())
    lines = "\n".join(f"  - {line}" for line in differences.values())
    for axis in fixed:
        lines += (
            f"\n  - the robot's neck does not {axis} ({axis}_min = {axis}_max); training needs"
            f" a range, so the settings below give it"
            f" +-{math.degrees(FIXED_AXIS_HALF_RANGE):g} degrees"
        )
    low, high = (math.degrees(getattr(robot, f"tilt_{end}")) for end in ("min", "max"))
    return (
        f"the robot's camera differs from the one {model_path} was trained for:\n{lines}\n"
        "The policy may not transfer to this camera. Retrain it for the robot's camera (angles"
        f" in radians, height in metres): activevision train ... {settings} (and"
        f" --set env.start_tilt_range_deg=[LOW,HIGH] within the tilt limits, {low:.4g} to"
        f" {high:.4g} degrees, if the preset's lie outside them); then `activevision export"
        " RUN_DIR` and load that policy.onnx. A policy trained on ActiveVisionMatch-v0"
        " takes the same values as match.camera.* (--set match.camera.hfov=...): a match"
        " run refuses env.*."
    )


#: Half the head range (rad) the retrain hint gives an axis the robot's neck cannot move
#: (its min = max): training's camera needs min < max.
FIXED_AXIS_HALF_RANGE = math.radians(0.5)
#: CameraModel's head limit fields
_HEAD_LIMITS = ("pan_min", "pan_max", "tilt_min", "tilt_max")
#: How far inside its open range (pan (-pi, pi), tilt (-pi/2, pi/2)) training's
#: CameraConfig is given a robot's limit at the end of CameraModel's closed one (rad)
_LIMIT_MARGIN = 1e-6


def _trainable_limit(name: str, value: float) -> float:
    """A robot's head limit as training's CameraConfig takes it: a neck that reaches 180
    degrees pan or 90 tilt (CameraModel takes them) trained just inside them."""
    bound = (math.pi if name.startswith("pan") else math.pi / 2) - _LIMIT_MARGIN
    return min(max(value, -bound), bound)


def _caller_level() -> int:
    """The ``stacklevel`` of the first frame outside this module, seen from a function of
    it that calls ``warnings.warn``."""
    frame: FrameType | None = sys._getframe(2)  # the warning function's caller
    level = 2
    while frame is not None and frame.f_code.co_filename == __file__:
        frame, level = frame.f_back, level + 1
    return level


def _finite_vector(name: str, value: Any, size: int) -> np.ndarray:
    try:
        # True, "0.5", alone or in a list: float64 would take them ((1, 2, True) as 1.0)
        items = np.ravel(np.asarray(value, dtype=object))
        if any(isinstance(v, bool | np.bool_ | str | bytes) for v in items):
            raise TypeError(name)
        array = np.asarray(value, dtype=np.float64).reshape(size)
    except (TypeError, ValueError) as error:
        count = "a number" if size == 1 else f"{size} numbers"
        raise ValueError(f"{name} must be {count}, got {value!r}") from error
    if not np.isfinite(array).all():
        raise ValueError(f"{name} must be finite, got {value!r}")
    return array


#: Python's exact float types and the ints every float64 holds exactly, which
#: :func:`_finite_numbers` reads without NumPy
_PLAIN_FLOATS = (float, np.float64)
_EXACT_INT = 2**53


def _finite_numbers(name: str, value: Any, size: int) -> list[float]:
    """:func:`_finite_vector` as a list of floats: a tuple or list of ``size`` finite
    Python floats (or small ints), or one for ``size`` 1, read directly; anything else
    through :func:`_finite_vector`, which refuses what it must."""
    if size == 1 and not isinstance(value, tuple | list | np.ndarray):
        items: Any = (value,)
    elif isinstance(value, tuple | list) and len(value) == size:
        items = value
    else:
        return _finite_vector(name, value, size).tolist()  # type: ignore[no-any-return]
    numbers: list[float] = []
    for item in items:
        kind = type(item)
        if kind is int and -_EXACT_INT <= item <= _EXACT_INT:
            item = float(item)
        elif kind not in _PLAIN_FLOATS or not math.isfinite(item):
            return _finite_vector(name, value, size).tolist()  # type: ignore[no-any-return]
        numbers.append(float(item))
    return numbers


#: The largest x or y (m) a pose or a ball position given to ``act`` may have: far beyond any
#: RoboCup field (the largest is 14 x 9 m) and any localisation error the policies are scored
#: at (10 m), yet below millimetres for all but a robot within 5 cm of the centre spot.
FIELD_BOUND_M = 50.0


def _on_the_field(name: str, values: list[float]) -> list[float]:
    """``values``, or ValueError: an x or y (its first two) beyond FIELD_BOUND_M, which the
    network would see clipped to 10 m, a place the robot is not (millimetres given)."""
    x, y = values[0], values[1]
    if max(abs(x), abs(y)) > FIELD_BOUND_M:
        raise ValueError(
            f"{name} x, y must be metres (within +-{FIELD_BOUND_M:g}), got ({x:g}, {y:g})"
            " (millimetres?)"
        )
    return values


def _non_negative(name: str, values: list[float]) -> list[float]:
    """``values``, or ValueError: a standard deviation below 0."""
    if any(v < 0 for v in values):
        raise ValueError(f"{name} must be standard deviations >= 0 (m and rad), got {values}")
    return values


def _proposal_vector(proposal: Any, pan: float, tilt: float) -> tuple[float, ...]:
    """(pan, tilt, d_pan, d_tilt, found); a (nan, nan) proposal is "none found"."""
    try:
        raw_pan, raw_tilt = proposal
        p_pan, p_tilt = float(raw_pan), float(raw_tilt)
    except (TypeError, ValueError) as error:
        raise ValueError(f"proposal must be (pan, tilt) radians, got {proposal!r}") from error
    if math.isnan(p_pan) and math.isnan(p_tilt):
        return (0.0, 0.0, 0.0, 0.0, 0.0)
    if not (math.isfinite(p_pan) and math.isfinite(p_tilt)):
        raise ValueError(f"proposal must be finite, or (nan, nan) for none, got {proposal!r}")
    # radians within +-pi, as the head angles (no degrees, no True for 1 rad)
    p_pan, p_tilt = _finite_angle("proposal pan", raw_pan), _finite_angle("proposal tilt", raw_tilt)
    return (p_pan, p_tilt, p_pan - pan, p_tilt - tilt, 1.0)


def _finite_angle(name: str, value: float) -> float:
    if type(value) is float and -math.pi <= value <= math.pi:  # the usual case, at once
        return value
    if isinstance(value, bool | np.bool_ | str | bytes):  # float() would take them
        raise ValueError(f"{name} must be a number of radians, got {value!r}")
    try:
        angle = float(value)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name} must be a number of radians, got {value!r}") from error
    if not math.isfinite(angle):
        raise ValueError(f"{name} must be finite, got {angle}")
    if abs(angle) > math.pi:  # no neck turns that far: degrees given for radians
        raise ValueError(f"{name} must be radians within +-pi, got {angle:g} (degrees?)")
    return angle


def _read_model(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except OSError as error:
        raise PolicyFileError(f"cannot read policy model {path}: {error}") from error


def _open_session(path: Path, model_bytes: bytes, num_threads: int) -> Any:
    """An onnxruntime CPU session (an ``onnxruntime.InferenceSession``; onnxruntime is
    untyped) for the model; PolicyFileError if onnxruntime rejects it."""
    try:
        import onnxruntime as ort
    except ImportError as error:
        raise ImportError(
            "HeadController needs onnxruntime: pip install 'activevision[runtime]'"
        ) from error
    try:
        return ort.InferenceSession(
            model_bytes,
            sess_options=robot_session_options(num_threads),
            providers=["CPUExecutionProvider"],
        )
    except Exception as error:  # onnxruntime raises its own Fail/InvalidProtobuf types
        raise PolicyFileError(f"policy model {path} is not a valid ONNX model: {error}") from error
