"""DAgger on the match (``ActiveVisionMatch-v0``): a student network learns to aim the head
from what the robot knows -- the camera image, its head angles, its belief (mean and
std) and its ball model (the observation ``"image+head+belief"``).

The teacher is this package's match planner, ``entropy_track``
(:class:`~activevision.envs.match.heads.EntropyTrackTeacher`: Algorithm 1 every tick among
the views that keep the ball ``dagger.track_margin_deg`` inside the image), or with
``dagger.match_teacher="glance_track"`` the ball tracker that localises when unsure or while
the ball is out of reach (:class:`~activevision.envs.match.heads.GlanceTrackTeacher`). It
reads the same knowledge as the student, nothing privileged: the student learns to plan as
it does in one forward pass (``bench/match_student.py``: 0.33 ms a decision on one core with
a 640 x 480 frame, the planner's compiled search over 481 views 0.82 ms), and to act on the
image besides.

One round: ``dagger.num_envs`` fresh matches (seeded from the run's generator) played to
the end together in the native vector env; at each tick the executed action is the
teacher's with probability ``beta`` (decayed linearly from ``teacher_initial`` to 0 over
``teacher_fraction`` of the run), else the student's greedy one; every visited state is
stored with the teacher's action. Then ``updates_per_rollout`` minibatches of stored
states, re-rendered by the exact renderer, train the student (cross-entropy on the
teacher's discrete move; squared error on its continuous one).

The run directory is a DAgger run's (``config.json``, ``metrics.csv`` with one row per
round crossing an ``epoch_steps`` boundary and one ``episodes.csv`` row per match,
``policy.safetensors``, ``checkpoints/``; rounds start fresh matches, so a checkpoint holds
everything and ``resume`` continues exactly). With ``run.eval_interval`` the student plays
``run.eval_episodes`` greedy validation matches (:meth:`MatchDaggerTrainer.validate`; their
position RMSE, ball in view and mean reward go to ``evaluations.csv``) and the weights of the
best mean match reward to ``best_policy.safetensors``. Measure it on held-out seeds with
``activevision match --run RUN --methods learned``.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
from torch.nn import functional as F

from activevision.agents.student import StudentNetwork
from activevision.envs.actions import action_table
from activevision.envs.match.config import MATCH_ACTION_SET, MatchConfig
from activevision.envs.match.heads import EntropyTrackTeacher, GlanceTrackTeacher
from activevision.envs.match.observations import (
    IMAGE_KEY,
    VECTOR_SIZES,
    knowledge_vectors,
    vector_keys,
)
from activevision.envs.match.scores import MatchScores
from activevision.envs.match.vector import ActiveVisionMatchVectorEnv
from activevision.geometry.occlusion import robot_cylinders
from activevision.training.config import MATCH_ENV_ID, TrainConfig
from activevision.training.dagger import ImitationRun
from activevision.training.loggers import Logger


class MatchDaggerTrainer(ImitationRun):
    """Trains a :class:`~activevision.agents.student.StudentNetwork` on the match by DAgger."""

    def __init__(
        self,
        config: TrainConfig,
        run_dir: str | os.PathLike[str],
        *,
        loggers: Sequence[Logger] | None = None,
        _resuming: bool = False,
    ) -> None:
        if config.algo != "dagger" or config.env_id != MATCH_ENV_ID:
            raise ValueError(
                f"MatchDaggerTrainer trains algo='dagger' on {MATCH_ENV_ID}, got"
                f" {config.algo!r} on {config.env_id!r}"
            )
        self.config = config
        match, dag = config.match, config.dagger
        self.continuous = match.action_type == "continuous"
        self.keys = vector_keys(match)
        self.n_actions = len(action_table(match.step_deg, MATCH_ACTION_SET))
        self.env = ActiveVisionMatchVectorEnv(dag.num_envs, match)
        self.teacher = (
            GlanceTrackTeacher(match, track_margin_deg=dag.glance_track_margin_deg)
            if dag.match_teacher == "glance_track"
            else EntropyTrackTeacher(match, dag.track_margin_deg)
        )
        self._start(
            run_dir,
            loggers,
            _resuming,
            outputs=self.n_actions,
            vector_size=sum(VECTOR_SIZES[k] for k in self.keys),
            image_shape=(match.camera.height, match.camera.width),
            robots=match.robots.max_count,
        )

    # ------------------------------------------------------------------ the loop
    def _rollout(self) -> None:
        """One round: ``num_envs`` fresh matches to the end, every tick labelled."""
        env, match = self.env, self.config.match
        beta = self._round_share = self.teacher_share
        obs, info = env.reset(seed=int(self.rng.integers(0, 2**31 - 1 - env.num_envs)))
        reward = np.zeros(env.num_envs)
        for _ in range(match.ticks):
            assert isinstance(obs, dict)
            vector = knowledge_vectors(info, self.keys, match.tick_seconds)
            teacher = self.teacher.actions(info)
            world = {"robots": info["robots"]} if "robots" in self.dataset.arrays else {}
            self.dataset.add(
                pose=info["pose"],
                head=info["head"],
                ball=info["ball"],
                vector=vector,
                action=teacher,
                goal=np.zeros(env.num_envs, dtype=np.int64),
                **world,
            )
            student = self.act(obs[IMAGE_KEY], vector)
            use_teacher = self.rng.random(env.num_envs) < beta
            if self.continuous:
                use_teacher = use_teacher[:, None]
            obs, r, _, _, info = env.step(np.where(use_teacher, teacher, student))
            reward += r
            self.step += env.num_envs
        for i in range(env.num_envs):  # every match ends together, after ``ticks`` ticks
            # a match has no success rate (NaN, not 0, in metrics.csv)
            self.record_episode(float(reward[i]), match.ticks, {"success_rate": math.nan})

    def act(self, image: np.ndarray, vector: np.ndarray) -> np.ndarray:
        """The student's greedy actions from images (N, 1, H, W) and vectors (N, V)."""
        return student_match_actions(self.network, self.device, image, vector)

    def _update(self) -> float:
        """One minibatch of re-rendered dataset states; returns the imitation loss."""
        data, match = self.dataset.arrays, self.config.match
        b = self.rng.integers(0, self.dataset.size, size=self.config.learner.batch_size)
        cylinders = (
            robot_cylinders(data["robots"][b], match.robots.radius) if "robots" in data else None
        )
        head = data["head"][b]
        images = self.env.sim.renderer.render(
            data["pose"][b], head[:, 0], head[:, 1], data["ball"][b], cylinders=cylinders
        )
        image = torch.from_numpy(images[:, None]).to(self.device)
        vector = torch.from_numpy(data["vector"][b]).to(self.device)
        output = self.network(image, vector)
        teacher = torch.from_numpy(data["action"][b]).to(self.device)
        loss = F.mse_loss(output, teacher) if self.continuous else F.cross_entropy(output, teacher)
        self.optimizer.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(self.network.parameters(), self.config.learner.max_grad_norm)
        self.optimizer.step()
        return float(loss.item())

    def validate(self) -> dict[str, float]:
        """The student's greedy matches on the validation seeds (``run.eval_episodes``
        matches seeded ``episode_seed(run.eval_seed, i)``, never the consecutive seeds that
        ``activevision match --seed S`` plays); keeps the weights of the best mean reward."""

        def play(network: StudentNetwork, seeds: Sequence[int]) -> list[dict[str, float]]:
            return play_student_matches(network, self.device, self.config.match, seeds)

        return self.validate_network(self.network, play, self.metadata())

    # ------------------------------------------------------------------ files
    def metadata(self) -> dict[str, Any]:
        """The policy files' metadata: the network's shape, the step and the observation."""
        match = self.config.match
        return {
            **self.network.metadata(),
            "env_id": MATCH_ENV_ID,
            "observation": match.observation,
            "vector_keys": list(self.keys),
            "act_by": "action",
            "max_move_deg": list(match.max_move_deg),
            "step": self.step,
        }

    def close(self) -> None:
        self.env.close()
        super().close()


def play_student_matches(
    network: StudentNetwork, device: torch.device, match: MatchConfig, seeds: Sequence[int]
) -> list[dict[str, float]]:
    """One greedy match of ``network`` from each seed (sub-environment ``i`` reset with
    ``seeds[i]``), played in lock-step: each match's total reward and the metrics of
    :mod:`activevision.envs.match.scores`."""
    env = ActiveVisionMatchVectorEnv(len(seeds), match)
    keys = vector_keys(match)
    obs, info = env.reset(seed=[int(s) for s in seeds])
    scores = MatchScores(match.ticks, len(seeds), match.tick_seconds)
    for _ in range(match.ticks):
        assert isinstance(obs, dict)
        vector = knowledge_vectors(info, keys, match.tick_seconds)
        actions = student_match_actions(network, device, obs[IMAGE_KEY], vector)
        obs, reward, _, _, info = env.step(actions)
        scores.add(info, reward)
    env.close()
    per_match = scores.per_match()
    return [
        {"reward": scores.reward[i], **{k: v[i] for k, v in per_match.items()}}
        for i in range(len(seeds))
    ]


def student_match_actions(
    network: StudentNetwork, device: torch.device, image: np.ndarray, vector: np.ndarray
) -> np.ndarray:
    """A match student's greedy actions: the argmax of its logits (N,), or its move (N, 2)."""
    with torch.inference_mode():
        output = network(torch.from_numpy(image).to(device), torch.from_numpy(vector).to(device))
    if network.continuous:
        return np.asarray(output.cpu().numpy(), dtype=np.float64)
    return np.asarray(output.argmax(dim=1).cpu().numpy(), dtype=np.int64)


__all__ = ["MatchDaggerTrainer", "play_student_matches", "student_match_actions"]
