"""Configuration of the match environment: one typed, nested config per part.

Nothing here is in the paper, whose robot stands still; each default names its source (a
KidSize rule, a team's report, or the reasoning) beside it.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from activevision.envs.actions import ActionType
from activevision.envs.config import field_spec
from activevision.envs.robots import RobotsConfig
from activevision.geometry import CameraConfig, FieldSpec
from activevision.localisation.config import UKFConfig
from activevision.localisation.tracking import TrackerConfig
from activevision.rendering.appearance import AppearanceConfig
from activevision.typecheck import (
    check_dataclass_fields,
    config_from_dict,
    config_to_dict,
    in_range,
    replace_fields,
)

#: What the agent observes: the image, plus the head angles, plus the belief (mean,
#: uncertainty) and the robot's ball model (``envs.match.observations``).
MatchObservation = Literal["image", "image+head", "image+head+belief"]
MATCH_OBSERVATIONS: tuple[str, ...] = typing.get_args(MatchObservation)
#: The discrete moves of a match's head: the paper's eight, of ``step_deg`` each
MATCH_ACTION_SET = "8way"
#: What the reward scores: the belief's entropy (what a robot can compute) or its true error.
RewardKind = Literal["entropy", "error"]
#: Where the robot walks: random waypoints, or scripted to the ball (a striker).
WalkTarget = Literal["waypoints", "ball"]


@dataclass(frozen=True)
class WalkConfig:
    """How our robot walks. KidSize robots walk at 0.1-0.3 m/s and turn at about 30 deg/s
    (team description papers, e.g. NUbots 2019 and Bit-Bots 2022)."""

    target: WalkTarget = "waypoints"
    speed: float = field(default=0.2, metadata=in_range(0.0, 1.0))  #: forward (m/s)
    turn_rate: float = field(default=0.5, metadata=in_range(0.0, 3.0))  #: rad/s
    reach: float = field(default=0.25, metadata=in_range(0.01, 2.0))  #: a waypoint is reached (m)
    #: ticks to stand at a reached waypoint, uniform (robots stop to kick, to look, to wait)
    pause_ticks: tuple[int, int] = (0, 15)
    #: waypoints are drawn this far (m) inside the field lines
    margin: float = field(default=0.5, metadata=in_range(0.0, 3.0))
    #: ``target="ball"``: stop this far (m) short of the ball, on the line from the robot, as
    #: a striker lines up a kick (standing over the ball would put it below the camera)
    ball_standoff: float = field(default=0.4, metadata=in_range(0.0, 2.0))

    def __post_init__(self) -> None:
        check_dataclass_fields(self)
        lo, hi = self.pause_ticks
        if not 0 <= lo <= hi:
            raise ValueError(f"WalkConfig.pause_ticks: must satisfy 0 <= low <= high, got {lo, hi}")


@dataclass(frozen=True)
class BallConfig:
    """The ball rolls with constant deceleration and is kicked at random times (by anyone)."""

    #: rolling deceleration on artificial turf (m/s^2); measured values lie 0.3-0.6
    deceleration: float = field(default=0.4, metadata=in_range(0.0, 5.0))
    kick_rate: float = field(default=0.02, metadata=in_range(0.0, 1.0))  #: kicks per tick
    kick_speed: tuple[float, float] = (0.5, 2.5)  #: initial speed of a kick (m/s), uniform
    #: the ball bounces off our own robot's body too, as off the others' (keeping
    #: ``others.ball_restitution``; a robot walking into it pushes it). Off by default: the
    #: docs/match.md's figures were measured with the ball rolling through our robot.
    bounces_off_own_robot: bool = False

    def __post_init__(self) -> None:
        check_dataclass_fields(self)
        lo, hi = self.kick_speed
        if not 0 <= lo <= hi <= 10:
            raise ValueError(
                f"BallConfig.kick_speed: must lie in [0, 10] m/s, ordered, got {lo, hi}"
            )


@dataclass(frozen=True)
class OthersConfig:
    """How the other robots (``MatchConfig.robots``) move. Each walks straight to a random
    waypoint on the field at ``speed``, and draws the next when it gets there or when its
    step would bring it within ``robots.min_spacing`` of another robot or ours (it stands
    that tick: robots give way). They step one after another, each checking where the
    others are as it steps, after our robot, which gives way to them as well
    (``envs.match.kernels.move_kernel``: it sidesteps round them, or turns on the spot),
    standing or walking:
    no two robots, ours included, ever end a tick within ``min_spacing`` of each other.
    Standing still by default. The ball bounces off every robot's
    body, keeping ``ball_restitution`` of its speed towards it (a body gives; a robot's legs
    and torso are not a wall). The ball's straight path in the tick is tested, so a fast
    ball stops where it first touched a body rather than passing through it (a ball that
    bounced off a field line in the same tick is tested along the straight line from where
    it began to where it ended)."""

    #: walking speed (m/s); KidSize 0.1-0.3, as ``WalkConfig.speed``
    speed: float = field(default=0.0, metadata=in_range(0.0, 1.0))
    #: share of its speed towards a robot that a ball keeps in the bounce (a reasoned
    #: guess: no KidSize measurement is published)
    ball_restitution: float = field(default=0.5, metadata=in_range(0.0, 1.0))

    def __post_init__(self) -> None:
        check_dataclass_fields(self)


@dataclass(frozen=True)
class DetectionConfig:
    """The landmark detector. A landmark in view is detected with a probability falling
    linearly from ``near`` at the robot to ``far`` at its detection range (small, distant
    features are missed more often); detections carry the UKF's own sensor noise. A false
    detection (a robot's foot taken for a corner) appears with ``false_rate`` per tick:
    a random point landmark at a random range and bearing inside the image."""

    near: float = field(default=0.95, metadata=in_range(0.0, 1.0))
    far: float = field(default=0.5, metadata=in_range(0.0, 1.0))
    false_rate: float = field(default=0.05, metadata=in_range(0.0, 1.0))
    #: std of the robot's ball detector, as a fraction of the ball's range
    ball_noise: float = field(default=0.05, metadata=in_range(0.0, 1.0))

    def __post_init__(self) -> None:
        check_dataclass_fields(self)


@dataclass(frozen=True)
class MatchRewardConfig:
    """Reward per tick: ``-entropy_weight * H`` (``kind="entropy"``, H the belief's entropy
    in nats) or ``-error_weight * |position error|`` (``kind="error"``, m), plus
    ``ball_weight`` with the ball in view, minus ``travel_weight`` per degree of head move."""

    kind: RewardKind = "entropy"
    entropy_weight: float = field(default=0.1, metadata=in_range(0.0))
    error_weight: float = field(default=1.0, metadata=in_range(0.0))
    ball_weight: float = field(default=0.5, metadata=in_range(0.0))
    travel_weight: float = field(default=0.005, metadata=in_range(0.0))

    def __post_init__(self) -> None:
        check_dataclass_fields(self)


@dataclass(frozen=True)
class KidnapConfig:
    """Kidnapping: our robot is picked up and put down elsewhere without its belief being
    told (a referee's removal and return, a robot carried off after a fall), in each tick
    with probability ``rate`` per minute of play times the tick's length and in each of
    ``ticks`` (1: the first tick). The chance is drawn from a generator spawned from the
    match's own, which leaves the match's draws as they were: the same seed, the same
    kidnaps, and until the first the same match as without them. A kidnap carries the robot
    ``distance`` m (uniform between the two) in a uniform direction, stopped at the walk's
    margin inside the field lines (near the lines the carry is shorter), never within
    ``robots.min_spacing`` of another robot (a carry that would be is drawn again, up to 16
    draws, from the same generator; with none clear the robot stays where it stands), and
    turns it by up to ``turn`` rad either way (uniform); its odometry reports none of it.
    A kidnap whose first carry is clear draws nothing more. Off by default;
    docs/match.md's kidnap check (teleported 2 m along, 1 m across, turned 0.8 rad) lies
    within the defaults' reach."""

    #: kidnaps per minute of play (0: none at random)
    rate: float = field(default=0.0, metadata=in_range(0.0, 60.0))
    #: kidnapped in these ticks too (1 = the first), e.g. ``(200,)``
    ticks: tuple[int, ...] = ()
    #: how far (m) a kidnap carries the robot, uniform LOW-HIGH
    distance: tuple[float, float] = (1.0, 2.0)
    #: how far (rad) it turns the robot, uniform in [-turn, turn]
    turn: float = field(default=0.8, metadata=in_range(0.0, math.pi))

    def __post_init__(self) -> None:
        check_dataclass_fields(self)
        lo, hi = self.distance
        if not 0 <= lo <= hi <= 20:
            raise ValueError(f"KidnapConfig.distance: must lie in [0, 20] m, ordered, got {lo, hi}")
        if any(t < 1 for t in self.ticks):
            raise ValueError(f"KidnapConfig.ticks: ticks count from 1, got {self.ticks!r}")
        object.__setattr__(self, "ticks", tuple(sorted(set(self.ticks))))

    @property
    def enabled(self) -> bool:
        """Whether any kidnap can happen."""
        return self.rate > 0 or bool(self.ticks)


def _match_ukf() -> UKFConfig:
    # A match starts from a known kick-off position (initial std 10 cm, 3 deg). A walking
    # KidSize humanoid's odometry is poor: feet slip on artificial turf, so its error is a
    # quarter of the distance walked and of the angle turned, plus a little slip per tick
    # while stepping on the spot.
    return UKFConfig(
        odometry_base=(0.003, 0.003, 0.006),
        odometry_translation_fraction=0.25,
        odometry_rotation_fraction=0.25,
        initial_std=(0.1, 0.1, 0.05),
    )


def _match_tracker() -> TrackerConfig:
    return TrackerConfig(ukf=_match_ukf())


@dataclass(frozen=True)
class MatchConfig:
    """Everything that defines a match of ``ActiveVisionMatch-v0``."""

    #: KidSize field (current rules); a preset name ("kidsize", "paper2019") is accepted
    field: FieldSpec = dataclasses.field(default_factory=FieldSpec)
    camera: CameraConfig = dataclasses.field(default_factory=CameraConfig)  #: the paper's camera
    #: control ticks per match: 600 ticks of 0.32 s is 3.2 minutes of play
    ticks: int = dataclasses.field(default=600, metadata=in_range(1))
    tick_seconds: float = dataclasses.field(default=0.32, metadata=in_range(0.01, 10.0))  #: P
    step_deg: float = dataclasses.field(default=3.0, metadata=in_range(0.1, 30.0))  #: P: 3 deg
    #: "discrete": the 9 moves of ``step_deg``; "continuous": Box(-1, 1, (2,)) times
    #: ``max_move_deg`` (pan, tilt degrees per tick; as ``EnvConfig``)
    action_type: ActionType = "discrete"
    max_move_deg: tuple[float, float] = (10.0, 10.0)
    observation: MatchObservation = "image"
    walk: WalkConfig = dataclasses.field(default_factory=WalkConfig)
    ball: BallConfig = dataclasses.field(default_factory=BallConfig)
    detection: DetectionConfig = dataclasses.field(default_factory=DetectionConfig)
    tracker: TrackerConfig = dataclasses.field(default_factory=_match_tracker)
    reward: MatchRewardConfig = dataclasses.field(default_factory=MatchRewardConfig)
    #: randomised appearance, drawn per match (``rendering.appearance``; off: clean)
    appearance: AppearanceConfig = dataclasses.field(default_factory=AppearanceConfig)
    #: other robots, placed as in the episodic env (``envs.robots``; none by default)
    robots: RobotsConfig = dataclasses.field(default_factory=RobotsConfig)
    #: how they move (standing still by default) and what the ball does when it meets one
    others: OthersConfig = dataclasses.field(default_factory=OthersConfig)
    #: our robot carried elsewhere unbeknown to its belief (off by default)
    kidnap: KidnapConfig = dataclasses.field(default_factory=KidnapConfig)

    def __post_init__(self) -> None:
        object.__setattr__(self, "field", field_spec(self.field, "MatchConfig.field"))
        check_dataclass_fields(self)
        if self.detection.far > self.detection.near:
            raise ValueError("MatchConfig.detection: far must not exceed near")
        if not all(0 < m <= 90 for m in self.max_move_deg):
            raise ValueError(
                f"MatchConfig.max_move_deg: must lie in (0, 90] degrees, got {self.max_move_deg!r}"
            )

    @property
    def max_move(self) -> tuple[float, float]:
        """``max_move_deg`` in radians."""
        return (math.radians(self.max_move_deg[0]), math.radians(self.max_move_deg[1]))

    @property
    def head_step(self) -> float:
        """The head move per action (rad)."""
        return math.radians(self.step_deg)

    def replace(self, **changes: Any) -> MatchConfig:
        """A copy with ``changes``; an unknown name is a ValueError naming the fields."""
        return replace_fields(self, changes)


def with_paths(config: MatchConfig, changes: Mapping[str, Any]) -> MatchConfig:
    """``config`` with values set by dotted path: ``{"tick_seconds": 0.16, "camera.hfov":
    1.2, "reward.kind": "error"}`` (a leading ``match.``, as a training run's ``--set``
    spells it, is allowed); a nested config may be given whole as an object of its fields
    (``{"camera": {"hfov": 1.2}}``, the others taking their defaults). ValueError names an
    unknown path with the fields where it went wrong, or a bad value (the config's own
    checks)."""
    nested = config_to_dict(config)
    for key, value in changes.items():
        parts = key.strip().removeprefix("match.").split(".")
        target: Any = nested
        for depth, part in enumerate(parts):
            where = ".".join(parts[:depth]) or "MatchConfig"
            if not isinstance(target, dict):
                raise ValueError(f"{key}: {where} is a value, not a config with fields")
            if part not in target:
                raise ValueError(f"{key}: {where} has no field {part!r}; known: {sorted(target)}")
            if depth == len(parts) - 1:
                target[part] = value
            else:
                target = target[part]
    return config_from_dict(MatchConfig, nested)
