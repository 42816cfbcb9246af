import csv

import numpy as np
import pytest
import torch

from activevision.agents.q_network import QNetwork
from activevision.training import checkpoint as ckpt
from activevision.training.config import TrainConfig
from activevision.training.metrics import EPOCH_FIELDS, TIMING_FIELDS
from activevision.training.plots import CURVES, plot_run
from activevision.training.trainer import Trainer, load_policy, resume, train


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
    return TrainConfig(**values)


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


def comparable(rows):
    return [{k: v for k, v in row.items() if k not in TIMING_FIELDS} for row in rows]


def test_resume_gives_exactly_the_uninterrupted_result(tmp_path, fake_env_factory):
    config = tiny_config()
    straight, interrupted = tmp_path / "straight", tmp_path / "interrupted"
    train(config, straight, fake_env_factory)

    first = Trainer(config, interrupted, fake_env_factory)
    first.train(steps=60)  # one epoch: checkpoint at step 60
    first.train(steps=10)  # stops mid-epoch: checkpoint at step 70 ...
    assert first._obs is not None  # ... which falls inside an episode
    for _ in range(25):  # progress after the checkpoint, lost in a "crash"
        first._env_step()
    first.close()
    resume(interrupted, fake_env_factory)  # redoes it exactly

    for name in ("metrics.csv", "episodes.csv"):
        assert comparable(read_rows(straight / name)) == comparable(read_rows(interrupted / name))
    a, b = load_policy(straight).state_dict(), load_policy(interrupted).state_dict()
    for key in a:
        assert torch.equal(a[key], b[key]), key


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
