"""A head-control strategy of your own, benchmarked beside the built-in ones:

    activevision match --strategy examples/uncertainty_glance.py:UncertaintyGlance \
        --methods ball_track entropy_track --baseline ball_track --out my-match

``activevision match`` calls ``UncertaintyGlance(config)`` once (``config``: the matches'
:class:`~activevision.envs.match.config.MatchConfig`), then ``reset(n, rng)`` as ``n``
matches start together and ``act(obs, info)`` every tick: ``info`` holds arrays over the
matches (the env's docstring lists them under "Info"; a fair strategy reads only what the
robot knows: ``head``, ``belief_mean``, ``belief_cov``, ``ball_relative``, ``ball_age``),
``obs`` the camera images. It returns one action per match, of the match's kind: (N,) ints
(the 9 moves) or (N, 2) floats in [-1, 1] with ``--action-type continuous``;
``move_towards`` makes either from head targets.

This one watches the ball while the robot is sure where it stands, and looks for landmarks
when it is not: while the belief's position std (the UKF's own uncertainty) exceeds
``threshold_m``, it turns to the view that Algorithm 1 expects to shrink the belief most
among those that keep the ball in the image (``entropy_track``'s target, margin 0).
"""

from __future__ import annotations

import numpy as np

from activevision.envs.match.config import MatchConfig
from activevision.envs.match.heads import ball_direction, entropy_track_targets, move_towards
from activevision.geometry import field_landmarks

#: what the belief-based target is computed from: the robot's knowledge only
KNOWN = ("belief_mean", "belief_cov", "ball_relative")


class UncertaintyGlance:
    name = "uncertainty_glance"  #: its label in the table, the CSV and the figures

    def __init__(self, config: MatchConfig, threshold_m: float = 0.08) -> None:
        self.config = config
        self.threshold = threshold_m
        self.landmarks = field_landmarks(config.field)

    def reset(self, n: int, rng: np.random.Generator) -> None:
        pass  # nothing to remember between ticks

    def act(self, obs: object, info: dict[str, np.ndarray]) -> np.ndarray:
        targets = ball_direction(info, self.config)
        cov = info["belief_cov"]
        unsure = np.sqrt(cov[:, 0, 0] + cov[:, 1, 1]) > self.threshold
        if unsure.any():
            known = {key: info[key][unsure] for key in KNOWN}
            targets[unsure] = entropy_track_targets(known, self.config, 0.0, self.landmarks)
        return move_towards(info["head"], targets, self.config)
