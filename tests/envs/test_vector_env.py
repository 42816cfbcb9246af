import os
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

import activevision.envs  # noqa: F401
from activevision.envs import ActiveVisionVectorEnv
from activevision.envs.config import EnvConfig
from activevision.envs.robots import RobotsConfig
from activevision.rendering.appearance import AppearanceConfig


def test_make_vec_returns_the_native_vector_env():
    envs = gym.make_vec("ActiveVision-v0", num_envs=3, vectorization_mode="vector_entry_point")
    assert isinstance(envs, ActiveVisionVectorEnv)
    obs, infos = envs.reset(seed=0)
    assert obs.shape == (3, 1, 120, 160)
    assert infos["success_rate"].shape == (3,)


#: A randomised world: every appearance factor on, 2-4 other robots.
WORLD = EnvConfig(appearance=AppearanceConfig.randomised(), robots=RobotsConfig(count=(2, 4)))


@pytest.mark.parametrize(
    "kwargs",
    [{"frame_stack": 1}, {"frame_stack": 3}, {"config": WORLD}],
    ids=["stack1", "stack3", "randomised-world"],
)
def test_vector_env_equals_single_envs_with_the_same_seeds(kwargs):
    n, seed, steps = 4, 11, 45
    rng = np.random.default_rng(0)
    actions = rng.integers(0, 9, (steps, n))
    venv = ActiveVisionVectorEnv(num_envs=n, **kwargs)
    singles = [gym.make("ActiveVision-v0", **kwargs) for _ in range(n)]
    vobs, _ = venv.reset(seed=seed)
    sobs = [e.reset(seed=seed + i)[0] for i, e in enumerate(singles)]
    done = np.zeros(n, dtype=bool)
    resets = 0
    for t in range(steps):
        for i in range(n):
            np.testing.assert_array_equal(vobs[i], sobs[i], err_msg=f"env {i} step {t}")
        vobs, vr, vterm, vtrunc, _ = venv.step(actions[t])
        for i, env in enumerate(singles):
            if done[i]:  # NEXT_STEP autoreset: this step resets the sub-env
                sobs[i], _ = env.reset()
                resets += 1
                assert vr[i] == 0 and not vterm[i] and not vtrunc[i]
            else:
                sobs[i], r, term, trunc, _ = env.step(int(actions[t, i]))
                assert (r, term, trunc) == (vr[i], vterm[i], vtrunc[i])
        done = vterm | vtrunc
    assert resets >= n  # 45 steps cross the 20-step limit: every sub-env was reset


def test_environments_leave_torch_thread_count_alone():
    """numba's OpenMP pool resets a shared libgomp's thread count when it starts; the envs
    must not silently turn a one-thread PyTorch into a two-thread one (fresh process, so the
    pool really starts here)."""
    code = (
        "import torch; torch.set_num_threads(1)\n"
        "torch.get_num_threads(), (torch.ones(1000) * 2).sum()  # torch in use, as a trainer\n"
        "import gymnasium as gym, numpy as np, activevision.envs\n"
        "env = gym.make('ActiveVision-v0'); env.reset(seed=0)\n"
        "for _ in range(30): env.step(1)\n"
        "print(torch.get_num_threads())\n"
        "v = gym.make_vec('ActiveVision-v0', num_envs=16,\n"
        "                 vectorization_mode='vector_entry_point')\n"
        "v.reset(seed=0)\n"
        "for _ in range(5): v.step(np.zeros(16, int))\n"
        "print(torch.get_num_threads())\n"
    )
    env = {**os.environ, "NUMBA_NUM_THREADS": "2"}
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=600
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["1", "1"]


def test_refused_seed_list_leaves_every_generator_as_it_was():
    """A seed list Gymnasium refuses part-way (-1 after 5) changes no generator: the next
    unseeded reset draws what it would have drawn without the refused call."""
    kept, refused = ActiveVisionVectorEnv(num_envs=2), ActiveVisionVectorEnv(num_envs=2)
    kept.reset(seed=0)
    refused.reset(seed=0)
    with pytest.raises(gym.error.Error, match="-1"):
        refused.reset(seed=[5, -1])
    assert np.array_equal(kept.reset()[0], refused.reset()[0])
    assert refused.np_random_seed == (0, 1)


def test_seed_array_of_numpy_integers_seeds_like_a_list_of_ints():
    from_array, from_list = ActiveVisionVectorEnv(num_envs=2), ActiveVisionVectorEnv(num_envs=2)
    obs, _ = from_array.reset(seed=np.array([3, 8]))
    assert np.array_equal(obs, from_list.reset(seed=[3, 8])[0])
    assert from_array.np_random_seed == (3, 8)
    assert all(type(s) is int for s in from_array.np_random_seed)
