"""The RoboCup Humanoid KidSize field: dimensions and its landmarks as data.

Coordinates: metres, origin at the centre spot, x along the field length (towards the
opponent goal at +x), y along the width (left when looking along +x), z up.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, fields

import numpy as np

from activevision.typecheck import check_dataclass_fields


class LandmarkType(enum.IntEnum):
    """Kinds of field features a RoboCup vision pipeline detects."""

    L_CORNER = 0
    T_JUNCTION = 1
    X_CROSSING = 2
    PENALTY_MARK = 3
    GOAL_POST = 4
    CENTRE_CIRCLE = 5
    LINE = 6
    FIELD_BOUNDARY = 7


#: Default maximum detection distance (m) per landmark type. The paper measured these
#: experimentally on its robot without publishing numbers; these are typical of KidSize
#: vision pipelines at 160x120: small features (marks, crossings) are lost first, long
#: high-contrast features (boundary, posts) are found furthest away.
DEFAULT_MAX_DISTANCE: dict[LandmarkType, float] = {
    LandmarkType.L_CORNER: 4.0,
    LandmarkType.T_JUNCTION: 4.0,
    LandmarkType.X_CROSSING: 3.5,
    LandmarkType.PENALTY_MARK: 3.0,
    LandmarkType.GOAL_POST: 5.0,
    LandmarkType.CENTRE_CIRCLE: 4.0,
    LandmarkType.LINE: 3.0,
    LandmarkType.FIELD_BOUNDARY: 6.0,
}


@dataclass(frozen=True)
class FieldSpec:
    """Field dimensions (m). Defaults: RoboCup Humanoid KidSize, 2025 rules (REFERENCE.md)."""

    length: float = 9.0  #: touchline length (rules)
    width: float = 6.0  #: goal line length (rules)
    line_width: float = 0.05  #: painted line width (rules: about 5 cm)
    goal_width: float = 2.6  #: inner distance between the posts (rules)
    goal_height: float = 1.2  #: height of the crossbar's lower edge (rules)
    goal_depth: float = 0.6  #: depth of the goal net (rules)
    post_diameter: float = 0.1  #: posts and crossbar: 8-12 cm (rules)
    goal_area_length: float = 1.0  #: goal area, along x (rules)
    goal_area_width: float = 3.0  #: goal area, along y (rules; 5 m in 2019)
    penalty_area_length: float | None = 2.0  #: None: no penalty area (2019 rules)
    penalty_area_width: float | None = 5.0  #: None: no penalty area (2019 rules)
    penalty_mark_distance: float = 1.5  #: from the goal line (rules)
    penalty_mark_size: float = 0.1  #: side of the painted square mark (rules)
    centre_circle_diameter: float = 1.5  #: (rules)
    border_strip_width: float = 1.0  #: green carpet beyond the lines (rules: at least 1 m)
    ball_radius: float = 0.07  #: FIFA size 1; the paper's world uses 0.07 m

    def __post_init__(self) -> None:
        check_dataclass_fields(self)  # types first: the comparisons below need numbers
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None:
                continue
            if not np.isfinite(value) or value <= 0:
                raise ValueError(f"FieldSpec.{f.name} must be a positive number, got {value!r}")
        if (self.penalty_area_length is None) != (self.penalty_area_width is None):
            raise ValueError(
                "FieldSpec.penalty_area_length and penalty_area_width must both be set or both None"
            )
        checks = [
            ("goal_width", self.goal_width, self.width),
            ("goal_area_width", self.goal_area_width, self.width),
            ("goal_area_length", self.goal_area_length, self.length / 2),
            ("penalty_mark_distance", self.penalty_mark_distance, self.length / 2),
            ("centre_circle_diameter", self.centre_circle_diameter, min(self.length, self.width)),
            ("line_width", self.line_width, self.goal_area_length),
        ]
        pa_length, pa_width = self.penalty_area_length, self.penalty_area_width
        if pa_length is not None and pa_width is not None:  # both or neither (checked above)
            checks += [
                ("penalty_area_width", pa_width, self.width),
                ("penalty_area_length", pa_length, self.length / 2),
                ("goal_area_length", self.goal_area_length, pa_length),
                ("goal_area_width", self.goal_area_width, pa_width),
            ]
        for name, value, limit in checks:
            if value >= limit:
                raise ValueError(f"FieldSpec.{name}={value} must be smaller than {limit}")

    @classmethod
    def kidsize(cls) -> FieldSpec:
        """The current KidSize field (the default)."""
        return cls()

    @classmethod
    def paper_2019(cls) -> FieldSpec:
        """The paper's Webots world (2019 rules): 1 m x 5 m goal area, no penalty area,
        0.7 m border strip."""
        return cls(
            goal_area_width=5.0,
            penalty_area_length=None,
            penalty_area_width=None,
            border_strip_width=0.7,
        )

    @property
    def half_length(self) -> float:
        return self.length / 2

    @property
    def half_width(self) -> float:
        return self.width / 2

    @property
    def carpet_half_extent(self) -> tuple[float, float]:
        """Half size of the green carpet (field plus border strip)."""
        return (
            self.half_length + self.border_strip_width,
            self.half_width + self.border_strip_width,
        )


FIELD_PRESETS = {"kidsize": FieldSpec.kidsize, "paper2019": FieldSpec.paper_2019}


def field_preset(name: str) -> FieldSpec:
    """Field by preset name (``kidsize`` or ``paper2019``)."""
    try:
        return FIELD_PRESETS[name]()
    except KeyError:
        raise ValueError(
            f"unknown field preset {name!r}; choose from {sorted(FIELD_PRESETS)}"
        ) from None
