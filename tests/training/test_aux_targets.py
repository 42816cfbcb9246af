"""The auxiliary target is a function handed to the trainer; goal_offset is ActiveVision-v0's."""

from __future__ import annotations

import numpy as np
import pytest

from activevision.training.aux_targets import aux_vector, goal_offset, resolve_aux_target
from activevision.training.config import TrainConfig
from activevision.training.policy_files import load_policy
from activevision.training.trainer import Trainer


def tiny_config(**changes) -> TrainConfig:
    values = dict(
        seed=11,
        total_timesteps=60,
        epoch_steps=60,
        batch_size=8,
        buffer_size=1000,
        learning_starts=20,
        checkpoint_interval=60,
        aux_goal_weight=1.0,
        tensorboard=False,
        progress_bar=False,
        num_threads=1,
        env_id="unused",
    )
    values.update(changes)
    return TrainConfig().replace(**values)


def pan_and_goal(obs: np.ndarray) -> tuple[int, int]:
    """The fake env's hidden state from its image: pan column 255, goal column 128 (+1)."""
    columns, width = obs[0].max(axis=0), obs.shape[-1]
    pan = np.flatnonzero(columns == 255)[0] * 10 // width
    goal = (np.flatnonzero(columns == 128)[0] - 1) * 10 // width
    return int(pan), int(goal)


def three_numbers(info: dict) -> np.ndarray:
    """A target of one's own, of another length than goal_offset's."""
    pan, goal = info["head"][0], info["goal_viewpoint"][0]
    return np.array([pan, goal, pan * goal + 7.0])


def test_the_replay_stores_what_the_given_function_returns(tmp_path, fake_env_factory):
    trainer = Trainer(tiny_config(), tmp_path, fake_env_factory, aux_target=three_numbers)
    trainer.train()
    assert trainer.buffer.aux_dim == 3 and trainer.learner.online.aux_outputs == 3
    batch = trainer.buffer.sample(64, beta=1.0)
    for obs, aux in zip(batch.obs, batch.aux, strict=True):
        pan, goal = pan_and_goal(obs)  # the target is that of the stored observation
        np.testing.assert_allclose(aux, [0.1 * pan, 0.1 * goal, 0.01 * pan * goal + 7], atol=1e-6)
    trainer.close()
    assert load_policy(tmp_path).aux_outputs == 3

    resumed = Trainer.resume(tmp_path, fake_env_factory, aux_target=three_numbers)
    assert resumed.buffer.aux_dim == 3 and resumed.step == 60
    resumed.close()


def test_another_env_without_a_function_is_a_clear_error(tmp_path, fake_env_factory):
    with pytest.raises(ValueError, match="aux_target") as error:
        Trainer(tiny_config(), tmp_path / "run", fake_env_factory)
    assert "'unused'" in str(error.value) and "ActiveVision-v0" in str(error.value)
    assert not (tmp_path / "run").exists()  # refused before anything is written

    trainer = Trainer(tiny_config(), tmp_path / "run", fake_env_factory, aux_target=goal_offset)
    trainer.train()
    trainer.close()
    with pytest.raises(ValueError, match="aux_target"):  # resuming needs it as well
        Trainer.resume(tmp_path / "run", fake_env_factory)


def test_the_default_is_goal_offset_for_active_vision_only():
    for env_id in ("ActiveVision-v0", "activevision:ActiveVision-v0"):
        assert resolve_aux_target(tiny_config(env_id=env_id), None) is goal_offset
    assert resolve_aux_target(tiny_config(env_id="CartPole-v1"), three_numbers) is three_numbers
    with pytest.raises(ValueError, match="CartPole-v1"):
        resolve_aux_target(tiny_config(env_id="CartPole-v1"), None)
    # no auxiliary head without aux_goal_weight: no target needed, a given one is unused
    assert resolve_aux_target(tiny_config(aux_goal_weight=0.0, env_id="CartPole-v1"), None) is None
    assert resolve_aux_target(tiny_config(aux_goal_weight=0.0), three_numbers) is None


def test_targets_are_flat_finite_float32_vectors():
    vector = aux_vector(lambda info: [[1, 2]], {})
    assert vector.dtype == np.float32 and vector.shape == (2,)
    with pytest.raises(ValueError, match="non-finite"):
        aux_vector(lambda info: np.array([0.0, np.nan]), {})


def test_no_target_means_no_auxiliary_head(tmp_path, fake_env_factory):
    config = tiny_config(aux_goal_weight=0.0)
    trainer = Trainer(config, tmp_path, fake_env_factory, aux_target=three_numbers)
    assert trainer.aux_target is None and trainer.buffer.aux_dim == 0
    assert trainer.learner.online.aux_outputs == 0
    trainer.close()
