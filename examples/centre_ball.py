"""An episodic head policy of your own, scored beside the built-in methods:

    activevision evaluate --strategy examples/centre_ball.py:CentreBall --episodes 20
    activevision compare --strategy examples/centre_ball.py:CentreBall --episodes 20

``activevision evaluate`` and ``compare`` call ``CentreBall(context)`` for each policy they
need (``context``: an :class:`~activevision.experiments.methods.MethodContext`, with the
episodes' ``config`` and the localisation ``error`` of the level played), then, as
:class:`~activevision.experiments.policies.HeadPolicy` says, ``reset(info, rng)`` at each
episode's start and ``act(obs, info)`` every step: one discrete action (an index into the
env's action table), or a :class:`~activevision.experiments.policies.HeadTarget` to jump
to. ``info`` is the env's (``ActiveVisionEnv``'s docstring); it holds the true ``pose``
and ``ball``, so a fair policy reads the pose through the localisation error, as this one
does.

This one keeps the ball in the middle of the image: the B-Human/NUbots scan without the
sweep, a lower bound for any policy that looks for landmarks.
"""

from __future__ import annotations

import numpy as np

from activevision.envs.actions import action_table
from activevision.envs.starts import corrupt_pose
from activevision.experiments.methods import MethodContext
from activevision.experiments.policies import greedy_action
from activevision.geometry.angles import wrap_angle


class CentreBall:
    name = "centre_ball"  #: its label in the table and the CSVs

    def __init__(self, context: MethodContext) -> None:
        self.config = context.config
        self.error = context.error
        self.table = action_table(self.config.step_deg, self.config.action_set)
        self.believed = np.zeros(3)

    def reset(self, info: dict, rng: np.random.Generator) -> None:
        self.believed = corrupt_pose(info["pose"], self.error, rng)

    def act(self, obs: object, info: dict) -> int:
        x, y, theta = self.believed
        dx, dy = np.asarray(info["ball"]) - (x, y)
        pan = wrap_angle(np.arctan2(dy, dx) - theta)
        tilt = np.arctan2(self.config.camera.camera_height, np.hypot(dx, dy))
        return greedy_action(info["head"], (pan, tilt), self.table)
