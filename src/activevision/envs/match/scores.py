"""What a match scores, recorded tick by tick over matches played in lock-step: the metrics
of ``activevision match`` (``experiments.match``) and of a match student's validation
(``training.match_dagger``).

Per match:

* ``position_rmse`` (m) and ``heading_rmse`` (deg): root mean square of the belief's error
  over every tick;
* ``lost_share``: the share of ticks with the position error above :data:`LOST_M`;
* ``ball_in_view``: the share of ticks with the ball in the image;
* ``entropy``: the belief's mean entropy (nats);
* ``head_travel``: how far the head moved, degrees per second.
"""

from __future__ import annotations

import numpy as np

LOST_M = 0.5  #: position error (m) beyond which a robot counts as lost


class MatchScores:
    """The per-tick errors, ball sightings, entropies and head moves of ``matches`` matches
    of ``ticks`` ticks of ``tick_seconds``, and their total rewards."""

    def __init__(self, ticks: int, matches: int, tick_seconds: float) -> None:
        self.tick_seconds = tick_seconds
        self.position = np.zeros((ticks, matches))  #: position error (m) per tick and match
        self.heading = np.zeros((ticks, matches))
        self.ball = np.zeros((ticks, matches), dtype=bool)
        self.entropy = np.zeros((ticks, matches))
        self.travel = np.zeros((ticks, matches))
        self.reward = np.zeros(matches)  #: total reward per match
        self.ticks = 0

    def add(self, info: dict[str, np.ndarray], reward: np.ndarray) -> None:
        """One tick: the vector env's ``info`` and ``reward`` after a step."""
        t = self.ticks
        self.position[t] = info["position_error"]
        self.heading[t] = info["heading_error"]
        self.ball[t] = info["ball_in_view"]
        self.entropy[t] = info["entropy"]
        self.travel[t] = np.degrees(np.hypot(*info["head_move"].T))
        self.reward += reward
        self.ticks += 1

    def per_match(self) -> dict[str, np.ndarray]:
        """Every metric of the module docstring over the ticks recorded: name -> (matches,)."""
        t = self.ticks
        position = self.position[:t]
        return {
            "position_rmse": np.sqrt(np.mean(position**2, axis=0)),
            "heading_rmse": np.degrees(np.sqrt(np.mean(self.heading[:t] ** 2, axis=0))),
            "lost_share": np.mean(position > LOST_M, axis=0),
            "ball_in_view": np.mean(self.ball[:t], axis=0),
            "entropy": np.mean(self.entropy[:t], axis=0),
            "head_travel": self.travel[:t].sum(axis=0) / (t * self.tick_seconds),
        }


__all__ = ["LOST_M", "MatchScores"]
