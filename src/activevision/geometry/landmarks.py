"""Every field landmark as data: id, type, geometry and detection range.

All landmarks share one representation, a ground segment ``(a, b)``: point landmarks
(corners, junctions, marks, posts, the circle's centre) have ``a == b``. Visibility and the
range-bearing measurement model then need one code path: the measured point is the closest
point of the (visible part of the) segment to the robot.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from activevision.geometry.field import DEFAULT_MAX_DISTANCE, FieldSpec, LandmarkType


@dataclass(frozen=True)
class LandmarkSet:
    """The landmarks of one field; row ``i`` of every array is landmark id ``i``."""

    names: tuple[str, ...]
    types: np.ndarray  #: (K,) int, LandmarkType values
    segments: np.ndarray  #: (K, 2, 2) float, endpoints (a, b) on the ground; a == b for points
    max_distance: np.ndarray  #: (K,) float, detection range (m)

    def __len__(self) -> int:
        return len(self.names)

    @property
    def ids(self) -> np.ndarray:
        return np.arange(len(self), dtype=np.int64)

    @property
    def is_point(self) -> np.ndarray:
        is_point: np.ndarray = np.all(self.segments[:, 0] == self.segments[:, 1], axis=1)
        return is_point

    def count_by_type(self) -> dict[LandmarkType, int]:
        return {t: int(np.sum(self.types == t)) for t in LandmarkType}


def _goal_end_features(
    spec: FieldSpec, s: float
) -> tuple[
    list[tuple[str, LandmarkType, tuple[float, float]]],
    list[tuple[str, tuple[float, float], tuple[float, float]]],
]:
    """Points and lines at the goal end with sign ``s`` (+1: +x goal)."""
    hl, hw = spec.half_length, spec.half_width
    side = "+x" if s > 0 else "-x"
    pts: list[tuple[str, LandmarkType, tuple[float, float]]] = []
    lines: list[tuple[str, tuple[float, float], tuple[float, float]]] = []
    for sy in (1.0, -1.0):
        y = "+y" if sy > 0 else "-y"
        pts.append((f"corner{side}{y}", LandmarkType.L_CORNER, (s * hl, sy * hw)))
        pts.append(
            (
                f"goal_area_corner{side}{y}",
                LandmarkType.L_CORNER,
                (s * (hl - spec.goal_area_length), sy * spec.goal_area_width / 2),
            )
        )
        pts.append(
            (
                f"goal_area_t{side}{y}",
                LandmarkType.T_JUNCTION,
                (s * hl, sy * spec.goal_area_width / 2),
            )
        )
        pts.append(
            (
                f"goal_post{side}{y}",
                LandmarkType.GOAL_POST,
                (s * hl, sy * (spec.goal_width + spec.post_diameter) / 2),
            )
        )
    pts.append(
        (
            f"penalty_mark{side}",
            LandmarkType.PENALTY_MARK,
            (s * (hl - spec.penalty_mark_distance), 0.0),
        )
    )
    lines.append((f"goal_line{side}", (s * hl, -hw), (s * hl, hw)))
    boxes = [("goal_area", spec.goal_area_length, spec.goal_area_width)]
    pa_length, pa_width = spec.penalty_area_length, spec.penalty_area_width
    if pa_length is not None and pa_width is not None:  # FieldSpec: both or neither
        boxes.append(("penalty_area", pa_length, pa_width))
        for sy in (1.0, -1.0):
            y = "+y" if sy > 0 else "-y"
            half = pa_width / 2
            pts.append(
                (
                    f"penalty_area_corner{side}{y}",
                    LandmarkType.L_CORNER,
                    (s * (hl - pa_length), sy * half),
                )
            )
            pts.append((f"penalty_area_t{side}{y}", LandmarkType.T_JUNCTION, (s * hl, sy * half)))
    for name, depth, width in boxes:
        x_front = s * (hl - depth)
        lines.append((f"{name}_front{side}", (x_front, -width / 2), (x_front, width / 2)))
        for sy in (1.0, -1.0):
            y = "+y" if sy > 0 else "-y"
            lines.append(
                (f"{name}_side{side}{y}", (x_front, sy * width / 2), (s * hl, sy * width / 2))
            )
    return pts, lines


def painted_lines(spec: FieldSpec) -> np.ndarray:
    """Centre lines of every straight painted line, (M, 2, 2); each is ``line_width`` wide."""
    hl, hw = spec.half_length, spec.half_width
    segs = [((-hl, hw), (hl, hw)), ((-hl, -hw), (hl, -hw)), ((0.0, -hw), (0.0, hw))]
    for s in (1.0, -1.0):
        segs += [(a, b) for _, a, b in _goal_end_features(spec, s)[1]]
    return np.asarray(segs, dtype=np.float64)


def field_landmarks(
    spec: FieldSpec, max_distance: Mapping[LandmarkType, float] | None = None
) -> LandmarkSet:
    """All landmarks of ``spec``: L-corners, T-junctions, X-crossings, penalty marks, goal
    posts, the centre circle (its centre), every straight line and the four edges of the
    carpet (the field boundary a robot sees as the end of the green)."""
    ranges = dict(DEFAULT_MAX_DISTANCE)
    if max_distance is not None:
        ranges.update(max_distance)
    for t, r in ranges.items():
        if not r > 0:
            raise ValueError(f"max_distance[{LandmarkType(t).name}] must be positive, got {r!r}")
    hl, hw = spec.half_length, spec.half_width
    radius = spec.centre_circle_diameter / 2
    pts: list[tuple[str, LandmarkType, tuple[float, float]]] = []
    lines: list[tuple[str, tuple[float, float], tuple[float, float]]] = []
    for s in (1.0, -1.0):
        p, ln = _goal_end_features(spec, s)
        pts += p
        lines += ln
    for sy in (1.0, -1.0):
        y = "+y" if sy > 0 else "-y"
        pts.append((f"halfway_t{y}", LandmarkType.T_JUNCTION, (0.0, sy * hw)))
        pts.append((f"centre_x{y}", LandmarkType.X_CROSSING, (0.0, sy * radius)))
        lines.append((f"touchline{y}", (-hl, sy * hw), (hl, sy * hw)))
    pts.append(("centre_circle", LandmarkType.CENTRE_CIRCLE, (0.0, 0.0)))
    lines.append(("halfway_line", (0.0, -hw), (0.0, hw)))

    bx, by = spec.carpet_half_extent
    boundary = [
        ("boundary+x", (bx, -by), (bx, by)),
        ("boundary-x", (-bx, -by), (-bx, by)),
        ("boundary+y", (-bx, by), (bx, by)),
        ("boundary-y", (-bx, -by), (bx, -by)),
    ]
    pts.sort(key=lambda p: (p[1], p[0]))
    names = [n for n, _, _ in pts] + [n for n, _, _ in lines] + [n for n, _, _ in boundary]
    types = [t for _, t, _ in pts] + [LandmarkType.LINE] * len(lines)
    types += [LandmarkType.FIELD_BOUNDARY] * len(boundary)
    segments = [(p, p) for _, _, p in pts] + [(a, b) for _, a, b in lines + boundary]
    types_arr = np.asarray(types, dtype=np.int64)
    return LandmarkSet(
        names=tuple(names),
        types=types_arr,
        segments=np.asarray(segments, dtype=np.float64),
        max_distance=np.asarray([ranges[LandmarkType(t)] for t in types_arr], dtype=np.float64),
    )
