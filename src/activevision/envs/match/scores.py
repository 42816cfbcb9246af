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

With kidnapping on (``MatchConfig.kidnap``), :meth:`MatchScores.kidnaps` follows every
kidnap: whether it left the robot lost, whether the lost detector fired, and how many ticks
until the error was back under :data:`LOST_M`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

LOST_M = 0.5  #: position error (m) beyond which a robot counts as lost


@dataclass(frozen=True)
class KidnapEvents:
    """Every kidnap of the matches recorded (``MatchConfig.kidnap``), each followed until
    the match's next kidnap or its end (its *window*)."""

    match: np.ndarray  #: (E,) the match it happened in
    tick: np.ndarray  #: (E,) the tick it happened in (0 = the first)
    #: (E,) bool: the position error was at least :data:`LOST_M` at the end of that tick
    lost: np.ndarray
    #: (E,) bool: the lost detector fired in its window (that tick included)
    detected: np.ndarray
    #: (E,) ticks from it to the first tick of its window whose error is under
    #: :data:`LOST_M` (0: that very tick); -1 where none is (not recovered)
    recovery_ticks: np.ndarray

    @property
    def recovered(self) -> np.ndarray:
        """(E,) bool: the error came back under :data:`LOST_M` within the window."""
        recovered: np.ndarray = self.recovery_ticks >= 0
        return recovered


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
        #: kidnapped, and the lost detector's alarm, per tick and match (kidnapping on only:
        #: the infos hold them then)
        self.kidnapped = np.zeros((ticks, matches), dtype=bool)
        self.alarm = np.zeros((ticks, matches), dtype=bool)
        self.kidnapping = False
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
        if "kidnapped" in info:
            self.kidnapping = True
            self.kidnapped[t] = info["kidnapped"]
            self.alarm[t] = info["lost_alarm"]
        self.ticks += 1

    def kidnaps(self) -> KidnapEvents | None:
        """Every kidnap over the ticks recorded, each followed to the next in its match or
        the last tick recorded; None where kidnapping was off."""
        if not self.kidnapping:
            return None
        t = self.ticks
        ticks, matches = np.nonzero(self.kidnapped[:t].T)[::-1]
        order = np.lexsort((ticks, matches))
        ticks, matches = ticks[order], matches[order]
        lost, detected = np.zeros(len(ticks), bool), np.zeros(len(ticks), bool)
        recovery = np.full(len(ticks), -1, dtype=np.int64)
        for e, (tick, match) in enumerate(zip(ticks, matches, strict=True)):
            later = ticks[(matches == match) & (ticks > tick)]
            end = int(later[0]) if len(later) else t
            errors = self.position[tick:end, match]
            lost[e] = errors[0] >= LOST_M
            detected[e] = self.alarm[tick:end, match].any()
            under = np.flatnonzero(errors < LOST_M)
            if len(under):
                recovery[e] = under[0]
        return KidnapEvents(matches, ticks, lost, detected, recovery)

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


__all__ = ["LOST_M", "KidnapEvents", "MatchScores"]
