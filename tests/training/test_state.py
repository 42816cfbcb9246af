"""TrainerState: state.json as a dataclass, its round trip and the check of every field."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from activevision.training import checkpoint as ckpt
from activevision.training.config import TrainConfig
from activevision.training.loggers import LogPosition
from activevision.training.metrics import EpochAccumulator
from activevision.training.state import STATE_FILE, TrainerState, load_checkpoint
from activevision.training.trainer import Trainer

DIGEST = "ab" * 32


def a_state(**changes) -> TrainerState:
    values = dict(
        step=70,
        episode=3,
        rng=np.random.default_rng(5).bit_generator.state,
        epoch_log=EpochAccumulator(
            episodes=[
                {
                    "episode": 3,
                    "step": 64,
                    "reward": 2.0,
                    "length": 20,
                    "success": 0.0,
                    "success_rate": 0.7,
                    "steps_to_success": 20.0,
                    "ball_lost_step": float("nan"),
                }
            ],
            losses=[0.25, 0.125],
        ),
        episode_open=True,
        episode_seed=123,
        episode_actions=(0, 1, 8),
        episode_reward=-1.0,
        obs_sha256=DIGEST,
        metrics_rows=1,
        episodes_rows=3,
        best_eval=0.5,
        best_step=60,
        evaluations_rows=2,
        config_sha256="cd" * 32,
    )
    values.update(changes)
    return TrainerState(**values)


def test_round_trip_keeps_every_field():
    state = a_state()
    text = state.to_json()
    assert list(json.loads(text)) == [f.name for f in dataclasses.fields(TrainerState)]
    back = TrainerState.from_json(text)
    assert back.to_json() == text
    assert back.episode_actions == (0, 1, 8) and back.best_eval == 0.5
    assert np.isnan(back.epoch_log.episodes[0]["ball_lost_step"])
    assert back.log_position == LogPosition(step=70, epochs=1, episodes=3, validations=2)
    between = a_state(
        episode_open=False, obs_sha256=None, best_eval=None, epoch_log=EpochAccumulator()
    )
    assert TrainerState.from_json(between.to_json()) == between


def test_a_checkpoint_holds_the_trainers_state(tmp_path, fake_env_factory):
    config = TrainConfig().replace(
        seed=1, total_timesteps=90, epoch_steps=30, batch_size=8, buffer_size=500,
        learning_starts=10, checkpoint_interval=30, tensorboard=False, progress_bar=False,
        num_threads=1, env_id="unused",
    )  # fmt: skip
    trainer = Trainer(config, tmp_path, fake_env_factory)
    trainer.train(steps=45)
    state = trainer.state()
    trainer.close()
    checkpoint = ckpt.latest_checkpoint(tmp_path)
    assert (checkpoint / STATE_FILE).read_text() == state.to_json()
    loaded = load_checkpoint(tmp_path)
    assert loaded.path == checkpoint and loaded.state.to_json() == state.to_json()
    assert state.step == 45 and state.episode_open and state.metrics_rows == 1
    assert state.episodes_rows == state.episode == trainer.episode
    assert loaded.weights("online").keys() == trainer.learner.online.state_dict().keys()
    assert not loaded.weights("best")  # no validation in this run


def tampered(change) -> str:
    values = json.loads(a_state().to_json())
    change(values)
    return json.dumps(values)


BAD_FIELDS = [
    # (what, change, what the error must name)
    ("step a string", lambda s: s.update(step="soon"), "'step'"),
    ("step negative", lambda s: s.update(step=-1), "'step'"),
    ("step a bool", lambda s: s.update(step=True), "'step'"),
    ("episode a float", lambda s: s.update(episode=2.5), "'episode'"),
    ("rng not a state", lambda s: s.update(rng={"bit_generator": "MT19937"}), "'rng'"),
    ("rng a list", lambda s: s.update(rng=[1, 2]), "'rng'"),
    ("epoch_log lacks losses", lambda s: s["epoch_log"].pop("losses"), "'epoch_log'"),
    ("epoch_log bad loss", lambda s: s["epoch_log"].update(losses=["x"]), "'epoch_log'"),
    ("epoch_log bad episode", lambda s: s["epoch_log"].update(episodes=[{"a": 1}]), "'epoch_log'"),
    ("episode_open a number", lambda s: s.update(episode_open=1), "'episode_open'"),
    ("episode_seed too large", lambda s: s.update(episode_seed=2**40), "'episode_seed'"),
    ("episode_actions a dict", lambda s: s.update(episode_actions={}), "'episode_actions'"),
    ("negative action", lambda s: s.update(episode_actions=[1, -2]), "'episode_actions'"),
    ("episode_reward a string", lambda s: s.update(episode_reward="1"), "'episode_reward'"),
    ("obs_sha256 not hex", lambda s: s.update(obs_sha256="zz"), "'obs_sha256'"),
    ("obs_sha256 missing for an open episode", lambda s: s.update(obs_sha256=None), "obs_sha256"),
    ("metrics_rows negative", lambda s: s.update(metrics_rows=-3), "'metrics_rows'"),
    ("episodes_rows null", lambda s: s.update(episodes_rows=None), "'episodes_rows'"),
    ("best_eval infinite", lambda s: s.update(best_eval=float("inf")), "'best_eval'"),
    ("best_step a string", lambda s: s.update(best_step="60"), "'best_step'"),
    ("evaluations_rows a list", lambda s: s.update(evaluations_rows=[]), "'evaluations_rows'"),
    ("config_sha256 short", lambda s: s.update(config_sha256="abc"), "'config_sha256'"),
    ("a field missing", lambda s: s.pop("episode_seed"), "episode_seed"),
    ("two fields missing", lambda s: (s.pop("best_step"), s.pop("step")), "step, best_step"),
    ("an unknown field", lambda s: s.update(extra=1), "extra"),
    ("no config checksum", lambda s: s.pop("config_sha256"), "older activevision"),
]


@pytest.mark.parametrize(
    ("change", "needle"), [b[1:] for b in BAD_FIELDS], ids=[b[0] for b in BAD_FIELDS]
)
def test_every_field_is_checked_on_read(change, needle):
    with pytest.raises(ckpt.CheckpointError, match=r"state\.json") as error:
        TrainerState.from_json(tampered(change), "run/checkpoints/step_000000070/state.json")
    assert needle in str(error.value)


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("[]", "JSON object"),
        ("{", "cannot read"),
        ("3", "JSON object"),
        ('{"step": 1, "step": 2}', "duplicate key 'step'"),  # the last one was taken
    ],
)
def test_not_an_object_is_refused(text, needle):
    with pytest.raises(ckpt.CheckpointError, match=needle):
        TrainerState.from_json(text)


def test_the_same_weights_and_metadata_are_the_same_bytes(tmp_path):
    import torch

    # safetensors keeps metadata in a hash map whose order changes map to map: five saves
    # of twelve keys come out in (almost surely) different orders unless the writer sorts
    tensors = {"b.weight": torch.arange(6.0).reshape(2, 3), "a.bias": torch.ones(3)}
    metadata = {f"key{i}": [i, "ü"] for i in range(12)}
    files = []
    for i in range(5):
        ckpt.save_tensors(tmp_path / f"{i}.safetensors", tensors, dict(reversed(metadata.items())))
        files.append((tmp_path / f"{i}.safetensors").read_bytes())
    assert len(set(files)) == 1
    loaded, read = ckpt.load_tensors(tmp_path / "0.safetensors")
    assert read == metadata
    assert all(torch.equal(loaded[k], tensors[k]) for k in tensors)


def test_weights_writes_a_kill_left_behind_are_removed(tmp_path):
    """A trainer killed while it wrote policy.safetensors (atomically, through a hidden temp
    file) left that file in the run for good, one more with each kill; other files stay."""
    stale = [tmp_path / ".policy.safetensors.a1b2.tmp", tmp_path / ".best_policy.safetensors.x.tmp"]
    kept = [tmp_path / ".report.md.c3d4.tmp", tmp_path / "policy.safetensors"]
    for path in stale + kept:
        path.write_bytes(b"\0" * 100)
    assert sorted(ckpt.remove_stale_writes(tmp_path)) == sorted(stale)
    assert not any(p.exists() for p in stale) and all(p.exists() for p in kept)


def test_a_checkpoint_write_on_a_full_disk_names_the_checkpoint(tmp_path):
    """``train`` on a full disk ended in "[Errno 28] No space left on device" alone."""

    def write_files(directory):
        raise OSError(28, "No space left on device")  # what the weights file's write() raises

    with pytest.raises(OSError) as caught:
        ckpt.write_checkpoint(tmp_path, 30, write_files)
    final = tmp_path / "checkpoints" / "step_000000030"
    assert str(caught.value) == f"[Errno 28] cannot write {final}: No space left on device"
    assert list((tmp_path / "checkpoints").iterdir()) == []  # nor the temporary folder


def test_a_manifest_that_lists_a_file_twice_is_refused(tmp_path):
    """json.loads kept the manifest's last entry of a file named twice, unsaid."""
    checkpoint = tmp_path / "step_000000070"
    checkpoint.mkdir()
    (checkpoint / ckpt.MANIFEST).write_text('{"state.json": 1, "state.json": 2}')
    with pytest.raises(ckpt.CheckpointError, match="no readable manifest: duplicate key"):
        ckpt.verify_checkpoint(checkpoint, ("state.json",))
