"""report.md says what was run: the evaluation's localisation error, the last epoch's
columns as what they are, and what the match comparison's strategies are."""

import csv
import functools
import json

import pytest

from activevision.experiments.report import write_report

METRICS = {
    "epoch": 8,
    "step": 40331,
    "episodes": 448,
    "success_rate": 0.857,
    "success_duration": 12.4,
    "ball_loss_duration": 19.4,
    "episode_reward": 4.2,
    "loss": 1.6,
    "updates": 112,
    "epsilon": 0.25,
    "beta": 0.0,
    "steps_per_s": 402.1,
}


def write_rows(path, rows):
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def make_run(tmp_path, algo="dagger", env_id="ActiveVision-v0", metrics=None):
    run = tmp_path / "run"
    run.mkdir(parents=True)
    config = {"algo": algo, "env_id": env_id, "seed": 0, "run": {"total_timesteps": 40000}}
    (run / "config.json").write_text(json.dumps(config))
    write_rows(run / "metrics.csv", [metrics or METRICS])
    return run


def evaluation_row(method, error):
    row = {"episodes": 100, "seed": 0, "error": error, "method": method}
    for name in ("success", "success_rate", "success_duration", "ball_loss_duration") + (
        "entropy_regret",
        "regret_within",
        "oscillating",
        "reward",
        "score",
        "head_travel",
    ):
        row |= {name: 0.5, f"{name}_low": 0.4, f"{name}_high": 0.6}
    return row


def write_evaluation(run, error, **more):
    rows = [evaluation_row(m, error) for m in ("learned", "oracle")]
    path = run / "evaluation" / "evaluation.json"
    path.parent.mkdir()
    data = {"methods": rows, "episodes": 100, "seed": 0} | more
    path.write_text(json.dumps(data))


def match_row(method, ticks=True):
    row = {"method": method, "matches": 16, "seed": 0} | ({"ticks": 300} if ticks else {})
    for name in ("position_rmse", "heading_rmse", "lost_share", "ball_in_view", "entropy"):
        row |= {name: 0.5, f"{name}_low": 0.4, f"{name}_high": 0.6}
    return row | {"head_travel": 7.0, "head_travel_low": 6.0, "head_travel_high": 8.0}


@pytest.mark.parametrize(("error", "said"), [(0.0, "exact localisation"), (1.0, "error 1 m")])
def test_the_evaluation_names_its_localisation_error(tmp_path, error, said):
    """evaluate --error 1 used to be reported as plain 'identical starts for every method'."""
    run = make_run(tmp_path)
    write_evaluation(run, error)
    report = write_report(run).read_text()
    line = next(x for x in report.splitlines() if x.startswith("100 episodes"))
    assert said in line
    assert "degrees the head moved in the episode" in report  # head_travel's unit


@pytest.mark.parametrize(
    ("weights", "said"),
    [
        ({"weights": "best"}, "best validated weights"),
        ({"weights": "final"}, "final weights"),
        ({}, None),
    ],
    ids=["best", "final", "unrecorded"],
)
def test_the_evaluation_names_the_weights_learned_played(tmp_path, weights, said):
    """evaluate --weights best was reported like the final weights."""
    run = make_run(tmp_path)
    write_evaluation(run, 0.0, **weights)
    line = next(x for x in write_report(run).read_text().splitlines() if x.startswith("100 "))
    if said is None:  # an evaluation from before the record: nothing claimed
        assert "weights" not in line
    else:
        assert f"`learned` plays the run's {said}." in line


def test_the_last_epoch_shows_counts_whole_and_names_dagger_epsilon(tmp_path):
    last = write_report(make_run(tmp_path)).read_text().split("Last epoch: ")[1].splitlines()[0]
    assert "step 40331," in last and "episodes 448," in last  # not 4.033e+04
    assert "teacher's share 0.25" in last  # DAgger's epsilon is the teacher's share
    assert "epsilon" not in last and "beta" not in last  # no PER in DAgger


def test_the_last_epoch_leaves_out_what_a_learner_does_not_measure(tmp_path):
    ppo = write_report(make_run(tmp_path, algo="ppo")).read_text()
    assert "epsilon" not in ppo.split("## Configuration")[0]
    assert "beta" not in ppo.split("## Configuration")[0]
    match_metrics = METRICS | {"success_rate": "nan", "success_duration": "nan"}
    run = make_run(tmp_path / "m", env_id="ActiveVisionMatch-v0", metrics=match_metrics)
    report = write_report(run).read_text()
    assert "dagger on `ActiveVisionMatch-v0`, 40000 steps (match ticks)" in report
    last = report.split("Last epoch: ")[1].splitlines()[0]
    assert "nan" not in last and "success_rate" not in last and "loss 1.6" in last
    ddqn = write_report(make_run(tmp_path / "d", algo="ddqn")).read_text()
    assert "epsilon 0.25, beta 0" in ddqn


def test_the_match_section_says_how_long_and_whose_policies(tmp_path):
    """onnx_policy in the quickstart's match table is the package's shipped policy, not
    the run's; and the section gave neither the matches' length nor head_travel's unit
    (degrees per second there, per episode in the evaluation)."""
    run = make_run(tmp_path)
    write_rows(run / "match" / "match.csv", [match_row("ball_track"), match_row("onnx_policy")])
    report = write_report(run).read_text()
    assert "16 matches of 300 ticks from seed 0" in report
    assert "the package's shipped one unless `match --model` named another" in report
    assert "There is no `learned` row" in report and "degrees per second" in report
    write_rows(run / "match" / "match.csv", [match_row("learned", ticks=False)])
    report = write_report(run).read_text()
    assert "16 matches from seed 0" in report  # a match.csv written before the ticks column
    assert "learned: the training run `match --run` named" in report
    assert "There is no `learned` row" not in report and "onnx_policy:" not in report
    assert "detected with probability" not in report  # a match.csv without the world's columns


def test_the_match_section_names_the_model_each_onnx_policy_row_played(tmp_path):
    """``match --model`` rows record the model's file and SHA-256: the report said "the
    package's shipped one unless `match --model` named another" whichever played; it names
    the file, its digest, and whether it is this run's policy.onnx as it is now."""
    import hashlib

    run = make_run(tmp_path)
    (run / "policy.onnx").write_bytes(b"exported")
    digest = hashlib.sha256(b"exported").hexdigest()
    rows = [
        match_row("onnx_policy[run]") | {"model": "runs/x/policy.onnx", "model_sha256": digest},
        match_row("onnx_policy[b]") | {"model": "b.onnx", "model_sha256": "ab" * 32},
        match_row("ball_track") | {"model": "", "model_sha256": ""},
    ]
    write_rows(run / "match" / "match.csv", rows)
    report = write_report(run).read_text()
    assert (
        f"onnx_policy[run]: `runs/x/policy.onnx` (`match --model`, SHA-256 {digest[:12]}…,"
        " this run's policy.onnx)." in report
    )
    assert (
        "onnx_policy[b]: `b.onnx` (`match --model`, SHA-256 abababababab…, not this run's"
        " policy.onnx as it is now)." in report
    )
    assert "shipped one" not in report and "ball_track:" not in report
    (run / "policy.onnx").write_bytes(b"exported again")
    report = write_report(run).read_text()  # exported again since the matches
    assert report.count("not this run's policy.onnx as it is now") == 2


def test_the_match_section_names_the_world(tmp_path):
    """match --run on a student trained with a weaker detector plays that detector: the
    report said nothing of which detector, head or other robots the matches had."""
    run = make_run(tmp_path)
    world = {"action_type": "continuous", "step_deg": 3.0, "robots": "2"}
    world |= {"detect_near": 0.6, "detect_far": 0.15, "false_detections": 0.2}
    write_rows(run / "match" / "match.csv", [match_row("learned") | world])
    report = write_report(run).read_text()
    assert (
        "; continuous head moves of up to 3 degrees a tick, 2 other robots, a landmark in view"
        " detected with probability 0.6 next to the robot falling to 0.15 at its detection"
        " range, and 0.2 false detections per tick." in report
    )
    assert "unlike the default world" not in report  # written before the walk, the ball...


def test_the_match_section_names_the_walk_robots_speed_and_ball_unlike_the_default(tmp_path):
    """match.csv records how our robot walked, the other robots' speed and the ball; the
    report names the settings that are not the default world's, and no others."""
    run = make_run(tmp_path)
    world = {"action_type": "discrete", "step_deg": 3.0, "robots": "2"}
    world |= {"detect_near": 0.95, "detect_far": 0.5, "false_detections": 0.05}
    world |= {"walk": "ball", "walk_speed": 0.2, "turn_rate": 0.5, "robot_speed": 0.2}
    world |= {"ball_decel": 0.4, "kick_rate": 0.02, "kick_speed": "0.5-2.5"}
    world |= {"bounce_us": True, "restitution": 0.5, "tick_s": 0.32, "ball_noise": 0.05}
    write_rows(run / "match" / "match.csv", [match_row("learned") | world])
    report = write_report(run).read_text()
    assert (
        "0.05 false detections per tick; unlike the default world: our robot walking to the"
        " ball, the other robots walking at 0.2 m/s, the ball bouncing off our robot." in report
    )
    world |= {"walk": "waypoints", "robot_speed": 0.0, "bounce_us": False}
    write_rows(run / "match" / "match.csv", [match_row("learned") | world])
    report = write_report(run).read_text()
    assert "0.05 false detections per tick. Mean" in report


def test_the_latency_is_reported_from_its_own_file_or_an_older_evaluation(tmp_path):
    """latency.json beside evaluation.json (which is seed-exact without it); an evaluation
    written before that kept it inside."""
    run = make_run(tmp_path / "new")
    write_evaluation(run, 0.0)
    (run / "evaluation" / "latency.json").write_text(json.dumps({"p50_ms": 1.5, "p99_ms": 2.25}))
    assert "p50 1.50 ms, p99 2.25 ms" in write_report(run).read_text()
    old = make_run(tmp_path / "old")
    write_evaluation(old, 0.0, latency={"p50_ms": 0.5, "p99_ms": 0.75})
    assert "p50 0.50 ms, p99 0.75 ms" in write_report(old).read_text()
    plain = make_run(tmp_path / "plain")
    write_evaluation(plain, 0.0)
    assert "p50" not in write_report(plain).read_text()
    (plain / "evaluation" / "latency.json").write_text("[]")
    with pytest.raises(ValueError, match=r"latency\.json is damaged"):
        write_report(plain)


def test_the_header_says_the_steps_played_where_they_differ_from_those_asked(tmp_path):
    """A learner plays whole rounds of its vector env: a DAgger run asked for 600 steps
    played 1,161, and the report said "600 steps"."""
    run = make_run(tmp_path)
    text = write_report(run).read_text()
    assert "on `ActiveVision-v0`, 40000 steps." in text  # no checkpoint: what was asked
    (run / "checkpoints" / "step_000040000").mkdir(parents=True)
    assert "on `ActiveVision-v0`, 40000 steps." in write_report(run).read_text()
    (run / "checkpoints" / "step_000040331").mkdir()
    assert "40000 steps asked, 40331 played." in write_report(run).read_text()


def test_the_evaluation_table_has_no_negative_zero_as_evaluate_prints_none(tmp_path):
    """An oracle's entropy regret of float noise (mean 2.7e-16 [-7.3e-16, 1.3e-15]) read
    "0.000 [-0.000, 0.000]" in report.md where evaluate's table prints "0.000 [ 0.000, 0.000]"."""
    from activevision.experiments.evaluate import METRICS as EVALUATED
    from activevision.experiments.evaluate import Interval, format_table

    run = make_run(tmp_path)
    write_evaluation(run, 0.0)
    path = run / "evaluation" / "evaluation.json"
    data = json.loads(path.read_text())
    noise = Interval(2.7e-16, -7.3e-16, 1.3e-15)
    for row in data["methods"]:
        row |= {"entropy_regret": noise.mean, "entropy_regret_low": noise.low}
        row |= {"entropy_regret_high": noise.high}
    path.write_text(json.dumps(data))
    report = write_report(run).read_text()
    line = next(x for x in report.splitlines() if x.startswith("| oracle | 0.000 [0.000, 0.000]"))
    assert "-0.000" not in report
    assert line.startswith("| oracle | 0.000 [0.000, 0.000] | 0.500 [0.400, 0.600]")
    printed = format_table({"oracle": dict.fromkeys(EVALUATED, noise)})
    assert "-0.000" not in printed  # the same value as evaluate's table shows it


def test_a_metrics_log_cut_mid_row_is_refused_naming_it(tmp_path):
    """A metrics.csv cut in its last row (a disk that filled up, a copy stopped) was reported
    with that row's last cell cut and the columns after it left out."""
    run = make_run(tmp_path)
    text = (run / "metrics.csv").read_text()
    (run / "metrics.csv").write_text(text[: text.index(",0.25,") + 3])  # epsilon "0."
    # all its cells are there up to the cut one: what tells the cut is its missing end of line
    with pytest.raises(ValueError, match=r"metrics\.csv line 2 has no end of line"):
        write_report(run)
    (run / "metrics.csv").write_text(text[: text.index(",0.25,") + 3] + "\n")
    with pytest.raises(ValueError, match=r"metrics\.csv line 2 has fewer cells than its header"):
        write_report(run)


def test_a_config_edited_after_the_checkpoint_is_refused(tmp_path):
    """The report shows config.json as the run's configuration: an edited one (a config.json
    of {} was reported as "training seed None") is refused, as export and evaluate do."""
    from activevision.training.state import config_digest

    run = make_run(tmp_path)
    checkpoint = run / "checkpoints" / "step_000040000"
    checkpoint.mkdir(parents=True)
    (checkpoint / "state.json").write_text(json.dumps({"config_sha256": config_digest(run)}))
    write_report(run)  # the file the checkpoint was taken under
    (run / "config.json").write_text("{}")
    with pytest.raises(RuntimeError, match=r"config\.json was changed after checkpoint"):
        write_report(run)


def test_plot_refuses_a_config_edited_after_the_checkpoint(tmp_path):
    """The config picks the figures' curves: a match run whose config.json became {} was
    drawn as an episodic run, refused as "evaluations.csv has no 'success_rate' column"."""
    from activevision.training.plots import plot_run
    from activevision.training.state import config_digest

    run = make_run(tmp_path)
    episode = {"episode": 1, "step": 20, "reward": 1.0, "length": 20, "success": 1.0}
    write_rows(run / "episodes.csv", [episode])
    checkpoint = run / "checkpoints" / "step_000040000"
    checkpoint.mkdir(parents=True)
    (checkpoint / "state.json").write_text(json.dumps({"config_sha256": config_digest(run)}))
    (run / "config.json").write_text("{}")
    with pytest.raises(RuntimeError, match=r"config\.json was changed after checkpoint"):
        plot_run(run, tmp_path / "plots")


def test_the_match_section_counts_one_match_in_the_singular(tmp_path):
    # match --matches 1 was reported as "1 matches of 300 ticks"
    run = make_run(tmp_path)
    write_rows(run / "match" / "match.csv", [match_row("ball_track") | {"matches": 1}])
    assert "`ActiveVisionMatch-v0`: 1 match of 300 ticks" in write_report(run).read_text()
    write_rows(run / "match" / "match.csv", [match_row("ball_track") | {"ticks": 1}])
    assert "16 matches of 1 tick from seed 0" in write_report(run).read_text()  # "1 ticks"


def robustness_row(name, setting, trained, success, goal, drops):
    """A robustness.csv row (``activevision robustness --run``'s columns)."""
    row = {
        "method": "learned",
        "error": 1.0,
        "name": name,
        "factor": name.split("-")[0],
        "level": "mild",
        "setting": setting,
        "in_training_range": trained,
        "in_robust_range": True,
        "n": 200,
        "seed": 0,
    }
    for metric, (mean, low, high) in (("success_rate", success), ("goal_reached", goal)):
        row |= {metric: mean, f"{metric}_low": low, f"{metric}_high": high}
    return row | {"success_rate_drop_pts": drops[0], "goal_reached_drop_pts": drops[1]}


def test_the_robustness_suite_of_the_run_is_reported(tmp_path):
    """``activevision robustness --run RUN`` writes RUN/robustness/: the report left it out."""
    run = make_run(tmp_path)
    rows = [
        robustness_row(
            "clean", "as trained", True, (0.865, 0.84, 0.891), (0.52, 0.451, 0.588), (0, 0)
        ),
        robustness_row(
            "gain-dark-mild",
            "gain=0.75",
            False,
            (0.759, 0.724, 0.793),
            (0.265, 0.209, 0.33),
            (10.64, 25.5),
        ),
    ]
    write_rows(run / "robustness" / "robustness.csv", rows)
    report = write_report(run).read_text()
    assert "## Robustness" in report
    assert "`learned` on 200 fixed-seed episodes a row from seed 0, localisation error 1" in report
    assert (
        "| clean | as trained | yes | 86.5 [84.0, 89.1] | +0.0 | 52.0 [45.1, 58.8] | +0.0 |"
        in report
    )
    assert (
        "| gain-dark-mild | gain=0.75 | no | 75.9 [72.4, 79.3] | -10.6 | 26.5 [20.9, 33.0] |"
        " -25.5 |" in report
    )
    assert "robustness/robustness.png" not in report  # no figure: no link to none
    (run / "robustness" / "robustness.png").write_bytes(b"")
    assert "![robustness](robustness/robustness.png)" in write_report(run).read_text()
    # a robustness.csv of another layout is named, not a KeyError
    write_rows(run / "robustness" / "robustness.csv", [{"method": "learned", "n": 1}])
    with pytest.raises(ValueError, match=r"robustness.csv has no 'name' column: it is damaged"):
        write_report(run)


def test_results_recording_another_run_are_left_out_with_a_warning(tmp_path):
    """match.csv and robustness.csv rows that record (``--run``) the run they scored: this
    run's digests are reported; another's (or this run's replaced weights) left out with a
    warning naming the file, the page still written; rows recording two runs are damaged."""
    import hashlib

    run = make_run(tmp_path)
    (run / "policy.safetensors").write_bytes(b"weights")
    mine = {
        "run_config_sha256": hashlib.sha256((run / "config.json").read_bytes()).hexdigest(),
        "run_weights_sha256": hashlib.sha256(b"weights").hexdigest(),
        "run_weights": "final",
    }
    theirs = mine | {"run_weights_sha256": hashlib.sha256(b"other weights").hexdigest()}
    robustness = [
        robustness_row("clean", "as trained", True, (0.8, 0.7, 0.9), (0.5, 0.4, 0.6), (0, 0))
    ]
    for recorded, shown in ((mine, True), (theirs, False)):
        rows = [match_row(m) | recorded for m in ("ball_track", "learned")]
        write_rows(run / "match" / "match.csv", rows)
        write_rows(run / "robustness" / "robustness.csv", [r | recorded for r in robustness])
        if shown:
            report = write_report(run).read_text()
        else:
            with pytest.warns(UserWarning) as caught:
                report = write_report(run).read_text()
            said = [str(w.message) for w in caught]
            assert len(said) == 2
            assert said[0].startswith(f"left {run / 'match' / 'match.csv'} out of the report")
            assert said[1].startswith(f"left {run / 'robustness' / 'robustness.csv'} out")
            assert all("scored another run's weights, or this run's before" in s for s in said)
        assert ("## Head control through whole matches" in report) is shown
        assert ("learned: this run's final weights (`match --run`)." in report) is shown
        assert ("## Robustness" in report) is shown
        assert "## Configuration" in report
    # best weights: the digest of best_policy.safetensors, and "--weights best" to redo them
    (run / "robustness" / "robustness.csv").unlink()
    (run / "best_policy.safetensors").write_bytes(b"best")
    best = mine | {"run_weights_sha256": hashlib.sha256(b"best").hexdigest(), "run_weights": "best"}
    write_rows(run / "match" / "match.csv", [match_row("learned") | best])
    assert "learned: this run's best validated weights" in write_report(run).read_text()
    (run / "best_policy.safetensors").write_bytes(b"better")
    with pytest.warns(UserWarning, match=r"--out \S+match --weights best --overwrite"):
        assert "## Head control" not in write_report(run).read_text()
    write_rows(run / "match" / "match.csv", [match_row("a") | mine, match_row("b") | theirs])
    with pytest.raises(ValueError, match=r"match.csv is damaged .* not one run's"):
        write_report(run)


def _report_warnings(run):
    """report's page and the warnings it gave."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        page = write_report(run).read_text()
    return page, [str(w.message) for w in caught]


def test_a_comparison_is_reported_only_where_its_csv_records_this_runs_weights(tmp_path):
    """``report`` showed RUN/compare/compare.png whatever played it, though compare.csv
    records the digest of the weights its learned method played (``run_sha256``): another
    run's, this run's replaced ones, or none (a compare without --run) are left out with one
    warning; a CSV from before the column, or no CSV, is reported as before."""
    import hashlib

    run = make_run(tmp_path)
    (run / "policy.safetensors").write_bytes(b"final")
    (run / "best_policy.safetensors").write_bytes(b"best")
    figure = run / "compare" / "compare.png"
    figure.parent.mkdir()
    figure.write_bytes(b"png")
    heading = "## Success vs localisation error"
    row = {"method": "learned", "error": 0.0, "episodes": 2, "seed": 0, "level_seed": 0}

    page, warned = _report_warnings(run)  # no compare.csv: as before
    assert heading in page and warned == []
    write_rows(figure.with_name("compare.csv"), [row])  # from before the column
    page, warned = _report_warnings(run)
    assert heading in page and "`learned` plays" not in page and warned == []
    for weights, which in ((b"final", "final"), (b"best", "best validated")):
        digest = hashlib.sha256(weights).hexdigest()
        write_rows(figure.with_name("compare.csv"), [row | {"run_sha256": digest}] * 2)
        page, warned = _report_warnings(run)
        assert warned == []
        assert f"{heading}\n\n`learned` plays this run's {which} weights.\n\n![comparison]" in page
    again = f"write it again: activevision compare --run {run} --out {figure.parent} --overwrite"
    for digest, why in (
        (hashlib.sha256(b"other").hexdigest(), "it played another run's weights, or this run's"),
        ("", "it played no run (a compare without --run)"),
    ):
        write_rows(figure.with_name("compare.csv"), [row | {"run_sha256": digest}])
        page, warned = _report_warnings(run)
        assert heading not in page and "## Configuration" in page
        assert len(warned) == 1 and warned[0].startswith(f"left {figure} out of the report: ")
        assert why in warned[0] and warned[0].endswith(again)
    rows = [row | {"run_sha256": "a" * 64}, row | {"run_sha256": "b" * 64}]
    write_rows(figure.with_name("compare.csv"), rows)
    with pytest.raises(ValueError, match=r"compare.csv is damaged .* not one run's"):
        write_report(run)
    # which weights (run_weights): one kind, of a run
    for recorded in (
        [("a" * 64, "final"), ("a" * 64, "best")],
        [("a" * 64, "latest")],
        [("", "final")],  # no run's
    ):
        rows = [row | {"run_sha256": d, "run_weights": w} for d, w in recorded]
        write_rows(figure.with_name("compare.csv"), rows)
        with pytest.raises(ValueError, match=r"compare.csv is damaged .* not one run's"):
            write_report(run)
    # the final weights' digest recorded as the best's: not this run's best
    final = hashlib.sha256(b"final").hexdigest()
    best = row | {"run_sha256": final, "run_weights": "best"}
    write_rows(figure.with_name("compare.csv"), [best])
    page, warned = _report_warnings(run)
    assert heading not in page and warned[0].endswith(
        f"compare --run {run} --weights best --out {figure.parent} --overwrite"
    )


def test_an_episode_is_reported_only_where_its_record_says_this_run_played(tmp_path):
    """``report`` showed RUN/episode.png whatever drew it: ``demo`` (the shipped policy),
    an episode without --run, another run's. ``episode`` and ``demo`` now record what
    played beside the figure (episode.png.json); report leaves out one that played no policy of
    this run, another run's or this run's replaced weights, or a figure replaced since its
    record, with one warning each; a figure without a record is reported as before."""
    import hashlib

    from activevision.experiments.provenance import write_episode_record
    from activevision.training.policy_files import scored_run

    run = make_run(tmp_path)
    (run / "policy.safetensors").write_bytes(b"final")
    figure, gif = run / "episode.png", run / "episode.gif"
    figure.write_bytes(b"png")
    gif.write_bytes(b"gif")
    heading = "## One episode"
    page, warned = _report_warnings(run)
    assert heading in page and warned == []  # no record: as before
    write = functools.partial(write_episode_record, figure, gif, seed=3)
    write(command="episode", policies=["learned", "random"], run=scored_run(run), weights="final")
    page, warned = _report_warnings(run)
    assert warned == []
    assert (
        f"{heading}\n\n`learned` and `random` from the start of seed 3; `learned` plays this"
        " run's final weights.\n\n![episode](episode.png)" in page
    )
    again = f"; write it again: activevision episode --run {run} --out {figure} --overwrite"
    # this run's weights replaced since (trained on, retrained)
    (run / "policy.safetensors").write_bytes(b"retrained")
    page, warned = _report_warnings(run)
    assert heading not in page and "## Configuration" in page
    assert warned == [
        f"left {figure} out of the report: it played another run's weights, or this run's"
        f" before they were replaced (trained on or retrained){again}"
    ]
    # its best validated weights, replaced since: written again with --weights best
    (run / "best_policy.safetensors").write_bytes(b"best")
    write(command="episode", policies=["learned"], run=scored_run(run, "best"), weights="best")
    assert "`learned` plays this run's best validated weights." in _report_warnings(run)[0]
    (run / "best_policy.safetensors").write_bytes(b"better")
    assert _report_warnings(run)[1][0].endswith(
        f"activevision episode --run {run} --weights best --out {figure} --overwrite"
    )
    # demo: the shipped policy, another model, or this run's exported policy.onnx
    shipped = hashlib.sha256(b"shipped model").hexdigest()
    write(command="demo", policies=["shipped", "random"], model_sha256=shipped)
    page, warned = _report_warnings(run)
    assert heading not in page
    assert warned == [
        f"left {figure} out of the report: it played the shipped policy (demo), not this"
        f" run's policy{again}"
    ]
    (run / "policy.onnx").write_bytes(b"exported")
    exported = hashlib.sha256(b"exported").hexdigest()
    model = str(run / "policy.onnx")
    write(command="demo", policies=["run", "random"], model=model, model_sha256=exported)
    page, warned = _report_warnings(run)
    assert warned == [] and "`run` is this run's policy.onnx." in page
    (run / "policy.onnx").write_bytes(b"exported again")
    assert "it played another exported model (demo)" in _report_warnings(run)[1][0]
    # an episode without --run (oracle and random in the paper's env)
    write(command="episode", policies=["oracle", "random"])
    page, warned = _report_warnings(run)
    assert warned[0].endswith(f"it played no policy of this run (an episode without --run){again}")
    # drawn elsewhere for this run (ep.png, ep.gif, ep.png.json), then moved in: this run's
    elsewhere = tmp_path / "ep.png"
    for name in ("ep.png", "ep.gif"):
        (tmp_path / name).write_bytes(b"gif" if name.endswith("gif") else b"png")
    moved = write_episode_record(
        elsewhere,
        elsewhere.with_suffix(".gif"),
        command="episode",
        policies=["learned"],
        seed=1,
        run=scored_run(run),
        weights="final",
    )
    (run / "episode.png.json").write_bytes(moved.read_bytes())
    page, warned = _report_warnings(run)
    assert warned == [] and "`learned` from the start of seed 1; `learned` plays" in page
    # this run's, but the figure or its GIF replaced since (another run's copied over it)
    write(command="episode", policies=["learned", "random"], run=scored_run(run), weights="final")
    for drawn in (gif, figure):
        drawn.write_bytes(b"another run's")
        page, warned = _report_warnings(run)
        assert heading not in page
        assert f"{drawn.name} is not the one episode.png.json records (replaced since)" in warned[0]
    (run / "episode.png.json").write_text('{"policies": []}')
    with pytest.raises(ValueError, match=r"episode.png.json is damaged or not a file activevision"):
        write_report(run)


@pytest.mark.parametrize(
    ("method", "how"), [("shipped", "robustness --shipped"), ("scan", "robustness --method")]
)
def test_a_robustness_suite_of_another_policy_than_the_runs_is_left_out(tmp_path, method, how):
    """``robustness --shipped --out RUN/robustness`` (or ``--method scan``) scored no policy
    of the run and records none, and the report showed it as the run's robustness (its
    only sign the method's name in a sentence): left out with one warning."""
    run = make_run(tmp_path)
    row = robustness_row("clean", "as trained", True, (0.8, 0.7, 0.9), (0.5, 0.4, 0.6), (0, 0))
    path = run / "robustness" / "robustness.csv"
    write_rows(path, [row | {"method": method}])
    page, warned = _report_warnings(run)
    assert "## Robustness" not in page and "## Configuration" in page
    assert warned == [
        f"left {path} out of the report: it scored `{method}` ({how}), not this run's learned"
        f" policy; write it again: activevision robustness --run {run} --out {path.parent}"
        " --overwrite"
    ]


def _sha256(data: bytes) -> str:
    import hashlib

    return hashlib.sha256(data).hexdigest()


def write_export(run, model=b"exported", **changes):
    """RUN/policy.onnx (``model``) and a policy.json beside it that records, as ``export``
    writes them, the run's config.json and final weights as they are now (``changes``:
    other values)."""
    from activevision.runtime import pretrained_policy_path

    values = json.loads(pretrained_policy_path().with_suffix(".json").read_text())
    (run / "policy.onnx").write_bytes(model)
    values |= {
        "model_sha256": _sha256(model),
        "training_config_sha256": _sha256((run / "config.json").read_bytes()),
        "training_weights": "final",
        "training_weights_sha256": _sha256((run / "policy.safetensors").read_bytes()),
    }
    (run / "policy.json").write_text(json.dumps(values | changes))


def test_a_policy_exported_before_the_run_was_trained_on_is_not_its_policy(tmp_path):
    """``match --model RUN/policy.onnx`` and ``demo --policy RUN/policy.onnx`` were this
    run's policy whenever the file was RUN/policy.onnx as it is now, though exported before
    the run was trained on: policy.json records the weights it was exported from (and
    which), and report tells such an export by them."""
    from activevision.experiments.provenance import write_episode_record

    run = make_run(tmp_path)
    (run / "policy.safetensors").write_bytes(b"final")
    write_export(run)
    digest = _sha256(b"exported")
    model = str(run / "policy.onnx")
    rows = [match_row("onnx_policy") | {"model": model, "model_sha256": digest}]
    write_rows(run / "match" / "match.csv", rows)
    figure = run / "episode.png"
    figure.write_bytes(b"png")
    figure.with_suffix(".gif").write_bytes(b"gif")
    write_episode_record(
        figure,
        figure.with_suffix(".gif"),
        command="demo",
        policies=["run", "random"],
        seed=0,
        model=model,
        model_sha256=digest,
    )
    said = f"onnx_policy: `{model}` (`match --model`, SHA-256 {digest[:12]}…, this run's"
    said += " policy.onnx"
    page, warned = _report_warnings(run)
    assert warned == []
    assert f"{said}, exported from its final weights)." in page
    assert "`run` is this run's policy.onnx, exported from its final weights." in page
    (run / "policy.safetensors").write_bytes(b"trained on")  # since the export
    stale = "exported from another run's weights, or this run's before they were replaced"
    page, warned = _report_warnings(run)
    assert f"{said}, {stale} (trained on or retrained))." in page
    assert "## One episode" not in page
    assert warned == [
        f"left {figure} out of the report: it played this run's policy.onnx, {stale} (trained"
        f" on or retrained); write it again: activevision episode --run {run} --out {figure}"
        " --overwrite"
    ]
    # exported again: this run's; of its best weights, which the run has replaced since
    write_export(run)
    assert _report_warnings(run)[1] == []
    (run / "best_policy.safetensors").write_bytes(b"best")
    best = {"training_weights": "best", "training_weights_sha256": _sha256(b"best")}
    write_export(run, **best)
    page, warned = _report_warnings(run)
    assert warned == [] and f"{said}, exported from its best validated weights)." in page
    (run / "best_policy.safetensors").write_bytes(b"validated again")
    assert f"{said}, {stale}" in _report_warnings(run)[0]
    # another run's config.json (a policy.json from before the weights' record checks it
    # alone); a policy.json of another model than policy.onnx
    older = {"training_weights": None, "training_weights_sha256": None}
    write_export(run, training_config_sha256="ab" * 32, **older)
    page, warned = _report_warnings(run)
    assert f"{said}, exported from another run's config.json, or this run's" in page
    write_export(run)
    values = json.loads((run / "policy.json").read_text())
    del values["training_weights"], values["training_weights_sha256"]
    (run / "policy.json").write_text(json.dumps(values))  # from before the record
    page, warned = _report_warnings(run)
    assert warned == [] and f"{said})." in page
    write_export(run, model_sha256=_sha256(b"another model"))
    page, warned = _report_warnings(run)
    assert f"{said}, whose policy.json describes another model (its model_sha256))." in page
    assert len(warned) == 1
