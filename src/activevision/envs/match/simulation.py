"""Batched simulation of N matches: the robot walks, the ball rolls, the head moves, the
detector sees landmarks and the UKF tracks the pose, every tick. Free of Gymnasium API (the
single and the vector env both drive this one class, so they agree by construction).

Every match draws from its own generator, the same amount every tick whatever happens, so
a match's trajectory depends only on its seed and its actions, not on the batch around it.
"""

from __future__ import annotations

import numpy as np

from activevision.envs.actions import action_table, head_moves, require_reset
from activevision.envs.match.config import MATCH_ACTION_SET, MatchConfig
from activevision.envs.match.dynamics import to_robot_frame
from activevision.envs.match.kernels import MatchParams, MatchState, move_kernel, sense_kernel
from activevision.envs.match.others import bounce_ball, walk_others
from activevision.envs.robots import draw_robots
from activevision.geometry import field_landmarks
from activevision.geometry.angles import wrap_angle
from activevision.geometry.field import LandmarkType
from activevision.geometry.kernels import ball_visible_mask, camera_fields
from activevision.geometry.occlusion import hidden_landmarks, hidden_points, robot_cylinders
from activevision.localisation import entropy
from activevision.localisation.bundles import SigmaWeights
from activevision.localisation.sigma_points import NotPositiveDefiniteError, merwe_weights
from activevision.localisation.viewpoint import landmark_fields
from activevision.rendering import Renderer
from activevision.rendering.appearance import (
    LOOK,
    draw_looks,
    identity_tone,
    neutral_looks,
    tone_curves,
)

#: landmark types a false detection is taken for (point features: corners, junctions, marks)
_POINT_TYPES = (
    LandmarkType.L_CORNER,
    LandmarkType.T_JUNCTION,
    LandmarkType.X_CROSSING,
    LandmarkType.PENALTY_MARK,
)
#: uniforms drawn per match per tick besides the K miss draws: false detection (4), kick (3),
#: next waypoint (2) and its pause (1); then, when there are other robots, our robot's next
#: waypoint should it give way to one (2), and when they walk, a next waypoint (2) for each
#: of them
_EXTRA_UNIFORMS = 10
_GIVE_WAY_UNIFORMS = 2
#: normals per tick besides the 2 K measurement draws: odometry (3), ball detector (2)
_EXTRA_NORMALS = 5
#: uniforms per match per tick with kidnapping on, from the match's kidnap generator:
#: whether (1), how far, which way and how much it turns (3)
_KIDNAP_UNIFORMS = 4
#: carries a kidnap draws (the first from the tick's uniforms, the others two uniforms each
#: from the match's kidnap generator) for one that keeps ``robots.min_spacing`` from every
#: other robot; when none does, the robot is only turned where it stands
KIDNAP_TRIES = 16


def _child(rng: np.random.Generator) -> np.random.Generator:
    """A generator of its own for ``rng``'s match, spawned from its seed sequence (which
    draws nothing from ``rng``: its stream stays as it was); one without a seed sequence
    (made from a bare state) gives its child's seed from its stream instead."""
    try:
        return rng.spawn(1)[0]
    except TypeError:
        return np.random.default_rng(int(rng.integers(2**63)))


class MatchBatch:
    """State and dynamics of N matches at once."""

    def __init__(self, cfg: MatchConfig, num_envs: int) -> None:
        self.cfg = cfg
        self.n = num_envs
        self.landmarks = field_landmarks(cfg.field)
        self.renderer = Renderer(cfg.field, cfg.camera)
        self.actions = action_table(cfg.step_deg, MATCH_ACTION_SET)
        k = self.k = len(self.landmarks)
        types = self.landmarks.types
        self._point_ids = np.flatnonzero(np.isin(types, [int(t) for t in _POINT_TYPES]))
        self._landmark_fields = landmark_fields(self.landmarks, cfg.tracker.ukf)
        self._noise_table = self._landmark_fields[3]
        self.pose = np.zeros((num_envs, 3))
        self.mean = np.zeros((num_envs, 3))
        self.cov = np.zeros((num_envs, 3, 3))
        self.gated_share = np.zeros(num_envs)
        self.head = np.zeros((num_envs, 2))
        self.started = np.zeros(num_envs, dtype=bool)  #: reset at least once
        self.last_move = np.zeros((num_envs, 2))
        self.ball = np.zeros((num_envs, 2))
        self.ball_velocity = np.zeros((num_envs, 2))
        self.ball_seen = np.zeros(num_envs, dtype=bool)
        #: the robot's ball model: the ball in its own frame (m) and ticks since it was seen
        self.ball_relative = np.zeros((num_envs, 2))
        self.ball_age = np.zeros(num_envs, dtype=np.int64)
        self.waypoint = np.zeros((num_envs, 2))
        self.pause = np.zeros(num_envs, dtype=np.int64)
        self.tick = np.zeros(num_envs, dtype=np.int64)
        self.detected = np.zeros((num_envs, k), dtype=bool)
        self.accepted = np.zeros(num_envs, dtype=np.int64)
        self.gated = np.zeros(num_envs, dtype=np.int64)
        self.declared_lost = np.zeros(num_envs, dtype=bool)
        self.robots = np.zeros((num_envs, cfg.robots.max_count, 4))
        self.robot_waypoints = np.zeros((num_envs, cfg.robots.max_count, 2))
        #: ticks left on a detour from the walk to the ball (kernels.move_kernel)
        self.detour = np.zeros(num_envs, dtype=np.int64)
        #: the lost detector fired this tick; our robot was kidnapped this tick
        self.lost_alarm = np.zeros(num_envs, dtype=bool)
        self.kidnapped = np.zeros(num_envs, dtype=bool)
        #: kidnapping (MatchConfig.kidnap): its draws per tick come from a child of each
        #: match's generator, which leaves the match's own draws as they were: a kidnapped
        #: match is the same match as without it until its first kidnap
        self._kidnaps = cfg.kidnap.enabled
        self._kidnap_draws = np.zeros((num_envs, _KIDNAP_UNIFORMS))
        self._kidnap_rngs: list[np.random.Generator] = [np.random.default_rng(0)] * num_envs
        #: whether the other robots walk (then they draw their waypoints every tick)
        self._others_walk = cfg.robots.max_count > 0 and cfg.others.speed > 0
        self.hidden = np.zeros((num_envs, k), dtype=bool)
        self.looks = neutral_looks(num_envs)
        self.tone = np.repeat(identity_tone()[None], num_envs, axis=0)
        give_way_draws = _GIVE_WAY_UNIFORMS if cfg.robots.max_count else 0
        walker_draws = 2 * cfg.robots.max_count if self._others_walk else 0
        self._uniforms = np.zeros((num_envs, k + _EXTRA_UNIFORMS + give_way_draws + walker_draws))
        self._normals = np.zeros((num_envs, 2 * k + _EXTRA_NORMALS))
        self.reward = np.zeros(num_envs)
        self._rngs: list[np.random.Generator] = [np.random.default_rng(0)] * num_envs
        self._bundles(cfg)

    def _bundles(self, cfg: MatchConfig) -> None:
        """The kernels' bundles, built once (the state bundle holds this batch's arrays)."""
        ukf, tracker, walk, ball, det, r = (
            cfg.tracker.ukf,
            cfg.tracker,
            cfg.walk,
            cfg.ball,
            cfg.detection,
            cfg.reward,
        )
        field, cam = cfg.field, cfg.camera
        self._state = tuple(
            MatchState(
                self.pose,
                self.mean,
                self.cov,
                self.gated_share,
                self.head,
                self.last_move,
                self.ball,
                self.ball_velocity,
                self.ball_relative,
                self.ball_age,
                self.ball_seen,
                self.waypoint,
                self.pause,
                self.detected,
                self.accepted,
                self.gated,
                self.declared_lost,
                self.hidden,
                self.reward,
                self.robots,
                self.detour,
                self.lost_alarm,
            )
        )
        carpet = field.carpet_half_extent
        self._params = tuple(
            MatchParams(
                cfg.tick_seconds,
                walk.speed,
                walk.turn_rate,
                walk.reach,
                float(walk.pause_ticks[0]),
                float(walk.pause_ticks[1]),
                field.half_length - walk.margin,
                field.half_width - walk.margin,
                float(walk.target == "ball"),
                walk.ball_standoff,
                carpet[0],
                carpet[1],
                field.half_length,
                field.half_width,
                det.near,
                det.far,
                det.false_rate,
                cam.hfov / 2,
                det.ball_noise,
                field.ball_radius,
                cam.pan_min,
                cam.pan_max,
                cam.tilt_min,
                cam.tilt_max,
                float(r.kind == "entropy"),
                r.entropy_weight,
                r.error_weight,
                r.ball_weight,
                r.travel_weight,
                cfg.robots.min_spacing,
            )
        )
        Wm, Wc = merwe_weights(ukf.n, ukf.alpha, ukf.beta, ukf.kappa)
        self._weights = tuple(SigmaWeights(Wm, Wc, ukf.n + ukf.lambda_))
        self._model = (
            *ukf.odometry_base,
            ukf.odometry_translation_fraction,
            ukf.odometry_rotation_fraction,
        )
        self._tracker = (tracker.gate, tracker.lost_rate, tracker.lost_share, *tracker.lost_std)
        self._ball_model = (ball.deceleration, ball.kick_rate, *ball.kick_speed)
        self._camera = camera_fields(cam)

    # ------------------------------------------------------------------ starts
    def reset(self, indices: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """Start new matches in slots ``indices``, slot ``indices[j]`` drawing from
        ``rngs[j]`` for the whole match: our robot anywhere on the field (a known kick-off
        position: the belief starts at it with the tracker's initial std), the ball anywhere
        on the field, at rest, and the head anywhere in its limits."""
        cfg, cam = self.cfg, self.cfg.camera
        hx, hy = cfg.field.half_length - cfg.walk.margin, cfg.field.half_width - cfg.walk.margin
        std = np.array(cfg.tracker.ukf.initial_std)
        for j, slot in enumerate(np.asarray(indices, dtype=np.int64)):
            rng = self._rngs[slot] = rngs[j]
            if self._kidnaps:
                self._kidnap_rngs[slot] = _child(rng)
            u = rng.random(9)
            self.pose[slot] = (hx * (2 * u[0] - 1), hy * (2 * u[1] - 1), np.pi * (2 * u[2] - 1))
            self.ball[slot] = (
                cfg.field.half_length * (2 * u[3] - 1),
                cfg.field.half_width * (2 * u[4] - 1),
            )
            self.head[slot] = (
                cam.pan_min + (cam.pan_max - cam.pan_min) * u[5],
                cam.tilt_min + (cam.tilt_max - cam.tilt_min) * u[6],
            )
            self.waypoint[slot] = (hx * (2 * u[7] - 1), hy * (2 * u[8] - 1))
            self.mean[slot] = self.pose[slot] + std * rng.standard_normal(3)
            if cfg.robots.max_count:
                self.robots[slot] = draw_robots(
                    cfg.robots,
                    rng,
                    (cfg.field.half_length, cfg.field.half_width),
                    self.pose[slot, :2],
                    self.ball[slot],
                    cfg.field.ball_radius,
                    cam.camera_height,
                )
                # standing on their waypoints: each draws its first in the first tick
                self.robot_waypoints[slot] = self.robots[slot, :, :2]
            if cfg.appearance.enabled:
                self.looks[slot] = draw_looks(cfg.appearance, rng)
        idx = np.asarray(indices, dtype=np.int64)
        self.mean[idx, 2] = wrap_angle(self.mean[idx, 2])
        self.cov[idx] = cfg.tracker.ukf.initial_cov
        self.gated_share[idx] = 0.0
        self.ball_velocity[idx] = 0.0
        self.last_move[idx] = 0.0
        self.pause[idx] = 0
        self.detour[idx] = 0
        self.tick[idx] = 0
        self.accepted[idx] = 0
        self.gated[idx] = 0
        self.declared_lost[idx] = False
        self.lost_alarm[idx] = False
        self.kidnapped[idx] = False
        self.detected[idx] = False
        if cfg.appearance.enabled:
            self.tone[idx] = tone_curves(self.looks[idx])
        self._update_hidden(idx)
        self.ball_seen[idx] = self._ball_visible(idx)
        # the ball's kick-off spot is known: the model starts at it
        for slot in idx:
            self.ball_relative[slot] = to_robot_frame(
                self.ball[slot, 0], self.ball[slot, 1], self.pose[slot]
            )
        self.ball_age[idx] = 0
        self.reward[idx] = 0.0
        self.started[idx] = True

    # ------------------------------------------------------------------ dynamics
    def step(self, actions: np.ndarray, active: np.ndarray | None = None) -> np.ndarray:
        """One tick of the matches ``active`` (all by default), each moving its head by its
        action (:mod:`activevision.envs.actions`: discrete, or (N, 2) continuous).
        Returns the rewards (N,)."""
        idx = np.arange(self.n) if active is None else np.flatnonzero(active)
        cfg = self.cfg
        move = head_moves(actions, cfg.action_type, self.actions, cfg.max_move, self.n)[idx]
        return self.move_head(idx, self.head[idx, 0] + move[:, 0], self.head[idx, 1] + move[:, 1])

    def move_head(self, idx: np.ndarray, pan: np.ndarray, tilt: np.ndarray) -> np.ndarray:
        """One tick of matches ``idx`` with their heads moved to ``(pan, tilt)`` (clipped to
        the limits). Returns the rewards (N,), 0 outside ``idx``."""
        require_reset(self.started, idx)
        reward = np.zeros(self.n)
        if not len(idx):
            return reward
        idx = np.ascontiguousarray(idx, dtype=np.int64)
        self._draw(idx)
        if self._kidnaps:
            self._kidnap(idx)
        uniforms, normals = self._uniforms[idx], self._normals[idx]
        targets = np.ascontiguousarray(np.column_stack([pan, tilt]), dtype=np.float64)
        start = self.ball[idx]  # where the balls begin the tick: bounces test their path
        odometry = move_kernel(
            idx,
            targets,
            self._state,
            self._params,
            self._model,
            self._ball_model,
            uniforms,
            normals,
        )
        ball_hidden = np.zeros(len(idx), dtype=bool)
        if self.cfg.ball.bounces_off_own_robot:
            self._bounce_off_own_robot(idx, start)
        if self.cfg.robots.max_count:
            self._move_others(idx, uniforms, start)
            self._update_hidden(idx)
            ball_hidden = self._ball_hidden(idx)
        errors = sense_kernel(
            idx,
            odometry,
            self._state,
            self._params,
            self._landmark_fields,
            self._weights,
            self._camera,
            self._model,
            self._tracker,
            self._point_ids,
            ball_hidden,
            uniforms,
            normals,
        )
        if errors.any():
            bad = int(idx[np.flatnonzero(errors)[0]])
            raise NotPositiveDefiniteError(f"match {bad}: the belief lost positive definiteness")
        self.tick[idx] += 1
        reward[idx] = self.reward[idx]
        return reward

    def _move_others(self, idx: np.ndarray, uniforms: np.ndarray, start: np.ndarray) -> None:
        """The other robots of matches ``idx`` walk (when they do), then the balls that
        met them on their way from ``start`` (N, 2) bounce off."""
        cfg = self.cfg
        robots, ball, velocity = self.robots[idx], self.ball[idx], self.ball_velocity[idx]
        if self._others_walk:
            waypoints = self.robot_waypoints[idx]
            draws = uniforms[:, -2 * cfg.robots.max_count :].reshape(len(idx), -1, 2)
            walk_others(
                robots,
                waypoints,
                self.pose[idx, :2],
                draws,
                cfg.others.speed * cfg.tick_seconds,
                cfg.robots.min_spacing,
                (cfg.field.half_length, cfg.field.half_width),
            )
            self.robots[idx] = robots
            self.robot_waypoints[idx] = waypoints
        bounce_ball(
            ball,
            velocity,
            robots,
            cfg.robots.radius,
            cfg.field.ball_radius,
            cfg.others.ball_restitution,
            start,
        )
        self.ball[idx], self.ball_velocity[idx] = ball, velocity

    def _bounce_off_own_robot(self, idx: np.ndarray, start: np.ndarray) -> None:
        """The balls of matches ``idx`` that met our robot's body on their way from
        ``start`` (N, 2) bounce off it."""
        cfg = self.cfg
        ball, velocity = self.ball[idx], self.ball_velocity[idx]
        own = np.zeros((len(idx), 1, 4))
        own[:, 0, :2] = self.pose[idx, :2]
        own[:, 0, 2] = 1.0  # a used slot (bounce_ball reads no more of it)
        bounce_ball(
            ball,
            velocity,
            own,
            cfg.robots.radius,
            cfg.field.ball_radius,
            cfg.others.ball_restitution,
            start,
        )
        self.ball[idx], self.ball_velocity[idx] = ball, velocity

    def _draw(self, idx: np.ndarray) -> None:
        """This tick's random numbers of matches ``idx``: always the same count."""
        for i in idx:
            rng = self._rngs[i]
            rng.random(out=self._uniforms[i])
            rng.standard_normal(out=self._normals[i])
            if self._kidnaps:
                self._kidnap_rngs[i].random(out=self._kidnap_draws[i])

    def _kidnap(self, idx: np.ndarray) -> None:
        """Kidnap our robot in the matches of ``idx`` whose draw or tick says so
        (:class:`~activevision.envs.match.config.KidnapConfig`), before the tick's moves:
        carried and turned, its belief and odometry told nothing."""
        cfg, kidnap = self.cfg, self.cfg.kidnap
        u = self._kidnap_draws[idx]
        chance = kidnap.rate * cfg.tick_seconds / 60.0
        now = (u[:, 0] < chance) | np.isin(self.tick[idx] + 1, kidnap.ticks)
        self.kidnapped[idx] = now
        if not now.any():
            return
        slots, u = idx[now], u[now]
        pose = self.pose[slots]
        carried = self._carried(pose[:, :2], u[:, 1], u[:, 2])
        if cfg.robots.max_count:  # never within the spacing of another robot
            for j in np.flatnonzero(self._crowded(slots, carried)):
                carried[j] = self._free_carry(int(slots[j]), pose[j, :2])
        pose[:, :2] = carried
        pose[:, 2] = wrap_angle(pose[:, 2] + kidnap.turn * (2 * u[:, 3] - 1))
        self.pose[slots] = pose

    def _carried(self, xy: np.ndarray, far: np.ndarray, way: np.ndarray) -> np.ndarray:
        """Where kidnaps carry robots from ``xy`` (n, 2), by uniforms ``far`` (how far,
        within ``kidnap.distance``) and ``way`` (which way) (n,): stopped at the walk's
        margin inside the field lines."""
        cfg = self.cfg
        low, high = cfg.kidnap.distance
        distance, heading = low + (high - low) * far, 2 * np.pi * way
        hx, hy = cfg.field.half_length - cfg.walk.margin, cfg.field.half_width - cfg.walk.margin
        return np.column_stack(
            [
                np.clip(xy[:, 0] + distance * np.cos(heading), -hx, hx),
                np.clip(xy[:, 1] + distance * np.sin(heading), -hy, hy),
            ]
        )

    def _crowded(self, slots: np.ndarray, xy: np.ndarray) -> np.ndarray:
        """Whether ``xy`` (n, 2), our robot's place in each match of ``slots``, lies within
        ``robots.min_spacing`` of another robot's centre (n,)."""
        robots = self.robots[slots]
        gap = np.hypot(robots[..., 0] - xy[:, None, 0], robots[..., 1] - xy[:, None, 1])
        crowded: np.ndarray = ((gap < self.cfg.robots.min_spacing) & (robots[..., 2] > 0)).any(1)
        return crowded

    def _free_carry(self, slot: int, xy: np.ndarray) -> np.ndarray:
        """A kidnap's place for match ``slot``'s robot, at ``xy`` (2,), whose first draw came
        within the spacing of another robot: drawn again from the match's kidnap generator
        (up to :data:`KIDNAP_TRIES` draws in all) until one keeps the spacing; where none
        does (robots all round), ``xy``, where it stands and the spacing holds (no walk
        ends a tick within it)."""
        rng, slots = self._kidnap_rngs[slot], np.array([slot])
        for _ in range(KIDNAP_TRIES - 1):
            far, way = rng.random((2, 1))
            carried = self._carried(xy[None], far, way)
            if not self._crowded(slots, carried)[0]:
                return np.asarray(carried[0])
        return xy

    def _ball_hidden(self, idx: np.ndarray) -> np.ndarray:
        """Whether another robot stands between each camera of ``idx`` and its ball."""
        cfg = self.cfg
        camera = np.column_stack([self.pose[idx, :2], np.full(len(idx), cfg.camera.camera_height)])
        points = np.column_stack([self.ball[idx], np.full(len(idx), cfg.field.ball_radius)])
        hidden: np.ndarray = hidden_points(camera, points[:, None], self.cylinders(idx))[:, 0]
        return hidden

    def _ball_visible(self, idx: np.ndarray) -> np.ndarray:
        cfg = self.cfg
        seen: np.ndarray = ball_visible_mask(
            self.ball[idx],
            self.pose[idx],
            self.head[idx, 0],
            self.head[idx, 1],
            cfg.camera,
            cfg.field.ball_radius,
        )
        if cfg.robots.max_count:  # a robot between camera and ball hides it
            seen &= ~self._ball_hidden(idx)
        return seen

    def _update_hidden(self, idx: np.ndarray) -> None:
        if not self.cfg.robots.max_count or not len(idx):
            return
        camera = np.column_stack(
            [self.pose[idx, :2], np.full(len(idx), self.cfg.camera.camera_height)]
        )
        self.hidden[idx] = hidden_landmarks(self.landmarks, camera, self.cylinders(idx))

    def cylinders(self, idx: np.ndarray) -> np.ndarray:
        """The other robots of slots ``idx`` as the renderer's cylinders."""
        return robot_cylinders(self.robots[idx], self.cfg.robots.radius)

    # ------------------------------------------------------------------ measures
    def entropy(self, idx: np.ndarray | None = None) -> np.ndarray:
        """Entropy (nats) of the beliefs of slots ``idx``."""
        idx = np.arange(self.n) if idx is None else idx
        return np.asarray(entropy(self.cov[idx]), dtype=np.float64).reshape(len(idx))

    def position_error(self, idx: np.ndarray | None = None) -> np.ndarray:
        """Distance (m) between the believed and the true position."""
        idx = np.arange(self.n) if idx is None else idx
        d = self.mean[idx, :2] - self.pose[idx, :2]
        return np.asarray(np.hypot(d[:, 0], d[:, 1]))

    def heading_error(self, idx: np.ndarray | None = None) -> np.ndarray:
        """Absolute heading error (rad) of the beliefs."""
        idx = np.arange(self.n) if idx is None else idx
        error: np.ndarray = np.abs(wrap_angle(self.mean[idx, 2] - self.pose[idx, 2]))
        return error

    # ------------------------------------------------------------------ outputs
    def render(self, idx: np.ndarray | None = None, out: np.ndarray | None = None) -> np.ndarray:
        """Camera images (len(idx), H, W) uint8 of the true poses and heads."""
        idx = np.arange(self.n) if idx is None else idx
        looks = None
        if self.cfg.appearance.enabled:
            looks = self.looks[idx]
            looks[:, LOOK["move_pan"]] = self.last_move[idx, 0]
            looks[:, LOOK["move_tilt"]] = self.last_move[idx, 1]
            looks[:, LOOK["frame"]] = self.tick[idx]
        return self.renderer.render(
            self.pose[idx],
            self.head[idx, 0],
            self.head[idx, 1],
            self.ball[idx],
            out=out,
            looks=looks,
            tone=None if looks is None else self.tone[idx],
            cylinders=self.cylinders(idx) if self.cfg.robots.max_count else None,
        )

    def info_arrays(self) -> dict[str, np.ndarray]:
        """Per-slot facts as arrays over all N slots (the env's Info section): what the robot
        knows (``belief_mean``, ``belief_cov``, ``head``, ``ball_relative``, ``ball_age``) and
        what only the simulator knows (``pose``, ``ball``, the errors). A slot never reset
        (a vector env's first reset with a ``reset_mask``) reports entropy 0: its belief is
        the zeros the state starts as, whose entropy does not exist."""
        started = np.flatnonzero(self.started)
        entropies = np.zeros(self.n)
        entropies[started] = self.entropy(started)
        return {
            "pose": self.pose.copy(),
            "belief_mean": self.mean.copy(),
            "belief_cov": self.cov.copy(),
            "entropy": entropies,
            "position_error": self.position_error(),
            "heading_error": self.heading_error(),
            "head": self.head.copy(),
            "head_move": self.last_move.copy(),
            "ball": self.ball.copy(),
            "ball_in_view": self.ball_seen.copy(),
            "ball_relative": self.ball_relative.copy(),
            "ball_age": self.ball_age.copy(),
            "detected_mask": self.detected.copy(),
            "detections_accepted": self.accepted.copy(),
            "detections_gated": self.gated.copy(),
            "declared_lost": self.declared_lost.copy(),
            "waypoint": self.waypoint.copy(),
            "robots": self.robots.copy(),
            "tick": self.tick.copy(),
            # with kidnapping on only: the default world's infos stay what they were
            **(
                {"kidnapped": self.kidnapped.copy(), "lost_alarm": self.lost_alarm.copy()}
                if self._kidnaps
                else {}
            ),
        }
