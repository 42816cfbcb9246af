"""Head-control methods behind one small interface, so one evaluator scores them all.

A policy sees what the method it models would see: the learned policy only the camera image;
the entropy-based head control the robot's *believed* pose (the true pose corrupted by the
localisation error) and the ball; the oracle the true goal (an upper bound, not a method).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, cast, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from activevision.envs.actions import action_table, greedy_actions
from activevision.envs.config import EnvConfig
from activevision.envs.observations import (
    IMAGE_KEY,
    Observation,
    flatten_vectors,
    vector_keys,
    vector_sizes,
)
from activevision.envs.robots import RobotsConfig
from activevision.envs.starts import corrupt_pose
from activevision.geometry import CameraConfig, field_landmarks
from activevision.geometry.angles import wrap_angle
from activevision.localisation import LocalisationConfig, ViewpointStatus, best_viewpoint
from activevision.rendering.appearance import AppearanceConfig
from activevision.runtime.goal_evidence import GoalEvidence, policy_actions
from activevision.runtime.metadata import PolicyFileError
from activevision.typecheck import config_from_dict

if TYPE_CHECKING:
    import torch

    from activevision.agents.student import StudentNetwork
    from activevision.runtime import HeadCommand


@dataclass(frozen=True)
class HeadTarget:
    """Jump the head straight to ``(pan, tilt)`` rad in one step."""

    pan: float
    tilt: float


@runtime_checkable
class HeadPolicy(Protocol):
    """What the evaluator needs of a method."""

    name: str

    def reset(self, info: dict, rng: np.random.Generator) -> None:
        """A new episode starts; ``rng`` is this episode's own generator."""

    def act(self, obs: Observation, info: dict) -> int | HeadTarget:
        """The next discrete action, or a head target to jump to (a continuous policy's
        move: the head's angles plus the move)."""


def greedy_action(head: ArrayLike, target: ArrayLike, table: np.ndarray) -> int:
    """The action whose move ends closest to ``target`` (pan, tilt rad)."""
    return int(greedy_actions(np.asarray(head)[None], np.asarray(target)[None], table)[0])


class RandomPolicy:
    """Uniformly random actions of the env's action set."""

    name = "random"

    def __init__(self, config: EnvConfig | None = None) -> None:
        cfg = config or EnvConfig()
        self.n_actions = len(action_table(cfg.step_deg, cfg.action_set))
        self._rng = np.random.default_rng(0)

    def reset(self, info: dict, rng: np.random.Generator) -> None:
        self._rng = rng

    def act(self, obs: Observation, info: dict) -> int:
        return int(self._rng.integers(self.n_actions))


class OraclePolicy:
    """Moves greedily to the true goal viewpoint with the same 3 degree moves (upper bound)."""

    name = "oracle"

    def __init__(self, config: EnvConfig | None = None) -> None:
        cfg = config or EnvConfig()
        self.table = action_table(cfg.step_deg, cfg.action_set)

    def reset(self, info: dict, rng: np.random.Generator) -> None:
        pass

    def act(self, obs: Observation, info: dict) -> int:
        return greedy_action(info["head"], info["goal_viewpoint"], self.table)


class EntropyPolicy:
    """Entropy-based head control (Seekircher et al. 2010; Czarnetzki et al. 2010): run the
    best-viewpoint search (Algorithm 1) from the believed pose, then either jump the head
    there (``jump=True``, the paper's comparison) or walk there with the 3 degree moves."""

    def __init__(
        self,
        localisation_error: float = 0.0,
        jump: bool = True,
        config: EnvConfig | None = None,
        localisation: LocalisationConfig | None = None,
    ) -> None:
        self.cfg = config or EnvConfig()
        self.loc = localisation or LocalisationConfig.for_camera(self.cfg.camera)
        self.error = localisation_error
        self.jump = jump
        self.name = "entropy_jump" if jump else "entropy_steps"
        self.landmarks = field_landmarks(self.cfg.field)
        self.table = action_table(self.cfg.step_deg, self.cfg.action_set)
        self.target: np.ndarray | None = None

    def reset(self, info: dict, rng: np.random.Generator) -> None:
        believed = corrupt_pose(info["pose"], self.error, rng)
        result = best_viewpoint(
            believed,
            self.loc.ukf.initial_cov,
            info["ball"],
            self.landmarks,
            self.cfg.camera,
            grid=self.loc.grid,
            ukf=self.loc.ukf,
            ball_radius=self.cfg.field.ball_radius,
        )
        # With no viewpoint showing the ball (a bad belief), the head stays where it is.
        ok = result.status == ViewpointStatus.OK
        self.target = np.array([result.pan, result.tilt]) if ok else None

    def act(self, obs: Observation, info: dict) -> int | HeadTarget:
        if self.target is None:
            return 0
        if self.jump:
            return HeadTarget(*self.target)
        return greedy_action(info["head"], self.target, self.table)


class ScanPolicy:
    """A classic RoboCup head motion (B-Human, NUbots): keep the tilt on the ball and sweep
    the pan back and forth around the ball's direction, with the same 3 degree moves."""

    name = "scan"

    def __init__(
        self, amplitude_deg: float = 25.0, period_steps: int = 12, config: EnvConfig | None = None
    ) -> None:
        self.cfg = config or EnvConfig()
        self.amplitude = np.radians(amplitude_deg)
        self.period = period_steps
        self.table = action_table(self.cfg.step_deg, self.cfg.action_set)
        self._t = 0

    def reset(self, info: dict, rng: np.random.Generator) -> None:
        self._t = 0

    def act(self, obs: Observation, info: dict) -> int:
        x, y, theta = info["pose"]
        dx, dy = np.asarray(info["ball"]) - (x, y)
        bearing = wrap_angle(np.arctan2(dy, dx) - theta)
        ball_tilt = np.arctan2(self.cfg.camera.camera_height, np.hypot(dx, dy))
        pan = bearing + self.amplitude * np.sin(2 * np.pi * self._t / self.period)
        self._t += 1
        return greedy_action(info["head"], (pan, ball_tilt), self.table)


class LearnedPolicy:
    """A trained network: the greedy action on the observation (a Q-network on the camera
    image, or a DAgger student on the image and the Dict observation's vectors). A
    continuous student (``max_move`` given) moves the head by its output times
    ``max_move``, returned as a :class:`HeadTarget`."""

    name = "learned"

    def __init__(
        self,
        q_network: torch.nn.Module,
        device: str = "cpu",
        num_threads: int | None = 1,
        vector_keys: tuple[str, ...] = (),
        goal_evidence: GoalEvidence | None = None,
        max_move: tuple[float, float] | None = None,
    ) -> None:
        import torch

        # Batch-1 inference of this small CNN is fastest on one thread, and a second busy
        # OpenMP team (training or rendering beside it) slows multi-threaded torch tenfold.
        # This sets torch's process-wide thread count; None leaves it alone.
        if num_threads is not None and device == "cpu":
            torch.set_num_threads(num_threads)
        self.torch = torch
        self.net = q_network.to(device).eval()
        self.device = device
        self.vector_keys = vector_keys
        self.takes_vector = getattr(q_network, "vector_size", None) is not None
        #: with a DAgger student that acts by its goal head (``dagger.act_by="goal"``)
        self.goal_evidence = goal_evidence
        #: a continuous student's largest move (pan, tilt) rad; None: discrete actions
        self.max_move = None if max_move is None else np.asarray(max_move, dtype=np.float64)
        #: the image (stack, H, W) and vector length the network takes (None: a network of
        #: another kind, which says neither)
        size = getattr(self.net, "image_shape", None)
        stack = int(getattr(self.net, "stack", 1))
        self._image_shape = None if size is None else (stack, *size)
        self._vector_size = int(getattr(self.net, "vector_size", 0) or 0)

    @classmethod
    def from_run(
        cls,
        run_dir: str | os.PathLike[str],
        device: str = "cpu",
        num_threads: int | None = 1,
        weights: str = "final",
    ) -> LearnedPolicy:
        """The run's final weights, or with ``weights="best"`` its best validated ones.

        CheckpointError if the run's config.json was edited after its newest checkpoint:
        its observation, moves and camera would no longer be those the network learnt."""
        from activevision.training import load_config, load_policy
        from activevision.training.state import PLAYING_WOULD, check_run_config_unchanged

        config = load_config(Path(run_dir) / "config.json")
        check_run_config_unchanged(Path(run_dir), PLAYING_WOULD)
        if config.algo == "dagger" and config.env_id == "ActiveVisionMatch-v0":
            raise ValueError(
                f"{run_dir} is a match student (it takes the belief and the ball model): play"
                f" it with `activevision match --run {run_dir}`"
            )
        keys = vector_keys(config.env)
        evidence = None
        if config.algo == "dagger" and config.dagger.act_by == "goal":
            # the candidate views the goal head names: those of the run's camera
            grid = LocalisationConfig.for_camera(config.env.camera).grid
            table = action_table(config.env.step_deg, config.env.action_set)
            dag = config.dagger
            evidence = GoalEvidence(1, grid.views, table, dag.switch_margin, dag.goal_frame)
        env = config.env
        max_move = env.max_move if env.action_type == "continuous" else None
        network = load_policy(run_dir, weights=weights)
        _check_weights_fit(network, config, run_dir, weights)
        return cls(network, device, num_threads, keys, evidence, max_move)

    def reset(self, info: dict, rng: np.random.Generator) -> None:
        if self.goal_evidence is not None:
            self.goal_evidence.reset()

    def act(self, obs: Observation, info: dict) -> int | HeadTarget:
        self._check_fits(obs)
        torch = self.torch
        with torch.inference_mode():
            if not self.takes_vector:
                x = torch.from_numpy(np.ascontiguousarray(obs)[None]).to(self.device)
                return int(self.net(x).argmax(dim=1).item())
            if not isinstance(obs, dict):
                image, vector = np.asarray(obs), np.zeros(0, np.float32)
            else:
                image, vector = obs[IMAGE_KEY], flatten_vectors(obs, self.vector_keys)
            student = cast("StudentNetwork", self.net)
            logits, goal_logits = student.forward_with_goal(
                torch.from_numpy(np.ascontiguousarray(image)[None]).to(self.device),
                torch.from_numpy(vector[None]).to(self.device),
            )
            head = np.asarray(info["head"], dtype=np.float64)[None]
            action = policy_actions(
                logits.cpu().numpy(),
                None if goal_logits is None else goal_logits.cpu().numpy(),
                head,
                self.max_move,
                self.goal_evidence,
            )[0]
            if self.max_move is not None:
                pan, tilt = head[0] + action * self.max_move
                return HeadTarget(float(pan), float(tilt))
            return int(action)

    def _check_fits(self, obs: Observation) -> None:
        """ValueError unless ``obs`` is what the network takes: an env of another observation
        (a policy of image + head angles in the paper's image-only env, a frame stack of 4 in
        one of 1) failed inside torch ("mat1 and mat2 shapes cannot be multiplied"). A Dict
        may hold more keys than the policy reads (``envs.observations.observes_within``)."""
        if self._image_shape is None:
            return
        image = obs.get(IMAGE_KEY) if isinstance(obs, dict) else obs
        shape = None if image is None else tuple(np.shape(image))
        # a Q-network takes the bare image; a student an image alone or in a Dict, which must
        # hold the vector it reads (if any)
        fits = shape == self._image_shape and (self.takes_vector or not isinstance(obs, dict))
        if fits and self._vector_size:
            fits = isinstance(obs, dict) and all(k in obs for k in self.vector_keys)
            fits = fits and sum(int(np.size(obs[k])) for k in self.vector_keys) == self._vector_size
        if fits:
            return
        takes = f"an image {self._image_shape}"
        if self._vector_size:
            takes = f"a Dict of {takes} and {list(self.vector_keys)} ({self._vector_size} numbers)"
        got = "no image" if shape is None else f"an image {shape}"
        if isinstance(obs, dict):
            got = f"a Dict of {got} and {sorted(k for k in obs if k != IMAGE_KEY)}"
        raise ValueError(
            f"method {self.name}: the observation does not fit the policy: it takes {takes},"
            f" got {got}; play it in an env of its run's observation (config.json's env)"
        )


def _check_weights_fit(network: Any, config: Any, run_dir: Any, weights: str) -> None:
    """ValueError unless ``network`` is what a run of ``config`` (a TrainConfig) trains: a
    Q-network for DDQN, a student taking the observation's vector for the others (weights
    copied in from another run would otherwise fail deep in the first episode)."""
    env = config.env
    size = getattr(network, "vector_size", None)  # a student's; None: a Q-network
    want = sum(vector_sizes(env, len(action_table(env.step_deg, env.action_set))).values())
    if (size is None) != (config.algo == "ddqn") or (size is not None and size != want):
        have = "a Q-network" if size is None else f"a student taking a vector of {size}"
        need = "a Q-network" if config.algo == "ddqn" else f"a student taking a vector of {want}"
        raise ValueError(
            f"the {weights} weights of {run_dir} do not fit its config.json: {have}, where its"
            f" {config.algo} run on {env.observation!r} trains {need} (copied from another run?)"
        )


def with_world(
    config: EnvConfig, world: Mapping[str, Mapping[str, Any]], source: str = "policy.json"
) -> EnvConfig:
    """``config`` in ``world``, a policy.json's record of the world its policy was trained in
    (:attr:`activevision.runtime.PolicyMetadata.world`): each of its ``appearance`` and
    ``robots`` replaces ``config``'s (missing fields take their defaults). PolicyFileError
    names ``source`` and what does not fit."""
    builders: dict[str, type[AppearanceConfig] | type[RobotsConfig]] = {
        "appearance": AppearanceConfig,
        "robots": RobotsConfig,
    }
    unknown = sorted(set(world) - set(builders))
    if unknown:
        raise PolicyFileError(
            f"{source}: 'world' records {unknown}, which this activevision does not know"
            f" (it plays {sorted(builders)})"
        )
    try:
        changes = {
            name: config_from_dict(builders[name], record, f"'world' {name}")
            for name, record in world.items()
        }
        return config.replace(**changes)
    except (TypeError, ValueError) as error:
        raise PolicyFileError(
            f"{source}: 'world' does not fit this activevision: {error}"
        ) from error


def with_camera(config: EnvConfig, camera: Any, source: str = "policy.json") -> EnvConfig:
    """``config`` seen through ``camera`` (a policy.json's record, a
    :class:`activevision.runtime.CameraModel`): the images, head limits and views a policy
    trained with it expects. A start tilt range outside its tilt limits becomes those limits
    (policy.json does not record the run's). PolicyFileError names ``source`` where the
    record is no camera this activevision's env takes."""
    try:
        trained = CameraConfig.of(camera)
    except (TypeError, ValueError) as error:
        raise PolicyFileError(
            f"{source}: 'camera' does not fit this activevision: {error}"
        ) from error
    return config.through_camera(trained)


class OnnxPolicy:
    """An exported policy run by :class:`activevision.runtime.HeadController` (no torch),
    fed the newest camera frame, as on a robot."""

    name = "onnx"

    def __init__(self, model_path: str | os.PathLike[str]) -> None:
        from activevision.runtime import HeadController

        self.controller = HeadController(model_path, color_order="rgb")

    def env_config(
        self, base: EnvConfig | None = None, *, trained_world: bool = False
    ) -> EnvConfig:
        """``base`` (default: the paper's env) observing what this policy was trained on.

        ``trained_world``: also in the world it was trained in (policy.json's ``world``, its
        appearance ranges and other robots; ``base``'s when the file predates the record).
        A discrete policy moves by its own steps (policy.json's ``step_deg`` and
        ``action_set``), and every policy sees through the camera it was trained with
        (policy.json's ``camera``; ``base``'s when the file predates the record), its start
        tilts within that camera's limits. Evaluation plays the paper's clean world whatever
        the policy was trained in;
        ``activevision robustness`` plays the trained one as its ``clean`` row.
        PolicyFileError if the record does not fit this activevision's configs; ValueError
        for a match student, which plays only in matches.
        """
        meta = self.controller.metadata
        if {"belief", "ball"} & set(meta.vector_keys):  # no episodic env gives them
            path = self.controller.model_path
            raise ValueError(
                f"{path} is a match student (it takes the belief and the ball model): play it"
                f" with `activevision match --methods onnx_policy --model {path}`"
            )
        base = base or EnvConfig()
        if trained_world and meta.world is not None:
            base = with_world(base, meta.world, source=str(self.controller.metadata_path))
        if meta.camera is not None:
            base = with_camera(base, meta.camera, source=str(self.controller.metadata_path))
        if not self.controller.continuous and meta.step_deg is not None:
            # a discrete policy's action i is row i of its table: the env moves by the same
            # (policy.json's step_deg and action_set; a bare export_onnx's: base's)
            moves = {"step_deg": meta.step_deg, "action_set": meta.action_set}
            if any(getattr(base, k) != v for k, v in moves.items()):
                base = base.replace(**moves)
        if meta.observation == base.observation and meta.action_history == base.action_history:
            return base
        return base.replace(observation=meta.observation, action_history=meta.action_history)

    def reset(self, info: dict, rng: np.random.Generator) -> None:
        self.controller.reset()

    def act(self, obs: Observation, info: dict) -> int | HeadTarget:
        command = self._command(obs, info)
        if self.controller.continuous:
            return HeadTarget(command.target_pan, command.target_tilt)
        return command.action

    def _command(self, obs: Observation, info: dict) -> HeadCommand:
        pan, tilt = info["head"]
        if not isinstance(obs, dict):
            if self.controller.metadata.vector_keys:
                raise ValueError(
                    f"this policy observes {self.controller.metadata.observation!r}; play it on"
                    " an env with that observation (OnnxPolicy.env_config())"
                )
            return self.controller.act(obs[-1], pan, tilt)
        inputs = self.controller.inputs
        pose = info["prior_pose"] if "pose" in inputs else None
        pose_error = info["prior_error"] if "pose_error" in inputs else None
        proposal = None
        if "proposal" in inputs:
            p_pan, p_tilt, _, _, found = obs["proposal"]
            proposal = (p_pan, p_tilt) if found else (math.nan, math.nan)
        image = obs[IMAGE_KEY][-1]
        return self.controller.act(image, pan, tilt, pose, proposal, pose_error=pose_error)
