"""``ActiveVision-v0``: move a humanoid robot's head camera to the viewpoint that best
localises the robot while keeping the ball in view."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from activevision.envs.actions import (
    check_actions,
    check_continuous_actions,
    head_action_space,
    head_angle,
)
from activevision.envs.config import (
    EnvConfig,
    check_render_mode,
    resolve_config,
)
from activevision.envs.observations import (
    Observation,
    ObservationBuilder,
    image_space,
    observation_space,
    single,
)
from activevision.envs.reset_options import check_no_options
from activevision.envs.seeding import single_env_seed
from activevision.envs.simulation import EpisodeBatch, StepOutcome
from activevision.envs.time_limit import never, resolve_limit
from activevision.localisation import LocalisationConfig


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

    ``action_type="continuous"`` (the paper's future work): ``Box(-1, 1, (2,), float32)``,
    ``(pan, tilt)`` as a fraction of ``max_move_deg`` (10 degrees on each axis by default)
    per step. Everything else is the same: the reward compares the Euclidean (pan, tilt)
    distance in degrees to the goal before and after the move (so any move, however small,
    that brings the head closer earns +1; ``reward_resolution_deg`` sets a dead band), the
    success rule, the ball-lost rule and the 20-step limit.

    ## Observation Space
    ``Box(0, 255, (frame_stack, 120, 160), uint8)``: the latest ``frame_stack`` (default 1,
    the paper's input) 160 x 120 grayscale camera images, oldest first, channel-first.
    With ``observation="image+head"``, ``"image+head+pose"`` or
    ``"image+head+pose+proposal"`` a ``Dict`` of that image (key ``"image"``) and float32
    vectors: the head angles, the robot's prior pose, Algorithm 1's proposal from that prior
    and (``action_history``) the previous actions; :mod:`activevision.envs.observations`
    lists every entry. The prior pose is the believed pose, or with ``prior_error_range`` the
    true pose corrupted by an error drawn per episode, quantised to ``prior_grid``.

    ## A world beyond the paper's (off by default)
    ``appearance=AppearanceConfig(...)`` (:mod:`activevision.rendering.appearance`) draws a
    look per episode: illumination gain, offset, gamma and vignetting, Gaussian and shot
    noise, defocus, motion blur along the head's move of the step, carpet mowing stripes and
    grain, painted line width and wear, a hall beyond the carpet (advertising boards,
    spectators, walls), and the camera mounted off its model (height, tilt, field of view:
    the image changes, the robot's model of its camera, and so Algorithm 1, does not).
    ``AppearanceConfig.randomised()`` turns every factor on at its robust range.

    ``robots=RobotsConfig(count=(lo, hi))`` (:mod:`activevision.envs.robots`) stands 0-8
    other KidSize robots on the field per episode: a body cylinder and a narrower head, 0.4-1
    m tall, uniform on the field, at least ``min_spacing`` from each other and from ours.
    They are rendered, over lines, landmarks and the ball (painter's order), and they occlude:
    a landmark is *hidden* when the straight sight line from the camera's optical centre to
    every one of 17 points along it passes through a robot's body or head
    (:mod:`activevision.geometry.occlusion`; a line a robot crosses is still seen on either
    side). The camera sits above the robot's ground position whatever the head angles, so what
    is hidden is fixed for the episode: hidden landmarks are left out of Algorithm 1's UKF
    updates (the goal search), of ``observed_mask`` and ``desired_mask``, and so of the
    success rate and the landmark success rule. Robots that would hide the ball are placed
    again, so every start keeps the ball in view. ``info`` then also has ``robots`` ((R, 4):
    x, y, height, grey; height 0 marks an unused slot) and ``hidden_mask`` ((K,) bool).

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
    image. Truncates after 20 steps (``max_episode_steps`` of the registration), or after
    ``gymnasium.make``'s ``max_episode_steps=n`` (``-1``: never truncates; Gymnasium's
    ``TimeLimit`` wrapper).

    ## Info
    ``goal_viewpoint`` (pan, tilt rad), ``goal_entropy``, ``desired_mask`` and
    ``observed_mask`` (the goal view's and the current view's landmarks: (K,) bool over
    landmark ids, K the field's landmark count), ``success_rate`` (|observed ∩ desired| /
    |desired|), ``success``, ``ball_lost``, ``steps_to_success`` and ``ball_lost_step`` (the
    constructor's ``max_episode_steps`` if it did not happen: 20, or -1 for none; ``make``'s
    limit does not reach the env, see docs/design.md's known limitations), ``episode_score``
    (the release's: 1 success, 0 ball lost, else the success rate), ``head``, ``pose``,
    ``believed_pose``, ``ball``, ``step``; with a prior pose in the observation also
    ``prior_pose`` and ``prior_error``. Every value
    keeps its shape and type at every step (arrays float64 or bool; scalars Python float,
    int or bool), so ``gymnasium.make_vec`` stacks them in every vectorization mode.

    ## Arguments
    ``gymnasium.make("ActiveVision-v0", config=EnvConfig(...), localisation=..., render_mode=...)``
    or any :class:`EnvConfig` field as a keyword (``frame_stack=4``, ``success_mode=...``).
    A wrong type, a value out of range or an unknown keyword raises ``ValueError`` naming it.
    ``config``, ``localisation`` and the config keywords (``appearance``, ``robots``, ...)
    may also be JSON objects of their fields, as ``env.spec.to_json()`` writes them:
    ``gymnasium.make(EnvSpec.from_json(...))`` makes the same env.
    ``max_episode_steps`` of the constructor only sets the infos' "did not happen" value (the
    ``TimeLimit`` wrapper truncates; ``None`` is 20, ``-1`` none, as ``gymnasium.make`` reads
    it): ``TimeLimit(ActiveVisionEnv(max_episode_steps=n), n)`` agrees with itself.
    ``render_mode="rgb_array"`` returns the camera image beside a top view of the field.

    ## Version History
    * v0: initial release; later options (appearance, robots, Dict observations) default to
      the paper's world, whose observations are unchanged byte for byte.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 3}

    def __init__(
        self,
        config: EnvConfig | None = None,
        localisation: LocalisationConfig | None = None,
        render_mode: str | None = None,
        max_episode_steps: int | None = 20,
        **config_overrides: Any,
    ) -> None:
        config = resolve_config(config, config_overrides)
        check_render_mode(render_mode, self.metadata["render_modes"])
        self.config = config
        self.render_mode = render_mode
        # Only the info's "did not happen" value: the time limit itself is the TimeLimit
        # wrapper's, whose limit gymnasium.make does not pass on to the env.
        self.max_episode_steps = resolve_limit(max_episode_steps, 20)
        self.sim = EpisodeBatch(config, 1, localisation)
        self.action_space = head_action_space(config.action_type, len(self.sim.actions))
        self.observation_space = observation_space(config, len(self.sim.actions))
        self._observations = ObservationBuilder(config, 1, len(self.sim.actions))
        self._frames = np.zeros(image_space(config).shape, dtype=np.uint8)
        self._slot = np.zeros(1, dtype=np.int64)

    def reset(
        self, *, seed: int | None = None, options: dict | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        check_no_options(options)
        super().reset(seed=single_env_seed(seed))
        self.sim.reset(self._slot, [self.np_random])
        self._observations.start(self._slot)
        frame = self.sim.render(self._slot)[0]
        self._frames[:] = frame
        return self._observe(), self.sim.info(0, never(self.max_episode_steps))

    def step(self, action: object) -> tuple[Observation, float, bool, bool, dict[str, Any]]:
        if self.config.action_type == "continuous":
            return self._after_move(self.sim.step(check_continuous_actions(action, (2,))[None]))
        action = check_actions(action, len(self.sim.actions), ()).reshape(1)
        self._observations.record(action, self._slot)
        return self._after_move(self.sim.step(action))

    def jump_head(
        self, pan: float, tilt: float
    ) -> tuple[Observation, float, bool, bool, dict[str, Any]]:
        """Move the head straight to ``(pan, tilt)`` rad in one step (clipped to the limits),
        scored like :meth:`step`. Not part of the Gymnasium API: for baselines that jump the
        head, such as the paper's entropy-based head control. Each angle must be one finite
        number (a NaN head would fail every later step until a reset)."""
        target = [head_angle(name, value) for name, value in (("pan", pan), ("tilt", tilt))]
        return self._after_move(self.sim.move_head(self._slot, *target))

    def entropy_regret(self) -> float:
        """Belief entropy after the current view's landmarks minus the goal view's (nats;
        see :meth:`EpisodeBatch.entropy_regret`)."""
        return float(self.sim.entropy_regret(self._slot)[0])

    def _observe(self) -> Observation:
        if self.config.observation == "image":
            return self._frames.copy()
        sim = self.sim
        batch = self._observations.batch(self._frames[None], sim)
        return single(batch)

    def _after_move(
        self, outcome: StepOutcome
    ) -> tuple[Observation, float, bool, bool, dict[str, Any]]:
        reward, terminated, _, _ = outcome
        if self.config.frame_stack > 1:
            self._frames[:-1] = self._frames[1:]
        self.sim.render(self._slot, out=self._frames[-1:])
        info = self.sim.info(0, never(self.max_episode_steps))
        return self._observe(), float(reward[0]), bool(terminated[0]), False, info

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        from activevision.envs.view import episode_panel  # imports matplotlib: only here

        return episode_panel(self.sim, 0, self._frames[-1])
