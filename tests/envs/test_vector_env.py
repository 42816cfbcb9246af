import gymnasium as gym
import numpy as np
import pytest

import activevision.envs  # noqa: F401
from activevision.envs import ActiveVisionVectorEnv


def test_make_vec_returns_the_native_vector_env():
    envs = gym.make_vec("ActiveVision-v0", num_envs=3, vectorization_mode="vector_entry_point")
    assert isinstance(envs, ActiveVisionVectorEnv)
    obs, infos = envs.reset(seed=0)
    assert obs.shape == (3, 1, 120, 160)
    assert infos["success_rate"].shape == (3,)


@pytest.mark.parametrize("frame_stack", [1, 3])
def test_vector_env_equals_single_envs_with_the_same_seeds(frame_stack):
    n, seed, steps = 4, 11, 45
    rng = np.random.default_rng(0)
    actions = rng.integers(0, 9, (steps, n))
    venv = ActiveVisionVectorEnv(num_envs=n, frame_stack=frame_stack)
    singles = [gym.make("ActiveVision-v0", frame_stack=frame_stack) for _ in range(n)]
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
