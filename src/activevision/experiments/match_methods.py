"""Head-control strategies for a whole match (``ActiveVisionMatch-v0``), batched over N
matches, and the registry ``activevision match`` takes its ``--methods`` from.

A strategy sees what a robot knows -- its head angles, its UKF belief and its ball model
(the env's info keys ``head``, ``belief_mean``, ``belief_cov``, ``ball_relative``,
``ball_age``, each an array over the N matches; the info is the vector env's, so it also
holds Gymnasium's ``_key`` masks and the simulator's truth, which a fair strategy leaves
alone) -- and, if it is learned, the camera image. It returns one action per match,
of the env's kind (``MatchConfig.action_type``): most strategies pick a head *target* and
move towards it at head speed, as a real head does -- the greedy discrete move, or the
continuous move straight there, at most ``max_move_deg`` per axis.

The handwritten strategies follow what RoboCup teams describe; their published code is
C++/Python behaviour trees with many more states, so each is the core of the pattern, not a
port:

* ``ball_track``: keep the ball centred (every team's default while the ball is seen).
* ``bhuman_cycle``: B-Human's active look (B-Human Team Report and Code Release 2019,
  "LookActive"): pan to and fro around the ball, the sweep narrowed as the robot walks
  faster, tilt on the ball.
* ``bitbots_search``: Bit-Bots (Hamburg Bit-Bots, ``bitbots_head_mover``): track the ball
  while it was seen in the last second, otherwise run the search pattern, two pan sweeps at
  a near and a far tilt.
* ``nubots_6point``: NUbots' 6-point look (NUbots Team Description 2019, "look at 6 points
  in turn"): left, centre and right at a near and a far tilt, dwelling at each.
* ``entropy_greedy``: Seekircher et al. 2010 / Czarnetzki et al. 2010 -- every 1.6 s
  (:data:`REPLAN_SECONDS`), Algorithm 1 from the current belief (mean *and* covariance)
  picks the view with the least expected entropy that keeps the ball; move there at head
  speed.
* ``entropy_track``: this package's variant of it -- every tick, Algorithm 1 from the belief
  over a 5-degree grid, among the views that keep the ball model at least
  ``track_margin_deg`` inside the image; the margin trades localisation for ball in view.
* ``glance_track``: this package's too -- track the ball, and look where Algorithm 1
  expects the most while the belief's position std exceeds 0.10 m (among the views that keep
  the ball in the image) or while the ball model lies 30 degrees beyond the head's reach (any
  view: the ball cannot be seen then anyway).
* ``onnx_policy``: an exported policy through the robot runtime's ``HeadController``; by
  default the package's shipped episodic policy, run every tick, its goal (Algorithm 1's
  proposal from the believed pose) re-planned every 1.6 s (:data:`REPLAN_SECONDS`).
* ``learned``: a training run's network (``--run``: ``--preset match_dagger``, a student of
  ``entropy_track``, or ``match_ddqn``), greedy, batched over the matches.
* ``random``: uniformly random moves.

A team's own strategy plays beside these (``--strategy FILE.py:NAME``, :func:`load_strategy`):
any class with ``reset(n, rng)`` and ``act(obs, info)`` (:class:`MatchPolicy`), made from the
:class:`MatchConfig`; ``examples/uncertainty_glance.py`` is one.

Two references are *privileged* -- they read what only the simulator knows, so no robot
can run them -- and bound what a learned strategy could reach from the same head:

* ``oracle_ball``: ``ball_track`` on the true ball;
* ``oracle_entropy``: ``entropy_greedy`` from the true pose (with the belief's covariance)
  on the true ball.
"""

from __future__ import annotations

import contextlib
import hashlib
import inspect
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from activevision.envs.actions import action_table
from activevision.envs.match.config import MATCH_ACTION_SET, MatchConfig
from activevision.envs.match.heads import (
    DEFAULT_TRACK_MARGIN_DEG,
    EntropyTrackTeacher,
    GlanceTrackTeacher,
    ball_direction,
    ball_on_field,
    move_towards,
)
from activevision.envs.match.observations import (
    IMAGE_KEY,
    Observation,
    knowledge_vectors,
    vector_keys,
)
from activevision.geometry import LandmarkSet, clip_head, field_landmarks
from activevision.localisation import LocalisationConfig, best_viewpoints

if TYPE_CHECKING:
    from activevision.runtime.metadata import PolicyMetadata


class MatchPolicy(Protocol):
    """What ``activevision match`` needs of a strategy, built-in or the user's
    (``--strategy FILE.py:NAME``, ``NAME(config)`` returning one). A fair strategy reads
    only what the robot knows (the module docstring, and the env's docstring under
    "Info"); ``info`` also holds the simulator's truth, for references."""

    name: str

    def reset(self, n: int, rng: np.random.Generator) -> None:
        """N matches start (all at once: the runner plays them in lock-step)."""

    def act(self, obs: Observation, info: dict[str, np.ndarray]) -> np.ndarray:
        """The actions for this tick: (N,) discrete, or (N, 2) continuous in [-1, 1]."""


class TargetPolicy:
    """A strategy that picks head targets and moves towards them at head speed."""

    name = "target"

    def __init__(self, config: MatchConfig) -> None:
        self.config = config
        self.step = config.head_step

    def reset(self, n: int, rng: np.random.Generator) -> None:
        self.n = n

    def targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        raise NotImplementedError

    def act(self, obs: Observation, info: dict[str, np.ndarray]) -> np.ndarray:
        return move_towards(info["head"], self.targets(info), self.config)

    def reached(self, info: dict[str, np.ndarray], target: np.ndarray) -> np.ndarray:
        """Heads within one move of ``target`` (N, 2)."""
        d = info["head"] - target
        reached: np.ndarray = np.hypot(d[:, 0], d[:, 1]) <= self.step * 0.75
        return reached


class BallTrack(TargetPolicy):
    name = "ball_track"

    def targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        return ball_direction(info, self.config)


class BHumanCycle(TargetPolicy):
    """Pan to and fro around the ball: +-45 deg standing, narrowed linearly to +-15 deg at
    full walking speed (speed from the belief's motion, an exponential average that keeps
    ``keep`` of its value per ``keep_seconds``, whatever a tick lasts), tilt on the ball."""

    name = "bhuman_cycle"
    wide, narrow = math.radians(45.0), math.radians(15.0)
    #: the speed estimate keeps 0.8 of its value per 0.32 s (a time constant of 1.43 s): 0.8
    #: per tick was 0.8 per 0.16 s of ticks of 0.16 s, reacting twice as fast
    keep, keep_seconds = 0.8, 0.32

    def __init__(self, config: MatchConfig) -> None:
        super().__init__(config)
        # exactly 0.8 and 0.2 at ticks of 0.32 s (docs/match.md's figures): the gain rounded
        # to 12 decimals, as 1 - 0.8 is 0.19999999999999996 in floating point
        self.keep_per_tick = self.keep ** (config.tick_seconds / self.keep_seconds)
        self.gain_per_tick = round(1.0 - self.keep_per_tick, 12)

    def reset(self, n: int, rng: np.random.Generator) -> None:
        super().reset(n, rng)
        self.side = np.ones(n)
        self.last_mean: np.ndarray | None = None
        self.speed = np.zeros(n)

    def targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        mean = info["belief_mean"]
        if self.last_mean is not None:
            moved = np.hypot(*(mean[:, :2] - self.last_mean[:, :2]).T) / self.config.tick_seconds
            self.speed = self.keep_per_tick * self.speed + self.gain_per_tick * moved
        self.last_mean = mean.copy()
        full = max(self.config.walk.speed, 1e-6)
        amplitude = self.wide - (self.wide - self.narrow) * np.clip(self.speed / full, 0, 1)
        ball = ball_direction(info, self.config)
        target = ball.copy()
        target[:, 0] = ball[:, 0] + self.side * amplitude
        target = np.column_stack(clip_head(target[:, 0], target[:, 1], self.config.camera))
        turn = self.reached(info, target) | (
            np.abs(info["head"][:, 0] - target[:, 0]) < self.step * 0.75
        )
        self.side = np.where(turn, -self.side, self.side)
        return target


class PatternPolicy(TargetPolicy):
    """Visit a fixed list of (pan, tilt) points in turn, holding the head at each for
    ``hold_seconds`` (counting the tick it arrives; at least that tick), whatever a tick
    lasts; a point beyond the head's limits (another camera than the paper's) is looked at
    from the nearest limit, where the head can reach it (unclipped, the head stopped at the
    limit, never within reach of the point, and the pattern stopped there for the whole
    match)."""

    points_deg: tuple[tuple[float, float], ...] = ()
    hold_seconds = 0.0

    def __init__(self, config: MatchConfig) -> None:
        super().__init__(config)
        #: the ticks it waits at a point after the one it arrives in
        self.dwell = max(0, round(self.hold_seconds / config.tick_seconds) - 1)

    def reset(self, n: int, rng: np.random.Generator) -> None:
        super().reset(n, rng)
        pan, tilt = np.radians(np.array(self.points_deg)).T
        self.points = np.column_stack(clip_head(pan, tilt, self.config.camera))
        self.index = np.zeros(n, dtype=np.int64)
        self.waited = np.zeros(n, dtype=np.int64)

    def pattern_targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        target = self.points[self.index]
        at = self.reached(info, target)
        self.waited = np.where(at, self.waited + 1, 0)
        advance = at & (self.waited > self.dwell)
        self.index = np.where(advance, (self.index + 1) % len(self.points), self.index)
        self.waited[advance] = 0
        return np.asarray(self.points[self.index])

    def targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        return self.pattern_targets(info)


class BitBotsSearch(PatternPolicy):
    """The ball while it was seen within the last second, else the search pattern."""

    name = "bitbots_search"
    points_deg = ((-90.0, 15.0), (90.0, 15.0), (90.0, 40.0), (-90.0, 40.0))
    recent_seconds = 1.0

    def __init__(self, config: MatchConfig) -> None:
        super().__init__(config)
        # the ticks of a second (3 of the paper's 0.32 s): a fixed 3 ticks was 0.3 s of
        # ticks of 0.1 s, 3 s of ticks of 1 s
        self.recent_ticks = max(1, round(self.recent_seconds / config.tick_seconds))

    def targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        search = self.pattern_targets(info)
        recent = info["ball_age"] <= self.recent_ticks
        return np.where(recent[:, None], ball_direction(info, self.config), search)


class NUbots6Point(PatternPolicy):
    name = "nubots_6point"
    points_deg = (
        (60.0, 15.0),
        (0.0, 15.0),
        (-60.0, 15.0),
        (-60.0, 45.0),
        (0.0, 45.0),
        (60.0, 45.0),
    )
    #: 0.96 s at each point: 3 ticks of 0.32 s (it was 3 ticks at every tick length)
    hold_seconds = 0.96


#: how often (s) ``entropy_greedy`` and ``onnx_policy`` plan their view again: 1.6 s, the 5
#: ticks of the paper's 0.32 s they re-planned at when the interval was counted in ticks (this
#: package's choice; the papers do not give one). Counted in ticks it was 0.8 s of ticks of
#: 0.16 s and 8 s of ticks of 1.6 s: a faster tick re-planned more often, a slower one less
REPLAN_SECONDS = 1.6


def replan_ticks(config: MatchConfig, seconds: float = REPLAN_SECONDS) -> int:
    """The ticks between two plans of ``seconds`` at the match's tick (at least 1): 5 at the
    paper's 0.32 s, 10 at 0.16 s."""
    return max(1, round(seconds / config.tick_seconds))


class EntropyGreedy(TargetPolicy):
    """Every ``replan_seconds`` (in ticks, :func:`replan_ticks`): Algorithm 1 from the belief
    (mean and covariance) and the ball model; the view with the least expected entropy that
    shows the ball (the ball itself when none does)."""

    name = "entropy_greedy"

    def __init__(self, config: MatchConfig, replan_seconds: float = REPLAN_SECONDS) -> None:
        super().__init__(config)
        self.every = replan_ticks(config, replan_seconds)
        self.landmarks = field_landmarks(config.field)
        self.localisation = LocalisationConfig.for_camera(config.camera, config.tracker.ukf)

    def reset(self, n: int, rng: np.random.Generator) -> None:
        super().reset(n, rng)
        self.tick = 0
        self.goal = np.zeros((n, 2))

    def targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        if self.tick % self.every == 0:
            self.goal = plan_views(info, self.config, self.landmarks, self.localisation, True)
        self.tick += 1
        return self.goal


class EntropyTrack(TargetPolicy):
    """Every tick: Algorithm 1 from the belief among the views that keep the ball model at
    least ``margin_deg`` inside the image (``envs.match.heads.entropy_track_targets``)."""

    name = "entropy_track"

    def __init__(self, config: MatchConfig, margin_deg: float = DEFAULT_TRACK_MARGIN_DEG) -> None:
        super().__init__(config)
        self.teacher = EntropyTrackTeacher(config, margin_deg)

    def targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        return self.teacher.targets(info)


class GlanceTrack(TargetPolicy):
    """Track the ball; localise when the belief is unsure or the ball out of reach
    (``envs.match.heads.glance_track_targets``)."""

    name = "glance_track"

    def __init__(self, config: MatchConfig) -> None:
        super().__init__(config)
        self.teacher = GlanceTrackTeacher(config)

    def targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        return self.teacher.targets(info)


def plan_views(
    info: dict[str, np.ndarray],
    config: MatchConfig,
    landmarks: LandmarkSet,
    localisation: LocalisationConfig,
    use_belief_cov: bool,
) -> np.ndarray:
    """Algorithm 1 from each belief's mean (with its covariance, or the episodic start
    covariance): the best view (N, 2) that shows the model's ball; the ball's direction
    where no view does."""
    means = info["belief_mean"]
    covs = info["belief_cov"] if use_belief_cov else localisation.ukf.initial_cov
    result = best_viewpoints(
        means,
        covs,
        ball_on_field(info),
        landmarks,
        config.camera,
        grid=localisation.grid,
        ukf=localisation.ukf,
        ball_radius=config.field.ball_radius,
        ball_views_only=True,
    )
    views = np.column_stack([result.pan, result.tilt])
    return np.where(result.ok[:, None], views, ball_direction(info, config))


class OnnxMatchPolicy:
    """An exported policy (default: the shipped episodic one) through ``HeadController``,
    every tick; an episodic policy that takes them is fed the belief as its prior pose and
    Algorithm 1's proposal, re-planned every ``replan_seconds`` (in ticks,
    :func:`replan_ticks`; from the believed pose with the episodic start covariance, as it
    was trained); a match student (``--preset match_dagger``) its belief's mean and stds and
    the ball model."""

    name = "onnx_policy"

    def __init__(
        self, config: MatchConfig, model: Path | None = None, replan_seconds: float = REPLAN_SECONDS
    ) -> None:
        from activevision.runtime import HeadController, pretrained_policy_path

        self.config = config
        self.model = Path(model) if model is not None else pretrained_policy_path()
        self.every = replan_ticks(config, replan_seconds)
        self.landmarks = field_landmarks(config.field)
        self.localisation = LocalisationConfig.for_camera(config.camera)
        self._make = lambda: HeadController(self.model)
        # the matches' camera is the robot's: one CameraMismatchWarning when the policy was
        # trained for another
        self._check_moves(HeadController(self.model, camera=config.camera).metadata)

    def _check_moves(self, meta: PolicyMetadata) -> None:
        """A discrete policy's actions index its own moves: in a discrete match they are
        played as the match's (``step_deg`` in 8 ways), so the two must be the same."""
        if self.config.action_type != "discrete" or meta.action_type != "discrete":
            return  # the command is followed towards its target, at the match's speed
        if meta.step_deg is None:
            return  # a bare export_onnx file: its moves are not recorded
        same_step = math.isclose(meta.step_deg, self.config.step_deg)
        if meta.action_set != MATCH_ACTION_SET or not same_step:
            raise ValueError(
                f"{self.model}: its policy's actions are {meta.step_deg:g}-degree"
                f" {meta.action_set} moves; play it with --step-deg {meta.step_deg:g}"
                + (" (the match's moves are 8-way)" if meta.action_set != MATCH_ACTION_SET else "")
                + ", or with --action-type continuous, which follows its commands"
            )

    def reset(self, n: int, rng: np.random.Generator) -> None:
        self.controllers = [self._make() for _ in range(n)]
        self.tick = 0
        self.proposal = np.zeros((n, 2))

    def act(self, obs: Observation, info: dict[str, np.ndarray]) -> np.ndarray:
        needs_proposal = "proposal" in self.controllers[0].inputs
        if needs_proposal and self.tick % self.every == 0:
            self.proposal = plan_views(info, self.config, self.landmarks, self.localisation, False)
        self.tick += 1
        images = obs[IMAGE_KEY] if isinstance(obs, dict) else obs
        mean, cov = info["belief_mean"], info["belief_cov"]
        ball, age = info["ball_relative"], info["ball_age"] * self.config.tick_seconds
        commands = []
        for i, controller in enumerate(self.controllers):
            inputs = controller.inputs
            pan, tilt = info["head"][i]
            commands.append(
                controller.act(
                    images[i, -1],
                    pan,
                    tilt,
                    pose=tuple(mean[i]) if "pose" in inputs else None,
                    proposal=tuple(self.proposal[i]) if "proposal" in inputs else None,
                    pose_error=float(np.sqrt(cov[i, 0, 0] + cov[i, 1, 1]))
                    if "pose_error" in inputs
                    else None,
                    belief=tuple(np.sqrt(np.diag(cov[i]))) if "belief" in inputs else None,
                    ball=(*ball[i], age[i]) if "ball" in inputs else None,
                )
            )
        if self.config.action_type == "discrete" and not self.controllers[0].continuous:
            return np.array([c.action for c in commands], dtype=np.int64)
        # a continuous policy, or a continuous match: towards the head angles the policy
        # commands, at the match's head speed
        targets = np.array([(c.target_pan, c.target_tilt) for c in commands])
        return move_towards(info["head"], targets, self.config)


def privileged(info: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """``info`` with the robot's knowledge replaced by the simulator's truth: the belief's
    mean by the true pose and the ball model by the true ball (in the true robot frame)."""
    pose, ball = info["pose"], info["ball"]
    # envs.match.dynamics.to_robot_frame, over all N matches at once
    gap = ball[:, :2] - pose[:, :2]
    c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    relative = np.column_stack([c * gap[:, 0] + s * gap[:, 1], -s * gap[:, 0] + c * gap[:, 1]])
    return {**info, "belief_mean": pose, "ball_relative": relative}


class OracleBall(BallTrack):
    """Privileged: keep the *true* ball centred."""

    name = "oracle_ball"

    def targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        return super().targets(privileged(info))


class OracleEntropy(EntropyGreedy):
    """Privileged: Algorithm 1 every ``replan_seconds`` from the *true* pose (with the belief's
    covariance) on the *true* ball."""

    name = "oracle_entropy"

    def targets(self, info: dict[str, np.ndarray]) -> np.ndarray:
        return super().targets(privileged(info))


class LearnedMatchPolicy:
    """A training run's network, greedy, every match in one batched forward pass: an image
    Q-network (``--preset match_ddqn``; discrete matches), or a match student
    (``--preset match_dagger``, ``match_dagger_continuous``: fed the image and what the
    robot knows, as ``ActiveVisionMatch-v0``'s ``"image+head+belief"`` observation has it;
    a match of its own action type)."""

    name = "learned"

    def __init__(self, config: MatchConfig, run: Path, weights: str = "final") -> None:
        import torch

        from activevision.agents.student import StudentNetwork
        from activevision.training import load_config, load_policy
        from activevision.training.config import MATCH_ENV_ID
        from activevision.training.match_dagger import student_match_actions
        from activevision.training.state import PLAYING_WOULD, check_run_config_unchanged

        self.student_actions = student_match_actions
        self.student_class = StudentNetwork

        run_config = load_config(run / "config.json")
        check_run_config_unchanged(run, PLAYING_WOULD)
        self.student = run_config.match_student
        if not self.student and run_config.algo != "ddqn":
            raise ValueError(
                f"{run}: the match plays image Q-networks (algo ddqn) and match students"
                f" (--preset match_dagger), not {run_config.algo} on {run_config.env_id}"
            )
        trained = run_config.match.action_type if self.student else "discrete"
        if config.action_type != trained:
            raise ValueError(
                f"{run}: its policy makes {trained} moves; play it with --action-type {trained}"
            )
        # the head move the network's outputs stand for, and the match's
        world = run_config.match if run_config.env_id == MATCH_ENV_ID else run_config.env
        if trained == "continuous":
            trained_move, move = max(world.max_move_deg), max(config.max_move_deg)
        else:
            trained_move, move = world.step_deg, config.step_deg
        if not math.isclose(move, trained_move):
            raise ValueError(
                f"{run}: its policy was trained with moves of up to {trained_move:g} degrees;"
                f" play it with --step-deg {trained_move:g}"
            )
        if world.camera != config.camera:  # its network takes that camera's image
            raise ValueError(
                f"{run}: its policy was trained for another camera ({world.camera}) than the"
                f" matches' ({config.camera}); play it in matches of its camera"
                " (`activevision match --run` does)"
            )
        self.torch = torch
        self.config = config
        self.keys = vector_keys(run_config.match) if self.student else ()
        self.net = load_policy(run, weights=weights).eval()

    def reset(self, n: int, rng: np.random.Generator) -> None:
        pass

    def act(self, obs: Observation, info: dict[str, np.ndarray]) -> np.ndarray:
        images = np.ascontiguousarray(obs[IMAGE_KEY] if isinstance(obs, dict) else obs)
        if self.student:
            vector = knowledge_vectors(info, self.keys, self.config.tick_seconds)
            net = self.net
            assert isinstance(net, self.student_class)  # the run's algo said so
            return self.student_actions(net, self.torch.device("cpu"), images, vector)
        with self.torch.inference_mode():
            q = self.net(self.torch.from_numpy(images))
        return np.asarray(q.argmax(dim=1).numpy(), dtype=np.int64)


class RandomMoves:
    name = "random"

    def __init__(self, config: MatchConfig) -> None:
        self.n_actions = len(action_table(config.step_deg, MATCH_ACTION_SET))
        self.continuous = config.action_type == "continuous"

    def reset(self, n: int, rng: np.random.Generator) -> None:
        self.n, self.rng = n, rng

    def act(self, obs: Observation, info: dict[str, np.ndarray]) -> np.ndarray:
        if self.continuous:
            return self.rng.uniform(-1.0, 1.0, size=(self.n, 2))
        return self.rng.integers(self.n_actions, size=self.n)


#: a strategy of the user's: ``MatchConfig -> MatchPolicy`` (a class, or a function)
StrategyFactory = Callable[[MatchConfig], MatchPolicy]
#: the method name of a user's strategy (``--strategy``; not one of ``--methods``)
USER_STRATEGY = "strategy"


@dataclass(frozen=True)
class StrategyOptions:
    """What some strategies take beyond the match's config."""

    #: a user's strategy (``activevision match --strategy FILE.py:NAME``)
    factory: StrategyFactory | None = None
    model: Path | None = None  #: onnx_policy: an exported policy (None: the shipped one)
    run: Path | None = None  #: learned: a training run
    weights: str = "final"  #: learned: the run's final weights, or "best" validated ones
    #: entropy_track: how far inside the image the ball stays (degrees)
    track_margin_deg: float = DEFAULT_TRACK_MARGIN_DEG


@dataclass(frozen=True)
class MatchMethod:
    name: str
    #: (config, options) -> a fresh strategy
    factory: Callable[[MatchConfig, StrategyOptions], MatchPolicy]
    help: str
    needs_run: bool = False  #: needs ``--run`` (a trained match policy)
    #: reads the simulator's truth: a reference, not a strategy (off the Pareto front)
    privileged: bool = False


MATCH_METHODS: dict[str, MatchMethod] = {
    m.name: m
    for m in (
        MatchMethod("ball_track", lambda c, _o: BallTrack(c), "keep the ball centred"),
        MatchMethod("bhuman_cycle", lambda c, _o: BHumanCycle(c), "B-Human-style pan cycle"),
        MatchMethod("bitbots_search", lambda c, _o: BitBotsSearch(c), "Bit-Bots-style search"),
        MatchMethod("nubots_6point", lambda c, _o: NUbots6Point(c), "NUbots-style 6-point look"),
        MatchMethod(
            "entropy_greedy",
            lambda c, _o: EntropyGreedy(c),
            "Algorithm 1 from the belief every 1.6 s",
        ),
        MatchMethod(
            "entropy_track",
            lambda c, o: EntropyTrack(c, o.track_margin_deg),
            "Algorithm 1 every tick among views that keep the ball inside by --track-margin",
        ),
        MatchMethod(
            "glance_track",
            lambda c, _o: GlanceTrack(c),
            "track the ball; Algorithm 1 when unsure (std > 0.10 m) or the ball out of reach",
        ),
        MatchMethod(
            "onnx_policy",
            lambda c, o: OnnxMatchPolicy(c, o.model),
            "an exported policy (--model; default: the shipped episodic one), goal re-planned",
        ),
        MatchMethod(
            "learned",
            lambda c, o: LearnedMatchPolicy(c, o.run, o.weights),  # type: ignore[arg-type]
            "a training run's policy (--run): --preset match_dagger or match_ddqn",
            needs_run=True,
        ),
        MatchMethod("random", lambda c, _o: RandomMoves(c), "uniformly random moves"),
        MatchMethod(
            "oracle_ball",
            lambda c, _o: OracleBall(c),
            "privileged reference: ball_track on the true ball",
            privileged=True,
        ),
        MatchMethod(
            "oracle_entropy",
            lambda c, _o: OracleEntropy(c),
            "privileged reference: entropy_greedy from the true pose on the true ball",
            privileged=True,
        ),
    )
}


def match_method_names() -> tuple[str, ...]:
    return tuple(MATCH_METHODS)


def privileged_methods() -> frozenset[str]:
    """The references that read the simulator's truth."""
    return frozenset(n for n, m in MATCH_METHODS.items() if m.privileged)


def default_match_methods(run: Path | None) -> tuple[str, ...]:
    """Every strategy, ``learned`` only with a run."""
    return tuple(n for n, m in MATCH_METHODS.items() if run is not None or not m.needs_run)


#: what a user's strategy may raise and have reported as one line: sys.exit() in their code
#: must not end ``activevision match`` with exit code 0 and no outputs (Ctrl-C still stops it)
USER_ERRORS = (Exception, SystemExit)


@contextlib.contextmanager
def user_errors(what: str) -> Iterator[None]:
    """Run a user's code: an exception it raises is one ValueError line naming ``what``
    (:func:`user_code_error`)."""
    try:
        yield
    except USER_ERRORS as error:
        raise user_code_error(what, error) from None


def user_code_error(what: str, error: BaseException) -> ValueError:
    """A one-line error for an exception ``error`` that a user's strategy raised: its type,
    message and the line of the user's code it came from (the innermost frame outside this
    package and the installed libraries), e.g. ``strategy mine, tick 0: act raised
    ZeroDivisionError: division by zero (mine.py, line 4, in act)``."""
    import traceback

    package = str(Path(__file__).resolve().parents[1])
    frames = traceback.extract_tb(error.__traceback__)
    theirs = [
        f
        for f in frames
        if not str(Path(f.filename).resolve()).startswith(package)
        and "site-packages" not in f.filename
        and not f.filename.startswith("<")
    ]
    place = ""
    if theirs or frames:
        frame = (theirs or frames)[-1]
        place = f" ({Path(frame.filename).name}, line {frame.lineno}, in {frame.name})"
    text = " ".join(str(error).split())  # one line, whatever the user's message holds
    message = f": {text}" if text else ""  # sys.exit(): no message
    return ValueError(f"{what} raised {type(error).__name__}{message}{place}")


def load_strategy(spec: str) -> tuple[str, StrategyFactory]:
    """A user's strategy from ``"path/to/file.py:NAME"`` or ``"package.module:NAME"``:
    ``NAME`` is a class (or function) that takes the :class:`MatchConfig` and returns a
    :class:`MatchPolicy`. Returns its label (its ``name`` attribute, else ``NAME``) and the
    factory; ValueError names what is wrong (:func:`_strategy_loader` says where the module
    is looked for)."""
    where, sep, attr = spec.rpartition(":")
    if not sep or not where or not attr.isidentifier():
        raise ValueError(f"--strategy {spec}: write FILE.py:NAME or MODULE:NAME")
    # the package's own checks first: what the import itself raises is the user's code's
    load = _strategy_loader(spec, where)
    try:
        module = load()
    except ImportError as error:
        raise ValueError(f"--strategy {spec}: cannot import it ({error})") from None
    except SyntaxError as error:
        where_bad = f"{error.filename}:{error.lineno}"
        raise ValueError(f"--strategy {spec}: {where_bad}: {error.msg}") from None
    except USER_ERRORS as error:  # the module's own code failed as it ran
        raise user_code_error(f"--strategy {spec}: importing {where}", error) from None
    factory = getattr(module, attr, None)
    if not callable(factory):
        raise ValueError(f"--strategy {spec}: {where} defines no class or function {attr}")
    name = getattr(factory, "name", None)
    label = name if isinstance(name, str) and name else attr
    if not label.isprintable():  # a newline broke the table's row, the CSV's and the legend's
        raise ValueError(
            f"--strategy {spec}: its label {label!r} is not one line of printable text;"
            " give NAME a name attribute that is"
        )
    return label, factory


def _strategy_loader(spec: str, where: str) -> Callable[[], ModuleType]:
    """What imports ``where`` (a FILE.py or a MODULE) of ``--strategy spec``; ValueError for
    a file that is not there. The file imports its own modules as ``python FILE.py`` would
    run it: its folder is put on ``sys.path`` (at the end, where it shadows no installed
    package); a MODULE is found in the current directory under the ``activevision`` script
    as under ``python -m activevision``, which has it on ``sys.path``. Either stays there,
    for the imports a strategy makes as it plays."""
    import importlib
    import importlib.util
    import os
    import sys

    def importable(folder: str) -> None:
        if folder not in sys.path:
            sys.path.append(folder)

    if not where.endswith(".py"):
        if "/" in where or os.sep in where or Path(where).is_file():
            # a path, or a file not named .py, was "No module named '/path/to/it'" (a
            # folder named alone may be a package: a MODULE)
            raise ValueError(f"--strategy {spec}: {where} is no FILE.py (nor a MODULE name)")

        def load_module() -> ModuleType:
            if "" not in sys.path:  # "": the current directory, wherever it goes (python -c)
                importable(os.getcwd())
            return importlib.import_module(where)

        return load_module
    path = Path(where)
    if path.is_dir():  # a folder named FILE.py was "no such file"
        raise ValueError(f"--strategy {spec}: {path} is a directory, not a file")
    if not path.is_file():
        raise ValueError(f"--strategy {spec}: no such file {path}")
    # one module per file: two files of one name in different folders were one module,
    # the second's replacing the first's in sys.modules (where pickling and dataclasses
    # look a class's module up)
    digest = hashlib.sha256(str(path.resolve()).encode()).hexdigest()[:12]
    module_name = f"activevision_strategy_{path.stem}_{digest}"
    module_spec = importlib.util.spec_from_file_location(module_name, path)
    if module_spec is None or module_spec.loader is None:
        raise ValueError(f"--strategy {spec}: {path} is not a Python module")
    found, loader = module_spec, module_spec.loader

    def load_file() -> ModuleType:
        importable(str(path.resolve().parent))  # `from helpers import x` beside it
        module = importlib.util.module_from_spec(found)
        sys.modules[module_name] = module  # dataclasses and pickling look modules up
        loader.exec_module(module)
        return module

    return load_file


def _user_strategy(config: MatchConfig, factory: StrategyFactory | None) -> MatchPolicy:
    """``factory(config)``, checked to be a :class:`MatchPolicy`."""
    if factory is None:
        raise ValueError("a user's strategy needs its factory (--strategy FILE.py:NAME)")
    label = getattr(factory, "__name__", repr(factory))
    contract = "a strategy has reset(n, rng) and act(obs, info): see MatchPolicy"
    policy: MatchPolicy = built_by_user(factory, config, label, "config", contract)
    return policy


def built_by_user(
    factory: Callable[[Any], Any], argument: object, label: str, parameter: str, contract: str
) -> Any:
    """``factory(argument)``, a user's ``--strategy`` (``label``): a call its signature does
    not take, an exception their code raises (:func:`user_code_error`) and a result without
    ``reset`` and ``act`` (``contract`` says what they are) are each one ValueError line
    naming ``label(parameter)``."""
    call = f"{label}({parameter})"
    try:
        signature = inspect.signature(factory)
    except (TypeError, ValueError):  # no signature to read (a builtin): just call it
        signature = None
    if signature is not None:
        try:
            signature.bind(argument)
        except TypeError as error:  # NAME(argument) is the contract
            raise ValueError(f"--strategy {label}: {call} failed: {error}") from None
    with user_errors(f"--strategy {label}: {call}"):
        built = factory(argument)
    missing = [m for m in ("reset", "act") if not callable(getattr(built, m, None))]
    if missing:
        raise ValueError(
            f"--strategy {label}: what it returns has no {' or '.join(missing)} method ({contract})"
        )
    return built


def make_match_policy(
    name: str, config: MatchConfig, options: StrategyOptions | None = None
) -> MatchPolicy:
    """A fresh strategy ``name`` for matches of ``config`` (:data:`USER_STRATEGY`: the
    user's ``options.factory``)."""
    options = options or StrategyOptions()
    if name == USER_STRATEGY:
        return _user_strategy(config, options.factory)
    if name not in MATCH_METHODS:
        raise ValueError(f"unknown match method {name!r}; choose from {', '.join(MATCH_METHODS)}")
    if MATCH_METHODS[name].needs_run and options.run is None:
        raise ValueError(f"the {name} strategy needs a training run (--run runs/NAME)")
    return MATCH_METHODS[name].factory(config, options)
