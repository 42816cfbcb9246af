"""``ActiveVisionMatch-v0``: head control while the robot plays -- a continuing task."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from activevision.envs.actions import check_actions, check_continuous_actions, head_action_space
from activevision.envs.config import check_render_mode
from activevision.envs.match.config import MatchConfig
from activevision.envs.match.observations import (
    Observation,
    image_space,
    observation_space,
    observe,
    single,
)
from activevision.envs.match.simulation import MatchBatch
from activevision.envs.match.view import match_panel
from activevision.envs.reset_options import check_no_options
from activevision.envs.seeding import single_env_seed
from activevision.typecheck import config_from_dict, nested_configs


def resolve_match_config(
    config: MatchConfig | Mapping[str, Any] | None, overrides: dict[str, Any]
) -> MatchConfig:
    """``config`` (default :class:`MatchConfig()`) with the keyword ``overrides``; the config
    and nested configs among the overrides may come as JSON objects of their fields, as
    ``EnvSpec.to_json`` writes them (:func:`typecheck.nested_configs`)."""
    if config is None:
        config = MatchConfig()
    elif isinstance(config, Mapping):
        config = config_from_dict(MatchConfig, config, "config")
    elif not isinstance(config, MatchConfig):
        raise ValueError(f"config: expects MatchConfig or None, got {config!r}")
    return config.replace(**nested_configs(MatchConfig, overrides)) if overrides else config


class ActiveVisionMatchEnv(gym.Env):
    """
    ## Description
    The robot plays: it walks about a RoboCup KidSize field while the ball rolls and is
    kicked, and its head camera must keep its localisation good *and* the ball in sight,
    every control tick, for a whole match. The paper's task (``ActiveVision-v0``) is one
    frozen moment; this is the question a RoboCup team asks of its head control.

    Every tick (``tick_seconds``, the paper's 320 ms):

    1. the head moves by the action (the episodic env's 9 moves of ``step_deg``, 3 deg);
    2. our robot walks (:class:`WalkConfig`): to random waypoints, pausing at each, or to
       the ball (``walk.target="ball"``), planning from its *believed* pose at KidSize speed
       (0.2 m/s, 0.5 rad/s). Its true motion drifts from the commanded step with the UKF's
       odometry model (std proportional to distance walked and angle turned, plus a small
       slip per tick); the commanded step is its odometry. It gives way to the other
       robots: a step that would end within ``robots.min_spacing`` of one it does not make,
       but sidesteps round that robot (the step's part across the way to it, and half a
       step away from it, as long as the step; the sidestep is its odometry). Where no
       sidestep is left (the robot about straight ahead) or it too is blocked, it turns on
       the spot (its odometry the turn alone), giving up a waypoint that lies beyond that
       robot, or any where another robot blocked its sidestep (wedged between two), for a
       new one (walking to the ball, with the ball beyond it or so wedged, it walks to such
       a waypoint for a detour of 20 ticks, then to the ball again);
    3. the ball (:class:`BallConfig`) rolls with constant deceleration, bounces off the
       field lines, and is kicked at random times in random directions. It rolls through
       our own robot unless ``ball.bounces_off_own_robot`` (then it bounces off our body as
       off the others', and our robot walking into it pushes it);
    4. the detector (:class:`DetectionConfig`) sees the landmarks in view (the episodic
       env's visibility model; behind another robot they are hidden), each with a
       probability falling with range, with the UKF's own sensor noise, plus occasional
       false detections of point features;
    5. the UKF (:mod:`activevision.localisation.tracking`) predicts from odometry and
       updates with each detection, closest first, behind a chi-square validation gate; a
       run of gated detections makes the robot declare itself lost (kidnapped) and widen
       its belief;
    6. the robot's ball model takes the ball's measured position when it is in view, and is
       carried along by odometry when it is not.

    With kidnapping on (:class:`KidnapConfig`, ``kidnap``; off by default), before step 1
    of a tick our robot may be carried elsewhere, its belief and odometry told nothing: in
    each tick with probability ``kidnap.rate`` per minute of play (seeded, from a generator
    spawned from the match's own: until the first kidnap, the same match) and in each tick
    of ``kidnap.ticks`` (1 = the first), ``distance`` m (1-2, uniform) in a uniform
    direction, stopped at the walk's margin inside the field, and turned by up to ``turn``
    rad (0.8) either way. The lost detector (step 5) is what may notice; ``activevision
    match --kidnap`` scores how often it does and how soon the error is back under 0.5 m.
    Among other robots a kidnap keeps ours at least ``robots.min_spacing`` from each, as a
    walk does: a carry that would end nearer one is drawn again from the match's kidnap
    generator (16 draws in all), and where none is clear the robot is only turned where it
    stands.

    Other robots (``robots``; none by default) are placed as in the episodic env and hide
    the landmarks and the ball behind them (the sight line from the camera passes through
    a robot's body or head: :mod:`activevision.geometry.occlusion`). With
    ``others.speed > 0`` they walk between random waypoints, giving way to each other and
    to ours (:mod:`activevision.envs.match.others`), as ours gives way to them (step 2): no
    two robots ever end a tick within ``robots.min_spacing``; standing or walking, the ball
    bounces off them (step 3, after it rolled; its path in the tick is
    tested, so a fast ball does not pass through a body).

    ## Action Space
    ``Discrete(9)``: stay, then the 8 head moves of ``ActiveVision-v0`` (pan positive to the
    left, tilt positive down), clipped to the head's limits. ``action_type="continuous"``:
    ``Box(-1, 1, (2,), float32)``, the (pan, tilt) move as a fraction of ``max_move_deg``.

    ## Observation Space
    ``Box(0, 255, (1, 120, 160), uint8)``: the camera image. ``observation="image+head"``
    and ``"image+head+belief"`` give a ``Dict`` adding the head angles, then the belief's
    mean and std and the ball model (:mod:`activevision.envs.match.observations`).

    ## Rewards
    Per tick (:class:`MatchRewardConfig`): ``-0.1 H`` with ``H`` the belief's entropy in
    nats (``kind="error"``: ``-|position error|`` in m, a simulator-only signal), ``+0.5``
    with the ball in view, ``-0.005`` per degree the head moved.

    ## Starting State
    Our robot anywhere on the field (0.5 m inside the lines), any heading; its belief starts
    at a known kick-off position (std 10 cm, 3 deg). The ball anywhere on the field, at rest,
    its position known to the ball model. The head anywhere within its limits.

    ## Episode End
    Never terminates; truncates after ``ticks`` ticks (600: 3.2 minutes of play), or
    after ``max_episode_steps`` ticks if sooner: ``gymnasium.make`` and the sync and async
    ``make_vec`` modes apply it in Gymnasium's ``TimeLimit``, the native vector env itself.

    ## Info
    What the robot knows: ``belief_mean`` (3,), ``belief_cov`` (3, 3), ``entropy``,
    ``head``, ``head_move`` (rad this tick), ``ball_relative`` (robot frame, m),
    ``ball_age`` (ticks since seen), ``declared_lost`` (the lost detector fired at some
    tick of this match: it stays True after the robot recovers), ``detections_accepted``
    and ``detections_gated`` (cumulative). What only the simulator knows: ``pose``, ``ball``,
    ``position_error`` (m), ``heading_error`` (rad), ``ball_in_view``, ``detected_mask``
    ((K,) bool: landmarks detected this tick), ``waypoint``, ``robots`` ((R, 4): the other
    robots' ``x, y, height, grey``; height 0 marks an empty slot), ``tick``. With
    kidnapping on only (the default world's infos are what they were): ``kidnapped`` (our
    robot was carried elsewhere this tick: simulator only) and ``lost_alarm`` (the lost
    detector fired this tick: the robot knows).

    ## Arguments
    ``gymnasium.make("ActiveVisionMatch-v0", config=MatchConfig(...))`` or any
    :class:`MatchConfig` field as a keyword (``ticks=300``, ``step_deg=6.0``,
    ``observation="image+head+belief"``). ``gymnasium.make_vec(..., vectorization_mode=
    "vector_entry_point")`` gives the native batched env. A config, or a config keyword
    (``walk``, ``tracker``, ...), may also be a JSON object of its fields, as
    ``env.spec.to_json()`` writes it: ``gymnasium.make(EnvSpec.from_json(...))`` makes the
    same env.

    ## Version History
    * v0: initial release.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 3}

    def __init__(
        self,
        config: MatchConfig | None = None,
        render_mode: str | None = None,
        **config_overrides: Any,
    ) -> None:
        config = resolve_match_config(config, config_overrides)
        check_render_mode(render_mode, self.metadata["render_modes"])
        self.config = config
        self.render_mode = render_mode
        self.sim = MatchBatch(config, 1)
        self.action_space = head_action_space(config.action_type, len(self.sim.actions))
        self.observation_space = observation_space(config)
        self._frames = np.zeros((1, *image_space(config).shape), dtype=np.uint8)
        self._slot = np.zeros(1, dtype=np.int64)

    def reset(
        self, *, seed: int | None = None, options: dict | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        check_no_options(options)
        super().reset(seed=single_env_seed(seed))
        self.sim.reset(self._slot, [self.np_random])
        return self._observe(), self._info()

    def step(self, action: object) -> tuple[Observation, float, bool, bool, dict[str, Any]]:
        if self.config.action_type == "continuous":
            reward = self.sim.step(check_continuous_actions(action, (2,))[None])
        else:
            reward = self.sim.step(check_actions(action, len(self.sim.actions), ()).reshape(1))
        truncated = bool(self.sim.tick[0] >= self.config.ticks)
        return self._observe(), float(reward[0]), False, truncated, self._info()

    def _observe(self) -> Observation:
        self.sim.render(self._slot, out=self._frames[:, 0])
        return single(observe(self._frames, self.sim))

    def _info(self) -> dict[str, Any]:
        return {
            key: value[0].item() if value.ndim == 1 else value[0]
            for key, value in self.sim.info_arrays().items()
        }

    def render(self) -> np.ndarray | None:
        """With ``render_mode="rgb_array"``: an RGB picture of the last observation's camera
        image beside the match from above (the true robot and its view, the belief's
        2-sigma ellipse, the ball, the other robots), as ``activevision match``'s clip draws
        it; None otherwise."""
        if self.render_mode != "rgb_array":
            return None
        return match_panel(self.sim, 0, self._frames[0, 0])
