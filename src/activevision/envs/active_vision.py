"""``ActiveVision-v0``: move a humanoid robot's head camera to the viewpoint that best
localises the robot while keeping the ball in view."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from activevision.envs.actions import check_actions
from activevision.envs.config import EnvConfig, check_count, resolve_config
from activevision.envs.simulation import EpisodeBatch, StepOutcome
from activevision.localisation import LocalisationConfig


def observation_space(cfg: EnvConfig) -> spaces.Box:
    shape = (cfg.frame_stack, cfg.camera.height, cfg.camera.width)
    return spaces.Box(0, 255, shape, dtype=np.uint8)


class ActiveVisionEnv(gym.Env):
    """
    ## Description
    The active-vision task of Khatibi et al., "Learning Where to Look: Active Vision for
    Humanoid Soccer Robots" (DDQN + PER). A humanoid robot stands on a RoboCup KidSize field
    with the ball in view. At the start of each episode the goal viewpoint is computed by the
    paper's Algorithm 1: of 10 x 4 candidate (pan, tilt) head poses, the one whose visible
    landmarks minimise the entropy of the UKF pose belief and that still shows the ball. The
    agent sees only the head camera's grayscale image and moves the head in 3 degree steps.

    ## Action Space
    ``Discrete(9)`` (``Discrete(5)`` with ``action_set="4way"``); pan positive to the left,
    tilt positive down; diagonals move ``3 * sqrt(2) / 2`` degrees on each axis:

    | Num | Action              | Num | Action               |
    |-----|---------------------|-----|----------------------|
    | 0   | stay                | 5   | pan left, tilt up    |
    | 1   | pan left            | 6   | pan left, tilt down  |
    | 2   | pan right           | 7   | pan right, tilt up   |
    | 3   | tilt up             | 8   | pan right, tilt down |
    | 4   | tilt down           |     |                      |

    Head angles are clipped to pan [-90, 90] and tilt [5, 65] degrees. An action outside the
    space raises ``ValueError``.

    ## Observation Space
    ``Box(0, 255, (frame_stack, 120, 160), uint8)``: the latest ``frame_stack`` (default 1,
    the paper's input) 160 x 120 grayscale camera images, oldest first, channel-first.

    ## Rewards
    ``+1`` when the action brings the head closer to the goal viewpoint (Euclidean distance in
    (pan, tilt) degrees), ``-1`` when it moves away, ``0`` otherwise; ``-2`` when the ball
    leaves the image. The paper prints ``sign(D' - D)``; that sign is a slip, its text (and
    this environment) rewards getting closer: ``sign(D - D')``.

    ## Starting State
    Robot at x ~ U(-3, 3) m, y ~ U(-1.5, 1.5) m, heading ~ U(-pi, pi); head pan ~ U(-90, 90)
    deg, tilt ~ U(5, 25) deg; the ball 1-3 m away, on the field and in view (the release).
    The goal is searched from the believed pose (true pose plus ``localisation_error``).
    Starts where no viewpoint shows the ball, the goal view shows no landmark, or the start
    already counts as success are redrawn.

    ## Episode End
    Terminates with success when the head is within ``success_tolerance_deg`` (3 deg, one
    action step) of the goal viewpoint (``success_mode="landmarks"``: when every landmark of
    the goal view is in view, the release's rule), and with failure when the ball leaves the
    image. Truncates after 20 steps (``max_episode_steps`` of the registration).

    ## Info
    ``goal_viewpoint`` (pan, tilt rad), ``goal_entropy``, ``desired_mask`` and
    ``observed_mask`` (the goal view's and the current view's landmarks: (K,) bool over
    landmark ids, K the field's landmark count), ``success_rate`` (|observed ∩ desired| /
    |desired|), ``success``, ``ball_lost``, ``steps_to_success`` and ``ball_lost_step`` (20
    if it did not happen), ``episode_score`` (the release's: 1 success, 0 ball lost, else the
    success rate), ``head``, ``pose``, ``believed_pose``, ``ball``, ``step``. Every value
    keeps its shape and type at every step (arrays float64 or bool; scalars Python float,
    int or bool), so ``gymnasium.make_vec`` stacks them in every vectorization mode.

    ## Arguments
    ``gymnasium.make("ActiveVision-v0", config=EnvConfig(...), localisation=..., render_mode=...)``
    or any :class:`EnvConfig` field as a keyword (``frame_stack=4``, ``success_mode=...``).
    A wrong type, a value out of range or an unknown keyword raises ``ValueError`` naming it.
    ``render_mode="rgb_array"`` returns the camera image beside a top view of the field.

    ## Version History
    * v0: initial release.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 3}

    def __init__(
        self,
        config: EnvConfig | None = None,
        localisation: LocalisationConfig | None = None,
        render_mode: str | None = None,
        max_episode_steps: int = 20,
        **config_overrides: Any,
    ) -> None:
        config = resolve_config(config, config_overrides)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode: expects one of {self.metadata['render_modes']} or None, "
                f"got {render_mode!r}"
            )
        self.config = config
        self.render_mode = render_mode
        # Only the info's "did not happen" value: the time limit is gymnasium.make's TimeLimit.
        self.max_episode_steps = check_count("max_episode_steps", max_episode_steps)
        self.sim = EpisodeBatch(config, 1, localisation)
        self.observation_space = observation_space(config)
        self.action_space = spaces.Discrete(len(self.sim.actions))
        self._frames = np.zeros(self.observation_space.shape, dtype=np.uint8)
        self._slot = np.zeros(1, dtype=np.int64)

    def reset(
        self, *, seed: int | None = None, options: dict | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self.sim.reset(self._slot, [self.np_random])
        frame = self.sim.render(self._slot)[0]
        self._frames[:] = frame
        return self._frames.copy(), self.sim.info(0, self.max_episode_steps)

    def step(self, action: object) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        action = check_actions(action, len(self.sim.actions), ())
        return self._after_move(self.sim.step(action.reshape(1)))

    def jump_head(
        self, pan: float, tilt: float
    ) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Move the head straight to ``(pan, tilt)`` rad in one step (clipped to the limits),
        scored like :meth:`step`. Not part of the Gymnasium API: for baselines that jump the
        head, such as the paper's entropy-based head control."""
        return self._after_move(self.sim.move_head(self._slot, np.array([pan]), np.array([tilt])))

    def _after_move(
        self, outcome: StepOutcome
    ) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        reward, terminated, _, _ = outcome
        if self.config.frame_stack > 1:
            self._frames[:-1] = self._frames[1:]
        self.sim.render(self._slot, out=self._frames[-1:])
        info = self.sim.info(0, self.max_episode_steps)
        return self._frames.copy(), float(reward[0]), bool(terminated[0]), False, info

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        from activevision.envs.view import episode_panel  # imports matplotlib: only here

        return episode_panel(self.sim, 0, self._frames[-1])
