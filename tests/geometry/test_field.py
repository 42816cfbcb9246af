import dataclasses

import numpy as np
import pytest

from activevision.geometry import (
    FieldSpec,
    LandmarkType,
    field_landmarks,
    field_preset,
    painted_lines,
)


def test_kidsize_landmark_counts_by_type():
    counts = field_landmarks(FieldSpec()).count_by_type()
    # Hand count on the 2025 field: 4 field corners + 4 goal-area + 4 penalty-area corners; T:
    # 4 goal-area + 4 penalty-area junctions on the goal lines + 2 at the halfway line; lines:
    # 2 touchlines, 2 goal lines, halfway, 3 per goal area and 3 per penalty area.
    assert counts == {
        LandmarkType.L_CORNER: 12,
        LandmarkType.T_JUNCTION: 10,
        LandmarkType.X_CROSSING: 2,
        LandmarkType.PENALTY_MARK: 2,
        LandmarkType.GOAL_POST: 4,
        LandmarkType.CENTRE_CIRCLE: 1,
        LandmarkType.LINE: 17,
        LandmarkType.FIELD_BOUNDARY: 4,
    }


def test_paper_2019_field_matches_the_release_counts():
    counts = field_landmarks(FieldSpec.paper_2019()).count_by_type()
    # The release's world: 8 L-corners and 6 T-junctions (no penalty area in 2019).
    assert counts[LandmarkType.L_CORNER] == 8
    assert counts[LandmarkType.T_JUNCTION] == 6
    assert counts[LandmarkType.FIELD_BOUNDARY] == 4


def test_landmarks_lie_on_the_carpet_and_are_symmetric():
    spec = FieldSpec()
    lm = field_landmarks(spec)
    bx, by = spec.carpet_half_extent
    assert np.all(np.abs(lm.segments[..., 0]) <= bx + 1e-12)
    assert np.all(np.abs(lm.segments[..., 1]) <= by + 1e-12)
    # Mirroring y -> -y maps the landmark set onto itself (the field is symmetric).
    points = lm.segments[lm.is_point, 0]
    mirrored = points * np.array([1, -1])
    for p in mirrored:
        assert np.min(np.linalg.norm(points - p, axis=1)) < 1e-12
    assert len(set(lm.names)) == len(lm)


def test_painted_lines_are_the_line_landmarks():
    spec = FieldSpec()
    lm = field_landmarks(spec)
    lines = lm.segments[lm.types == LandmarkType.LINE]
    painted = painted_lines(spec)
    assert len(painted) == len(lines)
    key = lambda s: tuple(np.round(np.sort(s.reshape(-1)), 9))  # noqa: E731
    assert sorted(map(key, painted)) == sorted(map(key, lines))


@pytest.mark.parametrize(
    ("change", "name"),
    [
        ({"length": -9.0}, "length"),
        ({"goal_area_width": 7.0}, "goal_area_width"),
        ({"penalty_area_width": 6.5}, "penalty_area_width"),
        ({"goal_width": float("nan")}, "goal_width"),
        ({"penalty_mark_distance": 5.0}, "penalty_mark_distance"),
    ],
)
def test_invalid_dimensions_name_the_field(change, name):
    with pytest.raises(ValueError, match=name):
        dataclasses.replace(FieldSpec(), **change)


def test_unknown_preset_is_a_clear_error():
    assert field_preset("paper2019").goal_area_width == 5.0
    with pytest.raises(ValueError, match="unknown field preset"):
        field_preset("spl")


def test_invalid_detection_range_is_rejected():
    with pytest.raises(ValueError, match="L_CORNER"):
        field_landmarks(FieldSpec(), {LandmarkType.L_CORNER: 0.0})
