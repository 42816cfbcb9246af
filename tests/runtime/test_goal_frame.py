"""A goal head in the camera's frame (``goal_frame="camera"``): it names the goal's offset
from where the head points, on a grid of offsets, and the evidence reads each view's
log-probability at the view's offset from the head. Checked against hand-computed cases
and SciPy's grid interpolator."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator

from activevision.localisation import LocalisationConfig
from activevision.runtime.goal_evidence import (
    GoalEvidence,
    log_softmax,
    offset_axes,
    offset_count,
    offset_weights,
)

VIEWS = LocalisationConfig().grid.views  # the paper's 10 pans x 4 tilts
TABLE = np.radians([[0.0, 0.0], [3.0, 0.0], [-3.0, 0.0], [0.0, 3.0], [0.0, -3.0]])


def test_offsets_span_every_difference_of_two_views():
    pans, tilts = offset_axes(VIEWS)
    pan_values, tilt_values = np.unique(VIEWS[:, 0]), np.unique(VIEWS[:, 1])
    # hand-computed for the paper's grid: pans -90..90 deg every 20, so offsets -180..180
    np.testing.assert_allclose(np.degrees(pans), np.arange(-180.0, 181.0, 20.0), atol=1e-9)
    assert len(tilts) == 2 * len(tilt_values) - 1 == 7
    for a in pan_values:  # every difference of two pans lies on the axis
        assert np.abs(pans[:, None] - (a - pan_values)[None]).min(axis=0).max() < 1e-12
    for a in tilt_values:
        assert np.abs(tilts[:, None] - (a - tilt_values)[None]).min(axis=0).max() < 1e-12
    assert offset_count(VIEWS) == 19 * 7


def test_offset_weights_by_hand():
    pans, tilts = np.radians([-20.0, 0.0, 20.0]), np.radians([-10.0, 10.0])
    on_knot = offset_weights(np.radians([[0.0, 10.0]]), pans, tilts)[0]
    np.testing.assert_allclose(on_knot, [0, 0, 0, 1, 0, 0])  # pan-major: (1, 1) is index 3
    # a quarter of the way from pan 0 to 20 and halfway between the tilts
    between = offset_weights(np.radians([[5.0, 0.0]]), pans, tilts)[0]
    np.testing.assert_allclose(between, [0, 0, 0.375, 0.375, 0.125, 0.125])
    beyond = offset_weights(np.radians([[90.0, -50.0]]), pans, tilts)[0]  # clipped
    np.testing.assert_allclose(beyond, [0, 0, 0, 0, 1, 0])
    single = offset_weights(np.radians([[10.0, 3.0]]), pans, np.zeros(1))[0]
    np.testing.assert_allclose(single, [0, 0.5, 0.5])


def test_offset_weights_are_a_distribution_whose_mean_is_the_offset():
    pans, tilts = offset_axes(VIEWS)
    rng = np.random.default_rng(0)
    points = np.stack(
        [rng.uniform(pans[0], pans[-1], 500), rng.uniform(tilts[0], tilts[-1], 500)], axis=1
    )
    weights = offset_weights(points, pans, tilts)
    np.testing.assert_allclose(weights.sum(axis=1), 1.0)
    assert (weights >= 0).all() and ((weights > 0).sum(axis=1) <= 4).all()
    knots = np.stack(np.meshgrid(pans, tilts, indexing="ij"), axis=-1).reshape(-1, 2)
    np.testing.assert_allclose(weights @ knots, points, atol=1e-12)


def test_camera_frame_evidence_matches_scipys_interpolator():
    pans, tilts = offset_axes(VIEWS)
    rng = np.random.default_rng(1)
    logits = rng.normal(size=(6, offset_count(VIEWS))) * 3.0
    heads = np.stack([rng.uniform(-1.5, 1.5, 6), rng.uniform(0.0, 1.2, 6)], axis=1)
    evidence = GoalEvidence(6, VIEWS, TABLE, frame="camera")
    got = evidence.view_log_probs(logits, heads)
    for row in range(6):
        table = log_softmax(logits[row]).reshape(len(pans), len(tilts))
        reference = RegularGridInterpolator((pans, tilts), table, method="linear")
        gap = VIEWS - heads[row]
        gap = np.clip(gap, [pans[0], tilts[0]], [pans[-1], tilts[-1]])
        want = log_softmax(reference(gap))
        np.testing.assert_allclose(got[row], want, atol=1e-9)
        assert math.isclose(np.exp(got[row]).sum(), 1.0)


def test_camera_frame_evidence_names_one_goal_from_every_head():
    # logits that peak at the goal's offset from wherever the head is: the evidence names
    # the goal view from each head
    pans, tilts = offset_axes(VIEWS)
    goal = 23
    evidence = GoalEvidence(1, VIEWS, TABLE, frame="camera")
    heads = np.radians([[-80.0, 10.0], [-3.0, 45.0], [55.0, 20.0], [90.0, 60.0]])
    for head in heads:
        peak = offset_weights((VIEWS[goal] - head)[None], pans, tilts)
        logits = np.log(peak + 1e-6)
        target = evidence.target(logits, np.array([0]), head[None])
        np.testing.assert_allclose(target[0], VIEWS[goal])
        best_alone = int(np.argmax(evidence.view_log_probs(logits, head[None])[0]))
        assert best_alone == goal
    with pytest.raises(ValueError, match="frame"):
        GoalEvidence(1, VIEWS, TABLE, frame="world")  # type: ignore[arg-type]
