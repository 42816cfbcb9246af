"""Dict observations: spaces, the prior pose, the proposal, the action history, and the
entropy regret."""

from __future__ import annotations

import math

import numpy as np
import pytest

from activevision.envs import ActiveVisionEnv, ActiveVisionVectorEnv, EnvConfig
from activevision.envs.actions import action_table, greedy_actions
from activevision.envs.observations import flatten_vectors, play_differences, vector_keys
from activevision.envs.starts import quantise_pose
from activevision.envs.view import viewpoint_search
from activevision.experiments.policies import greedy_action
from activevision.geometry import CameraConfig

KINDS = ("image+head", "image+head+pose", "image+head+pose+proposal")


@pytest.mark.parametrize("kind", KINDS)
def test_dict_observation_in_space_every_step(kind):
    env = ActiveVisionEnv(observation=kind, action_history=3)
    obs, info = env.reset(seed=5)
    for action in (1, 4, 8, 0, 2):
        assert env.observation_space.contains(obs)
        np.testing.assert_allclose(obs["head"], info["head"], rtol=1e-6)
        obs, _, terminated, _, info = env.step(action)
        if terminated:
            break
    assert set(obs) == {"image", *vector_keys(env.config)}


@pytest.mark.parametrize(
    "error", [{"localisation_error": 12.0}, {"prior_error_range": (5.0, 30.0)}], ids=str
)
def test_a_prior_error_beyond_the_bound_stays_in_the_space(error):
    """A prior error over 10 m put ``pose_error`` (and the prior pose) outside the Dict's
    Box(-10, 10): the vectors are clipped to the bound, as on the robot."""
    env = ActiveVisionEnv(observation="image+head+pose+proposal", **error)
    for seed in range(4):
        obs, info = env.reset(seed=seed)
        assert env.observation_space.contains(obs), seed
        want = np.clip(info["prior_error"], -10.0, 10.0)
        np.testing.assert_array_equal(obs["pose_error"], np.float32([want]))
        x, y = np.clip(info["prior_pose"][:2], -10.0, 10.0)
        np.testing.assert_array_equal(obs["pose"][:2], np.float32([x, y]))
        assert env.observation_space.contains(env.step(0)[0])


def test_action_history_remembers_the_last_actions_oldest_first():
    env = ActiveVisionEnv(observation="image+head", action_history=2)
    obs, _ = env.reset(seed=1)
    assert not obs["actions"].any()
    obs, *_ = env.step(3)
    obs, *_ = env.step(4)
    onehot = obs["actions"].reshape(2, 9)
    assert onehot[0].argmax() == 3 and onehot[1].argmax() == 4 and onehot.sum() == 2
    obs, _ = env.reset(seed=2)
    assert not obs["actions"].any()


def test_exact_prior_proposes_the_goal():
    # With no localisation error the prior is the true pose and Algorithm 1 from it is the
    # env's goal search itself.
    env = ActiveVisionEnv(observation="image+head+pose+proposal")
    for seed in range(10):
        obs, info = env.reset(seed=seed)
        np.testing.assert_array_equal(info["prior_pose"], info["pose"])
        pan, tilt, d_pan, d_tilt, found = obs["proposal"]
        assert found == 1.0
        np.testing.assert_allclose((pan, tilt), info["goal_viewpoint"], rtol=1e-6)
        np.testing.assert_allclose(
            (d_pan, d_tilt), info["goal_viewpoint"] - info["head"], atol=1e-6
        )
        x, y, c, s = obs["pose"]
        theta = info["pose"][2]
        np.testing.assert_allclose(
            (x, y, c, s),
            (*info["pose"][:2], math.cos(theta), math.sin(theta)),
            rtol=1e-6,
            atol=1e-6,
        )


def test_prior_error_drawn_per_episode_and_exact_in_distance():
    env = ActiveVisionEnv(observation="image+head+pose", prior_error_range=(0.2, 1.5))
    errors = []
    for seed in range(30):
        _, info = env.reset(seed=seed)
        e = info["prior_error"]
        errors.append(e)
        gap = np.hypot(*(info["prior_pose"][:2] - info["pose"][:2]))
        turn = abs(math.remainder(info["prior_pose"][2] - info["pose"][2], 2 * math.pi))
        assert gap == pytest.approx(e, abs=1e-9) and turn == pytest.approx(e, abs=1e-9)
    assert 0.2 <= min(errors) and max(errors) <= 1.5 and np.std(errors) > 0.2


def test_prior_does_not_change_the_episode():
    # The prior is drawn after the start: the same seed gives the same start and goal.
    plain = ActiveVisionEnv()
    prior = ActiveVisionEnv(observation="image+head+pose", prior_error_range=(0.0, 2.0))
    for seed in range(5):
        obs_a, info_a = plain.reset(seed=seed)
        obs_b, info_b = prior.reset(seed=seed)
        np.testing.assert_array_equal(obs_a, obs_b["image"])
        np.testing.assert_array_equal(info_a["goal_viewpoint"], info_b["goal_viewpoint"])


def test_quantised_prior_lies_on_the_grid():
    poses = np.array([[0.26, -1.13, 0.4], [2.99, 1.49, -3.1], [-0.01, 0.0, math.pi]])
    q = quantise_pose(poses, 0.5, 30.0)
    np.testing.assert_allclose(q[:, :2], [[0.5, -1.0], [3.0, 1.5], [0.0, 0.0]])
    np.testing.assert_allclose(q[:, 2], np.radians([30.0, 180.0, 180.0]))
    env = ActiveVisionEnv(observation="image+head+pose", prior_grid=(0.5, 45.0))
    _, info = env.reset(seed=3)
    cells = info["prior_pose"][:2] / 0.5
    np.testing.assert_allclose(cells, np.round(cells), atol=1e-9)


@pytest.mark.parametrize("kind", KINDS)
def test_vector_env_slots_equal_single_envs(kind):
    config = EnvConfig(observation=kind, action_history=2, prior_error_range=(0.0, 1.0))
    venv = ActiveVisionVectorEnv(3, config)
    singles = [ActiveVisionEnv(config) for _ in range(3)]
    obs, _ = venv.reset(seed=10)
    single_obs = [env.reset(seed=10 + i)[0] for i, env in enumerate(singles)]
    rng = np.random.default_rng(0)
    for _ in range(12):
        for i in range(3):
            for key in obs:
                np.testing.assert_array_equal(obs[key][i], single_obs[i][key])
        actions = rng.integers(0, 9, 3)
        obs, *_ = venv.step(actions)
        for i, env in enumerate(singles):
            single_obs[i], _, t, _, _ = env.step(int(actions[i]))
            if t:  # NEXT_STEP autoreset: compare again once both restarted
                single_obs[i] = None
        if any(o is None for o in single_obs):
            break
    assert flatten_vectors(obs, vector_keys(config)).shape[0] == 3


def test_bad_observation_settings_are_one_line_errors():
    with pytest.raises(ValueError, match="observation"):
        EnvConfig(observation="image+pose")
    with pytest.raises(ValueError, match="action_history"):
        EnvConfig(action_history=2)  # the image Box has nowhere to put it
    with pytest.raises(ValueError, match="frame_stack"):
        EnvConfig(observation="image+head", frame_stack=4)
    with pytest.raises(ValueError, match="prior_error_range"):
        EnvConfig(prior_error_range=(1.0, 0.5))


def test_greedy_actions_match_the_single_greedy_action():
    table = action_table(3.0)
    rng = np.random.default_rng(0)
    heads, targets = rng.uniform(-1, 1, (50, 2)), rng.uniform(-1, 1, (50, 2))
    batch = greedy_actions(heads, targets, table)
    assert [greedy_action(h, t, table) for h, t in zip(heads, targets, strict=True)] == list(batch)


def test_entropy_regret_is_the_search_entropy_difference():
    # At a candidate view (with no localisation error) the regret is Algorithm 1's entropy
    # of that view minus the goal's, computed independently by the search; 0 at the goal.
    env = ActiveVisionEnv()
    grid = env.sim.localisation.grid
    checked = 0
    for seed in range(8):
        _, info = env.reset(seed=seed)
        search = viewpoint_search(env.sim, 0)
        for v in range(0, len(grid), 3):
            env.sim.pan[0], env.sim.tilt[0] = grid.pans[v], grid.tilts[v]
            env.sim._observe(np.array([0]))
            want = search.entropies[v] - info["goal_entropy"]
            if np.isfinite(want):
                assert env.entropy_regret() == pytest.approx(want, abs=1e-9)
                checked += 1
        env.jump_head(*info["goal_viewpoint"])
        assert env.entropy_regret() == pytest.approx(0.0, abs=1e-12)
    assert checked > 20


HEAD = EnvConfig(observation="image+head")


@pytest.mark.parametrize(
    ("trained", "given", "named"),
    [
        (EnvConfig(), EnvConfig(), None),
        (HEAD, EnvConfig(observation="image+head+pose"), None),  # a subset of the vectors
        (HEAD, EnvConfig(), "against 'image': the env gives the bare image, no vectors"),
        (
            HEAD.replace(action_history=1),
            HEAD,
            "no actions (action_history 1: the moves it remembers)",
        ),
        # the same keys, vectors of other lengths: they reached the network
        (HEAD.replace(action_history=2), HEAD.replace(action_history=1), "action_history 2"),
        (EnvConfig(frame_stack=2), EnvConfig(), "frame_stack 2 against 1"),
        (
            EnvConfig(camera=CameraConfig(width=160, height=90)),
            EnvConfig(),
            "images of 160x90 px against 160x120",
        ),
        # the same image size, another view of the field: a silently different policy
        (
            EnvConfig(camera=CameraConfig(hfov=1.2)),
            EnvConfig(),
            "a camera of hfov 68.8 deg against hfov 58 deg",
        ),
        # a discrete policy's actions index its own moves
        (EnvConfig(step_deg=6.0), EnvConfig(), "moves of 6 deg, 8way, against 3 deg, 8way"),
        (EnvConfig(action_set="4way"), EnvConfig(), "moves of 3 deg, 4way"),
    ],
)
def test_play_differences_names_what_a_policy_would_meet_that_it_was_not_trained_on(
    trained, given, named
):
    differences = play_differences(trained, given)
    if named is None:
        assert differences == []
    else:
        assert len(differences) == 1 and named in differences[0], differences


def test_a_policy_moving_by_head_targets_plays_any_moves():
    """A continuous policy moves by head targets, which an env of any moves takes."""
    trained = EnvConfig(step_deg=6.0)
    assert play_differences(trained, EnvConfig(), moves_by_target=True) == []
