"""Other robots on the field: how many, how tall, where (drawn per episode).

Each is a KidSize robot as :func:`activevision.geometry.occlusion.robot_cylinders` builds it
(a body cylinder and a narrower head), standing still for an episode (in a match they may
walk: ``envs.match.others``). Placement: uniform on
the field of play, at least ``min_spacing`` from every other robot (ours included) and
``ball_clearance`` from the ball; a placement that would hide the ball from our camera is
drawn again, so every start keeps the ball in view.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from activevision.geometry.occlusion import hidden_points, robot_cylinders
from activevision.typecheck import check_dataclass_fields, in_range


@dataclass(frozen=True)
class RobotsConfig:
    """Other robots (none by default: the paper's empty field)."""

    #: how many, drawn per episode from ``count[0]..count[1]`` (at most 8; a KidSize match
    #: of 4 a side has 7 others)
    count: tuple[int, int] = (0, 0)
    #: height (m), uniform (KidSize rules: 40-100 cm)
    height: tuple[float, float] = (0.4, 1.0)
    radius: float = field(default=0.12, metadata=in_range(0.02, 0.5))  #: body radius (m)
    #: centre-to-centre distance (m) kept between robots, ours included (two bodies + a gap)
    min_spacing: float = field(default=0.6, metadata=in_range(0.0, 3.0))
    ball_clearance: float = field(default=0.3, metadata=in_range(0.0, 3.0))  #: from the ball (m)
    grey: tuple[float, float] = (25.0, 230.0)  #: body grey, uniform (dark to white robots)
    max_draws: int = field(default=200, metadata=in_range(1))  #: tries per robot

    def __post_init__(self) -> None:
        check_dataclass_fields(self)
        lo, hi = self.count
        if not 0 <= lo <= hi <= 8:
            raise ValueError(
                f"RobotsConfig.count: must satisfy 0 <= low <= high <= 8, got {self.count!r}"
            )
        lo_h, hi_h = self.height
        if not 0.1 <= lo_h <= hi_h <= 2.0:
            raise ValueError(
                f"RobotsConfig.height: must lie in [0.1, 2] m, ordered, got {self.height!r}"
            )
        lo_g, hi_g = self.grey
        if not 0 <= lo_g <= hi_g <= 255:
            raise ValueError(f"RobotsConfig.grey: must lie in [0, 255], ordered, got {self.grey!r}")

    @property
    def max_count(self) -> int:
        """The most robots an episode may hold (the size of the per-slot arrays)."""
        return self.count[1]


def draw_robots(
    config: RobotsConfig,
    rng: np.random.Generator,
    field_half: tuple[float, float],
    own: np.ndarray,
    ball: np.ndarray,
    ball_radius: float,
    camera_height: float,
) -> np.ndarray:
    """One episode's robots ``(x, y, height, grey)`` (max_count, 4); unused rows are 0.

    ``own``: our robot's (x, y); ``ball``: the ball's (x, y). A robot that cannot be placed
    in ``max_draws`` tries (a crowded field) is left out."""
    robots = np.zeros((config.max_count, 4))
    lo, hi = config.count
    count = int(rng.integers(lo, hi + 1)) if hi > 0 else 0
    placed = [np.asarray(own, dtype=np.float64)]
    camera = np.array([[own[0], own[1], camera_height]])
    ball_point = np.array([[[ball[0], ball[1], ball_radius]]])
    hx, hy = field_half
    for r in range(count):
        for _ in range(config.max_draws):
            xy = np.array([rng.uniform(-hx, hx), rng.uniform(-hy, hy)])
            height = rng.uniform(*config.height)
            grey = rng.uniform(*config.grey)
            if min(np.hypot(*(xy - p)) for p in placed) < config.min_spacing:
                continue
            if np.hypot(*(xy - ball)) < config.ball_clearance:
                continue
            cyl = robot_cylinders(np.array([[xy[0], xy[1], height, grey]]), config.radius)
            if hidden_points(camera, ball_point, cyl[None])[0, 0]:
                continue
            robots[r] = (xy[0], xy[1], height, grey)
            placed.append(xy)
            break
    return robots
