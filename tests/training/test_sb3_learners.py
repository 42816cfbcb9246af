"""Stable-Baselines3's SAC, TD3 and PPO: their actors are StudentNetworks exactly, runs keep
the package's layout, resume restores weights, optimisers and replay, and the policy plays
through evaluate, export and HeadController alike."""

from __future__ import annotations

import csv
import json
import tempfile

import numpy as np
import pytest
import torch

from activevision.agents.sb3_features import actor_network
from activevision.envs import ActiveVisionEnv
from activevision.envs.observations import flatten_vectors, vector_keys
from activevision.experiments.evaluate import evaluate_policy
from activevision.experiments.policies import LearnedPolicy, OnnxPolicy
from activevision.training import load_policy
from activevision.training.checkpoint import (
    CheckpointError,
    checkpoint_name,
    list_checkpoints,
)
from activevision.training.config import TrainConfig
from activevision.training.runs import reopen_run
from activevision.training.sb3_learners import Sb3Trainer, build_model, make_vec_env


def tiny(algo: str, observation: str = "image+head", steps: int = 400, **extra) -> TrainConfig:
    # what the algo reads (a key it never reads is refused): PPO's rollout, SAC's and TD3's
    # replay
    own = (
        {"sb3.n_steps": 32}
        if algo == "ppo"
        else {"replay.buffer_size": 1000, "learner.learning_starts": 50}
    )
    # validation's episodes only where the run validates (else never read: refused)
    validation = {"run.eval_interval": 200, "run.eval_episodes": 6}
    if extra.get("run.eval_interval", 200) == 0:
        validation = {}
    return TrainConfig().replace(
        **{
            "algo": algo,
            "env.action_type": "continuous",
            "env.observation": observation,
            "run.total_timesteps": steps,
            "run.epoch_steps": 100,
            **validation,
            "run.checkpoint_interval": 200,
            "run.tensorboard": False,
            "learner.batch_size": 16,
            "sb3.num_envs": 2,
            **own,
            **extra,
        }
    )


@pytest.mark.parametrize(
    ("algo", "observation", "action_type"),
    [
        ("sac", "image+head", "continuous"),
        ("td3", "image", "continuous"),
        ("ppo", "image+head+pose", "continuous"),
        ("ppo", "image+head", "discrete"),
    ],
)
def test_actor_network_is_sb3s_deterministic_policy(algo, observation, action_type):
    config = tiny(algo, observation, **{"env.action_type": action_type})
    vec = make_vec_env(config)
    model = build_model(config, vec, torch.device("cpu"))
    # weights away from their initialisation, so that the copy is tested on every layer
    with torch.no_grad():
        for parameter in model.policy.parameters():
            parameter.add_(0.05 * torch.randn_like(parameter))
    actor = actor_network(model, n_actions=9)
    env = ActiveVisionEnv(config.env)
    keys = vector_keys(config.env)
    for seed in range(5):
        obs, _ = env.reset(seed=seed)
        want, _ = model.predict(obs, deterministic=True)
        image = obs["image"] if isinstance(obs, dict) else obs
        vector = flatten_vectors(obs, keys) if keys else np.zeros(0, np.float32)
        with torch.inference_mode():
            got = actor(torch.from_numpy(image[None]), torch.from_numpy(vector[None])).numpy()[0]
        if action_type == "discrete":
            assert int(np.argmax(got)) == int(want)
        else:
            np.testing.assert_allclose(got, want, atol=1e-5)
            assert np.abs(got).max() <= 1.0 and np.abs(got).max() > 1e-3
    vec.close()


def test_run_layout_resume_and_export(tmp_path, monkeypatch):
    run = tmp_path / "sac"
    scratch = tmp_path / "tmp"  # the temporary directory, watched: SB3 made a folder per learn
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    monkeypatch.delenv("SB3_LOGDIR", raising=False)
    trainer = Sb3Trainer(tiny("sac"), run)
    first = trainer.train(200)
    buffer_pos = trainer.model.replay_buffer.pos
    saved = {k: v.clone() for k, v in trainer.model.policy.state_dict().items()}
    updates = trainer.model._n_updates
    trainer.close()
    for name in ("config.json", "metrics.csv", "episodes.csv", "evaluations.csv"):
        assert (run / name).exists(), name
    assert (run / "policy.safetensors").exists() and (run / "best_policy.safetensors").exists()
    assert [int(r["step"]) for r in first] == [100, 200]
    assert all(np.isfinite(r["loss"]) for r in first[1:]) and first[1]["updates"] > 0

    resumed = reopen_run(run)
    assert isinstance(resumed, Sb3Trainer) and resumed.step == 200
    assert resumed.model.replay_buffer.pos == buffer_pos > 0
    assert resumed.model._n_updates == updates
    for key, value in resumed.model.policy.state_dict().items():
        torch.testing.assert_close(value, saved[key], msg=key)
    np.testing.assert_array_equal(
        resumed.model.replay_buffer.actions[:buffer_pos],
        trainer.model.replay_buffer.actions[:buffer_pos],
    )
    rest = resumed.train()
    resumed.close()
    assert [int(r["step"]) for r in rest] == [300, 400]
    with (run / "metrics.csv").open() as f:
        assert [int(r["step"]) for r in csv.DictReader(f)] == [100, 200, 300, 400]
    with (run / "evaluations.csv").open() as f:
        assert [int(r["step"]) for r in csv.DictReader(f)] == [200, 400]
    assert list_checkpoints(run)[-1].name == checkpoint_name(400)
    assert list(scratch.glob("SB3-*")) == []  # the losses above came from memory

    # the policy: torch (evaluate) and ONNX (HeadController) play the same episodes
    from activevision.export import export_run

    exported = export_run(run)
    meta = json.loads(exported.metadata_path.read_text())
    assert meta["action_type"] == "continuous" and meta["max_move_deg"] == [10.0, 10.0]
    network = load_policy(run)
    assert network.continuous and network.squash == "tanh"
    learned, onnx = LearnedPolicy.from_run(run), OnnxPolicy(exported.model_path)
    env_config = onnx.env_config()
    torch_records, _, _ = evaluate_policy(learned, 8, seed=3, config=env_config)
    onnx_records, _, _ = evaluate_policy(onnx, 8, seed=3, config=env_config)
    for a, b in zip(torch_records, onnx_records, strict=True):
        assert a["steps"] == b["steps"] and a["success"] == b["success"]
        assert a["head_travel"] == pytest.approx(b["head_travel"], abs=1e-3)
    # continuous moves are not the 3-degree grid: some step is neither 0 nor a multiple of 3
    assert any(r["head_travel"] % 3 > 1e-3 for r in torch_records)


def test_a_run_shorter_than_an_epoch_logs_a_metrics_row(tmp_path):
    """A run of fewer steps than epoch_steps left metrics.csv with its header alone."""
    changes = {"run.epoch_steps": 1000, "run.eval_interval": 0, "run.checkpoint_interval": 0}
    trainer = Sb3Trainer(tiny("ppo", steps=64, **changes), tmp_path)
    try:
        rows = trainer.train()
    finally:
        trainer.close()
    with (tmp_path / "metrics.csv").open() as f:
        logged = list(csv.DictReader(f))
    assert len(rows) == len(logged) == 1
    assert (int(logged[0]["epoch"]), int(logged[0]["step"])) == (1, 64)
    assert np.isfinite(float(logged[0]["loss"]))  # the rollout's update is in it


def test_a_changed_config_refuses_to_resume(tmp_path):
    trainer = Sb3Trainer(tiny("ppo", steps=64, **{"run.checkpoint_interval": 0}), tmp_path)
    trainer.train()
    trainer.close()  # it holds the run until then (training.run_lock)
    config = json.loads((tmp_path / "config.json").read_text())
    config["sb3"]["n_epochs"] = 2
    (tmp_path / "config.json").write_text(json.dumps(config))
    with pytest.raises(CheckpointError, match="was changed"):
        reopen_run(tmp_path)


@pytest.mark.parametrize(
    ("changes", "needle"),
    [
        ({"algo": "sac"}, "needs env.action_type='continuous'"),
        ({"algo": "td3", "env.action_type": "continuous"}, "at most 200000"),
        ({"algo": "ddqn", "env.action_type": "continuous"}, "DDQN learns discrete actions"),
        ({"algo": "ppo", "env.frame_stack": 4}, "frame_stack=1"),
    ],
)
def test_configs_the_learners_cannot_train_are_refused(changes, needle):
    with pytest.raises(ValueError, match=needle.replace("(", r"\(")):
        TrainConfig().replace(**changes)
