"""Same seeds, same bytes for ``ActiveVisionMatch-v0``'s default world (no other robots):
observations, rewards and infos of the single and the native vector env against digests
stored on 2026-12-05, before our robot learned to give way to the others. A change to the
match physics must leave the empty field's matches unchanged; a change that is meant to
alter them must say so and store new digests."""

from __future__ import annotations

import pytest

import activevision.envs  # noqa: F401  (registers ActiveVisionMatch-v0)
from activevision.envs.match.config import BallConfig, MatchConfig, WalkConfig

from .test_digest import single_digest, vector_digest

MATCH = "ActiveVisionMatch-v0"

STORED = {
    "single": "6aed945434d4caa2d769a3ea9dc512705a0e2c28e6fb77962bb152447297996c",
    "vector": "87bcabd2c454f3930f07efcc981ea2c1264641d95efa820f63dee6fc2478c5c2",
    "striker": "e944a0ee9f4e29ca7eee2b0dfd991731d269278750f0b4770fd9cf03ac3783f9",
}

#: our robot walking onto the ball, which bounces off it: the empty field's other walk
STRIKER = MatchConfig(
    observation="image+head+belief",
    ticks=40,
    walk=WalkConfig(target="ball", ball_standoff=0.0),
    ball=BallConfig(kick_rate=0.05, bounces_off_own_robot=True),
)


@pytest.mark.parametrize(
    ("name", "digest"),
    [
        ("single", lambda: single_digest(70, MATCH, observation="image+head+belief", ticks=40)),
        ("vector", lambda: vector_digest(50, 4, MATCH, ticks=30)),
        ("striker", lambda: single_digest(70, MATCH, config=STRIKER)),
    ],
    ids=["single", "vector", "striker"],
)
def test_default_world_matches_the_stored_digest(name, digest):
    assert digest() == STORED[name]
