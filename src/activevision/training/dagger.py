"""DAgger with a privileged teacher: the simulator knows the goal view, so the oracle labels
every state the student visits (Ross et al. 2011; "Learning by Cheating", Chen et al. 2019).

One round: ``dagger.num_envs`` episodes are rolled out together in the native batched
simulation (:class:`~activevision.envs.simulation.EpisodeBatch`, the vector env's engine).
At each step the executed action is the teacher's with probability ``beta`` (1 at the start,
decayed linearly to 0 over ``teacher_fraction`` of the run), else the student's greedy one;
every visited state is stored with the teacher's action (the greedy 3-degree move to the
true goal) and the goal view's index. Then ``updates_per_rollout`` minibatches are drawn from
all states so far: cross-entropy on the teacher's action, plus ``goal_class_weight`` times
cross-entropy on the goal view (40 classes; with ``goal_frame="camera"`` on the goal's
offset from the head, 133 offsets with soft bilinear labels).

With ``env.action_type="continuous"`` the teacher's action is the move straight to the goal,
clipped to ``env.max_move_deg`` (``envs.actions.oracle_actions``), and the student regresses
it (squared error on its tanh output); acting by goal evidence, it moves straight towards the
best-supported view.

The dataset keeps *states* (pose, head, ball, the observation's vector), not images: each
minibatch is rendered on the fly by the exact renderer (about 30,000 frames/s), so a million
states take ~200 MB and a checkpoint stores them whole.

A run directory looks like a DDQN run's: ``config.json``, ``metrics.csv`` (one row per round
that crosses an ``epoch_steps`` boundary, numbered ``step // epoch_steps``: a round longer
than ``epoch_steps`` skips numbers; and one for the rounds after the last boundary when the
run ends between two, numbered as the epoch they lie in; ``loss`` is the imitation loss,
``epsilon`` the teacher's share ``beta``), ``episodes.csv``, ``evaluations.csv`` and
``best_policy`` (with ``eval_interval``), TensorBoard, ``policy.safetensors`` and
``checkpoints/``. Rounds start fresh episodes, so a checkpoint taken between rounds holds
everything: resuming continues exactly where the run stopped.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch
from gymnasium.utils import seeding
from torch.nn import functional as F

from activevision.agents.student import StudentNetwork
from activevision.envs.actions import oracle_actions
from activevision.envs.config import EnvConfig
from activevision.envs.observations import (
    ObservationBuilder,
    pose_features,
    proposal_features,
    vector_columns,
    vector_keys,
    vector_sizes,
)
from activevision.envs.simulation import EpisodeBatch
from activevision.rendering.appearance import LOOK, LOOK_FIELDS, draw_look_rows
from activevision.runtime.goal_evidence import (
    GoalEvidence,
    goal_output_count,
    offset_axes,
    offset_weights,
    policy_actions,
)
from activevision.training import checkpoint as ckpt
from activevision.training.config import TrainConfig
from activevision.training.cpu import configure_torch_cpu, training_device
from activevision.training.loggers import Logger
from activevision.training.metrics import episode_record
from activevision.training.policy_files import load_policy_and_metadata
from activevision.training.progress import advance, postfix, progress_bar
from activevision.training.student_runs import StudentRun

MAX_EPISODE_STEPS = 20  #: the registration's time limit


class StateDataset:
    """A ring buffer of labelled states (no images)."""

    def __init__(
        self,
        capacity: int,
        vector_size: int,
        look_size: int = 0,
        robots: int = 0,
        continuous: bool = False,
    ) -> None:
        self.capacity = capacity
        self.arrays: dict[str, np.ndarray] = {
            "pose": np.zeros((capacity, 3)),
            "head": np.zeros((capacity, 2)),
            "ball": np.zeros((capacity, 2)),
            "vector": np.zeros((capacity, vector_size), dtype=np.float32),
            # the teacher's action: an index, or a continuous move (pan, tilt) in [-1, 1]
            "action": (
                np.zeros((capacity, 2), dtype=np.float32)
                if continuous
                else np.zeros(capacity, dtype=np.int64)
            ),
            "goal": np.zeros(capacity, dtype=np.int64),
        }
        # a randomised world: each state's look and other robots, to render it again
        if look_size:
            self.arrays["looks"] = np.zeros((capacity, look_size))
        if robots:
            self.arrays["robots"] = np.zeros((capacity, robots, 4))
        self.size = 0
        self.next = 0

    def add(self, **columns: np.ndarray) -> None:
        n = len(columns["action"])
        slots = (self.next + np.arange(n)) % self.capacity
        for name, values in columns.items():
            self.arrays[name][slots] = values
        self.next = int((self.next + n) % self.capacity)
        self.size = min(self.size + n, self.capacity)

    def state_dict(self) -> dict[str, np.ndarray]:
        out = {k: v[: self.size] for k, v in self.arrays.items()}
        out["position"] = np.array([self.next, self.capacity])
        return out

    def load(self, arrays: dict[str, np.ndarray]) -> None:
        position, capacity = (int(v) for v in arrays["position"])
        if capacity != self.capacity or set(arrays) != {*self.arrays, "position"}:
            raise ckpt.CheckpointError("the checkpoint's dataset does not fit this run's config")
        self.size = len(arrays["action"])
        for name in self.arrays:
            self.arrays[name][: self.size] = arrays[name]
        self.next = position


def goal_indices(sim: EpisodeBatch) -> np.ndarray:
    """(N,) the grid index (0..39) of each slot's goal view."""
    grid = sim.localisation.grid
    gap = np.abs(grid.pans[None] - sim.goal_pan[:, None]) + np.abs(
        grid.tilts[None] - sim.goal_tilt[:, None]
    )
    index: np.ndarray = np.argmin(gap, axis=1)
    return index


#: policy metadata that a warm start (``DaggerConfig.init_from``) may change: how the
#: student acts on its outputs, and the file's own step and validation score
WARM_START_FREE_KEYS = frozenset(
    {"step", "act_by", "goal_switch_margin", "validation_success_rate", "validation_episode_reward"}
)


class ImitationRun(StudentRun):
    """What DAgger on the episodes (:class:`DaggerTrainer`) and on the match
    (:class:`~activevision.training.match_dagger.MatchDaggerTrainer`) share: the teacher's
    decaying share, the student and its dataset (:meth:`_start`), rounds of rollouts and
    updates, checkpoints. Subclasses implement :meth:`_rollout` and :meth:`_update`."""

    network: StudentNetwork
    optimizer: torch.optim.Optimizer
    dataset: StateDataset
    rng: np.random.Generator
    device: torch.device
    continuous: bool
    _round_share: float = 1.0

    def _start(
        self,
        run_dir: str | os.PathLike[str],
        loggers: Sequence[Logger] | None,
        resuming: bool,
        *,
        outputs: int,
        vector_size: int,
        image_shape: tuple[int, int],
        n_goals: int = 0,
        look_size: int = 0,
        robots: int = 0,
    ) -> None:
        """Build the generator, the student (``outputs`` actions, or a continuous move),
        its optimiser and the state dataset, all seeded from ``config.seed``, and open the
        run directory. Subclasses set ``config`` and ``continuous`` first."""
        config, dag = self.config, self.config.dagger
        self.device = training_device(config.run.device)
        trainer_seed, init_seed = np.random.SeedSequence(config.seed).generate_state(2)
        self.rng = np.random.default_rng(int(trainer_seed))
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(int(init_seed))
            self.network = StudentNetwork(
                2 if self.continuous else outputs,
                vector_size,
                image_shape,
                dag.downsample,
                n_goals=n_goals,
                continuous=self.continuous,
            )
        self.network.to(self.device)
        self.optimizer = torch.optim.Adam(
            self.network.parameters(), lr=config.learner.learning_rate
        )
        self.dataset = StateDataset(
            dag.dataset_size,
            vector_size,
            look_size=look_size,
            robots=robots,
            continuous=self.continuous,
        )
        configure_torch_cpu(config.run.num_threads)
        self.step = 0
        if dag.init_from is not None and not resuming:
            self._warm_start(dag.init_from)
        self._open_run(run_dir, loggers, resuming)

    def _warm_start(self, source: str) -> None:
        """Load the student weights of ``source`` (``DaggerConfig.init_from``) into the
        network; ValueError naming the first difference when ``source`` was trained for
        another network or other inputs (``max_move_deg``, the continuous moves' size, only
        where they are continuous: a discrete source's action_type is named first)."""
        try:
            network, meta = load_policy_and_metadata(source)
        except ckpt.CheckpointError as error:
            raise ValueError(f"dagger.init_from: {error}") from error
        mine = self.metadata()
        free = WARM_START_FREE_KEYS
        if not self.continuous:  # discrete moves are the action table's: no move's size
            free |= {"max_move_deg"}
        for key in sorted((set(mine) | set(meta)) - free):
            if meta.get(key) != mine.get(key):
                raise ValueError(
                    f"dagger.init_from: {source} holds a policy for another network or input"
                    f" ({key}: {meta.get(key)!r}; this run: {mine.get(key)!r})"
                )
        self.network.load_state_dict(network.state_dict())

    @property
    def teacher_share(self) -> float:
        """beta: the probability that the teacher's action is executed now."""
        dag, total = self.config.dagger, self.config.run.total_timesteps
        span = dag.teacher_fraction * total
        if span <= 0:
            return 0.0
        return dag.teacher_initial * max(0.0, 1.0 - self.step / span)

    def train(self, steps: int | None = None) -> list[dict[str, float]]:
        """Run rounds until ``steps`` more environment steps are done (default: to
        ``total_timesteps``); returns this call's ``metrics.csv`` rows."""
        run = self.config.run
        target = (
            run.total_timesteps if steps is None else min(self.step + steps, run.total_timesteps)
        )
        rows: list[dict[str, float]] = []
        logged_last_round = True  # nothing played since the last row
        rate = 0.0
        progress = progress_bar(self.config, self.step, target)
        try:
            while self.step < target:
                before, t0 = self.step, time.perf_counter()
                self._rollout()
                for _ in range(self.config.dagger.updates_per_rollout):
                    self.epoch_log.losses.append(self._update())
                rate = (self.step - before) / max(time.perf_counter() - t0, 1e-9)
                advance(progress, self.step)
                logged_last_round = self.step // run.epoch_steps > before // run.epoch_steps
                if logged_last_round:
                    # epsilon: the teacher's share in the round just played
                    rows.append(self.finish_epoch(self._round_share, rate))
                    progress.set_postfix(postfix(rows[-1], "dagger"), refresh=False)
                if run.eval_interval and self.step // run.eval_interval > (
                    before // run.eval_interval
                ):
                    self.validate()
                interval = run.checkpoint_interval
                if interval and self.step // interval > before // interval and self.step < target:
                    self.save_checkpoint()
            if self.step >= run.total_timesteps and not logged_last_round:
                # the run ends between two boundaries: its last rounds get their row (a run
                # shorter than epoch_steps left metrics.csv empty)
                rows.append(self.finish_epoch(self._round_share, rate, final=True))
            self.save_checkpoint()
        finally:
            progress.close()
            self.logger.flush()
        return rows

    def _rollout(self) -> None:
        """One round of rollouts, every visited state labelled by the teacher."""
        raise NotImplementedError

    def _update(self) -> float:
        """One minibatch update; returns the imitation loss."""
        raise NotImplementedError

    def validate(self) -> dict[str, float]:
        """Greedy validation (with ``run.eval_interval``)."""
        raise NotImplementedError

    def metadata(self) -> dict[str, Any]:
        """The policy files' metadata."""
        raise NotImplementedError

    def save_checkpoint(self) -> Path:
        """Write a checkpoint (atomically) and ``policy.safetensors``."""
        return self.write_checkpoint(
            self.network,
            self.metadata(),
            self.optimizer.state_dict(),
            self.dataset.state_dict(),
            self.run_state("dagger", rng=self.rng.bit_generator.state),
        )

    def _restore(self, path: Path, state: dict[str, Any], weights: dict[str, torch.Tensor]) -> None:
        self.network.load_state_dict(weights)
        self.optimizer.load_state_dict(ckpt.load_torch_state(path / "optimizer.pt"))
        self.dataset.load(ckpt.load_arrays(path / "replay.npz"))
        self.step = int(state["step"])
        self.rng.bit_generator.state = state["rng"]


class DaggerTrainer(ImitationRun):
    """Trains a :class:`~activevision.agents.student.StudentNetwork` by DAgger."""

    def __init__(
        self,
        config: TrainConfig,
        run_dir: str | os.PathLike[str],
        *,
        loggers: Sequence[Logger] | None = None,
        _resuming: bool = False,
    ) -> None:
        if config.algo != "dagger":
            raise ValueError(f"DaggerTrainer trains algo='dagger', got {config.algo!r}")
        self.config = config
        cfg, dag = config.env, config.dagger
        self.sim = EpisodeBatch(cfg, dag.num_envs)
        self.n_actions = len(self.sim.actions)
        self.continuous = cfg.action_type == "continuous"
        self.keys = vector_keys(cfg)
        self.observations = ObservationBuilder(cfg, dag.num_envs, self.n_actions)
        self.evidence = self._goal_evidence(dag.num_envs)
        self._start(
            run_dir,
            loggers,
            _resuming,
            outputs=self.n_actions,
            vector_size=sum(vector_sizes(cfg, self.n_actions).values()),
            image_shape=(cfg.camera.height, cfg.camera.width),
            n_goals=self._goal_outputs(),
            look_size=len(LOOK_FIELDS) if cfg.appearance.enabled else 0,
            robots=cfg.robots.max_count,
        )

    def _goal_outputs(self) -> int:
        """The goal head's logits: one per view, or per offset (``dagger.goal_frame``)."""
        dag, views = self.config.dagger, self.sim.localisation.grid.views
        if not dag.goal_class_weight > 0:
            return 0
        return goal_output_count(views, dag.goal_frame)

    def _goal_evidence(self, n: int) -> GoalEvidence | None:
        dag = self.config.dagger
        if dag.act_by != "goal":
            return None
        views = self.sim.localisation.grid.views
        return GoalEvidence(n, views, self.sim.actions, dag.switch_margin, dag.goal_frame)

    # ------------------------------------------------------------------ the loop
    def _rollout(self) -> None:
        """One round of ``num_envs`` fresh episodes, every visited state labelled."""
        sim = self.sim
        seeds = self.rng.integers(0, 2**31 - 1, size=sim.n)
        beta = self._round_share = self.teacher_share

        def choose(idx: np.ndarray, image: np.ndarray, vector: np.ndarray) -> np.ndarray:
            teacher = oracle_actions(
                sim.head[idx], sim.goal[idx], sim.cfg.action_type, sim.actions, sim.cfg.max_move
            )
            world: dict[str, np.ndarray] = {}
            looks = sim.frame_looks(idx)
            if looks is not None:
                world["looks"] = looks
            if "robots" in self.dataset.arrays:
                world["robots"] = sim.robots[idx]
            self.dataset.add(
                pose=sim.pose[idx],
                head=sim.head[idx],
                ball=sim.ball[idx],
                vector=vector,
                action=teacher,
                goal=goal_indices(sim)[idx],
                **world,
            )
            use_teacher = self.rng.random(len(idx)) < beta
            # the student sees every frame (its goal evidence must), even where it does not act
            student = self.act(image, vector, idx, self.evidence)
            self.step += len(idx)
            if self.continuous:
                use_teacher = use_teacher[:, None]
            return np.where(use_teacher, teacher, student)

        play_episodes(sim, self.observations, self.evidence, seeds, choose, self._end_episode)

    def act(
        self,
        image: np.ndarray,
        vector: np.ndarray,
        slots: np.ndarray,
        evidence: GoalEvidence | None,
        sim: EpisodeBatch | None = None,
    ) -> np.ndarray:
        """The student's actions for slots ``slots`` of ``sim`` (default: the training
        batch): see :func:`student_actions`."""
        sim = sim or self.sim
        return student_actions(self.network, self.device, image, vector, sim, slots, evidence)

    def _end_episode(self, i: int) -> None:
        sim = self.sim
        info = {k: v[i] for k, v in sim.info_arrays(MAX_EPISODE_STEPS).items()}
        self.record_episode(float(sim.episode_reward[i]), int(sim.step_count[i]), info)

    def _update(self) -> float:
        """One minibatch of rendered dataset states; returns the imitation loss."""
        data = self.dataset.arrays
        b = self.rng.integers(0, self.dataset.size, size=self.config.learner.batch_size)
        looks = data["looks"][b] if "looks" in data else None
        if looks is not None and self.config.dagger.redraw_look:
            looks = self._redraw_looks(looks)
        robots = data["robots"][b] if "robots" in data else np.zeros((len(b), 0, 4))
        images = self.sim.render_states(
            data["pose"][b], data["head"][b], data["ball"][b], looks, robots
        )
        image = torch.from_numpy(images[:, None]).to(self.device)
        vectors = data["vector"][b]
        if self.config.dagger.redraw_prior:
            vectors = self._redraw_priors(vectors, b)
        vector = torch.from_numpy(vectors).to(self.device)
        logits, goal_logits = self.network.forward_with_goal(image, vector)
        teacher = torch.from_numpy(data["action"][b]).to(self.device)
        if self.continuous:
            loss = F.mse_loss(logits, teacher)
        else:
            loss = F.cross_entropy(logits, teacher)
        if goal_logits is not None:
            goal = torch.from_numpy(self._goal_labels(b)).to(self.device)
            loss = loss + self.config.dagger.goal_class_weight * F.cross_entropy(goal_logits, goal)
        self.optimizer.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(self.network.parameters(), self.config.learner.max_grad_norm)
        self.optimizer.step()
        return float(loss.item())

    def _goal_labels(self, b: np.ndarray) -> np.ndarray:
        """The goal head's targets for dataset states ``b``: the goal view's index, or in
        the camera's frame the bilinear weights of the goal's offset from the head."""
        data = self.dataset.arrays
        if self.config.dagger.goal_frame == "body":
            indices: np.ndarray = data["goal"][b]
            return indices
        views = self.sim.localisation.grid.views
        labels: np.ndarray = offset_weights(
            views[data["goal"][b]] - data["head"][b], *offset_axes(views)
        ).astype(np.float32)
        return labels

    def _redraw_looks(self, looks: np.ndarray) -> np.ndarray:
        """The minibatch's looks drawn again from ``env.appearance`` (``dagger.redraw_look``):
        every episode column and the pattern key new, the frame's head move and counter
        kept."""
        out = looks.copy()
        episode = slice(0, LOOK["key"] + 1)
        fresh = draw_look_rows(self.config.env.appearance, len(looks), self.rng)
        out[:, episode] = fresh[:, episode]
        return out

    def _redraw_priors(self, vectors: np.ndarray, b: np.ndarray) -> np.ndarray:
        """The minibatch's vectors with the prior pose and proposal of every state whose
        prior was not exact drawn again at its error scale (``dagger.redraw_prior``)."""
        columns, data = vector_columns(self.config.env, self.n_actions), self.dataset.arrays
        errors = vectors[:, columns["pose_error"]][:, 0].astype(np.float64)
        rows = np.flatnonzero(errors > 0)
        if not len(rows):
            return vectors
        states = b[rows]
        prior, proposal = self.sim.redraw_priors(
            data["pose"][states],
            data["ball"][states],
            errors[rows],
            data["robots"][states] if "robots" in data else None,
            self.rng,
        )
        out = vectors.copy()
        out[rows, columns["pose"]] = pose_features(prior)
        if "proposal" in columns:
            out[rows, columns["proposal"]] = proposal_features(proposal, data["head"][states])
        return out

    def validate(self) -> dict[str, float]:
        """The student's greedy episodes on the validation seeds (the episodes of
        ``activevision evaluate --seed eval_seed``); keeps the best weights."""

        def play(network: StudentNetwork, seeds: Sequence[int]) -> list[dict[str, float]]:
            evidence = self._goal_evidence(len(seeds))
            return play_greedy(network, self.device, self.config.env, seeds, evidence)

        return self.validate_network(self.network, play, self.metadata())

    # ------------------------------------------------------------------ files
    def metadata(self) -> dict[str, Any]:
        """The policy files' metadata: the network's shape, the step and the observation."""
        cfg, grid = self.config.env, self.sim.localisation.grid
        return {
            **self.network.metadata(),
            "observation": cfg.observation,
            "action_history": cfg.action_history,
            "vector_keys": list(self.keys),
            "act_by": self.config.dagger.act_by,
            "goal_switch_margin": self.config.dagger.switch_margin,
            "goal_frame": self.config.dagger.goal_frame,
            "max_move_deg": list(cfg.max_move_deg),
            "goal_views_deg": np.degrees(grid.views).tolist(),
            "step": self.step,
        }


def play_episodes(
    sim: EpisodeBatch,
    observations: ObservationBuilder,
    evidence: GoalEvidence | None,
    seeds: Sequence[int] | np.ndarray,
    choose: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray],
    on_end: Callable[[int], None],
) -> None:
    """One episode in each slot of ``sim``, slot ``i`` reset as ``ActiveVision-v0`` with
    ``seeds[i]``: every step ``choose(slots, images, vectors)`` gives the actions of the
    slots still playing, and ``on_end(slot)`` is called when a slot's episode ends."""
    slots = np.arange(sim.n)
    sim.reset(slots, [seeding.np_random(int(s))[0] for s in seeds])
    observations.start(slots)
    if evidence is not None:
        evidence.reset(slots)
    active = np.ones(sim.n, dtype=bool)
    continuous = sim.cfg.action_type == "continuous"
    actions = np.zeros((sim.n, 2) if continuous else sim.n, np.float64 if continuous else int)
    for _ in range(MAX_EPISODE_STEPS):
        idx = np.flatnonzero(active)
        image = sim.render(idx)[:, None]
        vector = observations.vectors(sim)[idx]
        actions[idx] = choose(idx, image, vector)
        observations.record(actions[idx], idx)
        _, terminated, _, _ = sim.step(actions, active=active)
        ended = active & (terminated | (sim.step_count >= MAX_EPISODE_STEPS))
        for i in np.flatnonzero(ended):
            on_end(int(i))
        active &= ~ended
        if not active.any():
            return


def student_actions(
    network: StudentNetwork,
    device: torch.device,
    image: np.ndarray,
    vector: np.ndarray,
    sim: EpisodeBatch,
    slots: np.ndarray,
    evidence: GoalEvidence | None = None,
) -> np.ndarray:
    """A student's greedy actions for slots ``slots`` of ``sim`` from their images and
    vectors: the argmax of its action head (a continuous student: its move), or with
    ``evidence`` the oracle's move towards the view its summed goal evidence picks."""
    with torch.inference_mode():
        logits, goal_logits = network.forward_with_goal(
            torch.from_numpy(image).to(device), torch.from_numpy(vector).to(device)
        )
    continuous = sim.cfg.action_type == "continuous"
    return policy_actions(
        logits.cpu().numpy(),
        None if goal_logits is None else goal_logits.cpu().numpy(),
        sim.head[slots],
        np.asarray(sim.cfg.max_move) if continuous else None,
        evidence,
        slots,
    )


def play_greedy(
    network: StudentNetwork,
    device: torch.device,
    cfg: EnvConfig,
    seeds: Sequence[int],
    evidence: GoalEvidence | None = None,
) -> list[dict[str, float]]:
    """One greedy episode of ``network`` from each seed (each equal to ``ActiveVision-v0``
    with ``cfg`` reset with that seed), played as one batch; an ``episodes.csv``-style
    record each."""
    sim = EpisodeBatch(cfg, len(seeds))
    n_actions = len(sim.actions)
    observations = ObservationBuilder(cfg, len(seeds), n_actions)
    records: list[dict[str, float]] = [{} for _ in seeds]

    def record(i: int) -> None:
        info = {k: v[i] for k, v in sim.info_arrays(MAX_EPISODE_STEPS).items()}
        steps = int(sim.step_count[i])
        records[i] = episode_record(i, 0, float(sim.episode_reward[i]), steps, info)

    play_episodes(
        sim,
        observations,
        evidence,
        seeds,
        lambda idx, image, vector: student_actions(
            network, device, image, vector, sim, idx, evidence
        ),
        record,
    )
    return records
