"""The match runner and strategies: every strategy plays, the same seeds give the same
matches, the metrics are what they say, and the strategies aim where they claim."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest

from activevision.envs.match.config import MatchConfig
from activevision.envs.match.heads import track_grid
from activevision.experiments.evaluate import Interval, wilson_interval
from activevision.experiments.match import (
    MATCH_METRICS,
    MatchClip,
    MethodResult,
    compare_matches,
    csv_rows,
    expand_methods,
    format_difference,
    paired_differences,
    paired_rows,
    pareto_front,
    play_matches,
)
from activevision.experiments.match_methods import (
    BHumanCycle,
    BitBotsSearch,
    EntropyTrack,
    NUbots6Point,
    StrategyOptions,
    ball_direction,
    ball_on_field,
    default_match_methods,
    make_match_policy,
    move_towards,
    privileged,
    privileged_methods,
)
from activevision.geometry import CameraConfig, clip_head, field_landmarks

SMALL = MatchConfig(ticks=12)

TRACK = track_grid(MatchConfig().camera)  # entropy_track's candidates, paper camera


@pytest.mark.parametrize("method", default_match_methods(None))
def test_every_strategy_plays_and_the_metrics_are_in_range(method):
    result = play_matches(method, SMALL, 2, seed=3)
    assert set(result.per_match) == set(MATCH_METRICS)
    for name, values in result.per_match.items():
        assert values.shape == (2,) and np.isfinite(values).all(), name
    assert (result.per_match["ball_in_view"] >= 0).all() and (
        result.per_match["ball_in_view"] <= 1
    ).all()
    assert (result.per_match["position_rmse"] >= 0).all()
    assert result.error_curve.shape == (12, 2)
    assert len(result.clip.pose) == 13  # the start and every tick


CONTINUOUS = SMALL.replace(action_type="continuous", max_move_deg=(3.0, 3.0))


@pytest.mark.parametrize("method", default_match_methods(None))
def test_every_strategy_plays_a_continuous_match(method):
    """In a continuous match every strategy returns (N, 2) moves the env accepts."""
    result = play_matches(method, CONTINUOUS, 2, seed=3)
    assert np.isfinite(result.per_match["position_rmse"]).all()
    # no tick moves the head more than 3 deg per axis: sqrt(2) * 3 deg per tick at most
    most = math.sqrt(2) * 3.0 / CONTINUOUS.tick_seconds
    assert (result.per_match["head_travel"] <= most + 1e-9).all()


def test_move_towards_by_hand():
    """Discrete: the 3-deg move that ends closest; continuous: straight there, each axis
    capped at 3 deg (as a fraction of it)."""
    head = np.radians([[0.0, 20.0], [0.0, 20.0]])
    target = np.radians([[10.0, 21.0], [1.0, 20.5]])
    assert move_towards(head, target, SMALL).tolist() == [1, 0]  # pan left; stay
    np.testing.assert_allclose(
        move_towards(head, target, CONTINUOUS), [[1.0, 1 / 3], [1 / 3, 0.5 / 3]]
    )


def test_a_q_network_refuses_a_continuous_match(tmp_path):
    (tmp_path / "config.json").write_text('{"algo": "ddqn"}')
    with pytest.raises(ValueError, match="play it with --action-type discrete"):
        make_match_policy("learned", CONTINUOUS, StrategyOptions(run=tmp_path))


def test_same_seeds_same_matches():
    a = play_matches("entropy_greedy", SMALL, 2, seed=9)
    b = play_matches("entropy_greedy", SMALL, 2, seed=9)
    for name in MATCH_METRICS:
        np.testing.assert_array_equal(a.per_match[name], b.per_match[name])
    c = play_matches("ball_track", SMALL, 2, seed=9)  # another head, the same walks and balls
    np.testing.assert_array_equal(a.clip.pose[0], c.clip.pose[0])


def test_rmse_is_the_root_mean_square_of_the_error_curve():
    r = play_matches("random", SMALL, 3, seed=1)
    np.testing.assert_allclose(r.per_match["position_rmse"], np.sqrt((r.error_curve**2).mean(0)))
    np.testing.assert_allclose(r.per_match["lost_share"], (r.error_curve > 0.5).mean(0))


def test_intervals_stay_within_what_each_metric_can_take():
    """Two matches far apart: the normal approximation would put an RMSE and head travel
    below 0 and a share above 1; entropy, which can be negative, is not bounded."""
    per_match = {
        "position_rmse": np.array([0.01, 0.9]),
        "heading_rmse": np.array([0.2, 5.7]),
        "lost_share": np.array([0.0, 0.9]),
        "ball_in_view": np.array([0.1, 1.0]),
        "entropy": np.array([-6.0, 1.0]),
        "head_travel": np.array([0.0, 9.0]),
    }
    summary = MethodResult("a", per_match, np.zeros((1, 2)), MatchClip(), 0.0).summary()
    for name in ("position_rmse", "heading_rmse", "lost_share", "ball_in_view", "head_travel"):
        assert summary[name].low == 0.0, name
    assert summary["ball_in_view"].high == 1.0
    assert summary["entropy"].low < -6.0  # mean -2.5, half-width 6.86 x 1.96


def test_a_share_s_interval_never_narrows_as_it_leaves_0():
    """A share 0 in each of 50 matches read 0.0% [0.0, 7.1] (Wilson's 0 of 50), and the same
    share with one match lost for 3 ticks of 600 read [0.0, 0.1]: more loss, a narrower
    interval. One rule now, the normal approximation from the spread over matches (the
    ball in view's and every metric's): 0 in every match reads [0, 0], and each match lost
    for longer widens it, by the formula's own numbers."""
    uppers = []
    for lost_ticks in (0, 3, 30, 300):
        lost = np.zeros(50)
        lost[0] = lost_ticks / 600
        per_match = {name: np.full(50, 0.5) for name in MATCH_METRICS}
        per_match["lost_share"] = lost
        interval = MethodResult("a", per_match, np.zeros((1, 50)), MatchClip(), 0.0).summary()[
            "lost_share"
        ]
        half = 1.959964 * lost.std(ddof=1) / np.sqrt(50)
        assert (interval.low, interval.high) == pytest.approx(
            (max(0.0, lost.mean() - half), lost.mean() + half), abs=1e-9
        )
        uppers.append(interval.high)
    assert uppers[0] == 0.0 and uppers == sorted(uppers) and len(set(uppers)) == 4
    # the ball in view, which varies, keeps its interval to the digit
    ball = np.linspace(0.2, 0.5, 50)
    per_match = {name: np.full(50, 0.5) for name in MATCH_METRICS} | {"ball_in_view": ball}
    got = MethodResult("a", per_match, np.zeros((1, 50)), MatchClip(), 0.0).summary()
    half = 1.959964 * ball.std(ddof=1) / np.sqrt(50)
    assert got["ball_in_view"].high == pytest.approx(ball.mean() + half, rel=1e-6)


def fake(method: str, rmse: float, ball: float) -> MethodResult:
    per_match = {name: np.zeros(4) for name in MATCH_METRICS}
    per_match["position_rmse"] = np.full(4, rmse)
    per_match["ball_in_view"] = np.full(4, ball)
    return MethodResult(method, per_match, np.zeros((1, 4)), MatchClip(), 0.0)


def test_pareto_front_by_hand():
    results = [fake("a", 0.1, 0.5), fake("b", 0.2, 0.6), fake("c", 0.2, 0.4), fake("d", 0.1, 0.5)]
    assert pareto_front(results) == ["a", "b", "d"]  # c is beaten by a on both
    rows = csv_rows(results, 4, 0, SMALL)
    assert rows[0]["position_rmse"] == pytest.approx(0.1) and rows[0]["matches"] == 4
    assert rows[0]["ticks"] == 1  # how long the matches were (report.md says it)
    # the world, which report.md names: SMALL's head and the default detector
    world = ("action_type", "step_deg", "robots", "detect_near", "detect_far", "false_detections")
    assert [rows[0][key] for key in world] == ["discrete", 3.0, "0", 0.95, 0.5, 0.05]


def test_match_csv_records_the_walk_the_other_robots_speed_and_the_ball():
    """match.csv recorded the head, the robots' count and the detector, not how our robot
    walked, how fast the others did, nor the ball: a strategy's scores without the world
    they were scored in. Each WORLD_COLUMNS column follows its MatchConfig field."""
    import dataclasses

    from activevision.envs.match.config import BallConfig, OthersConfig, WalkConfig
    from activevision.experiments.match_world import WORLD_COLUMNS, world_differences

    world = SMALL.replace(
        walk=WalkConfig(target="ball", speed=0.3, turn_rate=0.8),
        others=OthersConfig(speed=0.25, ball_restitution=0.3),
        ball=BallConfig(
            deceleration=0.6, kick_rate=0.05, kick_speed=(1, 2), bounces_off_own_robot=True
        ),
        tick_seconds=0.5,
        detection=dataclasses.replace(SMALL.detection, ball_noise=0.1),
        # a robot's own camera (a run trained for it plays its matches through it)
        camera=CameraConfig(
            width=160, height=90, hfov=math.radians(70), camera_height=0.62, tilt_max=1.0
        ),
    )
    row = csv_rows([fake("a", 0.1, 0.5)], 4, 0, world)[0]
    recorded = {name: row[name] for name in WORLD_COLUMNS}
    assert recorded == {
        "walk": "ball",
        "walk_speed": 0.3,
        "turn_rate": 0.8,
        "robot_speed": 0.25,
        "ball_decel": 0.6,
        "kick_rate": 0.05,
        "kick_speed": "1-2",
        "bounce_us": True,
        "restitution": 0.3,
        "tick_s": 0.5,
        "ball_noise": 0.1,
        "camera_px": "160x90",
        "hfov_deg": 70.0,
        "camera_height": 0.62,
        "head_range_deg": "-90..90 5..57.3",
    }
    assert all(column.meaning for column in WORLD_COLUMNS.values())
    # as the CSV gives them back (text): every one differs from the default world
    as_text = {name: str(value) for name, value in row.items()}
    assert len(world_differences(as_text)) == len(WORLD_COLUMNS)
    default = {k: str(v) for k, v in csv_rows([fake("a", 0.1, 0.5)], 4, 0, SMALL)[0].items()}
    assert world_differences(default) == []
    assert world_differences({"method": "a", "robots": "0"}) == []  # an older match.csv


def test_paired_differences_by_hand():
    """Matches that vary far more than the methods: a is 1 cm better in every match, which
    the paired interval resolves ([-0.01, -0.01]) and the per-method intervals do not."""
    base = np.array([0.05, 0.10, 0.15, 0.20])
    a, b = fake("a", 0.0, 0.3), fake("b", 0.0, 0.3)
    a.per_match["position_rmse"][:] = base - 0.01
    b.per_match["position_rmse"][:] = base
    a.per_match["ball_in_view"][:] = [0.3, 0.4, 0.5, 0.6]  # differences 0, .1, .2, .3
    differences = paired_differences([a, b], "b")
    assert list(differences) == ["a"]
    rmse = differences["a"]["position_rmse"]
    assert (rmse.mean, rmse.low, rmse.high) == pytest.approx((-0.01, -0.01, -0.01))
    alone = [r.summary()["position_rmse"] for r in (a, b)]
    assert alone[0].high > alone[1].low  # the intervals of each method overlap
    ball = differences["a"]["ball_in_view"]
    half = 1.959964 * np.std([0, 0.1, 0.2, 0.3], ddof=1) / 2  # z * s / sqrt(4)
    assert (ball.mean, ball.high - ball.mean) == pytest.approx((0.15, half), rel=1e-5)
    assert format_difference("a", differences["a"]).split()[:2] == ["a", "-0.010"]
    # a difference that rounds to zero reads +0.000, not -0.000
    near_zero = {**differences["a"], "position_rmse": Interval(-1e-5, -2e-5, -1e-6)}
    assert format_difference("a", near_zero).split()[1:3] == ["+0.000", "[0.000,0.000]"]
    row = paired_rows(differences, "b", 4, 7)[0]
    assert (row["method"], row["baseline"], row["seed"]) == ("a", "b", 7)
    assert row["ball_in_view_diff_low"] == pytest.approx(0.15 - half, rel=1e-5)
    # neither ever lost: no difference in any match, by the rule of every other difference
    # (match_interval); it was Wilson's +-0.49 over these 4 matches, where one match of
    # difference read narrower
    a.per_match["lost_share"][:] = 0.0
    b.per_match["lost_share"][:] = 0.0
    lost = paired_differences([a, b], "b")["a"]["lost_share"]
    assert (lost.mean, lost.low, lost.high) == (0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="baseline 'c'"):
        paired_differences([a, b], "c")


def test_onnx_policy_plays_once_per_model():
    one, two = Path("runs/a/policy.onnx"), Path("runs/b/policy.onnx")
    assert expand_methods(["ball_track", "onnx_policy"]) == [
        ("ball_track", "ball_track", StrategyOptions()),
        ("onnx_policy", "onnx_policy", StrategyOptions()),
    ]
    assert expand_methods(["onnx_policy"], [one]) == [
        ("onnx_policy", "onnx_policy", StrategyOptions(model=one))
    ]
    labels = [label for label, _, _ in expand_methods(["onnx_policy"], [one, two])]
    assert labels == ["onnx_policy[a]", "onnx_policy[b]"]
    same = [Path("x/m.onnx"), Path("y/m.onnx")]
    assert [lab for lab, _, _ in expand_methods(["onnx_policy"], same)] == [
        "onnx_policy[m-1]",
        "onnx_policy[m-2]",
    ]


def test_entropy_track_plays_once_per_margin():
    assert expand_methods(["entropy_track"], margins=[7.5]) == [
        ("entropy_track", "entropy_track", StrategyOptions(track_margin_deg=7.5))
    ]
    entries = expand_methods(["entropy_track", "ball_track"], margins=[0, 20])
    assert [(label, o.track_margin_deg) for label, _, o in entries] == [
        ("entropy_track[0deg]", 0),
        ("entropy_track[20deg]", 20),
        ("ball_track", 5.0),
    ]


def test_references_neither_join_nor_beat_the_front():
    results = [fake("a", 0.1, 0.5), fake("b", 0.2, 0.6), fake("oracle", 0.05, 0.9)]
    assert pareto_front(results) == ["oracle"]
    assert pareto_front(results, references={"oracle"}) == ["a", "b"]
    assert privileged_methods() == {"oracle_ball", "oracle_entropy"}


def test_privileged_info_by_hand():
    """The robot at (1, 2) facing +y, the ball at (1, 4): 2 m straight ahead; its belief
    (wrong) and ball model (wrong) are replaced by the truth."""
    info = {
        "pose": np.array([[1.0, 2.0, math.pi / 2]]),
        "ball": np.array([[1.0, 4.0]]),
        "belief_mean": np.zeros((1, 3)),
        "ball_relative": np.array([[0.0, -1.0]]),
    }
    truth = privileged(info)
    np.testing.assert_allclose(truth["ball_relative"], [[2.0, 0.0]], atol=1e-12)
    np.testing.assert_array_equal(truth["belief_mean"], info["pose"])
    assert info["ball_relative"][0, 1] == -1.0  # the caller's dict is untouched


def test_the_true_ball_is_seen_at_least_as_often_as_the_model_s():
    """``oracle_ball`` tracks the true ball, ``ball_track`` the robot's (stale after kicks)
    model: over the same 6 matches the oracle sees it at least as often."""
    config = MatchConfig(ticks=200)
    model = play_matches("ball_track", config, 6, seed=5).per_match["ball_in_view"].mean()
    truth = play_matches("oracle_ball", config, 6, seed=5).per_match["ball_in_view"].mean()
    assert truth >= model


def test_ball_direction_by_hand():
    """The ball 1 m ahead and 1 m left: pan 45 deg; tilt atan((0.5 - 0.07) / sqrt 2)."""
    info = {"ball_relative": np.array([[1.0, 1.0]])}
    head = ball_direction(info, MatchConfig())
    np.testing.assert_allclose(head[0], [math.pi / 4, math.atan2(0.43, math.sqrt(2))])


def info_for(head, ball_relative, mean=None):
    n = len(head)
    return {
        "head": np.asarray(head, float),
        "ball_relative": np.asarray(ball_relative, float),
        "ball_age": np.zeros(n, dtype=np.int64),
        "belief_mean": np.zeros((n, 3)) if mean is None else np.asarray(mean, float),
    }


def test_bhuman_cycle_narrows_when_walking():
    """Standing, the sweep reaches 45 deg beside the ball; walking at full speed, 15."""
    policy = BHumanCycle(MatchConfig())
    policy.reset(1, np.random.default_rng(0))
    ball = [[2.0, 0.0]]
    standing = policy.targets(info_for([[0.0, 0.3]], ball))
    assert math.degrees(abs(standing[0, 0])) == pytest.approx(45.0)
    policy.reset(1, np.random.default_rng(0))
    for t in range(60):  # walking 0.2 m/s: 0.064 m per tick
        target = policy.targets(info_for([[0.0, 0.3]], ball, [[0.064 * t, 0.0, 0.0]]))
    assert math.degrees(abs(target[0, 0])) == pytest.approx(15.0, abs=0.5)


@pytest.mark.parametrize("tick_seconds", [0.16, 0.08])
def test_bhuman_cycle_estimates_its_speed_in_seconds_not_ticks(tick_seconds):
    """The walking speed's average kept 0.8 of its value per tick: with ticks of 0.16 s it
    reacted twice as fast as with the paper's 0.32 s. Now, walking at 0.1 m/s from rest,
    the estimate after the same seconds is the same at every tick length: 0.1 (1 - 0.8^(t /
    0.32 s)), as the paper's tick gives it."""

    def estimates(tick):
        policy = BHumanCycle(MatchConfig(tick_seconds=tick))
        policy.reset(1, np.random.default_rng(0))
        per_tick = round(1.28 / tick)  # 1.28 s of walking
        for t in range(per_tick + 1):
            policy.targets(info_for([[0.0, 0.3]], [[2.0, 0.0]], [[0.1 * tick * t, 0.0, 0.0]]))
        return float(policy.speed[0])

    expected = 0.1 * (1 - 0.8 ** (1.28 / 0.32))
    assert estimates(0.32) == pytest.approx(expected, rel=1e-9)
    assert estimates(tick_seconds) == pytest.approx(expected, rel=1e-9)
    # the paper's tick: exactly 0.8 and 0.2, as the README's tables were measured with
    policy = BHumanCycle(MatchConfig())
    assert (policy.keep_per_tick, policy.gain_per_tick) == (0.8, 0.2)


@pytest.mark.parametrize(("tick_seconds", "ticks_at_a_point"), [(0.32, 3), (0.16, 6), (0.08, 12)])
def test_the_six_point_look_dwells_for_seconds_not_ticks(tick_seconds, ticks_at_a_point):
    """NUbots' look held the head 3 ticks at each point whatever a tick lasted (0.96 s of the
    paper's ticks, 0.48 s of ticks of 0.16 s); now 0.96 s at every tick length."""
    policy = NUbots6Point(MatchConfig(tick_seconds=tick_seconds))
    policy.reset(1, np.random.default_rng(0))
    head = np.radians([[60.0, 15.0]])  # at the first point
    targets = []
    for _ in range(3 * ticks_at_a_point + 1):
        target = policy.targets(info_for(head, [[1.0, 0.0]]))
        head = target.copy()  # a head that arrives at once
        targets.append(tuple(np.round(np.degrees(target[0]))))
    runs = [len(list(run)) for _, run in itertools.groupby(targets)]
    # the first point's run lacks the tick the head arrived in; then each is held in full
    assert runs[1:3] == [ticks_at_a_point] * 2
    assert ticks_at_a_point * tick_seconds == pytest.approx(0.96)


@pytest.mark.parametrize("method", ["entropy_greedy", "oracle_entropy", "onnx_policy"])
@pytest.mark.parametrize(("tick_seconds", "ticks"), [(0.32, 16), (0.16, 32), (0.08, 64)])
def test_the_view_is_planned_again_every_1_6_seconds_whatever_a_tick_lasts(
    monkeypatch, method, tick_seconds, ticks
):
    """entropy_greedy (and its oracle) and onnx_policy planned their view every 5 ticks
    whatever a tick lasted: 1.6 s of the paper's ticks, 0.8 s of ticks of 0.16 s. Now every
    1.6 s: in 5.12 s of play, at 0, 1.6, 3.2 and 4.8 s, at every tick length (counted as
    real matches call Algorithm 1)."""
    import activevision.experiments.match_methods as methods

    planned: list[int] = []
    plan = methods.plan_views

    def counting(info, *args):
        planned.append(1)
        return plan(info, *args)

    monkeypatch.setattr(methods, "plan_views", counting)
    play_matches(method, MatchConfig(ticks=ticks, tick_seconds=tick_seconds), 1, seed=3)
    assert len(planned) == 4  # 5.12 s / 1.6 s, the first at the first tick


def test_entropy_track_keeps_the_ball_inside_its_margin():
    """From real match states: every target lies within half the field of view less the
    margin of the ball's direction (clipped to the head's limits, so also for a ball behind
    the robot) and has the least expected entropy of those views (brute force over Algorithm
    1's search); widening the margin can only cost expected entropy."""
    from activevision.envs.match.vector import ActiveVisionMatchVectorEnv
    from activevision.localisation import best_viewpoints

    config = MatchConfig()
    env = ActiveVisionMatchVectorEnv(16, config)
    _, info = env.reset(seed=4)
    for _ in range(20):  # the robots walk off, the balls roll: varied states
        _, _, _, _, info = env.step(np.zeros(16, dtype=np.int64))
    cam, ball = config.camera, ball_direction(info, config)
    search = best_viewpoints(
        info["belief_mean"],
        info["belief_cov"],
        ball_on_field(info),
        field_landmarks(config.field),
        cam,
        grid=TRACK,
        ukf=config.tracker.ukf,
    )
    views = {tuple(v): i for i, v in enumerate(TRACK.views)}
    entropies = []
    for margin in (0.0, 10.0, 20.0):
        policy = EntropyTrack(config, margin)
        policy.reset(16, np.random.default_rng(0))
        target = policy.targets(info)
        gap = np.abs(target - ball)
        inside = (gap[:, 0] <= cam.hfov / 2 - math.radians(margin) + 1e-12) & (
            gap[:, 1] <= cam.vfov / 2 - math.radians(margin) + 1e-12
        )
        assert inside.all()
        chosen = [views[tuple(t)] for t in target]  # always a grid view here
        entropies.append([search.entropies[i, v] for i, v in enumerate(chosen)])
        # the least expected entropy of the views allowed, by brute force
        for i, v in enumerate(chosen):
            gaps = np.abs(TRACK.views - ball[i])
            ok = (gaps[:, 0] <= cam.hfov / 2 - math.radians(margin)) & (
                gaps[:, 1] <= cam.vfov / 2 - math.radians(margin)
            )
            assert search.entropies[i, v] == np.min(search.entropies[i][ok])
    by_margin = np.array(entropies)
    assert (by_margin[1:] >= by_margin[:-1]).all() and (by_margin[2] > by_margin[0]).any()
    behind = np.abs(ball[:, 0]) >= cam.pan_max - 1e-9
    assert behind.any()  # some balls lie beyond the head's reach: covered above
    # beyond half the vertical view no view is allowed: the ball's direction itself
    tracking = EntropyTrack(config, math.degrees(cam.vfov / 2) + 1.0)
    tracking.reset(16, np.random.default_rng(0))
    np.testing.assert_array_equal(tracking.targets(info), ball)


def test_glance_track_tracks_the_ball_unless_unsure_or_the_ball_is_out_of_reach():
    """Row by row, from real match states made sure, unsure, and with the ball behind: a
    sure robot with the ball in reach looks at the ball; an unsure one takes entropy_track's
    target (margin 0); a ball beyond reach gives the least expected entropy of all views
    (brute force over Algorithm 1's search). The batch gives each row what it gets alone."""
    from activevision.envs.match.heads import (
        entropy_track_targets,
        glance_track_targets,
    )
    from activevision.envs.match.vector import ActiveVisionMatchVectorEnv
    from activevision.localisation import best_viewpoints

    config = MatchConfig()
    env = ActiveVisionMatchVectorEnv(9, config)
    _, info = env.reset(seed=11)
    for _ in range(10):
        _, _, _, _, info = env.step(np.zeros(9, dtype=np.int64))
    info = {k: np.array(v, copy=True) for k, v in info.items() if isinstance(v, np.ndarray)}
    sure, unsure = np.diag([0.02**2, 0.02**2, 0.01]), np.diag([0.2**2, 0.2**2, 0.05])
    info["belief_cov"][:] = sure
    info["belief_cov"][3:6] = unsure
    distance = np.hypot(*info["ball_relative"][6:].T)  # rows 6-8: the ball straight behind
    info["ball_relative"][6:] = np.column_stack([-distance, np.zeros(3)])
    std, reach = 0.1, math.radians(30.0)
    target = glance_track_targets(info, config, std, reach)
    np.testing.assert_array_equal(target[:3], ball_direction(info, config)[:3])
    np.testing.assert_array_equal(target[3:6], entropy_track_targets(info, config, 0.0)[3:6])
    search = best_viewpoints(
        info["belief_mean"][6:],
        info["belief_cov"][6:],
        ball_on_field(info)[6:],
        field_landmarks(config.field),
        config.camera,
        grid=TRACK,
        ukf=config.tracker.ukf,
    )
    best = TRACK.views[np.argmin(search.entropies, axis=1)]
    np.testing.assert_array_equal(target[6:], best)
    for i in np.random.default_rng(0).permutation(9):  # alone, in shuffled order
        row = {k: v[i : i + 1] for k, v in info.items()}
        np.testing.assert_array_equal(
            glance_track_targets(row, config, std, reach), target[i : i + 1]
        )
    # with a finite tracking margin a sure robot takes entropy_track's view at that margin
    margin = math.radians(15.0)
    tracked = glance_track_targets(info, config, std, reach, track_margin=margin)
    np.testing.assert_array_equal(tracked[:3], entropy_track_targets(info, config, margin)[:3])
    np.testing.assert_array_equal(tracked[3:], target[3:])
    # a ball just beyond the pan limit is still watched for (within the reach margin)
    pan = config.camera.pan_max + config.camera.hfov / 2 + math.radians(10.0)
    info["ball_relative"][6:] = distance[:, None] * np.column_stack(
        [np.cos([pan] * 3), np.sin([pan] * 3)]
    )
    np.testing.assert_array_equal(
        glance_track_targets(info, config, std, reach)[6:], ball_direction(info, config)[6:]
    )


def test_six_point_look_visits_its_points_in_turn():
    policy = NUbots6Point(MatchConfig())
    policy.reset(1, np.random.default_rng(0))
    visited = []
    head = np.radians([[60.0, 15.0]])
    for _ in range(30):
        target = policy.targets(info_for(head, [[1.0, 0.0]]))
        head = target.copy()  # a head that arrives at once
        visited.append(tuple(np.round(np.degrees(target[0]))))
    order = list(dict.fromkeys(visited))
    assert order == [(60, 15), (0, 15), (-60, 15), (-60, 45), (0, 45), (60, 45)]


NARROW_HEAD = CameraConfig(
    pan_min=math.radians(-60.0),
    pan_max=math.radians(60.0),
    tilt_min=math.radians(20.0),
    tilt_max=math.radians(60.0),
)


@pytest.mark.parametrize(
    ("policy_class", "expected"),
    [
        (NUbots6Point, [(60, 20), (0, 20), (-60, 20), (-60, 45), (0, 45), (60, 45)]),
        (BitBotsSearch, [(-60, 20), (60, 20), (60, 40), (-60, 40)]),
    ],
)
def test_a_pattern_goes_round_on_a_head_that_cannot_reach_its_points(policy_class, expected):
    """A camera whose head pans +-60 deg and tilts 20-60 (a run trained for a robot's own
    camera plays every strategy through it): the points beyond its limits are looked at
    from the nearest limit, and the pattern goes on. The head stopped at the first point it
    could not reach (the pattern's 90 or 15 degrees) and stayed there for the whole match."""
    policy = policy_class(MatchConfig(camera=NARROW_HEAD))
    policy.reset(1, np.random.default_rng(0))
    head = np.radians([[10.0, 30.0]])
    visited = []
    for _ in range(40):
        info = info_for(head, [[1.0, 0.0]])
        info["ball_age"][:] = 100  # Bit-Bots search: a ball not seen for long
        target = policy.targets(info)
        head = np.column_stack(clip_head(target[:, 0], target[:, 1], NARROW_HEAD))
        visited.append(tuple(np.round(np.degrees(target[0])).astype(int).tolist()))
    assert list(dict.fromkeys(visited)) == expected


@pytest.mark.parametrize(("tick_seconds", "tracked_age"), [(0.32, 3), (0.1, 10), (1.0, 1)])
def test_bitbots_search_tracks_a_ball_seen_within_the_last_second(tick_seconds, tracked_age):
    """The ball while it was seen within the last second, whatever a tick lasts: 3 ticks of
    0.32 s, 10 of 0.1 s, 1 of 1 s (it was 3 ticks at every tick length)."""
    policy = BitBotsSearch(MatchConfig(tick_seconds=tick_seconds))
    policy.reset(2, np.random.default_rng(0))
    ball = [[1.0, 0.5], [1.0, 0.5]]
    info = info_for(np.radians([[0.0, 30.0], [0.0, 30.0]]), ball)
    info["ball_age"] = np.array([tracked_age, tracked_age + 1])
    target = policy.targets(info)
    np.testing.assert_allclose(target[0], ball_direction(info, policy.config)[0])
    np.testing.assert_allclose(target[1], np.radians([-90.0, 15.0]))  # the search's first


def test_unknown_method_is_one_clear_error():
    with pytest.raises(ValueError, match="unknown match method 'nope'"):
        make_match_policy("nope", SMALL)
    with pytest.raises(ValueError, match="needs a training run"):
        make_match_policy("learned", SMALL)


class _ActsWrongAtTick:
    """A user's strategy that plays well until tick ``bad`` of a match, then sends a float."""

    def __init__(self, config, bad):
        self.bad, self.tick = bad, 0

    def reset(self, n, rng):
        self.n, self.tick = n, 0

    def act(self, obs, info):
        self.tick += 1
        return np.full(self.n, 0.5 if self.tick > self.bad else 0)


def test_a_user_strategy_that_fails_at_once_fails_before_the_others_play():
    played = []
    strategies = [("bad", lambda c: _ActsWrongAtTick(c, bad=0))]
    entries = expand_methods(["ball_track"], strategies=strategies)
    assert [label for label, _, _ in entries] == ["ball_track", "bad"]
    with pytest.raises(ValueError, match="strategy bad, tick 0: invalid action"):
        compare_matches(entries, SMALL, 2, seed=3, progress=played.append)
    assert played == []  # ball_track did not play its matches first
    # one that fails later than the trial is still caught, at its tick, after the others
    strategies = [("late", lambda c: _ActsWrongAtTick(c, bad=7))]
    entries = expand_methods(["ball_track"], strategies=strategies)
    with pytest.raises(ValueError, match="strategy late, tick 7: invalid action"):
        compare_matches(entries, SMALL, 2, seed=3, progress=played.append)
    assert [r.method for r in played] == ["ball_track"]


def test_table_cells_never_run_into_each_other():
    """A share difference of 22 characters ("-43.3% [-65.4%,-21.3%]") followed
    "+0.0% [-39.0%,39.0%]" with no space between: every cell is now apart from the last."""

    wide = dict.fromkeys(MATCH_METRICS, Interval(-0.433, -0.654, -0.213))
    wide["lost_share"] = Interval(0.0, -0.39, 0.39)
    line = format_difference("a", wide)
    assert "+0.0% [-39.0%,39.0%] -43.3% [-65.4%,-21.3%]" in line
    assert len(line.split()) == 1 + 2 * len(MATCH_METRICS)


def test_compare_matches_refuses_two_entries_of_one_label_before_playing():
    # entries built by hand (not by expand_methods) were both played under one name: the
    # paired table and the figures, keyed by it, kept one of them
    played = []
    entries = [("a", "ball_track", StrategyOptions()), ("a", "random", StrategyOptions())]
    with pytest.raises(ValueError, match="two strategies are named a: rename one"):
        compare_matches(entries, SMALL, 2, seed=3, progress=played.append)
    assert played == []


@pytest.mark.parametrize(
    ("arguments", "error", "match"),
    [
        ({"matches": 0}, ValueError, r"^matches: expects a positive integer, got 0$"),
        ({"matches": -2}, ValueError, r"^matches: expects a positive integer, got -2$"),
        ({"matches": 2.0}, ValueError, r"^matches: expects a positive integer, got 2\.0$"),
        ({"matches": True}, ValueError, r"^matches: expects a positive integer, got True$"),
        ({"matches": 10**12}, ValueError, r"^matches: expects a positive integer up to 65536"),
        ({"seed": -1}, ValueError, r"^seed: expects an integer >= 0, got -1$"),
        ({"seed": 1.5}, ValueError, r"^seed: expects an integer >= 0, got 1\.5$"),
        ({"config": {"ticks": 3}}, TypeError, r"^config: expects a MatchConfig, got dict$"),
    ],
)
def test_compare_matches_names_a_bad_count_before_playing(arguments, error, match):
    # matches=0 was refused as the env's "num_envs", a negative seed by gymnasium's
    # "Seed must be greater or equal to zero", once the user's strategies had played
    played = []
    entries = expand_methods(
        ["ball_track"], strategies=[("mine", lambda c: _ActsWrongAtTick(c, 99))]
    )
    given = {"config": SMALL, "matches": 2, "seed": 3, **arguments}
    with pytest.raises(error, match=match):
        compare_matches(entries, progress=played.append, **given)
    assert played == []


def test_play_matches_names_a_clip_match_past_the_matches():
    with pytest.raises(ValueError, match=r"^clip_match: expects a match's index, 0 to 1, got 2$"):
        play_matches("random", SMALL, 2, seed=3, clip_match=2)
    with pytest.raises(ValueError, match=r"^matches: expects a positive integer, got 0$"):
        play_matches("random", SMALL, 0, seed=3)


def test_two_strategy_files_of_one_name_are_two_modules(tmp_path, monkeypatch):
    """``a/mine.py`` and ``b/mine.py`` were both the module ``activevision_strategy_mine``:
    the second replaced the first in ``sys.modules``, where pickling and dataclasses look a
    class's module up, so the first's class was found as the second's."""
    import pickle
    import sys

    from activevision.experiments.match_methods import load_strategy

    monkeypatch.setattr(sys, "path", list(sys.path))
    for folder, pan in (("a", 0.1), ("b", 0.2)):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "mine.py").write_text(
            f"class Mine:\n    name = 'mine_{folder}'\n    pan = {pan}\n"
            "    def __init__(self, config=None):\n        pass\n"
        )
    first = load_strategy(f"{tmp_path / 'a' / 'mine.py'}:Mine")[1]
    second = load_strategy(f"{tmp_path / 'b' / 'mine.py'}:Mine")[1]
    assert first.__module__ != second.__module__
    assert sys.modules[first.__module__].Mine is first
    assert pickle.loads(pickle.dumps(first())).pan == 0.1
    assert pickle.loads(pickle.dumps(second())).pan == 0.2
    # the same file loaded again is the same module's name
    assert load_strategy(f"{tmp_path / 'a' / 'mine.py'}:Mine")[1].__module__ == first.__module__


def test_kidnap_events_follow_each_kidnap_to_the_next_or_the_end():
    """Hand-made ticks of two matches (errors, kidnaps, alarms), against what each kidnap
    should read: match 0 kidnapped in ticks 1 and 5 (the first back under 0.5 m 2 ticks
    later with an alarm; the second lost to the end), match 1 in tick 2 (carried 0.3 m: not
    lost, back at once, no alarm needed)."""
    from activevision.envs.match.scores import MatchScores
    from activevision.experiments.match import kidnap_summary

    errors = np.array(
        [
            [0.1, 0.1],
            [1.5, 0.1],  # tick 1: match 0 kidnapped
            [1.0, 0.3],  # tick 2: match 1 kidnapped (0.3 m)
            [0.4, 0.1],
            [0.3, 0.1],
            [2.0, 0.1],  # tick 5: match 0 again
            [1.9, 0.1],
            [1.8, 0.1],
        ]
    )
    kidnapped = np.zeros_like(errors, dtype=bool)
    kidnapped[[1, 5], 0] = kidnapped[2, 1] = True
    alarm = np.zeros_like(kidnapped)
    alarm[2, 0] = alarm[4, 1] = True
    scores = MatchScores(8, 2, 0.32)
    for t in range(8):
        info = {
            "position_error": errors[t],
            "heading_error": np.zeros(2),
            "ball_in_view": np.zeros(2, bool),
            "entropy": np.zeros(2),
            "head_move": np.zeros((2, 2)),
            "kidnapped": kidnapped[t],
            "lost_alarm": alarm[t],
        }
        scores.add(info, np.zeros(2))
    events = scores.kidnaps()
    assert events.match.tolist() == [0, 0, 1] and events.tick.tolist() == [1, 5, 2]
    assert events.lost.tolist() == [True, True, False]
    assert events.detected.tolist() == [True, False, True]
    assert events.recovery_ticks.tolist() == [2, -1, 0]
    summary = kidnap_summary(events, 0.32)
    # over the 2 kidnaps that left it lost: 1 detected, 1 back, after 2 ticks of 0.32 s
    assert summary["kidnap_detected"] == wilson_interval(1, 2)
    assert summary["kidnap_recovered"] == wilson_interval(1, 2)
    assert summary["recovery_s"].mean == pytest.approx(0.64)
    # a match without kidnapping has no events, not an empty list of them
    plain = MatchScores(8, 2, 0.32)
    plain.add({k: v for k, v in info.items() if k not in ("kidnapped", "lost_alarm")}, np.zeros(2))
    assert plain.kidnaps() is None
