"""Batched simulation of N matches: the robot walks, the ball rolls, the head moves, the
detector sees landmarks and the UKF tracks the pose, every tick. Free of Gymnasium API (the
single and the vector env both drive this one class, so they agree by construction).

Every match draws from its own generator, the same amount every tick whatever happens, so
a match's trajectory depends only on its seed and its actions, not on the batch around it.
"""

from __future__ import annotations

import numpy as np

from activevision.envs.actions import action_table, check_actions
from activevision.envs.match.config import MatchConfig
from activevision.envs.match.detections import detect_kernel
from activevision.envs.match.dynamics import (
    apply_motion,
    move_relative,
    odometry_stds,
    roll_ball,
    to_robot_frame,
    walk_command,
)
from activevision.envs.robots import draw_robots
from activevision.geometry import clip_head, field_landmarks
from activevision.geometry.angles import wrap_angle
from activevision.geometry.field import LandmarkType
from activevision.geometry.kernels import ball_visible_mask, visible_mask
from activevision.geometry.occlusion import hidden_landmarks, hidden_points, robot_cylinders
from activevision.localisation import entropy
from activevision.localisation.tracking import Tracker
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
#: next waypoint (2) and its pause (1)
_EXTRA_UNIFORMS = 10
#: normals per tick besides the 2 K measurement draws: odometry (3), ball detector (2)
_EXTRA_NORMALS = 5


class MatchBatch:
    """State and dynamics of N matches at once."""

    def __init__(self, cfg: MatchConfig, num_envs: int) -> None:
        self.cfg = cfg
        self.n = num_envs
        self.landmarks = field_landmarks(cfg.field)
        self.renderer = Renderer(cfg.field, cfg.camera)
        self.actions = action_table(cfg.step_deg, "8way")
        self.tracker = Tracker(self.landmarks, cfg.tracker)
        k = self.k = len(self.landmarks)
        types = self.landmarks.types
        self._point_ids = np.flatnonzero(np.isin(types, [int(t) for t in _POINT_TYPES]))
        _, _, _, self._noise_table = landmark_fields(self.landmarks, cfg.tracker.ukf)
        self.pose = np.zeros((num_envs, 3))
        self.mean = np.zeros((num_envs, 3))
        self.cov = np.zeros((num_envs, 3, 3))
        self.gated_share = np.zeros(num_envs)
        self.head = np.zeros((num_envs, 2))
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
        self.hidden = np.zeros((num_envs, k), dtype=bool)
        self.looks = neutral_looks(num_envs)
        self.tone = np.repeat(identity_tone()[None], num_envs, axis=0)
        self._uniforms = np.zeros((num_envs, k + _EXTRA_UNIFORMS))
        self._normals = np.zeros((num_envs, 2 * k + _EXTRA_NORMALS))
        self._rngs: list[np.random.Generator] = [np.random.default_rng(0)] * num_envs

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
            if cfg.appearance.enabled:
                self.looks[slot] = draw_looks(cfg.appearance, rng)
        idx = np.asarray(indices, dtype=np.int64)
        self.mean[idx, 2] = wrap_angle(self.mean[idx, 2])
        self.cov[idx] = cfg.tracker.ukf.initial_cov
        self.gated_share[idx] = 0.0
        self.ball_velocity[idx] = 0.0
        self.last_move[idx] = 0.0
        self.pause[idx] = 0
        self.tick[idx] = 0
        self.accepted[idx] = 0
        self.gated[idx] = 0
        self.declared_lost[idx] = False
        self.detected[idx] = False
        if cfg.appearance.enabled:
            self.tone[idx] = tone_curves(self.looks[idx])
        self._update_hidden(idx)
        self.ball_seen[idx] = self._ball_visible(idx)
        # the ball's kick-off spot is known: the model starts at it
        self.ball_relative[idx] = to_robot_frame(self.ball[idx], self.pose[idx])
        self.ball_age[idx] = 0

    # ------------------------------------------------------------------ dynamics
    def step(self, actions: np.ndarray, active: np.ndarray | None = None) -> np.ndarray:
        """One tick of the matches ``active`` (all by default), each moving its head by its
        discrete action (:mod:`activevision.envs.actions`, ``step_deg`` per tick).
        Returns the rewards (N,)."""
        idx = np.arange(self.n) if active is None else np.flatnonzero(active)
        actions = check_actions(actions, len(self.actions), (self.n,))
        move = self.actions[actions[idx]]
        return self.move_head(idx, self.head[idx, 0] + move[:, 0], self.head[idx, 1] + move[:, 1])

    def move_head(self, idx: np.ndarray, pan: np.ndarray, tilt: np.ndarray) -> np.ndarray:
        """One tick of matches ``idx`` with their heads moved to ``(pan, tilt)`` (clipped to
        the limits). Returns the rewards (N,), 0 outside ``idx``."""
        reward = np.zeros(self.n)
        if not len(idx):
            return reward
        cfg = self.cfg
        self._draw(idx)
        uniforms, normals = self._uniforms[idx], self._normals[idx]
        k = self.k
        old = self.head[idx]
        self.head[idx] = np.column_stack(clip_head(pan, tilt, cfg.camera))
        self.last_move[idx] = self.head[idx] - old
        # our robot walks from what it believes, and drifts
        self._next_waypoints(idx, uniforms[:, k + 7 :])
        command = walk_command(
            self.mean[idx], self.waypoint[idx], self.pause[idx] > 0, cfg.walk, cfg.tick_seconds
        )
        self.pause[idx] = np.maximum(self.pause[idx] - 1, 0)
        true_step = (
            command + odometry_stds(command, cfg.tracker.ukf) * normals[:, 2 * k : 2 * k + 3]
        )
        carpet = cfg.field.carpet_half_extent
        pose = self.pose[idx]
        apply_motion(pose, true_step, carpet)
        self.pose[idx] = pose
        ball, velocity = self.ball[idx], self.ball_velocity[idx]
        roll_ball(
            ball,
            velocity,
            uniforms[:, k + 4 : k + 7],
            cfg.ball,
            cfg.tick_seconds,
            (cfg.field.half_length, cfg.field.half_width),
        )
        self.ball[idx], self.ball_velocity[idx] = ball, velocity
        if cfg.robots.max_count:
            self._update_hidden(idx)
        self._sense_and_track(idx, command, uniforms, normals)
        self.tick[idx] += 1
        reward[idx] = self._reward(idx)
        return reward

    def _draw(self, idx: np.ndarray) -> None:
        """This tick's random numbers of matches ``idx``: always the same count."""
        for i in idx:
            rng = self._rngs[i]
            rng.random(out=self._uniforms[i])
            rng.standard_normal(out=self._normals[i])

    def _next_waypoints(self, idx: np.ndarray, draws: np.ndarray) -> None:
        """A robot at its waypoint (by its belief) pauses, then walks to the next: a random
        one, or (``walk.target="ball"``) the ball's believed position."""
        cfg = self.cfg
        walk = cfg.walk
        hx, hy = cfg.field.half_length - walk.margin, cfg.field.half_width - walk.margin
        reached = np.hypot(*(self.waypoint[idx] - self.mean[idx, :2]).T) < walk.reach
        reached &= self.pause[idx] == 0
        slots = idx[reached]
        d = draws[reached]
        if walk.target == "ball":
            c, s = np.cos(self.mean[slots, 2]), np.sin(self.mean[slots, 2])
            rel = self.ball_relative[slots]
            self.waypoint[slots, 0] = self.mean[slots, 0] + c * rel[:, 0] - s * rel[:, 1]
            self.waypoint[slots, 1] = self.mean[slots, 1] + s * rel[:, 0] + c * rel[:, 1]
        else:
            self.waypoint[slots] = np.column_stack([hx * (2 * d[:, 0] - 1), hy * (2 * d[:, 1] - 1)])
        lo, hi = walk.pause_ticks
        self.pause[slots] = lo + np.floor(d[:, 2] * (hi - lo + 1)).astype(np.int64)
        if walk.target == "ball":  # a striker re-plans to the ball every tick it walks
            moving = idx[~reached]
            c, s = np.cos(self.mean[moving, 2]), np.sin(self.mean[moving, 2])
            rel = self.ball_relative[moving]
            self.waypoint[moving, 0] = self.mean[moving, 0] + c * rel[:, 0] - s * rel[:, 1]
            self.waypoint[moving, 1] = self.mean[moving, 1] + s * rel[:, 0] + c * rel[:, 1]

    def _sense_and_track(
        self, idx: np.ndarray, command: np.ndarray, uniforms: np.ndarray, normals: np.ndarray
    ) -> None:
        cfg, k = self.cfg, self.k
        det = cfg.detection
        visible = (
            visible_mask(
                self.landmarks, self.pose[idx], self.head[idx, 0], self.head[idx, 1], cfg.camera
            )
            & ~self.hidden[idx]
        )
        ids, z, _ = detect_kernel(
            visible,
            np.ascontiguousarray(self.pose[idx]),
            np.ascontiguousarray(self.head[idx, 0]),
            self.landmarks.segments,
            self.landmarks.max_distance,
            self.landmarks.types,
            self._noise_table,
            self._point_ids,
            np.ascontiguousarray(uniforms[:, :k]),
            np.ascontiguousarray(normals[:, : 2 * k].reshape(-1, k, 2)),
            np.ascontiguousarray(uniforms[:, k : k + 4]),
            (det.near, det.far, det.false_rate, cfg.camera.hfov / 2),
        )
        self.detected[idx] = False
        rows = np.repeat(idx, ids.shape[1])
        valid = ids.ravel() >= 0
        self.detected[rows[valid], ids.ravel()[valid]] = True
        mean, cov, share = self.mean[idx], self.cov[idx], self.gated_share[idx]
        stats = self.tracker.step(mean, cov, command, ids, z, share)
        self.mean[idx], self.cov[idx], self.gated_share[idx] = mean, cov, share
        self.accepted[idx] += stats.accepted
        self.gated[idx] += stats.gated
        self.declared_lost[idx] |= stats.declared_lost
        # the ball model: measured when seen, else carried along by odometry
        seen = self._ball_visible(idx)
        self.ball_seen[idx] = seen
        relative = move_relative(self.ball_relative[idx], command)
        measured = to_robot_frame(self.ball[idx], self.pose[idx])
        distance = np.hypot(measured[:, 0], measured[:, 1])
        noisy = measured + (det.ball_noise * distance)[:, None] * normals[:, 2 * k + 3 :]
        self.ball_relative[idx] = np.where(seen[:, None], noisy, relative)
        self.ball_age[idx] = np.where(seen, 0, self.ball_age[idx] + 1)

    def _reward(self, idx: np.ndarray) -> np.ndarray:
        r = self.cfg.reward
        if r.kind == "entropy":
            reward = -r.entropy_weight * self.entropy(idx)
        else:
            reward = -r.error_weight * self.position_error(idx)
        travel = np.degrees(np.hypot(self.last_move[idx, 0], self.last_move[idx, 1]))
        result: np.ndarray = reward + r.ball_weight * self.ball_seen[idx] - r.travel_weight * travel
        return result

    def _ball_visible(self, idx: np.ndarray) -> np.ndarray:
        cfg = self.cfg
        seen = ball_visible_mask(
            self.ball[idx],
            self.pose[idx],
            self.head[idx, 0],
            self.head[idx, 1],
            cfg.camera,
            cfg.field.ball_radius,
        )
        if cfg.robots.max_count:  # a robot between camera and ball hides it
            camera = np.column_stack(
                [self.pose[idx, :2], np.full(len(idx), cfg.camera.camera_height)]
            )
            points = np.column_stack([self.ball[idx], np.full(len(idx), cfg.field.ball_radius)])
            seen &= ~hidden_points(camera, points[:, None], self.cylinders(idx))[:, 0]
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
        what only the simulator knows (``pose``, ``ball``, the errors)."""
        return {
            "pose": self.pose.copy(),
            "belief_mean": self.mean.copy(),
            "belief_cov": self.cov.copy(),
            "entropy": self.entropy(),
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
            "tick": self.tick.copy(),
        }
