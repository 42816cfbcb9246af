import gymnasium as gym
import numpy as np
import pytest

import activevision.envs  # noqa: F401  (registers ActiveVision-v0)
from activevision.envs import ActiveVisionEnv, EnvConfig
from activevision.envs.actions import action_table
from activevision.envs.reward import approach_reward
from activevision.envs.starts import draw_starts


def rollout(env, seed, actions):
    obs, info = env.reset(seed=seed)
    out = [(obs, 0.0, False, False, info)]
    for a in actions:
        step = env.step(a)
        out.append(step)
        if step[2] or step[3]:
            break
    return out


def test_spaces_and_registration():
    env = gym.make("ActiveVision-v0")
    assert env.observation_space == gym.spaces.Box(0, 255, (1, 120, 160), np.uint8)
    assert env.action_space == gym.spaces.Discrete(9)
    assert env.spec.max_episode_steps == 20
    obs, _ = env.reset(seed=0)
    assert obs.shape == (1, 120, 160) and obs.dtype == np.uint8
    assert env.observation_space.contains(obs)
    assert gym.make("ActiveVision-v0", action_set="4way").action_space.n == 5


def test_env_checker_passes():
    from gymnasium.utils.env_checker import check_env

    check_env(gym.make("ActiveVision-v0").unwrapped, skip_render_check=True)


def test_same_seed_same_episode_different_seed_differs():
    acts = np.random.default_rng(0).integers(0, 9, 20)
    a = rollout(ActiveVisionEnv(), 7, acts)
    b = rollout(ActiveVisionEnv(), 7, acts)
    assert len(a) == len(b)
    for (oa, ra, ta, ua, ia), (ob, rb, tb, ub, ib) in zip(a, b, strict=True):
        assert oa.tobytes() == ob.tobytes() and ra == rb and ta == tb and ua == ub
        assert ia.keys() == ib.keys()
        for k in ia:
            np.testing.assert_array_equal(ia[k], ib[k])
    c = rollout(ActiveVisionEnv(), 8, acts)
    assert c[0][0].tobytes() != a[0][0].tobytes()


def test_start_state_is_valid():
    env = ActiveVisionEnv()
    for seed in range(10):
        _, info = env.reset(seed=seed)
        k = len(env.sim.landmarks)
        assert info["desired_mask"].shape == info["observed_mask"].shape == (k,)
        assert info["desired_mask"].any()
        assert not info["success"]
        d = np.linalg.norm(info["ball"] - info["pose"][:2])
        assert 1.0 - 1e-9 <= d <= 3.0 + 1e-9
        np.testing.assert_array_equal(info["pose"], info["believed_pose"])


def test_reward_is_plus_one_for_moving_closer():
    # The paper's text, not its printed sign(D' - D).
    assert approach_reward(10.0, 7.0) == 1.0
    assert approach_reward(7.0, 10.0) == -1.0
    assert approach_reward(7.0, 7.0) == 0.0
    assert approach_reward(7.0, 6.5, resolution_deg=1.0) == 0.0  # the release: sign(int(D-D'))


def test_greedy_moves_reach_the_goal_with_positive_rewards():
    env = ActiveVisionEnv()
    table = np.degrees(action_table(3.0))
    successes = 0
    for seed in range(10):
        _, info = env.reset(seed=seed)
        for _ in range(20):
            delta = np.degrees(info["goal_viewpoint"] - info["head"])
            a = int(np.argmin(np.linalg.norm(delta - table, axis=1)))
            _, r, term, _, info = env.step(a)
            if term:
                break
            assert r == 1.0
        successes += info["success"]
    assert successes >= 7  # only ball loss or the 20-step limit stop the greedy path


def test_invalid_action_is_a_clear_error():
    env = ActiveVisionEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="invalid action"):
        env.step(9)


@pytest.mark.parametrize(
    ("pan", "tilt", "shown"),
    [
        (np.nan, 0.3, "pan expects a finite number (rad), got nan"),
        (0.1, np.inf, "tilt expects a finite number (rad), got inf"),
        ("left", 0.3, "'left'"),
        (None, 0.3, "None"),
        (np.array([0.1, 0.2]), 0.3, "array([0.1, 0.2])"),
        (0.1, True, "True"),
    ],
)
def test_a_bad_head_jump_is_a_clear_error_and_leaves_the_head(pan, tilt, shown):
    """``jump_head`` (the entropy baselines' move) refuses what is not one finite angle
    before it moves: a NaN head failed every later step ("pan must be finite") until a
    reset, and strings or None failed deep inside NumPy."""
    env = ActiveVisionEnv()
    _, info = env.reset(seed=0)
    with pytest.raises(ValueError, match="jump_head") as error:
        env.jump_head(pan, tilt)
    assert shown in str(error.value), str(error.value)
    _, _, _, _, after = env.step(0)  # the env goes on, from the head it had
    np.testing.assert_array_equal(after["head"], info["head"])
    assert after["step"] == 1


def test_entropy_regret_before_reset_is_refused():
    """It scored the zeros the state starts as (a regret of 1.67 nats for no episode)."""
    from gymnasium.error import ResetNeeded

    env = ActiveVisionEnv()
    with pytest.raises(ResetNeeded, match="entropy_regret before reset"):
        env.entropy_regret()
    _, info = env.reset(seed=0)
    env.jump_head(*info["goal_viewpoint"])
    assert env.entropy_regret() == pytest.approx(0.0, abs=1e-12)


def test_invalid_config_is_a_clear_error():
    with pytest.raises(ValueError, match="frame_stack"):
        EnvConfig(frame_stack=0)
    with pytest.raises(ValueError, match="success_mode"):
        ActiveVisionEnv(success_mode="nearby")


def test_frame_stack_keeps_the_latest_frames():
    env = ActiveVisionEnv(frame_stack=3)
    obs, _ = env.reset(seed=1)
    assert obs.shape == (3, 120, 160)
    assert (obs[0] == obs[2]).all()
    obs2, *_ = env.step(1)
    np.testing.assert_array_equal(obs2[:2], obs[1:])


def test_ball_loss_terminates_with_minus_two():
    env = ActiveVisionEnv()
    for seed in range(20):
        env.reset(seed=seed)
        for _ in range(20):
            _, r, term, _, info = env.step(1)  # keep panning left
            if term:
                break
        if info["ball_lost"]:
            assert r == -2.0 and info["ball_lost_step"] == info["step"]
            return
    pytest.fail("panning one way never lost the ball")


def test_rgb_render_shows_image_and_top_view():
    env = ActiveVisionEnv(render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.shape[1] > frame.shape[0]


def test_batched_starts_use_each_generator_as_alone():
    """Starts drawn for several episodes at once equal each episode's starts drawn alone:
    the vector env's equivalence to single envs rests on it."""
    cfg = EnvConfig(localisation_error=0.4)
    together = draw_starts([np.random.default_rng(s) for s in range(20)], cfg)
    for s in range(20):
        alone = draw_starts([np.random.default_rng(s)], cfg)
        for key, value in alone.items():
            assert np.array_equal(value[0], together[key][s]), key
    # every start has the ball 1-3 m away, on the field, and believed = true pose + error
    dist = np.hypot(*(together["ball"] - together["pose"][:, :2]).T)
    assert np.all((dist >= 1.0) & (dist <= 3.0))
    shift = np.hypot(*(together["believed_pose"] - together["pose"])[:, :2].T)
    assert np.allclose(shift, 0.4)


#: a team's camera: a narrower neck than the paper's (pan +-60 deg, tilt 0..60)
NARROW_NECK = {"pan_min": -np.pi / 3, "pan_max": np.pi / 3, "tilt_min": 0.0, "tilt_max": np.pi / 3}


def test_goals_lie_within_the_head_limits_of_any_camera():
    """The candidate views span the env's camera's head limits (the paper's grid for the
    paper's camera), so every goal can be reached: with the paper's grid and a narrower neck,
    about 1 goal in 5 lay beyond it and its episode could never succeed."""
    import dataclasses

    from activevision.experiments.evaluate import evaluate_policy
    from activevision.experiments.policies import OraclePolicy
    from activevision.localisation import DEFAULT_GRID, LocalisationConfig

    paper = EnvConfig().camera
    assert LocalisationConfig.for_camera(paper) == LocalisationConfig()
    assert LocalisationConfig.for_camera(paper).grid == DEFAULT_GRID
    config = EnvConfig(camera=dataclasses.replace(paper, **NARROW_NECK))
    cam = config.camera
    env = ActiveVisionEnv(config)
    for seed in range(60):
        _, info = env.reset(seed=seed)
        pan, tilt = info["goal_viewpoint"]
        assert cam.pan_min <= pan <= cam.pan_max and cam.tilt_min <= tilt <= cam.tilt_max, seed
    _, summary, _ = evaluate_policy(OraclePolicy(config), 30, seed=0, config=config)
    assert summary["success"].mean == 1.0  # every goal reached
    with pytest.raises(ValueError, match="beyond the camera's head limits"):
        ActiveVisionEnv(config, localisation=LocalisationConfig())
