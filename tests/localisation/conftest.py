"""Shared fixtures: the default KidSize field, camera and episode-start-like beliefs."""

from __future__ import annotations

import numpy as np
import pytest

from activevision.geometry import CameraConfig, FieldSpec, field_landmarks


@pytest.fixture(scope="session")
def field() -> FieldSpec:
    return FieldSpec()


@pytest.fixture(scope="session")
def landmarks(field):
    return field_landmarks(field)


@pytest.fixture(scope="session")
def cam() -> CameraConfig:
    return CameraConfig()


@pytest.fixture(scope="session")
def random_start():
    """``random_start(rng) -> (mean, ball)``: a robot on the field and a ball 1-3 m in front
    of it (within +-0.6 rad of the heading), on the field."""

    def draw(rng: np.random.Generator):
        while True:
            mean = np.array(
                [rng.uniform(-4.0, 4.0), rng.uniform(-2.6, 2.6), rng.uniform(-np.pi, np.pi)]
            )
            d, a = rng.uniform(1.0, 3.0), mean[2] + rng.uniform(-0.6, 0.6)
            ball = mean[:2] + d * np.array([np.cos(a), np.sin(a)])
            if abs(ball[0]) < 4.5 and abs(ball[1]) < 3.0:
                return mean, ball

    return draw
