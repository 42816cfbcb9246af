import math

import numpy as np
import pytest

from activevision.envs import ActiveVisionEnv
from activevision.envs.actions import action_table
from activevision.experiments.compare import compare
from activevision.experiments.evaluate import (
    Interval,
    episode_seed,
    evaluate_policy,
    mean_interval,
    run_episode,
    wilson_interval,
)
from activevision.experiments.policies import (
    EntropyPolicy,
    HeadPolicy,
    OraclePolicy,
    RandomPolicy,
    ScanPolicy,
    greedy_action,
)
from activevision.figures.compare import plot_compare


class Recorder:
    """Stays put and remembers the start it saw."""

    name = "recorder"

    def __init__(self):
        self.starts = []

    def reset(self, info, rng):
        self.starts.append((info["pose"].copy(), info["ball"].copy(), info["head"].copy()))

    def act(self, obs, info):
        return 0


def test_every_method_sees_identical_start_states():
    env = ActiveVisionEnv()
    a, b = Recorder(), Recorder()
    for policy in (a, RandomPolicy(), b, OraclePolicy()):
        for i in range(5):
            run_episode(env, policy, episode_seed(3, i))
    for (pa, ba, ha), (pb, bb, hb) in zip(a.starts, b.starts, strict=True):
        np.testing.assert_array_equal(pa, pb)
        np.testing.assert_array_equal(ba, bb)
        np.testing.assert_array_equal(ha, hb)
    assert isinstance(OraclePolicy(), HeadPolicy)


@pytest.mark.parametrize("goal_deg", [(10.0, 0.0), (0.0, -14.0), (9.0, 9.0), (-15.0, 15.0)])
def test_oracle_takes_the_minimum_number_of_steps_on_hand_made_cases(goal_deg):
    # No sequence of 3 degree moves can get within 3 degrees of a goal D degrees away in
    # fewer than ceil((D - 3) / 3) steps; the oracle's greedy moves need exactly that many.
    table = action_table(3.0)
    head, goal = np.zeros(2), np.radians(goal_deg)
    steps = 0
    while np.degrees(np.hypot(*(goal - head))) > 3.0:
        head = head + table[greedy_action(head, goal, table)]
        steps += 1
    assert steps == math.ceil((np.hypot(*goal_deg) - 3.0) / 3.0)


def test_oracle_is_near_perfect_and_random_far_below():
    _, oracle, _ = evaluate_policy(OraclePolicy(), episodes=30, seed=1)
    _, rand, _ = evaluate_policy(RandomPolicy(), episodes=30, seed=1)
    assert oracle["success"].mean >= 0.8
    assert rand["success"].mean < oracle["success"].mean - 0.4


def test_entropy_method_with_zero_error_targets_the_true_goal():
    env = ActiveVisionEnv()
    for i in range(5):
        _, info = env.reset(seed=i)
        policy = EntropyPolicy(0.0, jump=True)
        policy.reset(info, np.random.default_rng(i))
        np.testing.assert_allclose(policy.target, info["goal_viewpoint"])


def test_large_localisation_error_hurts_the_entropy_method():
    _, exact, _ = evaluate_policy(EntropyPolicy(0.0), episodes=40, seed=2)
    _, wrong, _ = evaluate_policy(EntropyPolicy(2.0), episodes=40, seed=2)
    assert exact["success"].mean > 0.9
    assert wrong["success"].high < exact["success"].low


def test_scan_policy_keeps_the_ball_mostly():
    _, scan, _ = evaluate_policy(ScanPolicy(), episodes=20, seed=4)
    _, rand, _ = evaluate_policy(RandomPolicy(), episodes=20, seed=4)
    assert scan["ball_loss_duration"].mean > rand["ball_loss_duration"].mean


def test_wilson_interval_on_known_data():
    # Wilson 95% interval for 8/10, computed by hand: centre 0.7167, half-width 0.2266.
    iv = wilson_interval(8, 10)
    assert iv.mean == 0.8
    assert iv.low == pytest.approx(0.4902, abs=1e-4)
    assert iv.high == pytest.approx(0.9433, abs=1e-4)
    assert wilson_interval(0, 10).low == 0.0


@pytest.mark.parametrize("n", [3, 6, 7, 10, 12, 13, 200, 1000])
def test_wilson_interval_holds_the_proportion_at_none_and_all(n):
    # Rounding put 0/3's low at 5.6e-17 and 10/10's high at 1 - 1.1e-16: the robustness
    # figure's whiskers (mean - low, high - mean) came out negative and matplotlib refused
    # them, after the CSV was written. Every n: each end on the right side of the proportion.
    for successes in range(n + 1):
        iv = wilson_interval(successes, n)
        assert 0.0 <= iv.low <= iv.mean <= iv.high <= 1.0
    assert wilson_interval(0, n).low == 0.0 and wilson_interval(n, n).high == 1.0


def test_mean_interval_on_known_data():
    iv = mean_interval([1.0, 2.0, 3.0, 4.0])
    half = 1.959963984540054 * math.sqrt(5 / 3) / 2
    assert iv.mean == 2.5
    assert iv.low == pytest.approx(2.5 - half) and iv.high == pytest.approx(2.5 + half)


def test_a_share_keeps_its_interval_within_0_and_1_and_one_value_has_none():
    # the paper's success rate of two episodes, 1.0 and 0.2: mean 0.6, +-0.784 unbounded
    iv = mean_interval([1.0, 0.2], bounds=(0.0, 1.0))
    assert iv.mean == pytest.approx(0.6) and (iv.low, iv.high) == (0.0, 1.0)
    assert summarise_success_rates([1.0, 0.2]) == (iv.low, iv.high)
    one = mean_interval([0.7])
    assert one.mean == 0.7 and math.isnan(one.low) and math.isnan(one.high)


@pytest.mark.parametrize("bounds", [(0.0, 1.0), (-2.0, 3.0)])
def test_values_all_equal_within_bounds_get_what_n_values_vouch_for_not_zero_width(bounds):
    # 200 episodes all at success rate 1 gave 100% [100, 100]: a certainty no sample gives.
    # Wilson of 200/200 by hand: low = 1 / (1 + z^2/200) = 0.98115, high 1.
    lo, hi = bounds
    top = mean_interval([hi] * 200, bounds=bounds)
    assert top.mean == hi and top.high == hi
    assert top.low == pytest.approx(lo + (hi - lo) / (1 + 1.959963984540054**2 / 200))
    bottom = mean_interval([lo] * 200, bounds=bounds)
    assert bottom.mean == lo and bottom.low == lo
    assert bottom.high == pytest.approx(lo + (hi - lo) * (1 - 1 / (1 + 1.959963984540054**2 / 200)))
    assert summarise_success_rates([1.0] * 200)[0] == pytest.approx(0.98115, abs=1e-5)
    # values all equal inside the bounds: none of 10 differs, so at most w = Wilson's upper
    # end of 0/10 (z^2 / (10 + z^2) = 0.27753) of them do, by at most the distance to a bound
    w = 1.959963984540054**2 / (10 + 1.959963984540054**2)
    inside = mean_interval([0.5] * 10, bounds=(-1.0, 1.0))
    assert inside.mean == 0.5
    assert (inside.low, inside.high) == pytest.approx((0.5 - 1.5 * w, 0.5 + 0.5 * w))
    # without bounds nothing limits the spread: the value itself
    assert mean_interval([1.0] * 10) == Interval(1.0, 1.0, 1.0)


def summarise_success_rates(rates):
    from activevision.experiments.evaluate import METRICS, summarise

    episodes = [dict.fromkeys(METRICS, 0.0) | {"success_rate": r} for r in rates]
    iv = summarise(episodes)["success_rate"]
    return iv.low, iv.high


def test_compare_draws_its_bar_on_a_terminal_only(tmp_path, capsys, monkeypatch):
    """As a training run's: off a terminal (make run's log, a pipe) the bar wrote every
    redraw into the log, 60 of them for quickstart's 5 levels."""
    import sys

    methods = {"oracle": lambda e: OraclePolicy()}
    compare(tmp_path / "pipe", methods, errors=[0.0, 1.0], episodes=2)  # stderr: no terminal
    assert "method/s" not in capsys.readouterr().err
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    compare(tmp_path / "tty", methods, errors=[0.0, 1.0], episodes=2)
    assert "2/2" in capsys.readouterr().err


def test_compare_is_incremental(tmp_path):
    methods = {"oracle": lambda e: OraclePolicy(), "entropy_jump": lambda e: EntropyPolicy(e)}
    rows = compare(tmp_path, methods, errors=[0.0, 1.0], episodes=5, progress=False)
    assert len(rows) == 4
    csv_text = (tmp_path / "compare.csv").read_text()
    # A second call finds every level done and runs nothing new.
    rows2 = compare(tmp_path, methods, errors=[0.0, 1.0], episodes=5, progress=False)
    assert len(rows2) == 4 and (tmp_path / "compare.csv").read_text() == csv_text
    plot_compare(tmp_path / "compare.csv", tmp_path / "compare.png")
    assert (tmp_path / "compare.png").stat().st_size > 10_000
    # more levels after those, in their places: only the new one is played, on its own seed
    rows3 = compare(tmp_path, methods, errors=[0.0, 1.0, 2.0], episodes=5, progress=False)
    assert [str(r["level_seed"]) for r in rows3] == ["0", "0", "1", "1", "2", "2"]
    # a level put before them would leave 1.0 on the episodes of 0.5's place: refused
    with pytest.raises(ValueError, match="error 1 played on the episodes of seed 1; in"):
        compare(tmp_path, methods, errors=[0.0, 0.5, 1.0], episodes=5, progress=False)


def test_paired_steps_compare_only_episodes_every_method_solves():
    from activevision.experiments.evaluate import paired_steps

    episodes = [
        {"method": "a", "seed": 1, "success": True, "success_duration": 4, "head_travel": 9.0},
        {"method": "b", "seed": 1, "success": True, "success_duration": 8},
        {"method": "a", "seed": 2, "success": True, "success_duration": 2},
        {"method": "b", "seed": 2, "success": False, "success_duration": 20},
        {"method": "a", "seed": 3, "success": True, "success_duration": 6, "head_travel": 3.0},
        {"method": "b", "seed": 3, "success": True, "success_duration": 6},
    ]
    out = paired_steps(episodes, ["a", "b"])
    assert out["episodes"] == 2  # seed 2: b did not solve it
    assert out["a"] == {"median": 5.0, "mean": 5.0, "head_travel": 6.0}
    assert out["b"]["median"] == 7.0 and out["b"]["mean"] == 7.0
    assert paired_steps(episodes, ["a"])["a"]["median"] == 4.0  # seeds 1-3: 4, 2, 6


def test_the_table_stays_aligned_with_long_method_names():
    from activevision.experiments.evaluate import METRICS, Interval, format_table

    summary = {m: Interval(0.5, 0.25, 0.75) for m in METRICS}
    lines = format_table({"oracle": summary, "onnx_policy[a_long_run_name]": summary}).splitlines()
    starts = {line.index("0.500") for line in lines[2:]}
    assert len(starts) == 1 and lines[0].index("method") == 0  # every row's cells line up


def test_evaluation_needs_a_time_limit() -> None:
    with pytest.raises(ValueError, match="time limit, got max_episode_steps=-1"):
        evaluate_policy(RandomPolicy(), episodes=1, env=ActiveVisionEnv(max_episode_steps=-1))


def test_the_table_prints_no_minus_zero():
    # entropy_jump's regret, 0 up to float noise (-1e-17), printed "0.000 [-0.000, 0.000]"
    from activevision.experiments.evaluate import METRICS, Interval, format_table

    summary = {m: Interval(-1e-17, -2e-17, 0.0) for m in METRICS}
    row = format_table({"entropy_jump": summary}).splitlines()[2]
    assert "-0.000" not in row and row.count("0.000 [ 0.000, 0.000]") == len(METRICS)
    negative = format_table({"a": {m: Interval(-0.5, -0.75, -0.25) for m in METRICS}})
    assert "-0.500 [-0.750,-0.250]" in negative


def test_durations_and_head_travel_stay_within_what_they_can_be():
    # episodes of 20 steps: the ball lost at step 15 in one of four, never in the rest, read
    # 18.75 [15.8, 21.7] (past the time limit); head travel of 0, 0, 0, 40 degrees read a
    # negative low end
    from activevision.experiments.evaluate import METRICS, summarise

    episodes = [dict.fromkeys(METRICS, 0.0) for _ in range(4)]
    for e, lost, travel in zip(episodes, (15, 20, 20, 20), (0.0, 0.0, 0.0, 40.0), strict=True):
        e |= {"ball_loss_duration": lost, "success_duration": 20, "head_travel": travel}
    summary = summarise(episodes, time_limit=20)
    lost = summary["ball_loss_duration"]
    assert (
        lost.mean == 18.75
        and lost.high == 20.0
        and lost.low == pytest.approx(18.75 - 1.959963984540054 * 2.5 / 2)
    )
    assert summary["head_travel"].low == 0.0 and summary["head_travel"].high > 10.0
    # never a success: 20 in every episode, the time limit, is a bound (Wilson of 4/4)
    never = summary["success_duration"]
    w = 1.959963984540054**2 / (4 + 1.959963984540054**2)
    assert (never.low, never.high) == pytest.approx((20 - 20 * w, 20.0))
    # without the time limit durations are only at least 0: a value all equal stays itself
    assert summarise(episodes)["success_duration"] == Interval(20.0, 20.0, 20.0)


def test_intervals_refuse_counts_and_values_they_cannot_hold():
    # 7 of 5 was a "math domain error", 1 of -1 a proportion of -1, a NaN count [0, 1]
    for successes, n in ((7, 5), (-1, 3), (1, -1), (math.nan, 3)):
        with pytest.raises(ValueError, match=r"wilson_interval: (successes|n) expects"):
            wilson_interval(successes, n)
    # values of 2 within (0, 1) read 2.0 [0.88, 1.44]: an interval without its mean
    with pytest.raises(ValueError, match=r"outside the bounds \(0, 1\): 2.0"):
        mean_interval([2.0, 2.0, 2.0], bounds=(0, 1))
    with pytest.raises(ValueError, match="low <= high"):
        mean_interval([0.2, 0.5], bounds=(1.0, 0.0))
    # a table was one sample of its 6 cells with n its 3 rows
    with pytest.raises(ValueError, match=r"a 1-D sequence, got shape \(3, 2\)"):
        mean_interval([[1, 2], [3, 4], [5, 6]])
    # NaN is no value, not one outside: it still makes a NaN interval
    assert math.isnan(mean_interval([0.2, math.nan], bounds=(0, 1)).mean)


def test_summarise_names_the_metric_of_an_episode_value_it_cannot_count():
    from activevision.experiments.evaluate import METRICS, summarise

    episodes = [dict.fromkeys(METRICS, 0.0) for _ in range(3)]
    # a NaN success was "cannot convert float NaN to integer"; 2 counted two successes
    for odd in (math.nan, 2, "True"):
        with pytest.raises(ValueError, match="success: expects True or False per episode"):
            summarise([*episodes, {**episodes[0], "success": odd}])
    with pytest.raises(ValueError, match=r"success_duration: .*outside the bounds \(0.0, 20.0\)"):
        summarise([*episodes, {**episodes[0], "success_duration": 25}], time_limit=20)


def test_plot_compare_fits_the_legend_of_long_names_in_the_figure(tmp_path, monkeypatch):
    from activevision.io import write_csv

    def rows(methods):
        cells = {
            m + end: 0.5
            for m in ("success_rate", "success", "regret_within")
            for end in ("", "_low", "_high")
        }
        return [{"method": m, "error": e, **cells} for m in methods for e in (0.0, 1.0)]

    drawn = []
    monkeypatch.setattr(
        "activevision.figures.compare.save_figure", lambda fig, path, dpi: drawn.append(fig)
    )
    # eight 40-character names in one row ran past both edges; one of 150 characters past
    # a single panel's
    write_csv(
        tmp_path / "many.csv",
        rows([f"strategy_with_a_forty_character_name_{i:03d}" for i in range(8)]),
    )
    plot_compare(tmp_path / "many.csv", "x")
    write_csv(tmp_path / "one.csv", rows(["scan", "a_strategy_" * 14]))
    plot_compare(tmp_path / "one.csv", "x", metrics="success")
    for fig in drawn:
        fig.draw_without_rendering()
        legend, box = fig.legends[0].get_window_extent(), fig.bbox
        assert box.x0 <= legend.x0 and legend.x1 <= box.x1 and box.y0 <= legend.y0


def test_plot_compare_draws_the_interval_of_a_single_error_level(tmp_path, monkeypatch):
    # --errors 0.3: the band over one error level had no width, and no interval was drawn
    from matplotlib.collections import LineCollection
    from matplotlib.colors import to_rgba

    from activevision.io import write_csv

    drawn = []
    monkeypatch.setattr(
        "activevision.figures.compare.save_figure", lambda fig, path, dpi: drawn.append(fig)
    )
    cells = {"success": 0.5, "success_low": 0.2, "success_high": 0.9}
    write_csv(tmp_path / "one.csv", [{"method": "scan", "error": 0.3, **cells}])
    plot_compare(tmp_path / "one.csv", "x", metrics="success")
    (ax,) = drawn[0].axes
    (whisker,) = [c for c in ax.collections if isinstance(c, LineCollection)]
    np.testing.assert_allclose(whisker.get_segments()[0], [[0.3, 0.2], [0.3, 0.9]])
    assert whisker.get_color()[0].tolist() == list(to_rgba(ax.lines[0].get_color()))


@pytest.mark.parametrize(
    ("values", "error", "match"),
    [
        (
            (v for v in [0.1, 0.2]),
            TypeError,
            r"^mean_interval: values .* of numbers, got generator$",
        ),
        (iter([0.1, 0.2]), TypeError, r"^mean_interval: values .* got list_iterator$"),
        ({0.1, 0.2}, TypeError, r"^mean_interval: values .* got set$"),
        ({"a": 0.1}, TypeError, r"^mean_interval: values .* got dict$"),
        ("12", TypeError, r"^mean_interval: values .* got str$"),
        (0.5, TypeError, r"^mean_interval: values .* got float$"),
        ([0.1, "a"], ValueError, r"^mean_interval: values expects numbers: could not convert"),
    ],
)
def test_mean_interval_names_values_of_a_type_it_cannot_take(values, error, match):
    # a generator was "float() argument must be a string or a real number, not 'generator'"
    with pytest.raises(error, match=match):
        mean_interval(values)


def test_summarise_names_episodes_of_a_type_it_cannot_take():
    from activevision.experiments.evaluate import METRICS, summarise

    episode = dict.fromkeys(METRICS, 0.0)
    # a dict was "string indices must be integers, not 'str'"; a generator was read by the
    # first metric alone, the others summarising no episodes
    for episodes, kind in (
        (episode, "dict"),
        ((e for e in [episode]), "generator"),
        ("abc", "str"),
    ):
        with pytest.raises(TypeError, match=rf"^summarise: episodes expects .*, got {kind}$"):
            summarise(episodes)
    with pytest.raises(TypeError, match=r"^summarise: episodes\[1\] expects a dict .*, got int$"):
        summarise([episode, 3])
    with pytest.raises(ValueError, match=r"^summarise: episodes\[1\] has no head_travel$"):
        summarise([episode, {k: v for k, v in episode.items() if k != "head_travel"}])
    assert summarise((episode, episode))["reward"] == summarise([episode, episode])["reward"]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"episodes": -3}, "episodes: expects a positive integer, got -3"),
        ({"episodes": 0}, "episodes: expects a positive integer, got 0"),
        ({"episodes": 2.0}, "episodes: expects a positive integer, got 2.0"),
        ({"episodes": 10**12}, "episodes: expects a positive integer up to 1000003, got 10"),
        ({"episodes": 1, "seed": -1}, "seed: expects an integer >= 0, got -1"),
        ({"episodes": 1, "seed": 1.5}, "seed: expects an integer >= 0, got 1.5"),
    ],
)
def test_evaluate_policy_refuses_a_count_or_seed_it_cannot_play(kwargs, message):
    # -3 episodes played none and returned NaN intervals; seed -1 was Gymnasium's refusal
    # of seed -1000003
    with pytest.raises(ValueError, match=message):
        evaluate_policy(RandomPolicy(), **kwargs)


def test_evaluate_policy_takes_a_numpy_seed_as_its_int():
    records, _, _ = evaluate_policy(Recorder(), episodes=2, seed=np.int64(3))
    assert [r["seed"] for r in records] == [episode_seed(3, 0), episode_seed(3, 1)]
    assert all(type(r["seed"]) is int for r in records)


def test_compare_refuses_to_resume_from_a_row_cut_short(tmp_path):
    # the cut row's method was taken as played and written back with its numbers empty,
    # which plot_compare then failed on ("float() argument must be ... not 'NoneType'")
    methods = {"oracle": lambda e: OraclePolicy(), "random": lambda e: RandomPolicy()}
    compare(tmp_path, methods, errors=[0.0], episodes=3, progress=False)
    path = tmp_path / "compare.csv"
    lines = path.read_text().splitlines()
    cut = lines[2][: lines[2].index(",random,") + len(",random,") + 3]
    path.write_text("\n".join([*lines[:2], cut]) + "\n")
    with pytest.raises(ValueError, match=r"compare\.csv line 3 has fewer cells than its header"):
        compare(tmp_path, methods, errors=[0.0], episodes=3, progress=False)
    assert path.read_text().splitlines()[2] == cut  # left as it was


def test_plot_compare_names_a_csv_it_cannot_draw(tmp_path):
    from activevision.io import write_csv

    def row(method, error, value):
        cells = {"method": method, "error": error}
        for m in ("success_rate", "success", "regret_within"):
            cells |= {m: value, f"{m}_low": value, f"{m}_high": value}
        return cells

    path, png = tmp_path / "compare.csv", tmp_path / "compare.png"
    write_csv(path, [row("a", 0.0, 0.5), row("a", 1.0, 0.4)])
    # a header alone drew three blank panels
    path.write_text(path.read_text().splitlines()[0] + "\n")
    with pytest.raises(ValueError, match=r"compare\.csv holds no levels to draw"):
        plot_compare(path, png)
    # none of the metrics asked: matplotlib's "Number of columns must be a positive integer"
    write_csv(path, [row("a", 0.0, 0.5), row("a", 1.0, 0.4)])
    with pytest.raises(ValueError, match="has none of the columns nope, other"):
        plot_compare(path, png, metrics=["nope", "other"])
    # one name is one panel, not a search for the columns of its letters
    plot_compare(path, png, metrics="success")
    assert png.exists()
    # an empty cell was "could not convert string to float: ''", naming no file
    write_csv(path, [row("a", 0.0, 0.5), row("a", 1.0, "")])
    with pytest.raises(ValueError, match=r"compare\.csv line 3: success_rate is not a number: ''"):
        plot_compare(path, png)
    assert not list(tmp_path.glob(".*.tmp"))


def test_evaluate_policy_names_an_env_gymnasium_wrapped():
    # gymnasium.make's env failed on its first episode with "'TimeLimit' object has no
    # attribute 'max_episode_steps'"; its .unwrapped env plays the same episodes
    import gymnasium as gym

    env = gym.make("ActiveVision-v0")
    with pytest.raises(
        TypeError, match=r"^evaluate_policy: env expects an ActiveVisionEnv.*Limit$"
    ):
        evaluate_policy(Recorder(), episodes=2, env=env)
    records, _, _ = evaluate_policy(Recorder(), episodes=2, env=env.unwrapped)
    assert records == evaluate_policy(Recorder(), episodes=2)[0]


def test_a_learned_policy_names_an_observation_its_network_does_not_take():
    # a student of image + head angles played in the paper's image-only env failed inside
    # torch ("mat1 and mat2 shapes cannot be multiplied"), a Q-network of 4 stacked frames
    # in an env of 1 with torch's "expected input[1, 1, 120, 160] to have 4 channels"
    import torch

    from activevision.agents.q_network import QNetwork
    from activevision.agents.student import StudentNetwork
    from activevision.envs import EnvConfig
    from activevision.experiments.policies import LearnedPolicy

    torch.manual_seed(0)
    student = LearnedPolicy(StudentNetwork(9, vector_size=2), vector_keys=("head",))
    stacked = LearnedPolicy(QNetwork(9, stack=4))
    cases = [
        (student, EnvConfig(), r"takes a Dict of an image \(1, 120, 160\) and \['head'\] \(2"),
        (stacked, EnvConfig(), r"takes an image \(4, 120, 160\), got an image \(1, 120, 160\);"),
        (LearnedPolicy(QNetwork(9)), EnvConfig(observation="image+head"), r"got a Dict of an"),
    ]
    for policy, config, message in cases:
        with pytest.raises(
            ValueError, match=rf"^method learned: the observation does not fit.*{message}"
        ):
            evaluate_policy(policy, episodes=1, config=config)
    # in the envs they were made for (a Dict holding more keys too), they play; so does a
    # student of the image alone (an SB3 run's actor) in the paper's env
    for policy, config in [
        (student, EnvConfig(observation="image+head")),
        (student, EnvConfig(observation="image+head+pose")),
        (stacked, EnvConfig(frame_stack=4)),
        (LearnedPolicy(StudentNetwork(9)), EnvConfig()),
    ]:
        records, _, _ = evaluate_policy(policy, episodes=1, config=config)
        assert records[0]["steps"] >= 1
