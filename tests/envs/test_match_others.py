"""Other robots in a match: their walk and the ball bouncing off them, by hand and through
whole matches (``envs.match.others``)."""

from __future__ import annotations

import numpy as np
import pytest

from activevision.envs.match.config import (
    BallConfig,
    KidnapConfig,
    MatchConfig,
    OthersConfig,
    WalkConfig,
)
from activevision.envs.match.dynamics import blocking_robot, sidestep
from activevision.envs.match.kernels import DETOUR_TICKS, move_kernel
from activevision.envs.match.others import bounce_ball, walk_others
from activevision.envs.match.simulation import MatchBatch
from activevision.envs.robots import RobotsConfig

HALF = (4.5, 3.0)


def _robots(*xy: tuple[float, float], height: float = 0.6) -> np.ndarray:
    """One match's robots ``(x, y, height, grey)`` (1, R, 4)."""
    return np.array([[(x, y, height, 100.0) for x, y in xy]])


def _walk(robots, waypoints, own=(4.0, 2.5), draws=None, step=0.1, spacing=0.6):
    draws = np.full((*robots.shape[:2], 2), 0.5) if draws is None else np.asarray(draws)
    walk_others(robots, waypoints, np.array([own], float), draws, step, spacing, HALF)


def test_a_robot_steps_towards_its_waypoint():
    robots = _robots((0.0, 0.0))
    waypoints = np.array([[[3.0, 4.0]]])  # 5 m away, along (0.6, 0.8)
    _walk(robots, waypoints)
    np.testing.assert_allclose(robots[0, 0, :2], [0.06, 0.08])
    np.testing.assert_allclose(waypoints[0, 0], [3.0, 4.0])
    np.testing.assert_allclose(robots[0, 0, 2:], [0.6, 100.0])  # height and grey kept


def test_a_robot_on_its_waypoint_takes_a_new_one_from_its_draws():
    robots = _robots((1.0, 1.0))
    waypoints = np.array([[[1.0, 1.0]]])
    _walk(robots, waypoints, draws=[[[0.75, 0.25]]])
    np.testing.assert_allclose(robots[0, 0, :2], [1.0, 1.0])  # stands this tick
    np.testing.assert_allclose(waypoints[0, 0], [2.25, -1.5])  # 4.5 * 0.5, 3 * -0.5


def test_the_last_step_ends_on_the_waypoint():
    robots = _robots((0.0, 0.0))
    waypoints = np.array([[[0.05, 0.0]]])
    _walk(robots, waypoints)
    np.testing.assert_allclose(robots[0, 0, :2], [0.05, 0.0])


def test_robots_closing_in_give_way_and_turn():
    robots = _robots((0.0, 0.0), (0.65, 0.0))
    waypoints = np.array([[[2.0, 0.0], [-2.0, 0.0]]])  # straight at each other
    _walk(robots, waypoints, draws=[[[1.0, 0.5], [0.0, 0.5]]])
    np.testing.assert_allclose(robots[0, :, :2], [[0.0, 0.0], [0.65, 0.0]])
    np.testing.assert_allclose(waypoints[0], [[4.5, 0.0], [-4.5, 0.0]])


def test_robots_stepping_towards_each_other_in_one_tick_keep_the_spacing():
    """0.75 m apart, each 0.1 m step ends 0.65 m from where the other stood: checked
    against where the others stood at the start of the tick, both stepped and ended 0.55 m
    apart. The second checks its step against where the first now is, and gives way."""
    robots = _robots((0.0, 0.0), (0.75, 0.0))
    waypoints = np.array([[[2.0, 0.0], [-2.0, 0.0]]])
    _walk(robots, waypoints, draws=[[[1.0, 0.5], [0.0, 0.5]]])
    np.testing.assert_allclose(robots[0, :, :2], [[0.1, 0.0], [0.75, 0.0]])
    np.testing.assert_allclose(waypoints[0], [[2.0, 0.0], [-4.5, 0.0]])  # the second turns
    assert np.hypot(*(robots[0, 1, :2] - robots[0, 0, :2])) >= 0.6


def test_a_robot_too_close_may_still_walk_away():
    robots = _robots((0.0, 0.0), (0.3, 0.0))
    waypoints = np.array([[[-2.0, 0.0], [0.3, 0.0]]])
    _walk(robots, waypoints)
    np.testing.assert_allclose(robots[0, 0, :2], [-0.1, 0.0])


def test_robots_give_way_to_ours_and_ignore_empty_slots():
    robots = _robots((0.0, 0.0), (0.3, 0.0))
    robots[0, 1, 2] = 0.0  # an empty slot next to the first robot
    waypoints = np.array([[[2.0, 0.0], [5.0, 5.0]]])
    _walk(robots, waypoints, own=(5.0, 0.0))
    np.testing.assert_allclose(robots[0, :, :2], [[0.1, 0.0], [0.3, 0.0]])
    np.testing.assert_allclose(waypoints[0, 1], [5.0, 5.0])  # an empty slot never turns
    _walk(robots, waypoints, own=(0.75, 0.0))  # ours 0.65 m ahead: closing in stops
    np.testing.assert_allclose(robots[0, 0, :2], [0.1, 0.0])


def test_a_ball_rolling_into_a_robot_bounces_off_it():
    robots = _robots((1.0, 0.0))
    ball = np.array([[0.9, 0.0]])
    velocity = np.array([[1.0, 0.5]])
    bounce_ball(ball, velocity, robots, 0.12, 0.05, 0.5)
    np.testing.assert_allclose(ball, [[0.83, 0.0]])  # at contact, 0.12 + 0.05 from the centre
    # the normal component (1 towards the robot) comes back at half speed
    np.testing.assert_allclose(velocity, [[-0.5, 0.5]])


def test_a_ball_leaving_a_robot_keeps_its_velocity_and_a_clear_ball_is_untouched():
    robots = _robots((1.0, 0.0), (-2.0, 0.0))
    ball = np.array([[1.0, 0.1], [0.0, 0.0]])
    velocity = np.array([[0.0, 2.0], [1.0, 0.0]])
    robots = np.concatenate([robots, robots])  # two matches, the same robots
    bounce_ball(ball, velocity, robots, 0.12, 0.05, 0.5)
    np.testing.assert_allclose(ball, [[1.0, 0.17], [0.0, 0.0]])
    np.testing.assert_allclose(velocity, [[0.0, 2.0], [1.0, 0.0]])


def test_a_fast_ball_stops_where_its_path_first_touched_a_robot():
    """Tested only where it ended, a ball that rolled past a robot's centre in one tick
    was put out on the far side, its velocity kept, and one that crossed the body entirely
    passed through: with where the ball began the tick, its path is tested."""
    robots = _robots((1.0, 0.0))
    start = np.array([[0.5, 0.0], [0.5, 0.05]])
    ball = np.array([[1.17, 0.0], [1.6, 0.05]])  # past the centre; through the body
    velocity = np.array([[1.372, 0.0], [1.5, 0.0]])
    robots = np.concatenate([robots, robots])
    bounce_ball(ball, velocity, robots, 0.12, 0.05, 0.5, start)
    across = np.sqrt(0.17**2 - 0.05**2)  # the path meets the circle of contact here
    np.testing.assert_allclose(ball, [[0.83, 0.0], [1.0 - across, 0.05]])
    np.testing.assert_allclose(velocity[0], [-0.686, 0.0])
    normal = np.array([-across, 0.05]) / 0.17
    towards = 1.5 * normal[0]
    np.testing.assert_allclose(velocity[1], [1.5, 0.0] - 1.5 * towards * normal)
    # without the path (the ends alone): the first put out beyond the centre, the second
    # untouched
    ball, velocity = np.array([[1.17, 0.0], [1.6, 0.05]]), np.array([[1.372, 0], [1.5, 0]])
    bounce_ball(ball, velocity, robots, 0.12, 0.05, 0.5)
    np.testing.assert_allclose(ball, [[1.17, 0.0], [1.6, 0.05]])


def _segment_distance(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Least distance from points ``c`` (..., 2) to segments ``a``-``b`` (..., 2)."""
    ab = b - a
    t = np.clip(((c - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-300), 0.0, 1.0)
    closest = a + t[..., None] * ab
    return np.asarray(np.hypot(*np.moveaxis(c - closest, -1, 0)))


def _config(speed: float, ticks: int = 200) -> MatchConfig:
    return MatchConfig(
        ticks=ticks,
        robots=RobotsConfig(count=(4, 4)),
        others=OthersConfig(speed=speed),
        # kicks often and hard, so the ball meets robots within a short test
        ball=BallConfig(kick_rate=0.2, kick_speed=(1.5, 3.0)),
    )


def _play(cfg: MatchConfig, seeds: list[int], ticks: int):
    """The other robots (T + 1, N, R, 4), the balls and our robot's poses (T + 1, N, 2 | 3)
    from the start of matches ``seeds`` through ``ticks`` ticks."""
    batch = MatchBatch(cfg, len(seeds))
    batch.reset(np.arange(len(seeds)), [np.random.default_rng(s) for s in seeds])
    robots, balls, own = [batch.robots.copy()], [batch.ball.copy()], [batch.pose.copy()]
    for t in range(ticks):
        batch.step(np.full(len(seeds), t % 9))
        robots.append(batch.robots.copy())
        balls.append(batch.ball.copy())
        own.append(batch.pose.copy())
    return np.stack(robots), np.stack(balls), np.stack(own)


@pytest.fixture(scope="module")
def walking():
    cfg = _config(0.3)
    return cfg, *_play(cfg, [3, 4, 5], 300)


def test_walking_robots_move_at_their_speed_keep_apart_and_stay_on_the_field(walking):
    cfg, robots, _, _ = walking
    step = cfg.others.speed * cfg.tick_seconds
    xy = robots[..., :2]
    moved = np.hypot(*np.moveaxis(np.diff(xy, axis=0), -1, 0))
    assert moved.max() <= step + 1e-9
    assert (moved > 0).mean() > 0.5  # they walk most of the time
    assert np.abs(xy[..., 0]).max() <= cfg.field.half_length + 1e-9
    assert np.abs(xy[..., 1]).max() <= cfg.field.half_width + 1e-9
    # each checks its step against where the others are as it steps: no pair ever comes
    # within the spacing (checked against where the others stood at the start of the tick,
    # two closing in at once came to 0.517 m of each other here)
    d = xy[:, :, :, None, :] - xy[:, :, None, :, :]
    pair = np.hypot(d[..., 0], d[..., 1]) + np.eye(4) * 99
    assert pair.min() >= cfg.robots.min_spacing
    height_grey = robots[..., 2:]
    np.testing.assert_array_equal(height_grey, np.broadcast_to(height_grey[:1], height_grey.shape))


def test_the_ball_never_ends_a_tick_inside_a_robot_and_does_meet_them(walking):
    cfg, robots, balls, _ = walking
    d = balls[:, :, None, :] - robots[..., :2]
    distance = np.hypot(d[..., 0], d[..., 1])
    contact = cfg.robots.radius + cfg.field.ball_radius
    assert distance[1:].min() >= contact - 1e-9
    assert (distance[1:] < contact + 0.02).any()  # a few contacts did happen
    # nor does its path in a tick cross a robot (kicks of 1.5-3 m/s roll 0.5-1 m a tick:
    # tested where they ended, 12 of 26 such meetings passed through a body)
    path = _segment_distance(balls[:-1, :, None], balls[1:, :, None], robots[1:, ..., :2])
    # (the path is tested against where the robots end the tick; a ball that began it
    # within reach of that, a robot walking onto it, is tested where it ends)
    began = balls[:-1, :, None, :] - robots[1:, ..., :2]
    began_clear = np.hypot(began[..., 0], began[..., 1]) > contact + 1e-9
    assert path[began_clear].min() >= contact - 1e-9


def test_standing_robots_stay_put_and_a_match_depends_on_its_seed_only(walking):
    cfg, robots, balls, own = walking
    still, _, _ = _play(_config(0.0), [3], 50)
    np.testing.assert_array_equal(still, np.broadcast_to(still[:1], still.shape))
    alone_robots, alone_balls, alone_own = _play(cfg, [4], 300)  # match 4 alone, not in 3
    np.testing.assert_array_equal(alone_robots[:, 0], robots[:, 1])
    np.testing.assert_array_equal(alone_balls[:, 0], balls[:, 1])
    np.testing.assert_array_equal(alone_own[:, 0], own[:, 1])


def _gaps(robots: np.ndarray, own: np.ndarray) -> np.ndarray:
    """Centre distances (T, N, R + 1, R + 1) between every two robots of each match, ours
    (index 0) included; inf for a robot and itself and for empty slots."""
    xy = np.concatenate([own[..., None, :2], robots[..., :2]], axis=-2)
    used = np.concatenate([np.ones((*own.shape[:-1], 1), dtype=bool), robots[..., 2] > 0], -1)
    d = xy[..., :, None, :] - xy[..., None, :, :]
    gap = np.hypot(d[..., 0], d[..., 1])
    pair = used[..., :, None] & used[..., None, :] & ~np.eye(xy.shape[-2], dtype=bool)
    return np.where(pair, gap, np.inf)


@pytest.mark.parametrize("target", ["waypoints", "ball"])
@pytest.mark.parametrize("speed", [0.0, 0.3])
def test_no_two_robots_ours_included_ever_come_within_the_spacing(speed, target):
    """Our robot, walking fast (0.3 m/s) to waypoints or onto the ball, among four robots
    standing or walking fast: at every tick every two robots stand at least ``min_spacing``
    apart (our robot gave way to no one and walked to 0.04-0.34 m of the others' centres
    here, into their bodies). It gives way without locking: it walks in most ticks (a tick
    it gives way in, it turns on the spot; most it goes round them)."""
    cfg = _config(speed).replace(walk=WalkConfig(target=target, speed=0.3))
    robots, _, own = _play(cfg, [3, 4, 5, 6, 7, 8], 300)
    gaps = _gaps(robots, own)
    assert gaps.min() >= cfg.robots.min_spacing
    assert (gaps[..., 0, :] < cfg.robots.min_spacing + 0.02).any()  # ours did meet them
    moved = np.hypot(*np.moveaxis(np.diff(own[..., :2], axis=0), -1, 0))
    assert (moved > 0).mean() > 0.9


def _facing(
    other: tuple[float, float],
    waypoint: tuple[float, float] = (3.0, 0.0),
    target: str = "waypoints",
) -> MatchBatch:
    """A match with our robot at the origin facing +x, its belief exact, walking without a
    pause to ``waypoint`` (or to the ball there), and one other robot, standing, at
    ``other``."""
    cfg = MatchConfig(
        robots=RobotsConfig(count=(1, 1)),
        walk=WalkConfig(target=target, pause_ticks=(0, 0)),
        ball=BallConfig(kick_rate=0.0),
    )
    batch = MatchBatch(cfg, 1)
    batch.reset(np.zeros(1, dtype=np.int64), [np.random.default_rng(0)])
    batch.pose[0] = batch.mean[0] = (0.0, 0.0, 0.0)
    batch.waypoint[0] = batch.ball[0] = batch.ball_relative[0] = waypoint
    batch.ball_velocity[0] = batch.pause[0] = 0
    batch.robots[0, 0] = (*other, 0.6, 100.0)
    return batch


def _move(batch: MatchBatch) -> np.ndarray:
    """One tick of our robot's walk (the compiled move step alone): its odometry (3,)."""
    idx = np.zeros(1, dtype=np.int64)
    batch._draw(idx)
    return move_kernel(
        idx,
        batch.head[idx].copy(),
        batch._state,
        batch._params,
        batch._model,
        batch._ball_model,
        batch._uniforms[idx],
        batch._normals[idx],
    )[0]


@pytest.mark.parametrize("target", ["waypoints", "ball"])
def test_our_robot_about_to_walk_into_another_stands_and_its_odometry_says_so(target):
    """A robot 0.61 m straight ahead, our 6.4 cm step would end within the 0.6 m spacing:
    our robot does not step (not even the step's drift: it made none), its odometry is
    zero, and walking to a waypoint beyond that robot it takes a new one from its give-way
    draws (onto the ball, as a detour of DETOUR_TICKS ticks). A robot behind it, or far
    ahead, does not stop it; nor does one it parts from."""
    batch = _facing((0.61, 0.0), target=target)
    odometry = _move(batch)
    np.testing.assert_array_equal(odometry, 0.0)
    np.testing.assert_array_equal(batch.pose[0, :2], 0.0)
    assert abs(batch.pose[0, 2]) < 0.03  # no turn commanded: the turn's drift alone
    u = batch._uniforms[0, batch.k + 10 : batch.k + 12]
    hx, hy = batch._params[6], batch._params[7]
    np.testing.assert_allclose(batch.waypoint[0], [hx * (2 * u[0] - 1), hy * (2 * u[1] - 1)])
    assert batch.detour[0] == (DETOUR_TICKS if target == "ball" else 0)
    # the whole tick, as the envs play it (the UKF predicts from that odometry)
    batch = _facing((0.61, 0.0), target=target)
    batch.step(np.zeros(1, dtype=np.int64))
    np.testing.assert_array_equal(batch.pose[0, :2], 0.0)
    for other in [(-0.61, 0.0), (1.5, 0.0), (-0.1, 0.5)]:
        batch = _facing(other, target=target)
        before = np.hypot(*other)
        odometry = _move(batch)
        assert 0.05 < odometry[0] <= 0.064 + 1e-12 and odometry[1] == 0.0
        assert batch.pose[0, 0] > 0.0
        assert np.hypot(*(batch.pose[0, :2] - other)) >= min(before, 0.6)


@pytest.mark.parametrize("seed", range(5))
def test_our_robot_walking_to_a_ball_beyond_a_standing_robot_goes_round_it(seed):
    """Walking to a ball at rest 3 m ahead, a standing robot 0.61 m ahead in the way: our
    robot waited (turning to the ball) for the ball or the robot to move, and neither
    did, for the whole match (one robot in ten among four standing ones, with kicks, stood
    100 to 570 ticks). It takes a detour and comes back to the ball from elsewhere,
    keeping the spacing."""
    batch = _facing((0.61, 0.0), target="ball")
    batch._rngs[0] = np.random.default_rng(seed)
    ball, gaps = [], []
    for _ in range(200):
        batch.step(np.zeros(1, dtype=np.int64))
        ball.append(np.hypot(*(batch.pose[0, :2] - batch.ball[0])))
        gaps.append(np.hypot(*(batch.pose[0, :2] - batch.robots[0, 0, :2])))
    np.testing.assert_array_equal(batch.ball[0], [3.0, 0.0])  # at rest: no kicks
    assert min(ball) < 1.5
    assert min(gaps) >= 0.6


def test_our_robot_sidesteps_round_a_robot_its_step_closes_in_on():
    """A robot 0.6 m away 45 degrees to the right, a waypoint 60 degrees to the left: our
    robot turns towards it (the most it may: 0.16 rad) and walks forward by cos 60 of a
    step, which closes in on the robot. It turned on the spot, and among standing robots
    near a corner stood so for up to 533 of a match's 600 ticks. It sidesteps instead: the
    step's part across the way to the robot, and half a step away from it (drift would
    bring a bare sidestep closer every other tick), at the step's length; the sidestep is
    its odometry, and it keeps its waypoint."""
    side = 0.6 / np.sqrt(2)
    waypoint = (1.5, 1.5 * np.sqrt(3))
    batch = _facing((side, -side), waypoint)
    odometry = _move(batch)
    step = np.array([0.2 * 0.32 * np.cos(np.pi / 3), 0.0])  # forward, robot frame
    towards = np.array([1.0, -1.0]) / np.sqrt(2)
    across = step - (step @ towards) * towards
    expected = across - 0.5 * np.hypot(*step) * towards
    expected *= np.hypot(*step) / np.hypot(*expected)  # no faster than it walks
    np.testing.assert_allclose(odometry, [*expected, 0.16], atol=1e-12)
    assert expected[1] > 0.02 and expected[0] > 0  # mostly to the left, a little on
    gap = np.hypot(*(batch.pose[0, :2] - (side, -side)))
    assert gap > 0.6  # it parted from the robot, drift and all
    np.testing.assert_array_equal(batch.waypoint[0], waypoint)


def test_the_blocking_robot_is_the_one_the_step_ends_nearest():
    """Of the robots a step closes in on within the spacing, the nearest blocks it (the
    sidestep goes round it), not the first by index; an empty slot nearer still, and a
    robot already too close that the step parts from, block nothing."""
    before, after = np.zeros(3), np.array([0.064, 0.0, 0.0])
    robots = np.array(
        [
            [0.6, 0.3, 0.6, 0.5],  # ends 0.614 m away, closing in: blocks
            [0.6, 0.0, 0.6, 0.5],  # ends 0.536 m away, closing in: nearer
            [0.1, 0.0, 0.0, 0.5],  # an empty slot (height 0)
            [-0.3, 0.0, 0.6, 0.5],  # 0.36 m away, but the step parts from it
        ]
    )
    assert blocking_robot(before, after, robots, 0.7) == 1
    assert blocking_robot(before, after, robots[[0, 2, 3]], 0.7) == 0
    assert blocking_robot(before, after, robots[[2, 3]], 0.7) == -1
    assert blocking_robot(before, after, robots, 0.6) == 1  # 0.614 is clear of 0.6


def test_a_sidestep_needs_a_way_across():
    """Straight at the robot (or with less than a quarter of the step across), there is no
    sidestep, and our robot stands (as in
    ``test_our_robot_about_to_walk_into_another_stands_and_its_odometry_says_so``)."""
    pose = np.zeros(3)
    assert sidestep(pose, 0.61, 0.0, 0.064, 0.0) == (0.0, 0.0)
    assert sidestep(pose, 0.61, 0.1, 0.064, 0.0) == (0.0, 0.0)  # 9 degrees off: 0.16 across
    # beside it (blocked only by the step's drift): the step, and half a step away, at the
    # step's length (a sidestep of 0.072 m walked 12% faster than the robot walks)
    np.testing.assert_allclose(
        sidestep(pose, 0.0, 0.61, 0.064, 0.0), 0.064 * np.array([2.0, -1.0]) / np.sqrt(5)
    )
    x, y = sidestep(pose, 0.5, 0.5, 0.064, 0.0)  # 45 degrees: 0.71 of it across
    way = np.array([0.032 - 0.032 / np.sqrt(2), -0.032 - 0.032 / np.sqrt(2)])
    np.testing.assert_allclose([x, y], way * 0.064 / np.hypot(*way))


def test_our_robot_whose_sidestep_is_blocked_too_turns_on_the_spot():
    """The robot 45 degrees to the right of the sidestep test, and a second one standing
    where the sidestep (to the left) ends within 0.6 m of it: our robot turns on the spot
    (its position unchanged, the turn its odometry) and, wedged between two robots, takes a
    new waypoint from its give-way draws."""
    side = 0.6 / np.sqrt(2)
    waypoint = (1.5, 1.5 * np.sqrt(3))
    batch = MatchBatch(
        MatchConfig(
            robots=RobotsConfig(count=(2, 2)),
            walk=WalkConfig(pause_ticks=(0, 0)),
            ball=BallConfig(kick_rate=0.0),
        ),
        1,
    )
    batch.reset(np.zeros(1, dtype=np.int64), [np.random.default_rng(0)])
    batch.pose[0] = batch.mean[0] = (0.0, 0.0, 0.0)
    batch.waypoint[0] = batch.ball[0] = batch.ball_relative[0] = waypoint
    batch.ball_velocity[0] = batch.pause[0] = 0
    batch.robots[0, 0] = (side, -side, 0.6, 100.0)
    batch.robots[0, 1] = (-0.1, 0.605, 0.6, 100.0)  # 0.613 m away: clear of a step on the spot
    odometry = _move(batch)
    np.testing.assert_allclose(odometry, [0.0, 0.0, 0.16])
    np.testing.assert_array_equal(batch.pose[0, :2], 0.0)
    assert abs(batch.pose[0, 2] - 0.16) < 0.03  # the turn and its drift
    u = batch._uniforms[0, batch.k + 10 : batch.k + 12]
    hx, hy = batch._params[6], batch._params[7]
    np.testing.assert_allclose(batch.waypoint[0], [hx * (2 * u[0] - 1), hy * (2 * u[1] - 1)])
    # without the second robot, the same tick is a sidestep
    batch.robots[0, 1] = (3.0, 3.0, 0.6, 100.0)
    batch.pose[0] = batch.mean[0] = (0.0, 0.0, 0.0)
    batch.waypoint[0] = waypoint
    assert _move(batch)[1] > 0.02
    np.testing.assert_array_equal(batch.waypoint[0], waypoint)


@pytest.mark.parametrize("target", ["waypoints", "ball"])
def test_our_robot_among_standing_robots_never_stands_long(target):
    """Among four standing robots, walking to waypoints or to the ball, our robot stands
    still (its position unchanged) for at most 60 ticks running in 300 matches of 600
    (waypoint pauses are up to 15 ticks). Turning on the spot where a robot stood half beside its
    way it stood for 533 ticks walking to waypoints, 212 walking to the ball; sidestepping,
    but keeping its waypoint when wedged between two robots, 188 (waypoints)."""
    cfg = MatchConfig(robots=RobotsConfig(count=(4, 4)), walk=WalkConfig(target=target))
    _, _, own = _play(cfg, list(range(1000, 1300)), 600)
    moved = np.hypot(*np.moveaxis(np.diff(own[..., :2], axis=0), -1, 0)) > 0  # (T, N)
    standing = np.zeros(moved.shape[1], dtype=int)
    longest = 0
    for step in moved:
        standing = np.where(step, 0, standing + 1)
        longest = max(longest, int(standing.max()))
    assert 0 < longest <= 60


def test_a_sidestep_cut_short_by_the_carpet_s_edge_keeps_a_waypoint_clear_of_the_robot():
    """The sidestep test on the carpet's edge (y = 4 m): the sidestep, to the left, is cut
    at the edge and still closes in on the same robot. Our robot turns on the spot and keeps
    its waypoint, which lies clear of that robot (it is not wedged between two: it took a
    new waypoint, and walking to the ball a detour, whenever a sidestep was blocked)."""
    side = 0.6 / np.sqrt(2)
    for target in ("waypoints", "ball"):
        waypoint = (1.5, 4.0 + 1.5 * np.sqrt(3))
        batch = _facing((side, 4.0 - side), waypoint=waypoint, target=target)
        batch.pose[0] = batch.mean[0] = (0.0, 4.0, 0.0)
        batch.ball_relative[0] = (1.5, 1.5 * np.sqrt(3))  # the ball on the waypoint
        odometry = _move(batch)
        np.testing.assert_allclose(odometry, [0.0, 0.0, 0.16])
        np.testing.assert_array_equal(batch.pose[0, :2], [0.0, 4.0])
        if target == "waypoints":
            np.testing.assert_array_equal(batch.waypoint[0], waypoint)
        assert batch.detour[0] == 0


def _play_own(bounces: bool, seeds: list[int], ticks: int):
    """Our robot's positions and the balls over ``ticks`` ticks of matches with no other
    robots, our robot walking onto the ball (so that it meets it), soft and rare kicks
    (so that it catches up)."""
    cfg = MatchConfig(
        ticks=ticks,
        walk=WalkConfig(target="ball", ball_standoff=0.0),
        ball=BallConfig(kick_rate=0.01, kick_speed=(0.3, 1.0), bounces_off_own_robot=bounces),
    )
    batch = MatchBatch(cfg, len(seeds))
    batch.reset(np.arange(len(seeds)), [np.random.default_rng(s) for s in seeds])
    own, balls, speeds = [], [], []
    for t in range(ticks):
        batch.step(np.full(len(seeds), t % 9))
        own.append(batch.pose[:, :2].copy())
        balls.append(batch.ball.copy())
        speeds.append(np.hypot(*batch.ball_velocity.T))
    d = np.stack(balls) - np.stack(own)
    return cfg, np.hypot(d[..., 0], d[..., 1]), np.stack(speeds)


def test_the_ball_bounces_off_our_robot_only_when_asked():
    cfg, through, _ = _play_own(False, [3, 4], 400)
    contact = cfg.robots.radius + cfg.field.ball_radius
    assert (through < contact - 0.1).any()  # by default it rolls through us (README)
    cfg, bounced, speeds = _play_own(True, [3, 4], 400)
    assert bounced.min() >= contact - 1e-9
    assert (bounced < contact + 1e-6).mean() > 0.03  # our robot walks into it and pushes it
    assert speeds.max() <= cfg.ball.kick_speed[1] + 1e-9  # a bounce adds no speed


@pytest.mark.parametrize("speed", [0.0, 0.3])
def test_a_kidnap_never_puts_our_robot_within_the_spacing_of_another(speed):
    """Kidnapped in every tick among eight robots, standing or walking: at the end of every
    tick every two robots, ours included, stand at least ``min_spacing`` apart (the carry
    was drawn without looking at the others: here it put ours 0.03 m from one standing,
    0.06 m from one walking), and the kidnaps still carry the robot (most by 1-2 m, fewer
    where the field's margin stops them)."""
    ticks = 60
    cfg = MatchConfig(
        ticks=ticks,
        robots=RobotsConfig(count=(8, 8)),
        others=OthersConfig(speed=speed),
        kidnap=KidnapConfig(ticks=tuple(range(1, ticks + 1))),
    )
    robots, _, own = _play(cfg, list(range(20, 28)), ticks)
    assert _gaps(robots, own).min() >= cfg.robots.min_spacing
    carried = np.hypot(*np.moveaxis(np.diff(own[..., :2], axis=0), -1, 0))
    assert np.median(carried) > 0.9


def test_a_kidnap_with_no_free_place_leaves_our_robot_where_it_stands_only_turned():
    """Eight robots in a ring 1.5 m round ours, 1.2 m apart at least: every place 1-2 m
    away lies within 1.2 m of one of them, so no draw keeps the spacing; the kidnap turns
    the robot where it stands (still a kidnap), the same way from the same seed."""
    cfg = MatchConfig(
        robots=RobotsConfig(count=(8, 8), min_spacing=1.2),
        kidnap=KidnapConfig(ticks=(1,)),
    )
    poses = []
    for _ in range(2):
        batch = MatchBatch(cfg, 1)
        batch.reset(np.arange(1), [np.random.default_rng(9)])
        batch.pose[0] = (0.0, 0.0, 0.3)
        angles = np.radians(np.arange(8) * 45.0)
        batch.robots[0] = np.column_stack(
            [1.5 * np.cos(angles), 1.5 * np.sin(angles), np.full(8, 0.6), np.full(8, 100.0)]
        )
        start = batch.pose[0].copy()
        idx = np.arange(1)
        batch._draw(idx)
        batch._kidnap(idx)  # the kidnap alone, before the tick's walk
        assert batch.kidnapped[0]
        np.testing.assert_array_equal(batch.pose[0, :2], start[:2])
        turn = batch.pose[0, 2] - start[2]
        assert 0 < abs(turn) <= 0.8
        poses.append(batch.pose[0].copy())
    np.testing.assert_array_equal(poses[0], poses[1])
