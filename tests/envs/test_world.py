"""The world beyond the paper: randomised appearance and other robots in the episodes.
(The paper's default world is checked byte for byte by test_digest.py.)"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import activevision.envs  # noqa: F401
from activevision.envs.config import EnvConfig
from activevision.envs.robots import RobotsConfig
from activevision.envs.simulation import EpisodeBatch
from activevision.geometry.kernels import ball_visible_mask
from activevision.geometry.occlusion import hidden_landmarks, robot_cylinders
from activevision.localisation import LocalisationConfig, best_viewpoints, entropy
from activevision.rendering.appearance import AppearanceConfig

WORLD = EnvConfig(appearance=AppearanceConfig.randomised(), robots=RobotsConfig(count=(2, 4)))


def test_default_world_has_no_robots_and_no_looks():
    env = gym.make("ActiveVision-v0")
    _, info = env.reset(seed=0)
    assert "robots" not in info and "hidden_mask" not in info
    assert not EnvConfig().appearance.enabled and EnvConfig().robots.max_count == 0


def test_hidden_landmarks_are_never_seen_and_starts_keep_the_ball():
    sim = EpisodeBatch(WORLD, 32)
    rngs = [np.random.default_rng(s) for s in range(32)]
    sim.reset(np.arange(32), rngs)
    assert sim.hidden.any()  # the robots hide something in some episodes
    assert (sim.robots[:, :, 2] > 0).sum(axis=1).min() >= 2
    assert ball_visible_mask(
        sim.ball, sim.pose, sim.pan, sim.tilt, WORLD.camera, WORLD.field.ball_radius
    ).all()
    # robots keep their spacing from ours and from each other, on the field
    used = sim.robots[:, :, 2] > 0
    for i in range(32):
        xy = np.vstack([sim.pose[i, :2], sim.robots[i, used[i], :2]])
        gaps = np.hypot(*(xy[:, None] - xy[None]).transpose(2, 0, 1))
        assert gaps[~np.eye(len(xy), dtype=bool)].min() >= WORLD.robots.min_spacing
        assert (np.abs(xy[:, 0]) <= WORLD.field.half_length).all()
    rng = np.random.default_rng(0)
    for _ in range(10):
        sim.step(rng.integers(0, 9, 32))
        assert not (sim.observed & sim.hidden).any()
        assert not (sim.desired & sim.hidden).any()


def test_the_goal_search_leaves_hidden_landmarks_out():
    sim = EpisodeBatch(WORLD.replace(robots=RobotsConfig()), 1)
    sim.reset(np.arange(1), [np.random.default_rng(3)])
    loc = LocalisationConfig()
    mean, ball = sim.believed_pose[:1], sim.ball[:1]
    cov = loc.ukf.initial_cov
    free = best_viewpoints(mean, cov, ball, sim.landmarks, WORLD.camera)
    all_hidden = best_viewpoints(
        mean, cov, ball, sim.landmarks, WORLD.camera, hidden=np.ones(len(sim.landmarks), bool)
    )
    assert free.visible.any() and not all_hidden.visible.any()
    shows_ball = all_hidden.ball_visible[0]
    np.testing.assert_allclose(all_hidden.entropies[0, shows_ball], entropy(cov))
    one = int(np.argwhere(free.visible[0])[0, 1])
    mask = np.zeros(len(sim.landmarks), bool)
    mask[one] = True
    partly = best_viewpoints(mean, cov, ball, sim.landmarks, WORLD.camera, hidden=mask)
    assert not partly.visible[0, :, one].any()
    np.testing.assert_array_equal(
        np.delete(partly.visible, one, -1), np.delete(free.visible, one, -1)
    )


def test_same_seed_same_bytes():
    # (the vector env against single envs in this world: test_vector_env.py)
    first = gym.make("ActiveVision-v0", config=WORLD)
    a = [first.reset(seed=5)[0].copy()] + [first.step(1)[0].copy() for _ in range(3)]
    second = gym.make("ActiveVision-v0", config=WORLD)
    b = [second.reset(seed=5)[0].copy()] + [second.step(1)[0].copy() for _ in range(3)]
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_gymnasium_vectorizers_play_the_randomised_world_as_the_native_one(mode):
    """Sync and Async vectorizers over single envs in the randomised world with robots give
    the native vector env's batches byte for byte, across autoresets (looks and robots are
    drawn anew at every reset, from each sub-environment's generator)."""
    n, steps = 3, 30
    actions = np.random.default_rng(4).integers(0, 9, (steps, n))
    native = gym.make_vec(
        "ActiveVision-v0", n, vectorization_mode="vector_entry_point", config=WORLD
    )
    other = gym.make_vec("ActiveVision-v0", n, vectorization_mode=mode, config=WORLD)
    try:
        a, b = native.reset(seed=11), other.reset(seed=11)
        resets = 0
        for step in [None, *actions]:
            if step is not None:
                a, b = native.step(step), other.step(step)
                resets += int((a[2] | a[3]).sum())
                for x, y in zip(a[1:4], b[1:4], strict=True):
                    np.testing.assert_array_equal(x, y)
            np.testing.assert_array_equal(a[0], b[0])
            for key in ("robots", "hidden_mask", "head", "goal_viewpoint", "observed_mask"):
                np.testing.assert_array_equal(a[-1][key], b[-1][key])
        assert resets >= 2  # the comparison crossed autoresets
    finally:
        native.close()
        other.close()


def test_frames_differ_from_the_clean_world_and_between_episodes():
    clean = gym.make("ActiveVision-v0").reset(seed=2)[0]
    looks = gym.make("ActiveVision-v0", config=WORLD.replace(robots=RobotsConfig()))
    a = looks.reset(seed=2)[0].copy()
    b = looks.reset(seed=3)[0]
    assert (a != clean).mean() > 0.3 and (a != b).mean() > 0.3


def test_stored_states_render_as_they_were_seen():
    # DAgger stores states and renders them again for its minibatches
    sim = EpisodeBatch(WORLD, 6)
    sim.reset(np.arange(6), [np.random.default_rng(s) for s in range(6)])
    rng = np.random.default_rng(2)
    for _ in range(3):
        sim.step(rng.integers(0, 9, 6))
        idx = np.arange(6)
        seen = sim.render(idx)
        again = sim.render_states(
            sim.pose.copy(),
            sim.head.copy(),
            sim.ball.copy(),
            sim.frame_looks(idx),
            sim.robots.copy(),
        )
        np.testing.assert_array_equal(again, seen)


@pytest.mark.parametrize("bad", [{"count": (3, 2)}, {"count": (0, 9)}, {"height": (1.0, 0.5)}])
def test_bad_robot_config_is_one_clear_error(bad):
    with pytest.raises(ValueError, match="RobotsConfig"):
        RobotsConfig(**bad)


def test_redrawn_exact_priors_propose_the_goal_with_the_robots_occlusion():
    # A prior drawn again with error 0 is the true pose; with no localisation error the
    # goal was planned from that same pose with the landmarks the robots hide, so the
    # redrawn proposal must be the goal wherever one is found; without the states' robots
    # the call is refused rather than planning through them.
    config = EnvConfig(
        observation="image+head+pose+proposal",
        prior_error_range=(0.5, 1.0),
        robots=RobotsConfig(count=(3, 4)),
    )
    sim = EpisodeBatch(config, 16)
    sim.reset(np.arange(16), [np.random.default_rng(s) for s in range(16)])
    assert sim.hidden.any()  # the robots hide some landmarks somewhere
    rng = np.random.default_rng(0)
    prior, proposal = sim.redraw_priors(sim.pose, sim.ball, np.zeros(16), sim.robots, rng)
    np.testing.assert_array_equal(prior, sim.pose)
    found = proposal[:, 2] == 1
    assert found.all()
    np.testing.assert_array_equal(proposal[:, :2], sim.goal)
    with pytest.raises(ValueError, match="robots"):
        sim.redraw_priors(sim.pose, sim.ball, np.zeros(16), None, rng)
    # a wall of four tall robots 0.6 m ahead along each goal view's bearing: the proposal
    # moves (in most slots) to best_viewpoints' with the landmarks the wall hides
    bearing = sim.pose[:, 2] + sim.goal[:, 0]
    ahead = sim.pose[:, :2] + 0.6 * np.column_stack([np.cos(bearing), np.sin(bearing)])
    side = np.column_stack([-np.sin(bearing), np.cos(bearing)])
    wall = np.stack(
        [
            np.column_stack([ahead + k * 0.2 * side, np.full(16, 1.0), np.full(16, 100.0)])
            for k in (-1.5, -0.5, 0.5, 1.5)
        ],
        axis=1,
    )
    _, walled = sim.redraw_priors(sim.pose, sim.ball, np.zeros(16), wall, rng)
    assert (np.abs(walled[:, :2] - sim.goal) > 0).any(axis=1).sum() >= 4
    camera = np.column_stack([sim.pose[:, :2], np.full(16, config.camera.camera_height)])
    hidden = hidden_landmarks(sim.landmarks, camera, robot_cylinders(wall, config.robots.radius))
    loc = sim.localisation
    want = best_viewpoints(
        sim.pose,
        np.broadcast_to(loc.ukf.initial_cov, (16, 3, 3)),
        sim.ball,
        sim.landmarks,
        config.camera,
        grid=loc.grid,
        ukf=loc.ukf,
        ball_radius=config.field.ball_radius,
        ball_views_only=True,
        hidden=hidden,
    )
    np.testing.assert_array_equal(walled[:, 2], want.ok)
    np.testing.assert_array_equal(
        walled[want.ok, :2], np.column_stack([want.pan, want.tilt])[want.ok]
    )
