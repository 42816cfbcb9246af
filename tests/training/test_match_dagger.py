"""DAgger on the match: the labels are entropy_track's moves, the teacher's rounds replay
entropy_track's matches, resume is exact, the config travels through config.json, and the
student plays in ``activevision match`` in either action type."""

from __future__ import annotations

import csv
import dataclasses
import math

import numpy as np
import pytest
import torch

from activevision.envs.match.config import DetectionConfig, MatchConfig
from activevision.envs.match.heads import EntropyTrackTeacher, GlanceTrackTeacher
from activevision.envs.match.vector import ActiveVisionMatchVectorEnv
from activevision.envs.seeding import episode_seed
from activevision.experiments.match import play_matches
from activevision.experiments.match_methods import StrategyOptions
from activevision.training import load_policy, plot_run
from activevision.training.checkpoint import load_tensors
from activevision.training.config import TrainConfig, apply_overrides, load_config, save_config
from activevision.training.match_dagger import MatchDaggerTrainer, play_student_matches
from activevision.training.presets import preset
from activevision.training.runs import reopen_run, train
from activevision.training.validation import MATCH_EVALUATION_FIELDS

TICKS = 12


def tiny(steps: int = 4 * TICKS, action_type: str = "discrete", **extra) -> TrainConfig:
    config = preset("match_dagger_continuous" if action_type == "continuous" else "match_dagger")
    return config.replace(
        **{
            "match.ticks": TICKS,
            "run.total_timesteps": steps,
            "run.epoch_steps": 2 * TICKS,
            "run.tensorboard": False,
            "run.progress_bar": False,
            "dagger.num_envs": 2,
            "dagger.updates_per_rollout": 2,
            "learner.batch_size": 8,
            **extra,
        }
    )


def test_run_layout_and_records(tmp_path):
    rows = train(tiny(), tmp_path)
    for name in ("config.json", "metrics.csv", "episodes.csv", "policy.safetensors"):
        assert (tmp_path / name).exists(), name
    assert len(rows) == 2 and all(np.isfinite(r["loss"]) for r in rows)
    assert all(math.isnan(r["success_rate"]) for r in rows)  # a match has none
    with (tmp_path / "episodes.csv").open() as f:
        episodes = list(csv.DictReader(f))
    assert len(episodes) == 4 * TICKS // TICKS and {e["length"] for e in episodes} == {"12"}
    network = load_policy(tmp_path)
    assert network.vector_size == 2 + 4 + 3 + 3 and network.n_actions == 9


def first_round_seed(config: TrainConfig, num_envs: int) -> int:
    """The env seed of the trainer's first round (its generator's first draw)."""
    trainer_seed, _ = np.random.SeedSequence(config.seed).generate_state(2)
    rng = np.random.default_rng(int(trainer_seed))
    return int(rng.integers(0, 2**31 - 1 - num_envs))


@pytest.mark.parametrize("teacher_name", ["entropy_track", "glance_track"])
def test_labels_are_the_teachers_moves_and_the_teacher_plays_its_matches(tmp_path, teacher_name):
    """With the teacher acting throughout, the first round is the teacher's matches: the
    same head path as ``activevision match --methods entropy_track`` (or glance_track) on its
    seeds, and every stored label is the teacher's move from the state the robot was in."""
    config = tiny(**{"dagger.teacher_fraction": 1.0, "dagger.match_teacher": teacher_name})
    trainer = MatchDaggerTrainer(config, tmp_path, loggers=[])
    trainer._rollout()
    data = trainer.dataset.arrays
    assert trainer.dataset.size == 2 * TICKS
    seed = first_round_seed(config, 2)
    played = play_matches(teacher_name, config.match, 2, seed)
    heads = np.array(played.clip.head[:TICKS])  # match 0 of the pair, tick by tick
    np.testing.assert_array_equal(data["head"][0 : 2 * TICKS : 2], heads)
    # relabel by hand: the teacher's move from each stored tick of match 0
    env = ActiveVisionMatchVectorEnv(2, config.match)
    _, info = env.reset(seed=seed)
    teacher = (
        GlanceTrackTeacher(config.match)
        if teacher_name == "glance_track"
        else EntropyTrackTeacher(config.match, config.dagger.track_margin_deg)
    )
    for t in range(TICKS):
        action = teacher.actions(info)
        np.testing.assert_array_equal(data["action"][2 * t : 2 * t + 2], action)
        _, _, _, _, info = env.step(action)
    trainer.close()


def test_resume_ends_with_the_same_weights(tmp_path):
    config = tiny(
        steps=6 * TICKS,
        **{
            "run.checkpoint_interval": 2 * TICKS,
            "run.eval_interval": 2 * TICKS,
            "run.eval_episodes": 2,
        },
    )
    train(config, tmp_path / "whole")
    trainer = MatchDaggerTrainer(config, tmp_path / "split")
    trainer.train(2 * TICKS)
    trainer.close()
    resumed = reopen_run(tmp_path / "split")
    assert isinstance(resumed, MatchDaggerTrainer)
    resumed.train()
    resumed.close()
    a = load_policy(tmp_path / "whole").state_dict()
    b = load_policy(tmp_path / "split").state_dict()
    for key in a:
        assert np.array_equal(a[key].numpy(), b[key].numpy()), key
    whole = (tmp_path / "whole" / "episodes.csv").read_text().splitlines()
    split = (tmp_path / "split" / "episodes.csv").read_text().splitlines()
    assert [r.split(",")[:4] for r in whole] == [r.split(",")[:4] for r in split]
    evaluations = [(tmp_path / d / "evaluations.csv").read_text() for d in ("whole", "split")]
    assert evaluations[0] == evaluations[1] and len(evaluations[0].splitlines()) == 4
    best = [load_tensors(tmp_path / d / "best_policy.safetensors") for d in ("whole", "split")]
    assert best[0][1] == best[1][1]
    assert all(torch.equal(best[0][0][k], best[1][0][k]) for k in best[0][0])


def test_the_match_config_travels_through_config_json(tmp_path):
    config = apply_overrides(tiny(), ["match.detection.far=0.2", "match.walk.speed=0.1"])
    assert config.match.detection == DetectionConfig(near=0.6, far=0.2, false_rate=0.2)
    save_config(config, tmp_path / "config.json")
    assert load_config(tmp_path / "config.json") == config
    # a short name means the episodic env's field, which a match run never reads: refused
    with pytest.raises(ValueError, match=r"'step_deg' sets env.step_deg.*set match.step_deg"):
        apply_overrides(config, ["step_deg=4"])
    with pytest.raises(ValueError, match=r"'frame_stack' sets env.frame_stack.*no such setting"):
        apply_overrides(config, ["frame_stack=1"])
    assert apply_overrides(config, ["match.step_deg=4"]).match.step_deg == 4
    # the same short name on the episodic env (named in the same --set) is the env's field
    episodic = apply_overrides(config, ["env_id=ActiveVision-v0", "algo=ddqn", "step_deg=4"])
    assert episodic.env.step_deg == 4
    # the episodic env's field by its full path is as unread on the match: refused too
    with pytest.raises(ValueError, match=r"'env.camera.hfov' sets .*set match.camera.hfov"):
        apply_overrides(config, ["env.camera.hfov=1.2"])


def test_match_keys_on_an_episodic_run_are_refused_not_stored_unread():
    """--set match.detection.far=0.2 on an episodic preset was stored in config.json and
    never read (only a run on ActiveVisionMatch-v0 reads TrainConfig.match)."""
    with pytest.raises(ValueError, match=r"'match.detection.far' sets the match env's config"):
        apply_overrides(preset("dagger_prior"), ["match.detection.far=0.2"])
    with pytest.raises(ValueError, match="never reads"):
        preset("paper").replace(**{"match.ticks": 40})
    # named with the match env in the same --set, it is that run's config
    config = apply_overrides(
        preset("paper"), ["env_id=ActiveVisionMatch-v0", "match.detection.far=0.2"]
    )
    assert config.match.detection.far == 0.2


@pytest.mark.parametrize(
    ("change", "needle"),
    [
        ({"match.observation": "image"}, "what its teacher plans from"),
        ({"match.appearance.gain": [0.8, 1.2]}, "clean world"),
        ({"env_id": "CartPole-v1"}, "CartPole-v1"),
    ],
)
def test_bad_match_dagger_configs_are_refused(change, needle):
    with pytest.raises(ValueError, match=needle):
        tiny(**change)


def test_a_continuous_student_regresses_straight_moves_and_plays(tmp_path):
    config = tiny(action_type="continuous")
    trainer = MatchDaggerTrainer(config, tmp_path, loggers=[])
    trainer.train()
    trainer.close()
    moves = trainer.dataset.arrays["action"][: trainer.dataset.size]
    assert moves.shape == (4 * TICKS, 2) and np.abs(moves).max() <= 1.0
    assert (np.abs(moves) == 1.0).any() and (np.abs(moves) < 1.0).any()  # capped and not
    match = MatchConfig(ticks=6, action_type="continuous", max_move_deg=(3.0, 3.0))
    result = play_matches("learned", match, 2, 7, StrategyOptions(run=tmp_path))
    assert np.isfinite(result.per_match["position_rmse"]).all()
    with pytest.raises(ValueError, match="--action-type continuous"):
        play_matches("learned", MatchConfig(ticks=6), 2, 7, StrategyOptions(run=tmp_path))


def test_the_student_learns_to_keep_the_ball_in_view(tmp_path):
    """A few hundred updates on the teacher's matches: the student sees the ball far more
    than random head moves do in the same matches (a test that fails for an untrained or
    mislabelled student)."""
    config = tiny(
        steps=16 * 40,
        **{
            "match.ticks": 40,
            "run.epoch_steps": 160,
            "dagger.num_envs": 4,
            "dagger.updates_per_rollout": 60,
            "dagger.teacher_fraction": 1.0,
            "learner.batch_size": 64,
        },
    )
    train(config, tmp_path)
    match = config.match.replace(ticks=60)
    options = StrategyOptions(run=tmp_path)
    learned = play_matches("learned", match, 8, 11, options).per_match["ball_in_view"].mean()
    random = play_matches("random", match, 8, 11).per_match["ball_in_view"].mean()
    assert learned > random + 0.1


@pytest.mark.parametrize("action_type", ["discrete", "continuous"])
def test_the_exported_student_plays_as_the_run_does(tmp_path, action_type):
    """Exported to ONNX, the student runs through HeadController (torch-free), fed the
    belief and the ball model by onnx_policy: the same matches, tick for tick, as the run's
    PyTorch network (discrete: the same moves exactly; continuous: the same to float32
    rounding of the two runtimes)."""
    from activevision.export import export_run
    from activevision.runtime import HeadController

    train(tiny(action_type=action_type), tmp_path)
    export_run(tmp_path, tmp_path / "policy.onnx")
    controller = HeadController(tmp_path / "policy.onnx")
    assert controller.inputs == ("pose", "belief", "ball")
    with pytest.raises(ValueError, match="needs belief"):
        controller.act(np.zeros((120, 160), np.uint8), 0.0, 0.3, pose=(0, 0, 0), ball=(1, 0, 0))
    match = MatchConfig(ticks=20, action_type=action_type, max_move_deg=(3.0, 3.0))
    run = play_matches("learned", match, 3, 5, StrategyOptions(run=tmp_path))
    onnx = play_matches("onnx_policy", match, 3, 5, StrategyOptions(model=tmp_path / "policy.onnx"))
    tolerance = 0.0 if action_type == "discrete" else 1e-6
    np.testing.assert_allclose(np.array(run.clip.head), np.array(onnx.clip.head), atol=tolerance)
    for name, values in run.per_match.items():
        np.testing.assert_allclose(values, onnx.per_match[name], atol=tolerance, err_msg=name)


def test_head_controller_bounds_the_vectors_as_the_match_env_does(tmp_path):
    """A ball unseen for 30 s and a belief 50 m wide reach the network as the env clips
    them: 10 s and 10 m."""
    from activevision.envs.match.observations import VECTOR_BOUND
    from activevision.export import export_run
    from activevision.runtime import HeadController

    train(tiny(steps=2 * TICKS), tmp_path)
    controller = HeadController(export_run(tmp_path).model_path)
    frame = np.zeros((120, 160), np.uint8)
    controller.act(frame, 0.1, 0.3, pose=(1, 2, 0.5), belief=(50, 0.2, 0.1), ball=(2, -1, 30))
    vector = controller._vector[0]  # head 2, pose 4, belief 3, ball 3
    np.testing.assert_allclose(vector[6:], [VECTOR_BOUND, 0.2, 0.1, 2, -1, VECTOR_BOUND])
    with pytest.raises(ValueError, match=r"belief must be standard deviations >= 0"):
        controller.act(frame, 0.1, 0.3, pose=(1, 2, 0.5), belief=(0.1, -0.2, 0.1), ball=(2, -1, 3))
    # the ball model in millimetres was clipped to 10 m, silently
    with pytest.raises(ValueError, match=r"ball x, y must be metres .*\(2000, -1000\)"):
        controller.act(
            frame, 0.1, 0.3, pose=(1, 2, 0.5), belief=(0.1, 0.2, 0.1), ball=(2000, -1000, 3)
        )


def test_a_student_refuses_what_it_was_not_trained_for(tmp_path, capsys):
    from activevision.cli import main
    from activevision.export import export_run

    train(tiny(steps=2 * TICKS), tmp_path / "run")
    run, out = str(tmp_path / "run"), str(tmp_path / "m")
    model = str(export_run(tmp_path / "run").model_path)
    base = ["match", "--matches", "1", "--ticks", "3", "--out", out]
    demo = ["demo", "--policy", model, "--out", str(tmp_path / "m" / "d.png")]
    for argv, needle in (
        # was "EnvConfig.observation: expects one of 'image', ..., got 'image+head+belief'"
        (demo, f"activevision match --methods onnx_policy --model {model}"),
        ([*base, "--methods", "ball_track", "--run", run], "add it to --methods"),
        (
            [*base, "--methods", "ball_track", "learned", "--run", run, "--step-deg", "6"],
            "--step-deg 3",
        ),
        (["evaluate", "--run", run, "--episodes", "2"], "activevision match --run"),
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert needle in err and "Traceback" not in err
    assert not (tmp_path / "m").exists()  # refused before any strategy played


def test_validation_matches_log_rmse_and_ball_and_keep_the_best_weights(tmp_path):
    config = tiny(**{"run.eval_interval": 2 * TICKS, "run.eval_episodes": 3})
    train(config, tmp_path)
    with (tmp_path / "evaluations.csv").open() as f:
        reader = csv.DictReader(f)
        rows = list(reader)
    assert tuple(reader.fieldnames or ()) == MATCH_EVALUATION_FIELDS
    assert [int(r["step"]) for r in rows] == [2 * TICKS, 4 * TICKS]
    rewards = [float(r["episode_reward"]) for r in rows]
    best = int(np.argmax(rewards))
    assert [int(r["best"]) for r in rows] == ([1, 0] if best == 0 else [1, 1])
    _, meta = load_tensors(tmp_path / "best_policy.safetensors")
    assert meta["step"] == 2 * TICKS * (best + 1)
    assert meta["validation_episode_reward"] == pytest.approx(rewards[best])
    # the last validation played the final weights: the same matches, played by the
    # `learned` strategy of `activevision match` (consecutive seeds from 17), agree
    network = load_policy(tmp_path)
    mine = play_student_matches(network, torch.device("cpu"), config.match, [17, 18, 19])
    theirs = play_matches("learned", config.match, 3, 17, StrategyOptions(run=tmp_path))
    np.testing.assert_allclose(
        [m["position_rmse"] for m in mine], theirs.per_match["position_rmse"], rtol=1e-12
    )
    np.testing.assert_allclose(
        [m["ball_in_view"] for m in mine], theirs.per_match["ball_in_view"], rtol=1e-12
    )
    # and the logged means are those of the validation seeds, not of these
    seeds = [episode_seed(config.run.eval_seed, i) for i in range(3)]
    validation = play_student_matches(network, torch.device("cpu"), config.match, seeds)
    assert float(rows[-1]["position_rmse"]) == pytest.approx(
        np.mean([m["position_rmse"] for m in validation])
    )
    assert float(rows[-1]["episode_reward"]) == pytest.approx(
        np.mean([m["reward"] for m in validation])
    )
    # `activevision match --weights best` plays the kept weights
    best_network = load_policy(tmp_path, weights="best")
    mine = play_student_matches(best_network, torch.device("cpu"), config.match, [17, 18])
    options = StrategyOptions(run=tmp_path, weights="best")
    theirs = play_matches("learned", config.match, 2, 17, options)
    np.testing.assert_allclose(
        [m["position_rmse"] for m in mine], theirs.per_match["position_rmse"], rtol=1e-12
    )
    # validating draws nothing from the run's generators: the same final weights as without
    train(tiny(), tmp_path / "unvalidated")
    unvalidated = load_policy(tmp_path / "unvalidated").state_dict()
    assert all(torch.equal(t, unvalidated[k]) for k, t in network.state_dict().items())
    # the training figure shows them where an episodic run shows its success rate
    figure = plot_run(tmp_path)
    names = {p.name for p in figure.parent.iterdir()}
    assert {"validation_position_rmse.png", "validation_ball_in_view.png"} <= names
    assert "success_rate.png" not in names


def test_a_match_student_starts_from_another_runs_weights(tmp_path):
    train(tiny(), tmp_path / "source")
    source = load_policy(tmp_path / "source").state_dict()
    warm = tiny(**{"dagger.init_from": str(tmp_path / "source")})
    start = MatchDaggerTrainer(warm, tmp_path / "warm", loggers=[]).network.state_dict()
    assert all(torch.equal(start[k].cpu(), source[k]) for k in source)  # from the GPU too
    # a continuous student has another action head: refused, naming the difference
    other = tiny(action_type="continuous", **{"dagger.init_from": str(tmp_path / "source")})
    with pytest.raises(ValueError, match=r"dagger\.init_from: .* another network or input"):
        MatchDaggerTrainer(other, tmp_path / "other", loggers=[])
    # a discrete student's moves are the action table's: the continuous moves' size, which
    # its config carries unread, is no difference (it was refused, naming max_move_deg). Set
    # on the config itself: --set and replace refuse it on a discrete run (never read)
    wider = dataclasses.replace(warm, match=warm.match.replace(max_move_deg=(10.0, 10.0)))
    start = MatchDaggerTrainer(wider, tmp_path / "wider", loggers=[]).network.state_dict()
    assert all(torch.equal(start[k].cpu(), source[k]) for k in source)
    # a continuous student's moves are scaled by it: refused, naming it
    train(tiny(action_type="continuous"), tmp_path / "continuous")
    faster = tiny(
        action_type="continuous",
        **{"match.max_move_deg": [6.0, 6.0], "dagger.init_from": str(tmp_path / "continuous")},
    )
    with pytest.raises(
        ValueError, match=r"\(max_move_deg: \[3\.0, 3\.0\]; this run: \[6\.0, 6\.0\]\)"
    ):
        MatchDaggerTrainer(faster, tmp_path / "faster", loggers=[])
