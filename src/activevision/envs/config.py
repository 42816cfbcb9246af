"""Configuration of the ActiveVision task: one frozen dataclass, paper values as defaults."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Literal

from activevision.geometry import CameraConfig, FieldSpec, field_preset

SuccessMode = Literal["tolerance", "landmarks"]
ActionSet = Literal["8way", "4way"]


@dataclass(frozen=True)
class EnvConfig:
    """Everything that defines an episode. Sources: the paper (P), the authors' release (R)."""

    #: KidSize field (current rules); a preset name ("kidsize", "paper2019") is accepted
    field: FieldSpec = dataclasses.field(default_factory=FieldSpec)
    #: the MRL-HSL head camera (P, R)
    camera: CameraConfig = dataclasses.field(default_factory=CameraConfig)
    step_deg: float = 3.0  #: head move per action (P: "3 degrees")
    action_set: ActionSet = "8way"  #: stay + 8 directions (R); "4way": stay + 4 directions
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
    max_start_draws: int = 1000  #: rejection-sampling guard for episode starts

    def __post_init__(self) -> None:
        if isinstance(self.field, str):  # a preset name, e.g. from a JSON run config
            object.__setattr__(self, "field", field_preset(self.field))

        def bad(name: str, why: str) -> ValueError:
            return ValueError(f"EnvConfig.{name}: {why}, got {getattr(self, name)!r}")

        if not 0 < self.step_deg <= 30:
            raise bad("step_deg", "must lie in (0, 30] degrees")
        if self.action_set not in ("8way", "4way"):
            raise bad("action_set", "must be '8way' or '4way'")
        if not isinstance(self.frame_stack, int) or self.frame_stack < 1:
            raise bad("frame_stack", "must be a positive integer")
        if self.success_mode not in ("tolerance", "landmarks"):
            raise bad("success_mode", "must be 'tolerance' or 'landmarks'")
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
        if math.radians(lo) < self.camera.tilt_min - 1e-9 or math.radians(hi) > (
            self.camera.tilt_max + 1e-9
        ):
            raise bad("start_tilt_range_deg", "must lie within the camera's tilt limits")
        if not self.ball_distance_range[0] > 0:
            raise bad("ball_distance_range", "must be positive")

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
        return dataclasses.replace(self, **changes)
