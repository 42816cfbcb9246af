"""Every learner shows the run's progress bar on a terminal (DDQN's steps, DAgger's rounds,
Stable-Baselines3's callback steps), and none off a terminal or with run.progress_bar off."""

from __future__ import annotations

import re
import sys

import pytest

from activevision.training.config import TrainConfig
from activevision.training.progress import postfix
from activevision.training.runs import train

#: per algo: a tiny run of ActiveVision-v0 and the postfix key its bar shows for epsilon
TINY: dict[str, dict] = {
    "ddqn": {
        "learner.batch_size": 8,
        "learner.learning_starts": 20,
        "replay.buffer_size": 1000,
    },
    "dagger": {
        "algo": "dagger",
        "env.observation": "image+head",
        "dagger.num_envs": 8,
        "dagger.updates_per_rollout": 1,
        "learner.batch_size": 8,
    },
    "ppo": {
        "algo": "ppo",
        "env.action_type": "continuous",
        "env.observation": "image+head",
        "sb3.num_envs": 2,
        "sb3.n_steps": 32,
        "learner.batch_size": 16,
    },
}


def tiny(algo: str, progress: bool) -> TrainConfig:
    return TrainConfig().replace(
        **{
            "run.total_timesteps": 120,
            "run.epoch_steps": 60,
            "run.checkpoint_interval": 0,
            "run.tensorboard": False,
            "run.num_threads": 1,
            "run.progress_bar": progress,
            **TINY[algo],
        }
    )


@pytest.mark.parametrize("algo", list(TINY))
def test_every_learner_draws_its_bar_on_a_terminal(algo, tmp_path, capsys, monkeypatch):
    """DAgger and SB3 runs printed nothing while they trained (the bar was DDQN's only)."""
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    train(tiny(algo, progress=True), tmp_path / "on")
    shown = capsys.readouterr().err
    # the bar ends at the run's last step, though DAgger's rounds and PPO's rollouts pass it
    assert re.search(r"\b120/120 \[", shown), shown[-400:]
    assert "step/s" in shown or "s/step" in shown
    assert "sps=" in shown  # an epoch row's summary


@pytest.mark.parametrize("algo", list(TINY))
def test_no_bar_when_it_is_off_or_off_a_terminal(algo, tmp_path, capsys, monkeypatch):
    train(tiny(algo, progress=True), tmp_path / "pipe")  # stderr is no terminal here
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    train(tiny(algo, progress=False), tmp_path / "off")
    assert "120/120" not in capsys.readouterr().err


def test_postfix_names_what_each_learner_logs_as_epsilon():
    row = {"success_rate": 0.5, "episode_reward": 1.0, "loss": 0.1, "epsilon": 0.3}
    row["steps_per_s"] = 12.0
    assert list(postfix(row)) == ["success", "reward", "loss", "eps", "sps"]
    assert postfix(row, "dagger")["teacher"] == "0.30"
    assert list(postfix(row, "dagger"))[-1] == "sps"
    assert "eps" not in postfix(row, "sac") and "teacher" not in postfix(row, "sac")
    assert "success" not in postfix({**row, "success_rate": float("nan")})
