"""Other RL libraries plug in: Stable-Baselines3 checks and trains on ActiveVision-v0."""

import gymnasium as gym
import numpy as np

import activevision.envs  # noqa: F401


def test_stable_baselines3_check_env_passes():
    from stable_baselines3.common.env_checker import check_env

    check_env(gym.make("ActiveVision-v0"), warn=True, skip_render_check=True)


def test_dict_observations_pass_check_env_and_feed_multi_input_policy():
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_checker import check_env

    env = gym.make(
        "ActiveVision-v0",
        observation="image+head+pose+proposal",
        action_history=2,
        prior_error_range=(0.0, 1.0),
    )
    check_env(env, warn=True, skip_render_check=True)
    torch.manual_seed(0)
    model = PPO(
        "MultiInputPolicy", env, n_steps=32, batch_size=16, n_epochs=1, seed=0, device="cpu"
    )
    model.learn(64)
    obs, _ = env.reset(seed=1)
    action, _ = model.predict(obs, deterministic=True)
    assert env.action_space.contains(int(action))


def test_stable_baselines3_dqn_trains_a_few_hundred_steps():
    import torch
    from stable_baselines3 import DQN

    torch.set_num_threads(1)
    env = gym.make("ActiveVision-v0")
    model = DQN(
        "CnnPolicy",
        env,
        buffer_size=1000,
        learning_starts=100,
        batch_size=8,
        train_freq=4,
        target_update_interval=100,
        seed=0,
        device="cpu",
        verbose=0,
    )
    model.learn(total_timesteps=300)
    assert model.num_timesteps == 300
    assert model._n_updates > 0
    obs, _ = env.reset(seed=1)
    action, _ = model.predict(obs, deterministic=True)
    assert env.action_space.contains(int(action))
    assert np.isfinite(model.q_net(torch.as_tensor(obs[None])).detach().numpy()).all()


def test_import_activevision_registers_the_env_without_heavy_imports():
    import subprocess
    import sys

    code = (
        "import sys, gymnasium as gym\n"
        "import activevision\n"
        "assert 'numba' not in sys.modules and 'torch' not in sys.modules\n"
        "env = gym.make('ActiveVision-v0')\n"
        "obs, info = env.reset(seed=0)\n"
        "assert obs.shape == (1, 120, 160)\n"
        "env = gym.make('activevision:ActiveVision-v0')\n"
        "assert 'torch' not in sys.modules\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=300)


def test_a_spec_written_to_json_makes_the_same_env():
    """Gymnasium's ``EnvSpec.to_json`` (how Minari stores a dataset's env) writes config
    keywords as JSON objects (``dataclasses.asdict``): ``make(EnvSpec.from_json(...))``
    refused them ("config: expects EnvConfig or None, got {...}"), and ``to_json`` itself
    failed on the UKF's noise table ("cannot pickle 'mappingproxy' object") for a match
    config or a localisation config."""
    from gymnasium.envs.registration import EnvSpec

    from activevision.envs import EnvConfig
    from activevision.envs.match.config import MatchConfig, WalkConfig
    from activevision.envs.robots import RobotsConfig
    from activevision.localisation import LocalisationConfig
    from activevision.rendering.appearance import AppearanceConfig

    made = [
        gym.make("ActiveVision-v0", config=EnvConfig(frame_stack=2), field="paper2019"),
        gym.make(
            "ActiveVision-v0",
            localisation=LocalisationConfig(),
            appearance=AppearanceConfig.randomised(),
            robots=RobotsConfig(count=(1, 2)),
        ),
        gym.make("ActiveVisionMatch-v0", config=MatchConfig(ticks=5)),
        gym.make("ActiveVisionMatch-v0", walk=WalkConfig(target="ball"), ticks=5),
    ]
    for env in made:
        assert env.spec is not None
        twin = gym.make(EnvSpec.from_json(env.spec.to_json()))
        assert twin.unwrapped.config == env.unwrapped.config
        assert np.array_equal(twin.reset(seed=3)[0], env.reset(seed=3)[0])
