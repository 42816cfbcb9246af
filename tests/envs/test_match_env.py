"""ActiveVisionMatch-v0: the Gymnasium contract, same seed same bytes in every
vectorization mode, the dynamics and the detector against hand-computed cases and the UKF's
measurement model, and bad input."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import activevision.envs  # noqa: F401  (registers the envs)
from activevision.envs import EnvConfig
from activevision.envs.match.config import (
    BallConfig,
    DetectionConfig,
    KidnapConfig,
    MatchConfig,
    OthersConfig,
    WalkConfig,
)
from activevision.envs.match.detections import detect_one
from activevision.envs.match.dynamics import carry, move_pose, roll_ball, to_robot_frame, walk_step
from activevision.envs.match.env import ActiveVisionMatchEnv
from activevision.envs.match.simulation import MatchBatch
from activevision.envs.match.vector import ActiveVisionMatchVectorEnv
from activevision.envs.robots import RobotsConfig
from activevision.geometry import field_landmarks
from activevision.geometry.angles import wrap_angle
from activevision.geometry.field import FieldSpec
from activevision.localisation import hx_range_bearing
from activevision.rendering.appearance import AppearanceConfig

TICKS = 25


def rollout(env, seed, actions):
    obs, info = env.reset(seed=seed)
    out = [(obs, info)]
    for a in actions:
        obs, reward, terminated, truncated, info = env.step(a)
        out.append((obs, info, reward, terminated, truncated))
    return out


def assert_same(a, b):
    if isinstance(a, list | tuple):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            assert_same(x, y)
    elif isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a:
            assert_same(a[key], b[key])
    else:
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize("observation", ["image", "image+head", "image+head+belief"])
def test_gymnasium_env_checker(observation):
    env = gym.make("ActiveVisionMatch-v0", observation=observation, ticks=30)
    check_env(env.unwrapped, skip_render_check=True)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)


def test_gymnasium_env_checker_with_a_whole_config_and_walking_robots():
    """A ``config=`` argument is deep-copied by the checker: every part of it must copy."""
    config = MatchConfig(ticks=30, robots=RobotsConfig(count=(2, 3)), others=OthersConfig(0.3))
    env = gym.make("ActiveVisionMatch-v0", config=config)
    check_env(env.unwrapped, skip_render_check=True)


def test_render_shows_the_camera_beside_the_match_from_above():
    """``render()`` is the clip's top view (belief ellipse in blue, the other robots as grey
    discs) beside the camera image; the same seed draws the same picture."""
    config = MatchConfig(ticks=30, robots=RobotsConfig(count=(3, 3)))
    check_env(gym.make("ActiveVisionMatch-v0", config=config, render_mode="rgb_array").unwrapped)
    pictures = []
    for _ in range(2):
        env = ActiveVisionMatchEnv(config, render_mode="rgb_array")
        env.reset(seed=5)
        for _ in range(4):
            env.step(0)
        pictures.append(env.render())
    picture = pictures[0]
    assert picture.shape == (340, 900, 3) and picture.dtype == np.uint8
    np.testing.assert_array_equal(pictures[0], pictures[1])
    r, g, b = (picture[..., c].astype(int) for c in range(3))
    assert ((b > 150) & (r < 80) & (g < 80)).sum() > 30  # the belief: mean and ellipse
    assert ((abs(r - 89) < 3) & (abs(g - 89) < 3) & (abs(b - 89) < 3)).sum() > 3 * 40  # robots
    # the camera panel on the left holds the observation's grey levels
    left = picture[:, : picture.shape[1] // 2]
    assert (left[..., 0] == left[..., 1]).mean() > 0.9
    assert len(np.intersect1d(np.unique(left), np.unique(env._frames[0, 0]))) > 5
    assert ActiveVisionMatchEnv(ticks=5).render() is None  # no render_mode: nothing


def test_same_seed_same_bytes_and_truncation():
    actions = np.random.default_rng(0).integers(0, 9, TICKS)
    a = rollout(ActiveVisionMatchEnv(ticks=TICKS), 7, actions)
    b = rollout(ActiveVisionMatchEnv(ticks=TICKS), 7, actions)
    for x, y in zip(a, b, strict=True):
        assert_same(list(x), list(y))
    assert all(not step[3] for step in a[1:])  # never terminates
    assert [step[4] for step in a[1:]] == [False] * (TICKS - 1) + [True]
    c = rollout(ActiveVisionMatchEnv(ticks=TICKS), 8, actions)
    assert not np.array_equal(a[-1][1]["pose"], c[-1][1]["pose"])


def vector_rollout(envs, seed, actions):
    obs, info = envs.reset(seed=seed)
    out = [(obs, info)]
    for a in actions:
        out.append(envs.step(a))
    return out


@pytest.mark.parametrize("world", ["empty", "walking-robots", "ball-bounces-off-us"])
@pytest.mark.parametrize("mode", ["sync", "async"])
def test_every_vectorizer_agrees_with_the_native_one(mode, world):
    """Gymnasium's Sync and Async vectorizers over single envs and the native vector env
    give the same batches, byte for byte, across an autoreset (also with other robots
    walking: their draws, the occlusion and the bounces; and with our robot walking onto a
    ball that bounces off it)."""
    n, ticks = 3, 12
    kwargs: dict = {"observation": "image+head+belief", "ticks": ticks}
    if world == "walking-robots":
        kwargs = {
            "config": MatchConfig(
                observation="image+head+belief",
                ticks=ticks,
                robots=RobotsConfig(count=(1, 4)),
                others=OthersConfig(speed=0.3),
            )
        }
    if world == "ball-bounces-off-us":
        ticks = 200  # our robot reaches the ball within it (checked below)
        kwargs = {
            "config": MatchConfig(
                observation="image+head+belief",
                ticks=ticks,
                walk=WalkConfig(target="ball", ball_standoff=0.0),
                ball=BallConfig(kick_rate=0.01, kick_speed=(0.3, 1.0), bounces_off_own_robot=True),
            )
        }
    actions = np.random.default_rng(2).integers(0, 9, (ticks + 3, n))
    native = gym.make_vec(
        "ActiveVisionMatch-v0", num_envs=n, vectorization_mode="vector_entry_point", **kwargs
    )
    other = gym.make_vec("ActiveVisionMatch-v0", num_envs=n, vectorization_mode=mode, **kwargs)
    try:
        expected = vector_rollout(native, 4, actions)
        if world == "ball-bounces-off-us":
            config = kwargs["config"]
            contact = config.robots.radius + config.field.ball_radius
            gap = np.stack([np.hypot(*(i["ball"] - i["pose"][:, :2]).T) for *_, i in expected])
            assert (np.abs(gap - contact) < 1e-6).any()  # the ball rests against us
            assert gap.min() > contact - 1e-6  # and never inside us
        for x, y in zip(expected, vector_rollout(other, 4, actions), strict=True):
            for part_x, part_y in zip(x, y, strict=True):
                if isinstance(part_x, dict) and "pose" in part_x:  # infos: the env's keys
                    for key in part_x:
                        if not key.startswith("_"):
                            assert_same(part_x[key], part_y[key])
                else:
                    assert_same(part_x, part_y)
    finally:
        native.close()
        other.close()


def test_vector_slots_are_the_single_envs_in_any_order():
    """Slot i reset with seed s_i plays exactly the single env reset with s_i, whatever the
    other slots hold (seeds shuffled)."""
    seeds = [31, 5, 17]
    actions = np.random.default_rng(3).integers(0, 9, (10, 3))
    envs = ActiveVisionMatchVectorEnv(3, ticks=50)
    batched = [envs.reset(seed=seeds)] + [envs.step(a) for a in actions]
    for i, s in enumerate(seeds):
        single = rollout(ActiveVisionMatchEnv(ticks=50), s, actions[:, i])
        for b, one in zip(batched, single, strict=True):
            np.testing.assert_array_equal(b[0][i], one[0])
            np.testing.assert_array_equal(b[-1]["belief_cov"][i], one[1]["belief_cov"])


def roll(ball, velocity, ticks, deceleration=0.4, kick_rate=0.0):
    ball, velocity = np.array(ball, float), np.array(velocity, float)
    for _ in range(ticks):
        roll_ball(ball, velocity, np.ones(3), (deceleration, kick_rate, 0.5, 2.5), 0.32, 4.5, 3.0)
    return ball, velocity


def test_ball_rolls_to_a_stop_where_constant_deceleration_stops_it():
    """From 1.2 m/s at 0.4 m/s^2 the ball stops after v^2 / 2a = 1.8 m."""
    ball, velocity = roll([0.0, 0.0], [1.2, 0.0], 100)
    np.testing.assert_allclose(ball, [1.8, 0.0], atol=1e-12)
    assert not velocity.any()


def test_ball_bounces_off_the_field_lines():
    ball, velocity = roll([4.4, 0.0], [1.0, 0.0], 1, deceleration=0.0)
    np.testing.assert_allclose(ball, [4.5 - 0.22, 0.0])
    assert velocity[0] == -1.0


def test_a_kick_sets_direction_and_speed():
    ball, velocity = np.zeros(2), np.zeros(2)
    roll_ball(ball, velocity, np.array([0.0, 0.25, 0.5]), (0.0, 0.1, 1.0, 3.0), 0.5, 4.5, 3.0)
    np.testing.assert_allclose(velocity, [0.0, 2.0], atol=1e-12)  # 90 deg, 2 m/s
    np.testing.assert_allclose(ball, [0.0, 1.0], atol=1e-12)


def test_walk_step_turns_then_walks():
    here = np.zeros(3)
    np.testing.assert_allclose(
        walk_step(here, np.array([2.0, 0.0]), False, 0.2, 0.5, 0.32), [0.064, 0, 0]
    )
    # 90 degrees off: turn only, at the turn rate
    np.testing.assert_allclose(
        walk_step(here, np.array([0.0, 2.0]), False, 0.2, 0.5, 0.32), [0, 0, 0.16], atol=1e-12
    )
    assert walk_step(here, np.array([2.0, 0.0]), True, 0.2, 0.5, 0.32) == (0.0, 0.0, 0.0)


def test_ball_model_follows_odometry():
    """A world point seen from the moved robot is where the ball model carries it."""
    rng = np.random.default_rng(5)
    for _ in range(20):
        pose = np.array([rng.uniform(-3, 3), rng.uniform(-2, 2), rng.uniform(-3, 3)])
        point = rng.uniform(-4, 4, 2)
        step = rng.normal(0, [0.1, 0.05, 0.3])
        before = to_robot_frame(point[0], point[1], pose)
        move_pose(pose, *step, 100.0, 100.0)
        np.testing.assert_allclose(
            carry(*before, *step), to_robot_frame(point[0], point[1], pose), atol=1e-12
        )


def detect(pose, visible, normals, false_draw, near=1.0, far=1.0, false_rate=0.0):
    lm = field_landmarks(FieldSpec())
    sim = MatchBatch(MatchConfig(), 1)
    k = len(lm)
    ids, z = np.empty(k + 1, dtype=np.int64), np.empty((k + 1, 2))
    count = detect_one(
        pose,
        0.0,
        visible,
        lm.segments,
        lm.max_distance,
        lm.types,
        sim._noise_table,
        sim._point_ids,
        np.full(k, 0.5),
        normals,
        false_draw,
        (near, far, false_rate, 0.5),
        ids,
        z,
        np.empty(k),
    )
    return ids, z, count


def test_detections_without_noise_are_the_ukf_measurement():
    """Zero noise: each detection is ``hx_range_bearing`` of the true pose (the UKF's own
    model), closest landmarks first; every visible landmark is detected at rate 1."""
    lm = field_landmarks(FieldSpec())
    for pose, seen in (([1.0, -0.5, 0.3], [3, 20, 40]), ([-2.0, 1.0, 2.5], [1, 45])):
        pose = np.array(pose)
        visible = np.zeros(len(lm), dtype=bool)
        visible[seen] = True
        ids, z, count = detect(pose, visible, np.zeros((len(lm), 2)), np.ones(4))
        assert count == len(seen) and sorted(ids[:count]) == seen and ids[count] == -1
        for d, k in enumerate(ids[:count]):
            np.testing.assert_allclose(z[d], hx_range_bearing(pose, lm.segments[k])[0])
        # none detected at rate 0; a false detection comes last, inside the image
        ids, z, count = detect(pose, visible, np.zeros((len(lm), 2)), np.zeros(4), 0.0, 0.0, 1.0)
        assert count == 1 and abs(z[0, 1]) <= 0.5 and 0.5 <= z[0, 0] <= 4.0


def test_randomised_world_with_robots_plays():
    """Appearance and other robots on: a hidden landmark is never detected."""
    config = MatchConfig(
        ticks=20,
        appearance=AppearanceConfig.randomised(),
        robots=RobotsConfig(count=(4, 4)),
    )
    sim = MatchBatch(config, 4)
    sim.reset(np.arange(4), [np.random.default_rng(s) for s in range(4)])
    frames = []
    for t in range(20):
        sim.step(np.full(4, t % 9))
        assert not (sim.detected & sim.hidden).any()
        frames.append(sim.render())
    assert np.ptp(np.asarray(frames)) > 50


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"ticks": 0}, "ticks"),
        ({"step_deg": 90.0}, "step_deg"),
        ({"observation": "pose"}, "observation"),
        ({"detection": DetectionConfig(near=0.2, far=0.5)}, "far"),
        ({"no_such": 1}, "unknown keyword"),
        ({"field": "paper2020"}, "MatchConfig.field.*paper2020"),
        ({"field": 3}, "MatchConfig.field.*preset name"),
    ],
)
def test_bad_config_is_one_clear_error(kwargs, match):
    with pytest.raises(ValueError, match=match):
        gym.make("ActiveVisionMatch-v0", **kwargs)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        # numpy's MemoryError allocating 10**12 matches, naming no argument
        (
            {"num_envs": 10**12},
            r"num_envs: expects a positive integer up to 65536, got 1000000000000",
        ),
        ({"num_envs": 2, "max_episode_steps": 2**70}, r"max_episode_steps: .*at most 2\*\*63 - 1"),
    ],
)
def test_sizes_past_any_batch_are_one_clear_error(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ActiveVisionMatchVectorEnv(**kwargs)
    with pytest.raises(ValueError, match=match):
        gym.make_vec("ActiveVisionMatch-v0", vectorization_mode="vector_entry_point", **kwargs)


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: WalkConfig(pause_ticks=(5, 1)), "pause_ticks"),
        (lambda: WalkConfig(speed=-0.1), "speed"),
        (lambda: BallConfig(kick_speed=(3.0, 1.0)), "kick_speed"),
        (lambda: DetectionConfig(near=1.5), "near"),
    ],
)
def test_bad_part_config_names_the_field(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_a_field_preset_name_is_its_field_as_in_the_episodic_env():
    """``MatchConfig(field="paper2019")`` was refused while ``EnvConfig`` took the name."""
    assert MatchConfig(field="paper2019").field == FieldSpec.paper_2019()
    env = gym.make("ActiveVisionMatch-v0", field="paper2019", ticks=3)
    assert env.unwrapped.config.field == EnvConfig(field="paper2019").field


def test_a_striker_aims_short_of_the_ball():
    """``walk.target="ball"``: the waypoint is the ball model's position through the belief,
    ``ball_standoff`` short of it on the line from the robot."""
    sim = MatchBatch(MatchConfig(walk=WalkConfig(target="ball", ball_standoff=0.4)), 2)
    sim.reset(np.arange(2), [np.random.default_rng(s) for s in (1, 2)])
    mean, relative = sim.mean.copy(), sim.ball_relative.copy()
    sim.step(np.zeros(2, dtype=np.int64))
    for i in range(2):
        c, s = np.cos(mean[i, 2]), np.sin(mean[i, 2])
        ball = mean[i, :2] + np.array([[c, -s], [s, c]]) @ relative[i]
        distance = np.hypot(*(ball - mean[i, :2]))
        expected = mean[i, :2] + (ball - mean[i, :2]) * (distance - 0.4) / distance
        np.testing.assert_allclose(sim.waypoint[i], expected, atol=1e-12)


def _kidnap_pair(m: int, kidnap: KidnapConfig, ticks: int, seed: int = 40):
    """The same ``m`` matches without and with ``kidnap``, played ``ticks`` ticks with the
    same random head moves; yields after each tick."""
    sims = [MatchBatch(MatchConfig(), m), MatchBatch(MatchConfig(kidnap=kidnap), m)]
    for sim in sims:
        sim.reset(np.arange(m), [np.random.default_rng(seed + i) for i in range(m)])
    moves = np.random.default_rng(seed)
    for t in range(1, ticks + 1):
        actions = moves.integers(9, size=m)
        for sim in sims:
            sim.step(actions)
        yield t, sims


def test_a_kidnap_carries_the_robot_unbeknown_to_its_belief():
    """Kidnapped in tick 5 (KidnapConfig.ticks): until then the very same matches as
    without it (its draws come from a generator of its own); in tick 5 every robot is
    carried 1-2 m (less where the field's margin stops it) and turned by at most 0.8 rad,
    while its belief, which nothing told, stays where the same match's belief is. The
    infos say so in that tick only; a world without kidnapping has no such keys."""
    m = 8
    for t, (plain, kidnapped) in _kidnap_pair(m, KidnapConfig(ticks=(5,)), 6):
        if t < 5:
            np.testing.assert_array_equal(plain.pose, kidnapped.pose)
            np.testing.assert_array_equal(plain.mean, kidnapped.mean)
            assert not kidnapped.kidnapped.any()
        if t == 5:
            assert kidnapped.kidnapped.all()
            info = kidnapped.info_arrays()
            assert info["kidnapped"].all() and "kidnapped" not in plain.info_arrays()
            assert "lost_alarm" in info and "lost_alarm" not in plain.info_arrays()
            moved = kidnapped.pose - plain.pose
            carried = np.hypot(moved[:, 0], moved[:, 1])
            # each then took the same commanded step (its belief's), turned: at most 2 x 6.4 cm
            hx, hy = 4.5 - 0.5, 3.0 - 0.5
            at_margin = (np.abs(kidnapped.pose[:, 0]) > hx - 0.07) | (
                np.abs(kidnapped.pose[:, 1]) > hy - 0.07
            )
            assert np.all(((carried > 1 - 0.13) & (carried < 2 + 0.13)) | at_margin), carried
            assert (~at_margin).sum() >= m // 2
            assert np.all(np.abs(wrap_angle(moved[:, 2])) <= 0.8 + 1e-9)
            # the belief was told nothing: it moved as the same match's, give or take what
            # one tick's detections (from elsewhere) made of it
            assert np.abs(kidnapped.mean[:, :2] - plain.mean[:, :2]).max() < 0.3
            assert np.all(kidnapped.position_error() > plain.position_error())
        if t == 6:
            assert not kidnapped.kidnapped.any()


def test_kidnaps_at_a_rate_come_as_often_as_it_says_and_by_the_seed():
    """``rate`` kidnaps per minute of play: 6 per minute of ticks of 0.32 s is a chance of
    0.032 a tick, so 32 matches of 300 ticks hold about 307 (binomial std 17); the same
    seeds the same kidnaps."""
    kidnap = KidnapConfig(rate=6.0)
    counts = []
    for _ in range(2):
        sim = MatchBatch(MatchConfig(kidnap=kidnap), 32)
        sim.reset(np.arange(32), [np.random.default_rng(7 + i) for i in range(32)])
        ticks = []
        for _ in range(300):
            sim.step(np.zeros(32, dtype=np.int64))
            ticks.append(sim.kidnapped.copy())
        counts.append(np.array(ticks))
    np.testing.assert_array_equal(counts[0], counts[1])
    expected = 32 * 300 * 6.0 * 0.32 / 60
    std = (32 * 300 * 0.032 * 0.968) ** 0.5
    assert abs(counts[0].sum() - expected) < 5 * std, counts[0].sum()


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"distance": (2.0, 1.0)}, "ordered"),
        ({"distance": (1.0, 30.0)}, r"\[0, 20\]"),
        ({"ticks": (0,)}, "count from 1"),
        ({"rate": -1.0}, "rate"),
        ({"turn": 4.0}, "turn"),
    ],
)
def test_a_bad_kidnap_is_refused(values, message):
    with pytest.raises(ValueError, match=message):
        KidnapConfig(**values)
    assert not KidnapConfig().enabled and KidnapConfig(ticks=(3, 3, 1)).ticks == (1, 3)


def test_gym_make_takes_a_kidnap_as_json_and_its_spec_makes_the_same_env():
    env = gym.make("ActiveVisionMatch-v0", kidnap={"ticks": [2]}, ticks=4)
    env.reset(seed=0)
    flags = [env.step(0)[4]["kidnapped"] for _ in range(3)]
    assert flags == [False, True, False]
    again = gym.make(gym.envs.registration.EnvSpec.from_json(env.spec.to_json()))
    assert again.unwrapped.config.kidnap == KidnapConfig(ticks=(2,))
