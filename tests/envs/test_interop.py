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
