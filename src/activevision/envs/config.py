"""Configuration of the ActiveVision task: one frozen dataclass, paper values as defaults."""

from __future__ import annotations

import dataclasses
import math
import numbers
import typing
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from activevision.envs.actions import ActionType
from activevision.envs.robots import RobotsConfig
from activevision.geometry import CameraConfig, FieldSpec, field_preset
from activevision.geometry.field import FIELD_PRESETS
from activevision.registration import MAX_VECTOR_ENVS as _MAX_VECTOR_ENVS
from activevision.rendering.appearance import AppearanceConfig
from activevision.runtime.metadata import MAX_ACTION_HISTORY
from activevision.typecheck import (
    check_dataclass_fields,
    config_from_dict,
    nested_configs,
    replace_fields,
)

SuccessMode = Literal["tolerance", "landmarks"]
ActionSet = Literal["8way", "4way"]
#: What the agent observes (see ``activevision.envs.observations``): the paper's image, or a
#: ``Dict`` that adds what a robot knows of itself.
ObservationKind = Literal["image", "image+head", "image+head+pose", "image+head+pose+proposal"]
OBSERVATION_KINDS: tuple[str, ...] = typing.get_args(ObservationKind)
#: The most images an observation stacks (P: 1; Atari's DQN: 4): a larger number (a typo,
#: 10**12) is refused naming the field, not a MemoryError allocating the stack.
MAX_FRAME_STACK = 64
#: The most sub-environments a native vector env (``num_envs``) steps together
#: (``registration.MAX_VECTOR_ENVS``, where ``make_vec`` checks it for every mode).
MAX_VECTOR_ENVS = _MAX_VECTOR_ENVS
#: The most rejection-sampling draws for one episode start (``max_start_draws``): the
#: default 1,000 finds a start in a few; a million take seconds where no start exists.
MAX_START_DRAWS = 1_000_000


@dataclass(frozen=True)
class EnvConfig:
    """Everything that defines an episode. Sources: the paper (P), the authors' release (R)."""

    #: KidSize field (current rules); a preset name ("kidsize", "paper2019") is accepted
    field: FieldSpec = dataclasses.field(default_factory=FieldSpec)
    #: the MRL-HSL head camera (P, R)
    camera: CameraConfig = dataclasses.field(default_factory=CameraConfig)
    step_deg: float = 3.0  #: head move per action (P: "3 degrees")
    action_set: ActionSet = "8way"  #: stay + 8 directions (R); "4way": stay + 4 directions
    #: "discrete" (P); "continuous": a Box(-1, 1, (2,)) times ``max_move_deg`` (P's future work)
    action_type: ActionType = "discrete"
    #: continuous actions: the largest head move per tick (pan, tilt degrees). Not in P; a
    #: KidSize neck servo turns 30 deg in a 320 ms tick with ease, 10 deg keeps the image sharp
    max_move_deg: tuple[float, float] = (10.0, 10.0)
    frame_stack: int = 1  #: images per observation (P: one 160x120x1 frame)
    success_mode: SuccessMode = "tolerance"  #: P: within tolerance of the goal; R: "landmarks"
    #: P leaves the tolerance open. One action step (3 deg): every start can get that close,
    #: since axis moves alone bring each axis within 1.5 deg (2.1 deg in all).
    success_tolerance_deg: float = 3.0
    #: R scores sign(int(D - D')) with D in degrees, so changes under 1 deg score 0; P none.
    reward_resolution_deg: float = 0.0
    ball_lost_reward: float = -2.0  #: P
    localisation_error: float = 0.0  #: e: believed position off by e m, heading by +-e rad (R)
    robot_x_range: tuple[float, float] = (-3.0, 3.0)  #: start pose (R)
    robot_y_range: tuple[float, float] = (-1.5, 1.5)  #: start pose (R)
    start_tilt_range_deg: tuple[float, float] = (5.0, 25.0)  #: start head tilt (R); pan: full
    ball_distance_range: tuple[float, float] = (1.0, 3.0)  #: ball 1-3 m from the robot (R)
    max_start_draws: int = 1000  #: rejection-sampling guard for episode starts (ours)
    #: the observation: "image" (P) or a Dict adding the head angles, the robot's prior pose
    #: and the entropy method's proposal from it (not in P; ``envs.observations``)
    observation: ObservationKind = "image"
    #: the prior pose's error, drawn per episode from U(low, high) (m and rad, as
    #: ``localisation_error`` corrupts); None: the prior is the believed pose (P's future work)
    prior_error_range: tuple[float, float] | None = None
    #: with ``prior_error_range``: the share of episodes whose prior is exact (error 0), so
    #: that a policy trained across errors sees the prior it can trust often enough
    prior_exact_share: float = 0.0
    #: the prior pose quantised to (metres, degrees) cells, "a rough representation of the
    #: robot position" (P's future work); 0: exact
    prior_grid: tuple[float, float] = (0.0, 0.0)
    #: the previous actions, one-hot, in a Dict observation (memory; 0: none)
    action_history: int = 0
    #: randomised appearance drawn per episode (not in P: domain randomisation; off = P's
    #: clean render, ``rendering.appearance``)
    appearance: AppearanceConfig = dataclasses.field(default_factory=AppearanceConfig)
    #: other robots on the field, occluding (not in P: none; ``envs.robots``)
    robots: RobotsConfig = dataclasses.field(default_factory=RobotsConfig)

    def __post_init__(self) -> None:
        object.__setattr__(self, "field", field_spec(self.field, "EnvConfig.field"))
        # Types first (one message naming field and value), so that the range checks below
        # compare numbers, never strings or None.
        check_dataclass_fields(self)

        def bad(name: str, why: str) -> ValueError:
            return ValueError(f"EnvConfig.{name}: {why}, got {getattr(self, name)!r}")

        self._check_actions(bad)
        if not 1 <= self.frame_stack <= MAX_FRAME_STACK:
            raise bad("frame_stack", f"must be an integer in [1, {MAX_FRAME_STACK}]")
        if not self.success_tolerance_deg > 0:
            raise bad("success_tolerance_deg", "must be positive")
        if not self.reward_resolution_deg >= 0:
            raise bad("reward_resolution_deg", "must be >= 0")
        if not self.localisation_error >= 0:
            raise bad("localisation_error", "must be >= 0")
        for name in (
            "robot_x_range",
            "robot_y_range",
            "start_tilt_range_deg",
            "ball_distance_range",
        ):
            lo, hi = getattr(self, name)
            if not lo <= hi:
                raise bad(name, "must be an ordered (low, high) pair")
        lo, hi = self.start_tilt_range_deg
        # within a micro-radian: limits given to 9 digits (the runtime's retrain hint) would
        # otherwise refuse a range ending on them (draw_starts clips to the limits)
        if math.radians(lo) < self.camera.tilt_min - 1e-6 or math.radians(hi) > (
            self.camera.tilt_max + 1e-6
        ):
            low, high = (math.degrees(t) for t in (self.camera.tilt_min, self.camera.tilt_max))
            raise bad(
                "start_tilt_range_deg",
                f"must lie within the camera's tilt limits, {low:.4g} to {high:.4g} degrees"
                " (set env.start_tilt_range_deg=[LOW,HIGH] with the camera)",
            )
        if not self.ball_distance_range[0] > 0:
            raise bad("ball_distance_range", "must be positive")
        # an upper bound: a start no draw can satisfy (a ball range the camera never sees)
        # spun for hours through 10**9 draws before naming the range
        if not 1 <= self.max_start_draws <= MAX_START_DRAWS:
            raise bad("max_start_draws", f"must be a positive integer up to {MAX_START_DRAWS:,}")
        self._check_observation(bad)

    def _check_actions(self, bad: typing.Callable[[str, str], ValueError]) -> None:
        if not 0 < self.step_deg <= 30:
            raise bad("step_deg", "must lie in (0, 30] degrees")
        if not all(0 < m <= 90 for m in self.max_move_deg):
            raise bad("max_move_deg", "must lie in (0, 90] degrees on each axis")
        if self.action_type == "continuous" and self.action_history:
            raise bad("action_history", "holds discrete actions, not action_type='continuous'")

    def _check_observation(self, bad: typing.Callable[[str, str], ValueError]) -> None:
        if self.prior_error_range is not None:
            lo, hi = self.prior_error_range
            if not 0 <= lo <= hi:
                raise bad("prior_error_range", "must be an ordered (low, high) pair >= 0")
        if not 0 <= self.prior_exact_share <= 1:
            raise bad("prior_exact_share", "must lie in [0, 1]")
        if min(self.prior_grid) < 0:
            raise bad("prior_grid", "must be >= 0 (metres, degrees)")
        if not 0 <= self.action_history <= MAX_ACTION_HISTORY:
            raise bad("action_history", f"must lie in 0..{MAX_ACTION_HISTORY}")
        if self.observation == "image" and self.action_history:
            raise bad("action_history", "needs a Dict observation (observation='image+head...')")
        if self.observation != "image" and self.frame_stack != 1:
            raise bad("observation", "a Dict observation takes frame_stack=1 (use action_history)")

    @property
    def max_move(self) -> tuple[float, float]:
        """``max_move_deg`` in radians."""
        return (math.radians(self.max_move_deg[0]), math.radians(self.max_move_deg[1]))

    @property
    def observes_prior(self) -> bool:
        """Whether observations carry the prior pose (and so episodes draw one)."""
        return "pose" in self.observation

    @classmethod
    def release(cls, **overrides: Any) -> EnvConfig:
        """The authors' release: 2019 field, landmark-based success, 1-degree reward steps."""
        return cls(
            field=FieldSpec.paper_2019(),
            success_mode="landmarks",
            reward_resolution_deg=1.0,
            **overrides,
        )

    def replace(self, **changes: Any) -> EnvConfig:
        """A copy with ``changes``; an unknown name is a ValueError naming the fields."""
        return replace_fields(self, changes)

    def through_camera(self, camera: CameraConfig) -> EnvConfig:
        """This config seen through ``camera``: the images, head limits and views a policy
        trained with it expects. A start tilt range outside its tilt limits becomes those
        limits (a neck that barely tilts left the default 5-25 degrees outside them)."""
        if camera == self.camera:
            return self
        low, high = math.degrees(camera.tilt_min), math.degrees(camera.tilt_max)
        start = self.start_tilt_range_deg
        if not low <= start[0] <= start[1] <= high:
            start = (low, high)
        return self.replace(camera=camera, start_tilt_range_deg=start)


def field_spec(value: object, name: str) -> FieldSpec:
    """A config's ``field`` (``name``, for messages) as a FieldSpec: a preset name (how JSON
    run configs store the field) becomes its FieldSpec. Checked here, not by the generic
    type check, so that the message names the presets too."""
    if isinstance(value, str):
        try:
            return field_preset(value)
        except ValueError as e:
            raise ValueError(f"{name}: {e}") from None
    if not isinstance(value, FieldSpec):
        raise ValueError(
            f"{name}: expects FieldSpec or a preset name {sorted(FIELD_PRESETS)}, got {value!r}"
        )
    return value


def resolve_config(
    config: EnvConfig | Mapping[str, Any] | None, overrides: Mapping[str, Any]
) -> EnvConfig:
    """The environments' configuration: ``config`` (default :class:`EnvConfig()`) with the
    keyword ``overrides`` applied. The config and a nested config among the overrides
    (``appearance``, ``robots``, ``camera``, ``field``) may also come as JSON objects of
    their fields, as ``EnvSpec.to_json`` writes them (:func:`typecheck.nested_configs`)."""
    if config is None:
        config = EnvConfig()
    elif isinstance(config, Mapping):
        config = config_from_dict(EnvConfig, config, "config")
    elif not isinstance(config, EnvConfig):
        raise ValueError(f"config: expects EnvConfig or None, got {config!r}")
    return config.replace(**nested_configs(EnvConfig, overrides)) if overrides else config


def check_render_mode(render_mode: str | None, modes: list[str]) -> None:
    """ValueError unless ``render_mode`` is None or one of ``modes``."""
    if render_mode is not None and render_mode not in modes:
        raise ValueError(f"render_mode: expects one of {modes} or None, got {render_mode!r}")


def check_count(name: str, value: object, most: int | None = None) -> int:
    """``value`` as a positive int up to ``most`` (``num_envs``); bools, floats, numbers
    past ``most`` and the rest are a ValueError naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise ValueError(f"{name}: expects a positive integer, got {value!r}")
    if most is not None and int(value) > most:
        raise ValueError(f"{name}: expects a positive integer up to {most}, got {value!r}")
    return int(value)
