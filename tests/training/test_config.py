import json

import pytest

from activevision.training.config import (
    TrainConfig,
    apply_overrides,
    load_config,
    preset,
    save_config,
)


def test_paper_defaults_and_release_preset():
    config = TrainConfig()
    assert (config.batch_size, config.buffer_size, config.learning_rate) == (32, 1_000_000, 5e-4)
    assert (config.gamma, config.target_update_interval) == (0.99, 10_000)
    assert (config.exploration_initial, config.exploration_final) == (1.0, 0.02)
    assert (config.per_alpha, config.per_beta0, config.per_eps) == (0.6, 0.4, 1e-6)
    assert (config.learning_starts, config.exploration_fraction) == (1000, 0.1)
    assert preset("paper") == config
    release = preset("release")
    assert (release.learning_starts, release.exploration_fraction) == (500, 0.85)
    with pytest.raises(ValueError, match="nope"):
        preset("nope")


@pytest.mark.parametrize("name, factor", [("data4x", 4), ("data8x", 8)])
def test_more_episodes_keep_the_papers_update_budget(name, factor):
    paper, more = preset("paper"), preset(name)

    def updates(c):
        return (c.total_timesteps - c.learning_starts) // c.train_freq

    assert more.total_timesteps == factor * paper.total_timesteps
    assert updates(more) == updates(paper)  # 29,000 gradient updates each
    assert more.target_update_interval // more.train_freq == paper.target_update_interval
    assert more.learning_starts // more.train_freq == paper.learning_starts
    assert more.eval_interval > 0  # validated, so the run's curve shows the greedy policy
    # exploration spans the same fraction of the run; the learner itself is the paper's
    for key in ("learning_rate", "gamma", "batch_size", "exploration_fraction", "per_alpha"):
        assert getattr(more, key) == getattr(paper, key)


def test_drq_aux_is_the_paper_run_with_two_training_aids():
    paper, drq_aux = preset("paper"), preset("drq_aux")
    assert (drq_aux.augment_shift, drq_aux.aux_goal_weight) == (8, 1.0)
    assert drq_aux.replace(augment_shift=0, aux_goal_weight=0.0) == paper


def test_json_round_trip(tmp_path):
    env_kwargs = {"frame_stack": 2, "max_episode_steps": 20}
    config = TrainConfig(seed=3, env_kwargs=env_kwargs, learning_rate=1e-3)
    save_config(config, tmp_path / "config.json")
    assert load_config(tmp_path / "config.json") == config
    assert not list(tmp_path.glob(".*tmp"))  # the temporary file is gone


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("learning_rate", -1e-3),
        ("exploration_fraction", 1.5),
        ("gamma", -0.1),
        ("batch_size", 0),
        ("n_step", 0),
        ("learning_starts", -1),
        ("per_eps", 0.0),
        ("checkpoint_interval", 250),  # not a multiple of epoch_steps
        ("batch_size", 3.5),
        ("dueling", "yes"),
        ("device", "tpu"),
    ],
)
def test_invalid_values_name_the_key(key, value):
    with pytest.raises(ValueError, match=key):
        TrainConfig(**{key: value})


def test_unknown_keys_name_the_key(tmp_path):
    path = tmp_path / "config.json"
    path.write_text(json.dumps({"learning_rate": 1e-3, "lerning_rate": 1e-3}))
    with pytest.raises(ValueError, match="lerning_rate"):
        load_config(path)


def test_cli_overrides():
    config = apply_overrides(
        TrainConfig(),
        ["learning_rate=1e-3", "dueling=true", "env_id=Other-v1", "env_kwargs.stack=4"],
    )
    assert config.learning_rate == 1e-3 and config.dueling and config.env_id == "Other-v1"
    assert config.env_kwargs == {"stack": 4}
    assert apply_overrides(config, ['env_kwargs={"a": 1}']).env_kwargs == {"a": 1}
    with pytest.raises(ValueError, match="bogus"):
        apply_overrides(config, ["bogus=1"])
    with pytest.raises(ValueError, match="total_timesteps"):
        apply_overrides(config, ["total_timesteps=-5"])
