"""DAgger: the student learns the oracle's moves, runs keep a DDQN run's layout, resume is
exact, and the policy plays through evaluate, export and HeadController alike."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from activevision.envs import ActiveVisionEnv
from activevision.envs.observations import pose_features, proposal_features, vector_columns
from activevision.experiments.evaluate import evaluate_policy
from activevision.experiments.policies import LearnedPolicy, OraclePolicy
from activevision.localisation import best_viewpoints
from activevision.rendering.appearance import LOOK, AppearanceConfig, draw_look_rows
from activevision.training import load_policy
from activevision.training.config import TrainConfig
from activevision.training.dagger import DaggerTrainer
from activevision.training.runs import reopen_run, resume, train


def tiny(observation: str = "image+head+pose+proposal", steps: int = 600, **extra) -> TrainConfig:
    return TrainConfig().replace(
        **{
            "algo": "dagger",
            "env.observation": observation,
            "env.action_history": 2 if observation != "image" else 0,
            "run.total_timesteps": steps,
            "run.epoch_steps": 100,
            "run.checkpoint_interval": 0,
            "run.tensorboard": False,
            "run.progress_bar": False,
            "dagger.num_envs": 8,
            "dagger.updates_per_rollout": 2,
            "learner.batch_size": 16,
            **extra,
        }
    )


def test_a_run_shorter_than_an_epoch_logs_a_metrics_row(tmp_path):
    """A tiny DAgger run (fewer steps than epoch_steps) left metrics.csv with its header
    alone: its rounds get a row at the end of the run, numbered as the epoch they lie in."""
    config = tiny(steps=40, **{"run.epoch_steps": 10_000})
    rows = train(config, tmp_path)
    with (tmp_path / "metrics.csv").open() as f:
        logged = list(csv.DictReader(f))
    assert len(rows) == len(logged) == 1
    assert int(logged[0]["epoch"]) == 1 and int(logged[0]["step"]) >= 40
    assert int(logged[0]["episodes"]) > 0 and np.isfinite(float(logged[0]["loss"]))


def test_run_layout_and_records(tmp_path):
    rows = train(tiny(**{"run.eval_interval": 300, "run.eval_episodes": 5}), tmp_path)
    for name in (
        "config.json",
        "metrics.csv",
        "episodes.csv",
        "evaluations.csv",
        "policy.safetensors",
        "best_policy.safetensors",
    ):
        assert (tmp_path / name).exists(), name
    assert rows and all(np.isfinite(r["loss"]) for r in rows)
    shares = [r["epsilon"] for r in rows]  # the teacher's share: 1 -> 0 over a quarter
    assert shares == sorted(shares, reverse=True) and shares[0] > 0 and shares[-1] == 0
    with (tmp_path / "episodes.csv").open() as f:
        episodes = list(csv.DictReader(f))
    assert len(episodes) >= 600 // 20 and all(1 <= int(e["length"]) <= 20 for e in episodes)
    network = load_policy(tmp_path)
    assert network.vector_size == 2 + 4 + 1 + 5 + 18


@pytest.mark.parametrize(
    "extra",
    [
        {},
        {"env.prior_error_range": (0.0, 2.0), "dagger.redraw_prior": True},
        {"dagger.goal_frame": "camera"},
    ],
    ids=["stored-priors", "redrawn-priors", "camera-frame-goal"],
)
def test_resume_ends_with_the_same_weights(tmp_path, extra):
    config = tiny(steps=900, **{"run.epoch_steps": 100, "run.checkpoint_interval": 300, **extra})
    train(config, tmp_path / "whole")
    trainer = DaggerTrainer(config, tmp_path / "split")
    trainer.train(350)  # stops at the first round past 350 steps, with a checkpoint
    trainer.close()
    resume(tmp_path / "split")
    a = load_policy(tmp_path / "whole").state_dict()
    b = load_policy(tmp_path / "split").state_dict()
    for key in a:
        assert np.array_equal(a[key].numpy(), b[key].numpy()), key
    for name in ("metrics.csv", "episodes.csv"):
        whole = (tmp_path / "whole" / name).read_text().splitlines()
        split = (tmp_path / "split" / name).read_text().splitlines()
        assert [r.split(",")[:4] for r in whole] == [r.split(",")[:4] for r in split], name
    assert isinstance(reopen_run(tmp_path / "split"), DaggerTrainer)


def test_labels_are_the_oracles_moves(tmp_path):
    trainer = DaggerTrainer(tiny(), tmp_path, loggers=[])
    trainer._rollout()
    data, grid, oracle = trainer.dataset.arrays, trainer.sim.localisation.grid, OraclePolicy()
    assert trainer.dataset.size >= 8
    for i in range(trainer.dataset.size):
        goal = (grid.pans[data["goal"][i]], grid.tilts[data["goal"][i]])
        want = oracle.act(None, {"head": data["head"][i], "goal_viewpoint": goal})
        assert data["action"][i] == want


def test_student_learns_to_follow_an_exact_proposal(tmp_path):
    # With the exact prior the proposal is the goal: a few thousand labelled states teach
    # the move towards it, far above what the image alone gives so early (random: ~3%).
    config = tiny(
        steps=4000,
        **{
            "dagger.updates_per_rollout": 8,
            "learner.batch_size": 64,
            "learner.learning_rate": 1e-3,
        },
    )
    train(config, tmp_path)
    policy = LearnedPolicy.from_run(tmp_path)
    env = ActiveVisionEnv(config.env)
    _, summary, _ = evaluate_policy(policy, 40, seed=500, env=env)
    assert summary["success"].mean >= 0.5


def test_ddqn_refuses_dict_observations():
    with pytest.raises(ValueError, match="algo='dagger'"):
        TrainConfig().replace(**{"env.observation": "image+head"})
    with pytest.raises(ValueError, match="frame_stack"):
        TrainConfig().replace(**{"algo": "dagger", "env.frame_stack": 4})


def test_tampered_dagger_checkpoints_are_refused(tmp_path, capsys):
    from activevision.cli import main

    config = tiny(steps=400, **{"run.checkpoint_interval": 100})
    trainer = DaggerTrainer(config, tmp_path / "run")
    trainer.train(150)
    trainer.close()
    run = tmp_path / "run"
    text = (run / "config.json").read_text()
    (run / "config.json").write_text(text.replace('"seed": 0', '"seed": 1'))
    assert main(["train", "--resume", str(run)]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and "config.json" in err[0] and "changed" in err[0]
    (run / "config.json").write_text(text)
    checkpoint = sorted((run / "checkpoints").iterdir())[-1]
    data = bytearray((checkpoint / "replay.npz").read_bytes())
    data[len(data) // 2] ^= 0xFF
    (checkpoint / "replay.npz").write_bytes(bytes(data))
    assert main(["train", "--resume", str(run)]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and "replay.npz" in err[0]


def continuous(steps: int = 600, **extra) -> TrainConfig:
    return tiny(steps=steps, **{"env.action_type": "continuous", "env.action_history": 0, **extra})


def test_continuous_labels_are_the_oracles_straight_moves(tmp_path):
    trainer = DaggerTrainer(continuous(), tmp_path, loggers=[])
    trainer._rollout()
    data, grid = trainer.dataset.arrays, trainer.sim.localisation.grid
    n = trainer.dataset.size
    goal = np.stack([grid.pans[data["goal"][:n]], grid.tilts[data["goal"][:n]]], axis=1)
    reach = np.radians(10.0)
    for head, target, label in zip(data["head"][:n], goal, data["action"][:n], strict=True):
        gap = target - head  # hand-computed: the move straight there, each axis capped
        want = [max(-1.0, min(1.0, g / reach)) for g in gap]
        np.testing.assert_allclose(label, want, atol=1e-6)
    assert (np.abs(data["action"][:n]) == 1.0).any()  # some goals lie beyond one move
    assert ((np.abs(data["action"][:n]) < 1.0) & (data["action"][:n] != 0)).any()


def test_continuous_student_reaches_goals_in_fewer_steps_and_exports(tmp_path):
    from activevision.experiments.policies import OnnxPolicy
    from activevision.export import export_run

    config = continuous(
        steps=4000,
        **{
            "dagger.num_envs": 24,  # episodes are short: as many updates as the discrete test
            "dagger.updates_per_rollout": 8,
            "learner.batch_size": 64,
            "learner.learning_rate": 1e-3,
            "dagger.switch_margin": 1.0,  # hysteresis in training, evaluation and runtime
        },
    )
    train(config, tmp_path)
    learned = LearnedPolicy.from_run(tmp_path)
    assert learned.goal_evidence is not None and learned.goal_evidence.switch_margin == 1.0
    env = ActiveVisionEnv(config.env)
    records, summary, _ = evaluate_policy(learned, 40, seed=500, env=env)
    assert summary["success"].mean >= 0.5
    # 10-degree moves: the goal in a few steps, where the 3-degree oracle needs about 8
    discrete = ActiveVisionEnv(config.env.replace(action_type="discrete"))
    _, oracle, _ = evaluate_policy(OraclePolicy(), 40, seed=500, env=discrete)
    solved = [r["success_duration"] for r in records if r["success"]]
    assert np.median(solved) <= 0.6 * oracle["success_duration"].mean
    # HeadController (ONNX, goal evidence in NumPy) plays the same episodes
    onnx = OnnxPolicy(export_run(tmp_path).model_path)
    assert onnx.controller.continuous and onnx.controller.metadata.goal_switch_margin == 1.0
    onnx_records, _, _ = evaluate_policy(onnx, 40, seed=500, env=env)
    assert [r["steps"] for r in onnx_records] == [r["steps"] for r in records]
    assert [r["success"] for r in onnx_records] == [r["success"] for r in records]


def test_the_library_entry_points_pick_the_learner_and_refuse_an_env_factory(tmp_path):
    from activevision.training import make_env, start_run

    config = tiny()
    with pytest.raises(ValueError, match="builds its own environments"):
        train(config, tmp_path / "a", env_factory=make_env)
    assert not (tmp_path / "a").exists()  # refused before anything is written
    trainer = start_run(config, tmp_path / "b", loggers=[])
    assert isinstance(trainer, DaggerTrainer)
    trainer.close()


def test_redrawn_priors_keep_each_states_error_scale_and_propose_from_the_new_pose(tmp_path):
    # dagger.redraw_prior: each minibatch sees its states with a fresh prior of the same
    # error scale (the release's corruption: e metres off, heading exactly +-e) and
    # Algorithm 1's proposal from that prior; exact priors and every other input stay.
    config = tiny(
        **{
            "env.prior_error_range": (0.0, 2.0),
            "env.prior_exact_share": 0.3,
            "dagger.redraw_prior": True,
        }
    )
    trainer = DaggerTrainer(config, tmp_path, loggers=[])
    trainer._rollout()
    data, n = trainer.dataset.arrays, trainer.dataset.size
    stored = data["vector"][:n].copy()
    draws = trainer.rng.bit_generator.state
    out = trainer._redraw_priors(stored, np.arange(n))
    columns = vector_columns(config.env, trainer.n_actions)
    errors = stored[:, columns["pose_error"]][:, 0]
    exact = errors == 0
    assert exact.any() and (~exact).any()
    np.testing.assert_array_equal(out[exact], stored[exact])
    for key in ("head", "pose_error", "actions"):
        np.testing.assert_array_equal(out[:, columns[key]], stored[:, columns[key]])
    pose, true = out[:, columns["pose"]].astype(np.float64), data["pose"][:n]
    gap = np.hypot(pose[:, 0] - true[:, 0], pose[:, 1] - true[:, 1])
    turn = np.abs(np.angle(np.exp(1j * (np.arctan2(pose[:, 3], pose[:, 2]) - true[:, 2]))))
    np.testing.assert_allclose(gap[~exact], errors[~exact], atol=1e-5)
    np.testing.assert_allclose(turn[~exact], errors[~exact], atol=1e-5)
    assert np.abs(pose[~exact] - stored[~exact][:, columns["pose"]]).max() > 0.1  # a new draw
    # the columns written are those draws' prior and Algorithm 1's proposal from it (the
    # move there from the head), and that proposal is best_viewpoints' from the new prior
    rng = np.random.default_rng()
    rng.bit_generator.state = draws
    rows = np.flatnonzero(~exact)
    prior, proposal = trainer.sim.redraw_priors(
        true[rows], data["ball"][rows], errors[rows].astype(np.float64), None, rng
    )
    np.testing.assert_array_equal(
        out[rows][:, columns["pose"]], pose_features(prior).astype(np.float32)
    )
    np.testing.assert_array_equal(
        out[rows][:, columns["proposal"]],
        proposal_features(proposal, data["head"][rows]).astype(np.float32),
    )
    loc = trainer.sim.localisation
    want = best_viewpoints(
        prior,
        np.broadcast_to(loc.ukf.initial_cov, (len(rows), 3, 3)),
        data["ball"][rows],
        trainer.sim.landmarks,
        config.env.camera,
        grid=loc.grid,
        ukf=loc.ukf,
        ball_radius=config.env.field.ball_radius,
        ball_views_only=True,
    )
    np.testing.assert_array_equal(proposal[:, 2], want.ok)
    np.testing.assert_array_equal(
        proposal[want.ok, :2], np.column_stack([want.pan, want.tilt])[want.ok]
    )
    found = out[:, columns["proposal"]][:, 4] == 1
    moves = out[:, columns["proposal"]][:, :2] - data["head"][:n]
    np.testing.assert_allclose(out[found][:, columns["proposal"]][:, 2:4], moves[found], atol=1e-5)


def test_camera_frame_goal_labels_are_the_goals_offset_from_the_head(tmp_path):
    from activevision.runtime.goal_evidence import offset_axes

    trainer = DaggerTrainer(tiny("image", **{"dagger.goal_frame": "camera"}), tmp_path, loggers=[])
    trainer._rollout()
    data, views = trainer.dataset.arrays, trainer.sim.localisation.grid.views
    b = np.arange(trainer.dataset.size)
    labels = trainer._goal_labels(b)
    pans, tilts = offset_axes(views)
    assert trainer.network.n_goals == labels.shape[1] == len(pans) * len(tilts)
    knots = np.stack(np.meshgrid(pans, tilts, indexing="ij"), axis=-1).reshape(-1, 2)
    gap = views[data["goal"][b]] - data["head"][b]  # hand-computed: goal minus head
    inside = (np.abs(gap[:, 1]) <= tilts[-1]) & (np.abs(gap[:, 0]) <= pans[-1])
    assert inside.mean() > 0.9
    np.testing.assert_allclose(labels.sum(axis=1), 1.0, atol=1e-6)
    np.testing.assert_allclose(labels[inside] @ knots, gap[inside], atol=1e-6)
    assert trainer.metadata()["goal_frame"] == "camera"


def test_camera_frame_goal_needs_a_goal_head_on_the_episodes():
    with pytest.raises(ValueError, match="goal_frame"):
        tiny(
            "image",
            **{
                "dagger.goal_frame": "camera",
                "dagger.goal_class_weight": 0.0,
                "dagger.act_by": "action",
            },
        )
    from activevision.training import presets

    with pytest.raises(ValueError, match="goal_frame"):
        presets.preset("match_dagger").replace(**{"dagger.goal_frame": "camera"})


def test_redraw_prior_needs_a_drawn_prior_in_the_observation():
    with pytest.raises(ValueError, match="redraw_prior"):
        tiny("image+head", **{"dagger.redraw_prior": True})
    with pytest.raises(ValueError, match="prior_error_range"):  # the prior is the belief
        tiny(**{"dagger.redraw_prior": True, "env.localisation_error": 0.5})


def test_redrawn_looks_are_new_draws_of_the_appearance_and_keep_each_frames_move(
    tmp_path, monkeypatch
):
    # dagger.redraw_look: each minibatch renders its states under looks drawn again from
    # env.appearance (the label does not depend on the look); the frame's head move and
    # counter (motion blur, the noise's key) stay the state's own
    clutter = (30.0, 80.0)
    config = tiny(
        **{
            "env.appearance": AppearanceConfig.randomised().replace(
                clutter=clutter, neutral_share=0.5
            ),
            "dagger.redraw_look": True,
            "learner.batch_size": 64,
        }
    )
    trainer = DaggerTrainer(config, tmp_path, loggers=[])
    trainer._rollout()
    data, n = trainer.dataset.arrays, trainer.dataset.size
    stored = data["looks"][:n]
    assert (stored[:, LOOK["move_pan"]] != 0).any() and (stored[:, LOOK["frame"]] > 0).any()
    rendered = []
    render = trainer.sim.render_states

    def spy(pose, head, ball, looks, robots, **kw):
        rendered.append((pose, looks))
        return render(pose, head, ball, looks, robots, **kw)

    monkeypatch.setattr(trainer.sim, "render_states", spy)
    draws = trainer.rng.bit_generator.state
    trainer._update()
    pose, looks = rendered[0]
    rng = np.random.default_rng()
    rng.bit_generator.state = draws
    b = rng.integers(0, n, size=64)
    np.testing.assert_array_equal(pose, data["pose"][b])  # the same minibatch of states
    episode = slice(0, LOOK["key"] + 1)
    fresh = draw_look_rows(config.env.appearance, 64, rng)
    np.testing.assert_array_equal(looks[:, episode], fresh[:, episode])
    np.testing.assert_array_equal(looks[:, LOOK["key"] + 1 :], stored[b][:, LOOK["key"] + 1 :])
    assert (looks[:, LOOK["key"]] != stored[b][:, LOOK["key"]]).all()  # new carpets
    seen = looks[:, LOOK["clutter"]]
    assert ((seen == 0) | ((seen >= clutter[0]) & (seen <= clutter[1]))).all()
    assert 0 < (seen == 0).sum() < 64  # some states seen clean, some not


def test_redraw_look_needs_a_randomised_appearance():
    with pytest.raises(ValueError, match="redraw_look"):
        tiny(**{"dagger.redraw_look": True})


def test_warm_start_takes_the_source_weights_resumes_without_them_and_refuses_others(tmp_path):
    import torch

    train(tiny(steps=300), tmp_path / "source")
    source = load_policy(tmp_path / "source").state_dict()
    warm = tiny(
        steps=600,
        **{"run.checkpoint_interval": 300, "dagger.init_from": str(tmp_path / "source")},
    )
    trainer = DaggerTrainer(warm, tmp_path / "split")  # its logs, which the resume continues
    start = trainer.network.state_dict()  # on the training device (a GPU where there is one)
    assert all(torch.equal(start[k].cpu(), source[k]) for k in source)
    cold = DaggerTrainer(tiny(steps=300), tmp_path / "cold", loggers=[]).network.state_dict()
    assert not all(torch.equal(cold[k].cpu(), source[k]) for k in source)
    trainer.train(350)
    trainer.close()
    train(warm, tmp_path / "whole")
    # a resumed run restores its checkpoint: the source may be gone by then
    (tmp_path / "source").rename(tmp_path / "moved")
    resume(tmp_path / "split")
    a = load_policy(tmp_path / "whole").state_dict()
    b = load_policy(tmp_path / "split").state_dict()
    assert all(torch.equal(a[k], b[k]) for k in a)
    moved = str(tmp_path / "moved")
    for other in ({"env.observation": "image+head"}, {"dagger.goal_frame": "camera"}):
        with pytest.raises(ValueError, match=r"dagger\.init_from: .* another network or input"):
            DaggerTrainer(tiny(**{**other, "dagger.init_from": moved}), tmp_path / "x", loggers=[])
    with pytest.raises(ValueError, match=r"dagger\.init_from: no policy weights"):
        DaggerTrainer(tiny(**{"dagger.init_from": str(tmp_path / "source")}), tmp_path / "z")
    # how the student acts on its outputs may change
    DaggerTrainer(
        tiny(**{"dagger.switch_margin": 3.0, "dagger.init_from": moved}), tmp_path / "y", loggers=[]
    )
