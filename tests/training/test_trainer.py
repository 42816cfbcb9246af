import csv
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch

from activevision.agents.q_network import QNetwork
from activevision.envs.seeding import episode_seed
from activevision.figures.training import CURVES
from activevision.training import checkpoint as ckpt
from activevision.training.aux_targets import goal_offset
from activevision.training.config import TrainConfig
from activevision.training.environment import make_env
from activevision.training.metrics import EPOCH_FIELDS, TIMING_FIELDS
from activevision.training.plots import plot_run
from activevision.training.policy_files import load_policy
from activevision.training.runs import resume, train
from activevision.training.trainer import Trainer
from activevision.training.validation import (
    MATCH_EVALUATION_FIELDS,
    greedy_episodes,
    summarise_validation,
)


def tiny_config(**changes) -> TrainConfig:
    values = dict(
        seed=7,
        total_timesteps=120,
        epoch_steps=60,
        batch_size=8,
        buffer_size=1000,
        learning_starts=20,
        target_update_interval=50,
        exploration_fraction=0.5,
        checkpoint_interval=60,
        tensorboard=False,
        progress_bar=False,
        num_threads=1,  # robust timing on a busy machine; the math is the same
        env_id="unused",
    )
    values.update(changes)
    return TrainConfig().replace(**values)


def read_rows(path):
    with open(path, newline="") as file:
        return list(csv.DictReader(file))


def test_smoke_run_writes_metrics_checkpoint_and_plots(tmp_path, paper_image_env_factory):
    config = tiny_config(
        total_timesteps=200,
        epoch_steps=100,
        checkpoint_interval=200,
        learning_starts=150,
        tensorboard=True,
    )
    epochs = train(config, tmp_path, paper_image_env_factory)
    assert [e["step"] for e in epochs] == [100, 200]
    rows = read_rows(tmp_path / "metrics.csv")
    assert list(rows[0]) == list(EPOCH_FIELDS) and len(rows) == 2
    assert float(rows[-1]["updates"]) == 50 and np.isfinite(float(rows[-1]["loss"]))
    assert 0.0 <= float(rows[-1]["success_rate"]) <= 1.0
    assert len(read_rows(tmp_path / "episodes.csv")) >= 200 // 20
    assert (tmp_path / "config.json").exists()
    assert list((tmp_path / "tensorboard").glob("events.out.tfevents.*"))
    checkpoint = ckpt.latest_checkpoint(tmp_path)
    assert checkpoint.name == ckpt.checkpoint_name(200)
    ckpt.verify_checkpoint(checkpoint)

    policy = load_policy(tmp_path)
    assert isinstance(policy, QNetwork) and not policy.training
    assert policy(torch.zeros(1, 1, 120, 160, dtype=torch.uint8)).shape == (1, 9)

    combined = plot_run(tmp_path)
    assert combined.stat().st_size > 10_000
    for curve in CURVES:
        assert (tmp_path / "plots" / curve.file).stat().st_size > 5_000


def test_gradient_steps_and_train_freq_set_the_update_count(tmp_path, fake_env_factory):
    # updates happen at steps learning_starts+1 .. total whose index is a multiple of train_freq
    config = tiny_config(total_timesteps=60, learning_starts=20, train_freq=2, gradient_steps=3)
    train(config, tmp_path, fake_env_factory)
    assert float(read_rows(tmp_path / "metrics.csv")[-1]["updates"]) == 3 * 20
    with pytest.raises(ValueError, match="gradient_steps"):
        tiny_config(gradient_steps=0)


def test_a_run_ending_between_epochs_logs_its_last_steps(tmp_path, fake_env_factory):
    """A run shorter than epoch_steps left metrics.csv with its header alone, and a run
    ending mid-epoch dropped its last steps: each gets a row, numbered as its epoch."""
    short = train(tiny_config(total_timesteps=45), tmp_path / "short", fake_env_factory)
    rows = read_rows(tmp_path / "short" / "metrics.csv")
    assert (
        [(r["epoch"], r["step"]) for r in rows]
        == [("1", "45")]
        == [(str(e["epoch"]), str(e["step"])) for e in short]
    )
    assert int(rows[0]["episodes"]) > 0 and float(rows[0]["updates"]) == 45 - 20
    config = tiny_config(total_timesteps=150, checkpoint_interval=0)
    train(config, tmp_path / "long", fake_env_factory)
    rows = read_rows(tmp_path / "long" / "metrics.csv")
    assert [(r["epoch"], r["step"]) for r in rows] == [("1", "60"), ("2", "120"), ("3", "150")]
    # a call that stops before total_timesteps is no end of the run: no row until the end
    trainer = Trainer(tiny_config(total_timesteps=45), tmp_path / "parts", fake_env_factory)
    assert trainer.train(steps=30) == []
    assert [e["step"] for e in trainer.train()] == [45]
    trainer.close()


def comparable(rows):
    return [{k: v for k, v in row.items() if k not in TIMING_FIELDS} for row in rows]


@pytest.mark.parametrize("options", [{}, {"n_step": 3, "augment_shift": 2, "aux_goal_weight": 1.0}])
def test_resume_gives_exactly_the_uninterrupted_result(tmp_path, fake_env_factory, options):
    config = tiny_config(**options)
    straight, interrupted = tmp_path / "straight", tmp_path / "interrupted"
    train(config, straight, fake_env_factory, aux_target=goal_offset)  # used with aux_goal_weight

    first = Trainer(config, interrupted, fake_env_factory, aux_target=goal_offset)
    first.train(steps=60)  # one epoch: checkpoint at step 60
    first.train(steps=10)  # stops mid-epoch: checkpoint at step 70 ...
    assert first._obs is not None  # ... which falls inside an episode
    for _ in range(25):  # progress after the checkpoint, lost in a "crash"
        first._env_step()
    first.close()
    resume(interrupted, fake_env_factory, aux_target=goal_offset)  # redoes it exactly

    for name in ("metrics.csv", "episodes.csv"):
        assert comparable(read_rows(straight / name)) == comparable(read_rows(interrupted / name))
    a, b = load_policy(straight).state_dict(), load_policy(interrupted).state_dict()
    for key in a:
        assert torch.equal(a[key], b[key]), key


def tensorboard_scalars(log_dir) -> dict[str, list[tuple[int, float]]]:
    """Every scalar TensorBoard shows, as it shows them (purged events left out)."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    events = EventAccumulator(str(log_dir), size_guidance={"scalars": 0})
    events.Reload()
    return {
        tag: [(e.step, e.value) for e in events.Scalars(tag)]
        for tag in events.Tags()["scalars"]
        if tag != "charts/SPS"  # timed
    }


def test_a_resumed_run_shows_the_uninterrupted_curves_in_tensorboard(tmp_path, fake_env_factory):
    # the resumed writer purged the checkpoint's own step: the epoch row and validation of
    # step 60 were gone from TensorBoard (the CSV logs kept them)
    config = tiny_config(tensorboard=True, eval_interval=60, eval_episodes=2)
    straight, interrupted = tmp_path / "straight", tmp_path / "interrupted"
    train(config, straight, fake_env_factory)
    first = Trainer(config, interrupted, fake_env_factory)
    first.train(steps=60)  # checkpoint at step 60, after its epoch row and validation
    for _ in range(25):  # logged after the checkpoint, lost in a "crash"
        first._env_step()
    first.logger.flush()
    first.close()
    resume(interrupted, fake_env_factory)
    expected = tensorboard_scalars(straight / "tensorboard")
    assert [step for step, _ in expected["eval/success_rate"]] == [60, 120]
    assert tensorboard_scalars(interrupted / "tensorboard") == expected


def test_a_run_resumed_after_its_last_boundary_ends_with_the_same_final_row(
    tmp_path, fake_env_factory
):
    """Checkpointed at step 130, after the last epoch boundary (120) and before the end
    (150), and resumed: the final row (epoch 3, the steps 120-150) is the uninterrupted
    run's, its episodes and losses from both sessions."""
    config = tiny_config(total_timesteps=150, checkpoint_interval=0)
    straight, interrupted = tmp_path / "straight", tmp_path / "interrupted"
    train(config, straight, fake_env_factory)
    first = Trainer(config, interrupted, fake_env_factory)
    assert [e["step"] for e in first.train(steps=130)] == [60, 120]  # checkpoint at 130
    for _ in range(7):  # progress after the checkpoint, lost in a "crash"
        first._env_step()
    first.close()
    resume(interrupted, fake_env_factory)
    for name in ("metrics.csv", "episodes.csv"):
        assert comparable(read_rows(straight / name)) == comparable(read_rows(interrupted / name))
    assert [r["epoch"] for r in read_rows(interrupted / "metrics.csv")] == ["1", "2", "3"]


def test_corrupt_checkpoint_is_a_clear_error(tmp_path, fake_env_factory):
    trainer = Trainer(tiny_config(), tmp_path, fake_env_factory)
    trainer.train(steps=60)
    good = ckpt.latest_checkpoint(tmp_path)
    trainer.train(steps=60)
    trainer.close()
    latest = ckpt.latest_checkpoint(tmp_path)
    assert latest != good and good.exists()  # two kept
    with open(latest / "replay.npz", "r+b") as file:
        file.seek(100)
        file.write(b"garbage")
    with pytest.raises(ckpt.CheckpointError, match="corrupt"):
        Trainer.resume(tmp_path, fake_env_factory)
    (latest / "optimizer.pt").unlink()
    with pytest.raises(ckpt.CheckpointError, match="missing"):
        Trainer.resume(tmp_path, fake_env_factory)
    # the previous checkpoint is intact and still loads
    ckpt.verify_checkpoint(good)
    assert Trainer.resume(tmp_path, fake_env_factory, checkpoint=good).step == 60


def test_failed_save_keeps_the_last_good_checkpoint(tmp_path, fake_env_factory, monkeypatch):
    trainer = Trainer(tiny_config(), tmp_path, fake_env_factory)
    trainer.train(steps=60)
    good = ckpt.latest_checkpoint(tmp_path)

    def disk_full(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(ckpt, "save_arrays", disk_full)
    with pytest.raises(OSError, match="disk full"):
        trainer.train(steps=60)
    trainer.close()
    assert ckpt.list_checkpoints(tmp_path) == [good]
    assert not [p for p in (tmp_path / "checkpoints").iterdir() if p.name.startswith(".")]
    assert Trainer.resume(tmp_path, fake_env_factory).step == 60


def test_missing_checkpoint_and_existing_run(tmp_path, fake_env_factory):
    with pytest.raises(ckpt.CheckpointError, match="no checkpoint"):
        Trainer.resume(tmp_path / "nothing", fake_env_factory)
    trainer = Trainer(tiny_config(), tmp_path, fake_env_factory)
    trainer.train(steps=60)
    trainer.close()
    with pytest.raises(ValueError, match="resume"):
        Trainer(tiny_config(), tmp_path, fake_env_factory)


# ---------------------------------------------------------------------- validation
def test_greedy_episodes_play_each_seed_to_the_end(fake_env_factory):
    env = fake_env_factory()
    seeds = [episode_seed(3, i) for i in range(5)]

    def toward_goal(obs):  # an oracle reading the env's hidden state: always succeeds
        q = np.zeros(9)
        q[0 if env.goal < env.pan else 1] = 1.0
        return q

    records = greedy_episodes(toward_goal, env, seeds, (1, 60, 80))
    assert len(records) == 5
    for seed, record in zip(seeds, records, strict=True):
        env.reset(seed=seed)
        assert record["success_rate"] == 1.0
        assert record["length"] == abs(env.pan - env.goal)  # straight there
        assert record["reward"] == record["length"]

    def stay(obs):  # action 2 does nothing: truncated after 20 steps, partial credit
        q = np.zeros(9)
        q[2] = 1.0
        return q

    for seed, record in zip(seeds, greedy_episodes(stay, env, seeds, (1, 60, 80)), strict=True):
        env.reset(seed=seed)
        assert record["length"] == 20 and record["reward"] == 0
        assert record["success_rate"] == pytest.approx(1 - abs(env.pan - env.goal) / 10)


def test_summary_marks_improvements_only():
    records = [{"success_rate": r, "success": 0.0, "reward": 1.0} for r in (0.5, 0.7)]
    row = summarise_validation(600, records, best_before=0.5)
    assert row["success_rate"] == pytest.approx(0.6) and row["best"] == 1
    assert summarise_validation(600, records, best_before=0.6)["best"] == 0


def best_metadata(run_dir):
    return ckpt.load_tensors(run_dir / "best_policy.safetensors")[1]


def test_validation_keeps_the_best_weights_and_leaves_training_alone(tmp_path, fake_env_factory):
    plain, validated = tmp_path / "plain", tmp_path / "validated"
    train(tiny_config(), plain, fake_env_factory)
    train(tiny_config(eval_interval=30, eval_episodes=4), validated, fake_env_factory)

    # same training: validation plays on an environment of its own
    for name in ("metrics.csv", "episodes.csv"):
        assert comparable(read_rows(plain / name)) == comparable(read_rows(validated / name))

    rows = read_rows(validated / "evaluations.csv")
    assert [int(r["step"]) for r in rows] == [30, 60, 90, 120]
    rates = [float(r["success_rate"]) for r in rows]
    best_index = int(np.argmax(rates))  # first of the best: later ties do not replace it
    assert [int(r["best"]) for r in rows][best_index] == 1
    meta = best_metadata(validated)
    assert meta["step"] == int(rows[best_index]["step"])
    assert meta["validation_success_rate"] == pytest.approx(rates[best_index])

    # the kept weights score what was logged when replayed on the same seeds
    best = load_policy(validated, weights="best")
    env = fake_env_factory()
    seeds = [episode_seed(1000, i) for i in range(4)]

    def q_values(obs):
        with torch.no_grad():
            return best(torch.from_numpy(obs[None])).numpy()[0]

    replay = greedy_episodes(q_values, env, seeds, (1, 60, 80))
    assert np.mean([r["success_rate"] for r in replay]) == pytest.approx(rates[best_index])
    assert plot_run(validated).stat().st_size > 10_000  # validation drawn with the success rate


def test_a_ddqn_run_on_the_match_validates_matches_and_keeps_the_best_reward(tmp_path):
    # a match has no success: every validation scored a success rate of 0, so the first
    # one's weights stayed the best for the whole run, and metrics.csv logged 0% success
    config = tiny_config(
        env_id="ActiveVisionMatch-v0",
        **{"match.ticks": 20},
        total_timesteps=80,
        epoch_steps=20,
        checkpoint_interval=80,
        eval_interval=20,
        eval_episodes=2,
        learning_rate=0.05,  # the weights change between validations
    )
    train(config, tmp_path)
    rows = read_rows(tmp_path / "evaluations.csv")
    assert list(rows[0]) == list(MATCH_EVALUATION_FIELDS)
    rewards = [float(r["episode_reward"]) for r in rows]
    assert len(set(rewards)) > 1  # the check below can tell the first from the best
    best_index = int(np.argmax(rewards))
    assert best_index > 0  # not the first validation's, which was kept before
    assert [int(r["best"]) for r in rows] == [
        int(reward > max(rewards[:i], default=-np.inf)) for i, reward in enumerate(rewards)
    ]
    meta = best_metadata(tmp_path)
    assert meta["step"] == int(rows[best_index]["step"])
    assert meta["validation_episode_reward"] == pytest.approx(rewards[best_index])
    assert all(r["success_rate"] == "nan" for r in read_rows(tmp_path / "metrics.csv"))

    # the last validation (of the final weights) against a loop of its own over the info
    network = load_policy(tmp_path)
    env = make_env(config)
    totals, ball, squared = [], [], []
    for i in range(2):
        obs, _ = env.reset(seed=episode_seed(config.run.eval_seed, i))
        done, total = False, 0.0
        while not done:
            with torch.no_grad():
                q = network(torch.from_numpy(np.asarray(obs).reshape(1, 1, 120, 160)))
            obs, reward, terminated, truncated, info = env.step(int(q.argmax()))
            total += float(reward)
            ball.append(float(info["ball_in_view"]))
            squared.append(float(info["position_error"]) ** 2)
            done = terminated or truncated
        totals.append(total)
    env.close()
    assert float(rows[-1]["episode_reward"]) == pytest.approx(np.mean(totals))
    assert float(rows[-1]["ball_in_view"]) == pytest.approx(np.mean(ball))
    rmse = float(rows[-1]["position_rmse"])
    assert rmse == pytest.approx(np.mean(np.sqrt(np.reshape(squared, (2, 20)).mean(axis=1))))
    plot_run(tmp_path)
    figures = {path.name for path in (tmp_path / "plots").glob("*.png")}
    assert "validation_position_rmse.png" in figures and "success_rate.png" not in figures


def test_resume_restores_validation_state(tmp_path, fake_env_factory):
    config = tiny_config(eval_interval=30, eval_episodes=4)
    straight, interrupted = tmp_path / "straight", tmp_path / "interrupted"
    train(config, straight, fake_env_factory)

    first = Trainer(config, interrupted, fake_env_factory)
    first.train(steps=60)  # checkpoint at 60 after validations at 30 and 60
    for _ in range(35):  # lost progress, including a validation at step 90
        first._env_step()
        if first.step % 30 == 0:
            first.validate()
    first.close()
    resume(interrupted, fake_env_factory)

    assert read_rows(straight / "evaluations.csv") == read_rows(interrupted / "evaluations.csv")
    assert best_metadata(straight) == best_metadata(interrupted)
    a = load_policy(straight, weights="best").state_dict()
    b = load_policy(interrupted, weights="best").state_dict()
    for key in a:
        assert torch.equal(a[key], b[key]), key


def test_best_weights_need_validation(tmp_path, fake_env_factory):
    train(tiny_config(total_timesteps=60), tmp_path, fake_env_factory)
    with pytest.raises(ckpt.CheckpointError, match="eval_interval"):
        load_policy(tmp_path, weights="best")
    with pytest.raises(ValueError, match="weights"):
        load_policy(tmp_path, weights="newest")
    with pytest.raises(ValueError, match="eval_interval"):
        tiny_config(eval_interval=-1)
    with pytest.raises(ValueError, match="eval_episodes"):
        tiny_config(eval_episodes=0)


def test_auxiliary_goal_targets_are_the_goal_offsets_of_each_stored_observation(
    tmp_path, fake_env_factory
):
    config = tiny_config(aux_goal_weight=1.0, total_timesteps=60)
    trainer = Trainer(config, tmp_path, fake_env_factory, aux_target=goal_offset)
    trainer.train()
    buffer = trainer.buffer
    batch = buffer.sample(64, beta=1.0)
    for obs, aux in zip(batch.obs, batch.aux, strict=True):
        columns = obs[0].max(axis=0)  # the fake image: pan column 255, goal column 128 (+1)
        pan = np.flatnonzero(columns == 255)[0] * 10 // obs.shape[-1]
        goal = (np.flatnonzero(columns == 128)[0] - 1) * 10 // obs.shape[-1]
        np.testing.assert_allclose(aux, [0.1 * (goal - pan), 0.0], atol=1e-6)
    network = load_policy(tmp_path)
    assert network.aux_outputs == 2  # the policy file keeps the auxiliary head ...
    obs = torch.from_numpy(batch.obs[:4])
    q_values, _ = network.forward_with_aux(obs)
    torch.testing.assert_close(network(obs), q_values)  # ... which never changes the Q-values
    trainer.close()


def test_auxiliary_goal_task_needs_head_and_goal_in_info():
    with pytest.raises(ValueError, match="goal_viewpoint"):
        goal_offset({"head": np.zeros(2)})
    np.testing.assert_allclose(
        goal_offset({"head": np.array([0.5, 0.2]), "goal_viewpoint": np.array([-0.1, 0.6])}),
        [-0.6, 0.4],
    )


@pytest.mark.parametrize(
    ("env_id", "need"),
    [("CartPole-v1", "need a uint8 Box observation space"), ("Pendulum-v1", "need a Discrete")],
)
def test_a_custom_env_id_the_ddqn_cannot_learn_is_named(tmp_path, env_id, need):
    """``env_id=CartPole-v1`` (vector observations) was "need a uint8 Box observation space,
    got Box(...)", naming neither the field nor the env; an env_factory's env is named as
    such. Nothing is written."""
    config = TrainConfig(env_id=env_id)
    with pytest.raises(ValueError, match=rf"^TrainConfig.env_id '{env_id}': {need}"):
        Trainer(config, tmp_path / "run")
    with pytest.raises(ValueError, match=rf"^env_factory's env: {need}"):
        Trainer(config, tmp_path / "run", env_factory=lambda: gym.make(env_id))
    assert not (tmp_path / "run").exists()


def _earlier_attempt(run: Path) -> list[str]:
    """``run`` as an attempt that stopped before its first checkpoint, with the outputs the
    other commands wrote into it; returns their names."""
    run.mkdir()
    (run / "config.json").write_text("{}")
    (run / "metrics.csv").write_text("epoch,step\r\n")
    for folder in ("plots", "evaluation", "compare", "match", "robustness"):
        (run / folder).mkdir()
        (run / folder / "old.png").write_bytes(b"old")
    for name in ("report.md", "policy.onnx", "policy.json") + ("episode.png", "episode.gif"):
        (run / name).write_bytes(b"old")
    (run / "episode.png.json").write_text("{}")  # what played in the figure (report reads it)
    return sorted(p.name for p in run.iterdir() if p.name not in ("config.json", "metrics.csv"))


@pytest.mark.parametrize("algo", ["ddqn", "dagger"])
def test_a_run_started_over_removes_the_earlier_attempts_outputs(tmp_path, fake_env_factory, algo):
    """``train --out RUN --overwrite`` over an attempt that stopped before its first
    checkpoint kept its figures, report.md and policy.onnx: report and demo read them as
    the new run's. A folder that held no run keeps the same names (the user's files)."""
    from activevision.training.dagger import DaggerTrainer

    def start(run: Path) -> None:
        if algo == "ddqn":
            Trainer(tiny_config(), run, fake_env_factory).close()
        else:  # a StudentRun: DAgger's and SB3's
            config = TrainConfig().replace(**{"algo": "dagger", "dagger.num_envs": 2})
            DaggerTrainer(config, run, loggers=[]).close()

    outputs = _earlier_attempt(tmp_path / "run")
    assert len(outputs) == 11
    start(tmp_path / "run")
    left = sorted(p.name for p in (tmp_path / "run").iterdir())
    assert not set(outputs) & set(left), left
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "report.md").write_text("my notes")
    start(mine)
    assert (mine / "report.md").read_text() == "my notes"
