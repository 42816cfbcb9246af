"""Batched simulation of N ActiveVision episodes: the task itself, free of Gymnasium API.

Both :class:`~activevision.envs.active_vision.ActiveVisionEnv` (N = 1) and the native
vector environment drive this one class, so a vector environment and N single environments
with the same seeds produce identical trajectories by construction. Each episode draws from
its own generator; nothing here touches global random state.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from activevision.envs.actions import action_table, head_moves, require_reset
from activevision.envs.config import EnvConfig
from activevision.envs.reward import approach_reward, viewpoint_distance_deg
from activevision.envs.robots import draw_robots
from activevision.envs.starts import StartGenerationError, corrupt_pose, draw_starts, quantise_pose
from activevision.geometry import clip_head, field_landmarks
from activevision.geometry.kernels import ball_visible_mask, visible_mask
from activevision.geometry.occlusion import hidden_landmarks, robot_cylinders
from activevision.localisation import (
    LocalisationConfig,
    ViewpointBatch,
    best_viewpoints,
    check_grid_reachable,
    entropy,
    hx_range_bearing,
    ukf_update_sequential,
)
from activevision.rendering import Renderer
from activevision.rendering.appearance import (
    LOOK,
    draw_looks,
    identity_tone,
    neutral_looks,
    tone_curves,
)
from activevision.typecheck import config_from_dict

#: ``(reward, terminated, success, ball_lost)``, each (N,): the outcome of one step.
StepOutcome = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


class EpisodeBatch:
    """State and dynamics of N episodes at once (true pose, belief, head, ball, goal)."""

    def __init__(
        self,
        cfg: EnvConfig,
        num_envs: int,
        localisation: LocalisationConfig | Mapping[str, Any] | None = None,
    ) -> None:
        if isinstance(localisation, Mapping):  # a JSON object, as EnvSpec.to_json writes it
            localisation = config_from_dict(LocalisationConfig, localisation, "localisation")
        if localisation is not None and not isinstance(localisation, LocalisationConfig):
            raise ValueError(
                f"localisation: expects LocalisationConfig or None, got {localisation!r}"
            )
        self.cfg = cfg
        self.n = num_envs
        # the candidate views span this camera's head limits (the paper's grid for its camera)
        self.localisation = localisation or LocalisationConfig.for_camera(cfg.camera)
        check_grid_reachable(self.localisation.grid, cfg.camera)
        self.landmarks = field_landmarks(cfg.field)
        self.renderer = Renderer(cfg.field, cfg.camera)
        self.actions = action_table(cfg.step_deg, cfg.action_set)
        k = len(self.landmarks)
        self.pose = np.zeros((num_envs, 3))
        self.believed_pose = np.zeros((num_envs, 3))
        # (pan, tilt) pairs; the pan/tilt properties are views of their columns
        self.head = np.zeros((num_envs, 2))
        self.ball = np.zeros((num_envs, 2))
        self.goal = np.zeros((num_envs, 2))
        self.goal_entropy = np.zeros(num_envs)
        self.desired = np.zeros((num_envs, k), dtype=bool)
        self.observed = np.zeros((num_envs, k), dtype=bool)
        self.step_count = np.zeros(num_envs, dtype=np.int64)
        self.success_step = np.full(num_envs, -1, dtype=np.int64)
        self.ball_lost_step = np.full(num_envs, -1, dtype=np.int64)
        self.episode_reward = np.zeros(num_envs)
        # What the robot knows of itself (Dict observations only): a prior pose, its error
        # and Algorithm 1's view from it, (pan, tilt, found).
        self.prior_pose = np.zeros((num_envs, 3))
        self.prior_error = np.zeros(num_envs)
        self.proposal = np.zeros((num_envs, 3))
        # The world beyond the paper's (off by default): other robots (x, y, height, grey),
        # the landmarks they hide, and each episode's look (rendering.appearance).
        self.robots = np.zeros((num_envs, cfg.robots.max_count, 4))
        self.hidden = np.zeros((num_envs, k), dtype=bool)
        self.looks = neutral_looks(num_envs)
        self.tone = np.repeat(identity_tone()[None], num_envs, axis=0)
        self.last_move = np.zeros((num_envs, 2))
        self.started = np.zeros(num_envs, dtype=bool)  #: reset at least once

    # Views of the (pan, tilt) columns, made on each access: views kept as attributes
    # would become copies in a deepcopy or pickle of the batch (and its env), which then
    # moved its head without rendering the move.
    @property
    def pan(self) -> np.ndarray:
        return self.head[:, 0]

    @property
    def tilt(self) -> np.ndarray:
        return self.head[:, 1]

    @property
    def goal_pan(self) -> np.ndarray:
        return self.goal[:, 0]

    @property
    def goal_tilt(self) -> np.ndarray:
        return self.goal[:, 1]

    # ------------------------------------------------------------------ starts
    def reset(self, indices: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """Start new episodes in slots ``indices``, slot ``indices[j]`` drawing from
        ``rngs[j]``. Starts are redrawn while no viewpoint shows the ball, the goal view shows
        no landmark, or the start already counts as success."""
        todo = np.asarray(indices, dtype=np.int64)
        pending = np.arange(len(todo))
        for _ in range(self.cfg.max_start_draws):
            if not len(pending):
                if self.cfg.observes_prior:
                    self._draw_priors(todo, rngs)
                if self.cfg.appearance.enabled:
                    for j, slot in enumerate(todo):
                        self.looks[slot] = draw_looks(self.cfg.appearance, rngs[j])
                    self.tone[todo] = tone_curves(self.looks[todo])
                self.last_move[todo] = 0.0
                self.started[todo] = True
                return
            slots = todo[pending]
            starts = draw_starts([rngs[j] for j in pending], self.cfg)
            self.pose[slots] = starts["pose"]
            self.believed_pose[slots] = starts["believed_pose"]
            self.head[slots] = starts["head"]
            self.ball[slots] = starts["ball"]
            if self.cfg.robots.max_count:
                self._draw_robots(slots, [rngs[j] for j in pending])
            pending = pending[~self._search_goals(slots)]
        raise StartGenerationError(f"no valid episode start after {self.cfg.max_start_draws} tries")

    def _draw_robots(self, slots: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """Other robots for the starts of ``slots`` (after the start's own draws), and the
        landmarks they hide from the camera (``geometry.occlusion``)."""
        cfg = self.cfg
        half = (cfg.field.half_length, cfg.field.half_width)
        for slot, rng in zip(slots, rngs, strict=True):
            self.robots[slot] = draw_robots(
                cfg.robots,
                rng,
                half,
                self.pose[slot, :2],
                self.ball[slot],
                cfg.field.ball_radius,
                cfg.camera.camera_height,
            )
        self.hidden[slots] = self._hidden(self.pose[slots], self.robots[slots])

    def _hidden(self, pose: np.ndarray, robots: np.ndarray) -> np.ndarray:
        """(M, K) the landmarks that the robots (M, R, 4) hide from cameras at ``pose``."""
        cfg = self.cfg
        camera = np.column_stack([pose[:, :2], np.full(len(pose), cfg.camera.camera_height)])
        return hidden_landmarks(self.landmarks, camera, robot_cylinders(robots, cfg.robots.radius))

    def _draw_priors(self, slots: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """The prior pose of each new episode (after its start: the start's draws come
        first, so the images and goals of an episode do not depend on the prior), then the
        proposal: Algorithm 1 run from the prior."""
        cfg = self.cfg
        for j, slot in enumerate(slots):
            if cfg.prior_error_range is None:
                self.prior_error[slot] = cfg.localisation_error
                self.prior_pose[slot] = self.believed_pose[slot]
            else:
                lo, hi = cfg.prior_error_range
                error = lo + (hi - lo) * rngs[j].random()
                if cfg.prior_exact_share and rngs[j].random() < cfg.prior_exact_share:
                    error = 0.0  # the extra draw happens only when asked for
                self.prior_error[slot] = error
                self.prior_pose[slot] = corrupt_pose(
                    self.pose[slot], self.prior_error[slot], rngs[j]
                )
        self.prior_pose[slots] = quantise_pose(self.prior_pose[slots], *cfg.prior_grid)
        self.proposal[slots] = self._proposals(
            self.prior_pose[slots], self.ball[slots], self.hidden[slots]
        )

    def redraw_priors(
        self,
        pose: np.ndarray,
        ball: np.ndarray,
        errors: np.ndarray,
        robots: np.ndarray | None,
        rng: np.random.Generator,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Stored states' priors drawn again: for true poses (M, 3), balls (M, 2), error
        scales (M,) and other robots (M, R, 4; None: none), prior poses corrupted as an
        episode's are (``corrupt_pose``, quantised to ``prior_grid``) from ``rng``, and the
        proposals (M, 3) Algorithm 1 makes from them. A learner's augmentation: one
        state seen with many priors of its error scale cannot be recognised by its prior."""
        prior = np.stack(
            [corrupt_pose(p, float(e), rng) for p, e in zip(pose, errors, strict=True)]
        )
        prior = quantise_pose(prior, *self.cfg.prior_grid)
        if self.cfg.robots.max_count and robots is None:
            raise ValueError("redraw_priors: this world has other robots; pass the states' robots")
        hidden = (
            self._hidden(pose, robots)
            if robots is not None
            else np.zeros((len(pose), len(self.landmarks)), dtype=bool)
        )
        return prior, self._proposals(prior, ball, hidden)

    def _proposals(self, prior: np.ndarray, ball: np.ndarray, hidden: np.ndarray) -> np.ndarray:
        """(M, 3) Algorithm 1's view from each prior pose: (pan, tilt, found)."""
        result = self._viewpoints(prior, ball, hidden)
        return np.column_stack(
            [np.where(result.ok, result.pan, 0.0), np.where(result.ok, result.tilt, 0.0), result.ok]
        )

    def _viewpoints(
        self, means: np.ndarray, ball: np.ndarray, hidden: np.ndarray
    ) -> ViewpointBatch:
        """Algorithm 1 from ``means`` (the start covariance) for balls ``ball``, with the
        landmarks ``hidden`` (M, K) behind other robots."""
        cfg, loc = self.cfg, self.localisation
        return best_viewpoints(
            means,
            np.broadcast_to(loc.ukf.initial_cov, (len(means), 3, 3)),
            ball,
            self.landmarks,
            cfg.camera,
            grid=loc.grid,
            ukf=loc.ukf,
            ball_radius=cfg.field.ball_radius,
            parallel=self.renderer.parallel,  # the search runs one row serially itself
            ball_views_only=True,
            hidden=hidden if cfg.robots.max_count else None,
        )

    def _search_goals(self, slots: np.ndarray) -> np.ndarray:
        cfg = self.cfg
        result = self._viewpoints(self.believed_pose[slots], self.ball[slots], self.hidden[slots])
        found = result.ok
        self.goal_pan[slots] = np.where(found, result.pan, 0.0)
        self.goal_tilt[slots] = np.where(found, result.tilt, cfg.camera.tilt_min)
        self.goal_entropy[slots] = np.where(found, result.entropy, np.nan)
        # What the goal view really shows: the true pose at the goal head angles.
        self.desired[slots] = (
            visible_mask(
                self.landmarks,
                self.pose[slots],
                self.goal_pan[slots],
                self.goal_tilt[slots],
                cfg.camera,
            )
            & ~self.hidden[slots]
        )
        self._observe(slots)
        self.step_count[slots] = 0
        self.success_step[slots] = -1
        self.ball_lost_step[slots] = -1
        self.episode_reward[slots] = 0.0
        already = self._succeeded(slots)
        valid: np.ndarray = found & self.desired[slots].any(axis=1) & ~already
        return valid

    # ------------------------------------------------------------------ dynamics
    def step(self, actions: np.ndarray, active: np.ndarray | None = None) -> StepOutcome:
        """Apply one action per slot (only where ``active``): discrete, or (N, 2) continuous.

        Returns:
            ``(reward, terminated, success, ball_lost)``, each (N,).
        """
        idx = np.arange(self.n) if active is None else np.flatnonzero(active)
        cfg = self.cfg
        move = head_moves(actions, cfg.action_type, self.actions, cfg.max_move, self.n)[idx]
        return self.move_head(idx, self.pan[idx] + move[:, 0], self.tilt[idx] + move[:, 1])

    def move_head(self, idx: np.ndarray, pan: np.ndarray, tilt: np.ndarray) -> StepOutcome:
        """Move the heads of slots ``idx`` to ``(pan, tilt)`` (clipped to the limits) as one
        step: discrete actions use it, and so do baselines that jump the head to a target.

        Returns:
            ``(reward, terminated, success, ball_lost)``, each (N,).
        """
        require_reset(self.started, idx)
        reward = np.zeros(self.n)
        success = np.zeros(self.n, dtype=bool)
        lost = np.zeros(self.n, dtype=bool)
        if len(idx) == 0:
            return reward, success.copy(), success, lost
        cam = self.cfg.camera
        before = viewpoint_distance_deg(
            self.pan[idx], self.tilt[idx], self.goal_pan[idx], self.goal_tilt[idx]
        )
        old_head = self.head[idx]
        self.pan[idx], self.tilt[idx] = clip_head(pan, tilt, cam)
        self.last_move[idx] = self.head[idx] - old_head
        after = viewpoint_distance_deg(
            self.pan[idx], self.tilt[idx], self.goal_pan[idx], self.goal_tilt[idx]
        )
        self.step_count[idx] += 1
        self._observe(idx)
        lost[idx] = ~ball_visible_mask(
            self.ball[idx],
            self.pose[idx],
            self.pan[idx],
            self.tilt[idx],
            cam,
            self.cfg.field.ball_radius,
        )
        success[idx] = self._succeeded(idx) & ~lost[idx]
        reward[idx] = approach_reward(before, after, self.cfg.reward_resolution_deg)
        reward[lost] = self.cfg.ball_lost_reward
        self.success_step[success] = self.step_count[success]
        self.ball_lost_step[lost] = self.step_count[lost]
        self.episode_reward += reward
        return reward, lost | success, success, lost

    def _observe(self, idx: np.ndarray) -> None:
        self.observed[idx] = (
            visible_mask(
                self.landmarks, self.pose[idx], self.pan[idx], self.tilt[idx], self.cfg.camera
            )
            & ~self.hidden[idx]
        )

    def _succeeded(self, idx: np.ndarray) -> np.ndarray:
        if self.cfg.success_mode == "landmarks":
            # The release: every landmark of the goal view is in view now.
            all_seen: np.ndarray = ~(self.desired[idx] & ~self.observed[idx]).any(axis=1)
            return all_seen
        dist = viewpoint_distance_deg(
            self.pan[idx], self.tilt[idx], self.goal_pan[idx], self.goal_tilt[idx]
        )
        return dist <= self.cfg.success_tolerance_deg + 1e-9  # float slack at the boundary

    # ------------------------------------------------------------------ outputs
    def render(self, idx: np.ndarray | None = None, out: np.ndarray | None = None) -> np.ndarray:
        """Camera images (len(idx), H, W) uint8 of the true pose and head."""
        idx = np.arange(self.n) if idx is None else idx
        looks = self.frame_looks(idx)
        return self.render_states(
            self.pose[idx],
            self.head[idx],
            self.ball[idx],
            looks,
            self.robots[idx],
            out=out,
            tone=None if looks is None else self.tone[idx],
        )

    def frame_looks(self, idx: np.ndarray) -> np.ndarray | None:
        """The look rows (len(idx), len(LOOK_FIELDS)) of the current frames of slots ``idx``
        (the episode's draw, this step's head move and frame counter); None when the config
        has no randomised appearance."""
        if not self.cfg.appearance.enabled:
            return None
        looks: np.ndarray = self.looks[idx]
        looks[:, LOOK["move_pan"]] = self.last_move[idx, 0]
        looks[:, LOOK["move_tilt"]] = self.last_move[idx, 1]
        looks[:, LOOK["frame"]] = self.step_count[idx]
        return looks

    def render_states(
        self,
        pose: np.ndarray,
        head: np.ndarray,
        ball: np.ndarray,
        looks: np.ndarray | None,
        robots: np.ndarray,
        out: np.ndarray | None = None,
        tone: np.ndarray | None = None,
    ) -> np.ndarray:
        """Camera images of stored states (a learner's dataset) in this batch's world: poses
        (M, 3), heads (M, 2), balls (M, 2), look rows (:meth:`frame_looks`, None: clean) and
        other robots (M, R, 4). ``tone``: the looks' tone curves when known."""
        cfg = self.cfg
        if looks is not None and tone is None:
            tone = tone_curves(looks)
        return self.renderer.render(
            pose,
            head[:, 0],
            head[:, 1],
            ball,
            out=out,
            looks=looks,
            tone=tone,
            cylinders=robot_cylinders(robots, cfg.robots.radius) if cfg.robots.max_count else None,
        )

    def info_arrays(self, never: int) -> dict[str, np.ndarray]:
        """Per-slot episode facts as arrays over all N slots (see the env's Info section);
        ``never`` is ``steps_to_success`` and ``ball_lost_step`` of an episode where that did
        not happen (the time limit, or -1 without one).

        Every entry has the same shape and dtype at every step (float64, int64 or bool,
        landmark sets as (N, K) boolean masks over landmark ids), so Gymnasium's vectorizers
        can stack the single environments' infos and get exactly these arrays.
        """
        success = self.success_step >= 0
        lost = self.ball_lost_step >= 0
        rate = (self.desired & self.observed).sum(1) / np.maximum(self.desired.sum(1), 1)
        return {
            "goal_viewpoint": self.goal.copy(),
            "goal_entropy": self.goal_entropy.copy(),
            "success_rate": rate,
            "success": success,
            "ball_lost": lost,
            "steps_to_success": np.where(success, self.success_step, never),
            "ball_lost_step": np.where(lost, self.ball_lost_step, never),
            "episode_score": np.where(success, 1.0, np.where(lost, 0.0, rate)),
            "head": self.head.copy(),
            "pose": self.pose.copy(),
            "believed_pose": self.believed_pose.copy(),
            "ball": self.ball.copy(),
            "step": self.step_count.copy(),
            "desired_mask": self.desired.copy(),
            "observed_mask": self.observed.copy(),
            **(
                {"prior_pose": self.prior_pose.copy(), "prior_error": self.prior_error.copy()}
                if self.cfg.observes_prior
                else {}
            ),
            **(
                {"robots": self.robots.copy(), "hidden_mask": self.hidden.copy()}
                if self.cfg.robots.max_count
                else {}
            ),
        }

    def entropy_regret(self, idx: np.ndarray) -> np.ndarray:
        """Per slot of ``idx``: the entropy (nats) of the start belief updated with the
        landmarks the current view really shows, minus the goal view's entropy (both from
        the believed pose, as Algorithm 1 scores views). 0 at the goal and at any view as
        informative; what a head pose costs the robot's localisation. ResetNeeded for a slot
        never reset (its state is zeros)."""
        require_reset(self.started, idx, "entropy_regret")
        ukf = self.localisation.ukf
        out = np.empty(len(idx))
        for j, i in enumerate(idx):
            # Algorithm 1's update: z = h(mu) for each landmark in view, closest first
            mean = self.believed_pose[i]
            seen = np.flatnonzero(self.observed[i])
            zs = np.array([hx_range_bearing(mean, seg)[0] for seg in self.landmarks.segments[seen]])
            order = np.argsort(zs[:, 0], kind="stable") if len(seen) else seen
            seen, zs = seen[order], zs.reshape(-1, 2)[order]
            _, cov = ukf_update_sequential(
                mean,
                ukf.initial_cov,
                zs,
                self.landmarks.segments[seen],
                self.landmarks.types[seen],
                ukf,
            )
            out[j] = entropy(cov) - self.goal_entropy[i]
        return out

    def info(self, i: int, never: int) -> dict[str, Any]:
        """The single-environment ``info`` dict of slot ``i``: slot ``i`` of
        :meth:`info_arrays`, scalars as Python ``float``, ``int`` and ``bool``.

        Python scalars, not NumPy ones: Gymnasium's vectorizers stack those into float64,
        int64 and bool arrays, but put a NumPy bool into an object array.
        """
        return slot_info(self.info_arrays(never), i)


def slot_info(arrays: dict[str, np.ndarray], i: int) -> dict[str, Any]:
    """Slot ``i`` of :meth:`EpisodeBatch.info_arrays` as a single env's ``info``: scalars as
    Python ``float``, ``int`` and ``bool``, rows as arrays."""
    return {key: value[i].item() if value.ndim == 1 else value[i] for key, value in arrays.items()}
