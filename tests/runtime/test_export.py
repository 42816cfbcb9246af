"""ONNX export: outputs match PyTorch, metadata is complete, files are written atomically."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import onnxruntime as ort
import pytest
import torch

import activevision
from activevision.export import export_onnx, policy_metadata
from activevision.geometry import CameraConfig
from activevision.runtime import load_metadata


def onnx_q(model_path, batch: np.ndarray) -> np.ndarray:
    session = ort.InferenceSession(str(model_path), providers=["CPUExecutionProvider"])
    return np.concatenate([session.run(None, {"frames": b[None]})[0] for b in batch])


def torch_q(network, batch: np.ndarray) -> np.ndarray:
    with torch.inference_mode():
        return network(torch.from_numpy(batch)).numpy()


def test_onnx_matches_torch_on_real_frames(policy, frames):
    batch = frames(160, 120)[:, None]  # (4, 1, 120, 160) uint8
    got, want = onnx_q(policy.model_path, batch), torch_q(policy.network, batch)
    assert np.abs(got - want).max() <= 1e-4


@pytest.mark.parametrize(
    ("stack", "dueling", "options"),
    [(3, False, {}), (1, True, {"fold_scaling": False}), (1, False, {"dynamic_batch": True})],
)
def test_variants_match_torch(tmp_path, frames, helpers, stack, dueling, options):
    network = helpers.make_network(stack=stack, seed=stack, dueling=dueling)
    paths = helpers.export(network, tmp_path, **options)
    images = frames(160, 120)
    batch = np.stack([np.roll(images, shift, axis=0)[:stack] for shift in range(4)])
    got, want = onnx_q(paths.model_path, batch), torch_q(network, batch)
    assert np.abs(got - want).max() <= 1e-4
    if options.get("dynamic_batch"):
        session = ort.InferenceSession(str(paths.model_path), providers=["CPUExecutionProvider"])
        assert np.abs(session.run(None, {"frames": batch})[0] - want).max() <= 1e-4


def test_metadata_contents(policy):
    meta = json.loads(policy.metadata_path.read_text())
    assert meta["image_height"] == 120 and meta["image_width"] == 160 and meta["stack"] == 1
    assert meta["package_version"] == activevision.__version__
    assert meta["opset"] == 17 and meta["input_dtype"] == "uint8"
    assert meta["model_sha256"] == hashlib.sha256(policy.model_path.read_bytes()).hexdigest()
    assert meta["head_limits_deg"] == pytest.approx(
        {"pan_min": -90.0, "pan_max": 90.0, "tilt_min": 5.0, "tilt_max": 65.0}
    )
    assert np.asarray(meta["action_table_deg"])[1] == pytest.approx([3.0, 0.0])
    parsed = load_metadata(policy.metadata_path)
    assert parsed.n_actions == 9 and parsed.input_shape == (1, 120, 160)
    cam = CameraConfig()
    assert parsed.head_limits.pan_max == pytest.approx(cam.pan_max, abs=1e-12)
    assert parsed.head_limits.tilt_min == pytest.approx(cam.tilt_min, abs=1e-12)


def test_export_to_directory_replaces_atomically(tmp_path, helpers):
    first = helpers.export(helpers.make_network(seed=1), tmp_path)
    metadata = policy_metadata(helpers.eight_way_table(), CameraConfig(), "ab" * 32)
    second = export_onnx(helpers.make_network(seed=2), tmp_path, metadata)
    assert second == first  # directory -> policy.onnx + policy.json in it
    assert sorted(p.name for p in tmp_path.iterdir()) == ["policy.json", "policy.onnx"]
    assert json.loads(second.metadata_path.read_text())["training_config_sha256"] == "ab" * 32


def test_export_rejects_metadata_that_does_not_fit(tmp_path, helpers):
    network = helpers.make_network()
    metadata = policy_metadata(helpers.eight_way_table()[:5], CameraConfig())
    with pytest.raises(ValueError, match="5 rows"):
        export_onnx(network, tmp_path / "p.onnx", metadata)
    metadata = policy_metadata(helpers.eight_way_table(), CameraConfig())
    with pytest.raises(ValueError, match="stack"):
        export_onnx(network, tmp_path / "p.onnx", {**metadata, "stack": 2})
    with pytest.raises(ValueError, match="head_limits_deg"):
        export_onnx(network, tmp_path / "p.onnx", {"action_table_deg": [[0, 0]] * 9})
    assert not any(tmp_path.iterdir())  # nothing written, no temporary files left


def test_export_run(tmp_path, frames):
    try:
        from activevision.envs.actions import action_table
        from activevision.training.checkpoint import save_tensors
    except Exception as error:  # another subpackage is broken or absent
        pytest.skip(f"activevision.envs / training not importable: {error}")
    from activevision.export import export_run

    torch.manual_seed(5)
    from activevision.agents.q_network import QNetwork

    network = QNetwork(9).eval()
    run = tmp_path / "run"
    run.mkdir()
    config = json.dumps({"seed": 0, "env_kwargs": {"step_deg": 4.0}}).encode()
    (run / "config.json").write_bytes(config)
    shape = {"n_actions": 9, "stack": 1, "image_shape": [120, 160], "dueling": False}
    save_tensors(run / "policy.safetensors", network.state_dict(), shape)

    paths = export_run(run, tmp_path / "out" / "policy.onnx")
    meta = load_metadata(paths.metadata_path)
    assert meta.training_config_sha256 == hashlib.sha256(config).hexdigest()
    # and the weights it was exported from, so that report tells an export from before the
    # run was trained on (policy.json recorded the config's digest alone)
    final = hashlib.sha256((run / "policy.safetensors").read_bytes()).hexdigest()
    assert (meta.training_weights, meta.training_weights_sha256) == ("final", final)
    best = dict(shape, step=7, validation_success_rate=0.5)
    save_tensors(run / "best_policy.safetensors", network.state_dict(), best)
    meta = load_metadata(export_run(run, tmp_path / "best", weights="best").metadata_path)
    digest = hashlib.sha256((run / "best_policy.safetensors").read_bytes()).hexdigest()
    assert (meta.training_weights, meta.training_weights_sha256) == ("best", digest)
    assert digest != final
    np.testing.assert_allclose(meta.action_table, action_table(4.0), atol=1e-12)
    batch = frames(160, 120)[:, None]
    assert np.abs(onnx_q(paths.model_path, batch) - torch_q(network, batch)).max() <= 1e-4


def test_export_run_refuses_a_config_edited_after_training(tmp_path):
    """config.json edited after the newest checkpoint (its SHA-256 is in state.json): the
    export would have recorded the edited moves (5 degrees a step for a 3-degree policy)."""
    from activevision.agents.q_network import QNetwork
    from activevision.export import export_run
    from activevision.training.checkpoint import CheckpointError, save_tensors

    run = tmp_path / "run"
    checkpoint = run / "checkpoints" / "step_000000300"
    checkpoint.mkdir(parents=True)
    config = json.dumps({"seed": 0, "env": {"step_deg": 3.0}}).encode()
    (run / "config.json").write_bytes(config)
    digest = hashlib.sha256(config).hexdigest()
    (checkpoint / "state.json").write_text(json.dumps({"config_sha256": digest}))
    shape = {"n_actions": 9, "stack": 1, "image_shape": [120, 160], "dueling": False}
    save_tensors(run / "policy.safetensors", QNetwork(9).state_dict(), shape)
    export_run(run, tmp_path / "ok" / "policy.onnx")  # unchanged: exported
    (run / "config.json").write_text(json.dumps({"seed": 0, "env": {"step_deg": 5.0}}))
    message = r"config\.json was changed after checkpoint step_000000300: policy\.json would"
    with pytest.raises(CheckpointError, match=message):
        export_run(run, tmp_path / "edited" / "policy.onnx")
    assert not (tmp_path / "edited").exists()


@pytest.mark.parametrize("action_type", ["continuous", "discrete"])
def test_export_run_records_the_moves_the_policy_makes(tmp_path, action_type):
    """A continuous policy moves by ``max_move_deg``; its policy.json recorded the
    ``step_deg`` (and ``action_set``) of its config, a field a continuous run never reads
    (here 4 degrees, as a --config file may carry: the runtime never read it either). It
    records its max move alone, beside the paper's discrete table (3 degrees, 8 ways); a
    discrete policy's step stays its own (its actions index that table)."""
    try:
        from activevision.agents.q_network import QNetwork
        from activevision.agents.student import StudentNetwork
        from activevision.envs.actions import action_table
        from activevision.training import preset, save_config
        from activevision.training.checkpoint import save_tensors
    except Exception as error:  # another subpackage is broken or absent
        pytest.skip(f"activevision.envs / training not importable: {error}")
    from activevision.export import export_run

    run = tmp_path / "run"
    run.mkdir()
    torch.manual_seed(0)
    if action_type == "continuous":
        config = preset("dagger_head_continuous").replace(**{"dagger.act_by": "action"})
        network: torch.nn.Module = StudentNetwork(2, 2, continuous=True).eval()
        shape = network.metadata()
    else:
        config = preset("paper")
        network = QNetwork(9).eval()
        shape = {"n_actions": 9, "stack": 1, "image_shape": [120, 160], "dueling": False}
    save_config(config, run / "config.json")
    values = json.loads((run / "config.json").read_text())
    values["env"]["step_deg"] = 4.0  # carried by the file: --set refuses it for continuous
    (run / "config.json").write_text(json.dumps(values))
    save_tensors(run / "policy.safetensors", network.state_dict(), shape)

    written = json.loads(export_run(run, tmp_path / "out", verify=False).metadata_path.read_text())
    meta = load_metadata(tmp_path / "out" / "policy.json")
    if action_type == "continuous":
        assert "step_deg" not in written and "action_set" not in written
        assert written["max_move_deg"] == list(config.env.max_move_deg) == [10.0, 10.0]
        assert (meta.step_deg, meta.action_set) == (None, None)
        np.testing.assert_allclose(meta.action_table, action_table(3.0, "8way"), atol=1e-9)
    else:
        assert (written["step_deg"], written["action_set"]) == (4.0, "8way")
        assert "max_move_deg" not in written
        np.testing.assert_allclose(meta.action_table, action_table(4.0, "8way"), atol=1e-9)


def test_an_older_continuous_policy_json_with_its_step_still_reads():
    """The shipped policy (continuous) was exported with ``step_deg`` and ``action_set``:
    it reads as before (the file's bytes are not rewritten)."""
    from activevision.runtime import pretrained_policy_path

    meta = load_metadata(pretrained_policy_path().with_suffix(".json"))
    assert meta.action_type == "continuous"
    assert (meta.step_deg, meta.action_set) == (3.0, "8way")
    assert meta.max_move == pytest.approx((np.radians(10.0), np.radians(10.0)))
