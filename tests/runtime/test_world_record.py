"""policy.json's training world: written by export from the run's ``env.appearance`` and
``env.robots``, checked for shape on read (no envs or rendering import), absent in old files."""

from __future__ import annotations

import json
import shutil

import pytest

from activevision.envs.robots import RobotsConfig
from activevision.export import export_onnx, policy_metadata
from activevision.rendering.appearance import AppearanceConfig
from activevision.runtime import (
    HeadController,
    load_metadata,
    pretrained_policy_path,
)
from activevision.training.presets import preset
from activevision.typecheck import config_from_dict, config_to_dict

ROBUST = AppearanceConfig.randomised()
ROBOTS = RobotsConfig(count=(1, 2), height=(0.5, 0.9), radius=0.1)


def clean_world() -> dict:
    return {
        "appearance": config_to_dict(AppearanceConfig()),
        "robots": config_to_dict(RobotsConfig()),
    }


@pytest.fixture
def world_policy(policy, tmp_path):
    """A copy of the session policy whose policy.json records the clean world."""
    model = tmp_path / "policy.onnx"
    shutil.copy(policy.model_path, model)
    values = json.loads(policy.metadata_path.read_text())
    values["world"] = clean_world()
    model.with_suffix(".json").write_text(json.dumps(values))
    return model


def test_export_onnx_writes_the_world_and_it_round_trips(tmp_path, helpers):
    from activevision.geometry import CameraConfig

    world = {"appearance": ROBUST, "robots": ROBOTS}
    metadata = policy_metadata(helpers.eight_way_table(), CameraConfig(), world=world)
    paths = export_onnx(helpers.make_network(seed=4), tmp_path, metadata, verify=False)
    record = json.loads(paths.metadata_path.read_text())["world"]
    assert record == {"appearance": config_to_dict(ROBUST), "robots": config_to_dict(ROBOTS)}
    assert record["robots"]["count"] == [1, 2] and record["robots"]["radius"] == 0.1
    got = load_metadata(paths.metadata_path).world
    assert got == record
    assert config_from_dict(AppearanceConfig, got["appearance"]) == ROBUST
    assert config_from_dict(RobotsConfig, got["robots"]) == ROBOTS
    assert HeadController(paths.model_path).metadata.world == record


def test_export_run_writes_the_runs_world(tmp_path):
    try:
        from activevision.training import TrainConfig, apply_overrides, save_config
        from activevision.training.checkpoint import save_tensors
    except Exception as error:  # another subpackage is broken or absent
        pytest.skip(f"activevision.training not importable: {error}")
    from activevision.agents.q_network import QNetwork
    from activevision.export import export_run

    # the settings `activevision train --set env.robots.count=[1,2] ...` applies
    config = apply_overrides(
        TrainConfig(), ["env.robots.count=[1,2]", "env.appearance.gain=[0.8,1.2]"]
    )
    run = tmp_path / "run"
    run.mkdir()
    save_config(config, run / "config.json")
    network = QNetwork(9).eval()
    shape = {"n_actions": 9, "stack": 1, "image_shape": [120, 160], "dueling": False}
    save_tensors(run / "policy.safetensors", network.state_dict(), shape)

    paths = export_run(run, tmp_path / "out", verify=False)
    world = load_metadata(paths.metadata_path).world
    assert world is not None
    assert world["robots"]["count"] == [1, 2]
    assert world["appearance"]["gain"] == [0.8, 1.2]
    assert config_from_dict(RobotsConfig, world["robots"]) == config.env.robots
    assert config_from_dict(AppearanceConfig, world["appearance"]) == config.env.appearance


def test_shipped_policy_records_its_randomised_world():
    # the shipped policy is the dagger_robust_continuous preset's run
    world = load_metadata(pretrained_policy_path().with_suffix(".json")).world
    assert world is not None and world != clean_world()
    recipe = preset("dagger_robust_continuous").env.appearance  # wider textures, a quarter clean
    assert recipe != AppearanceConfig.randomised()
    assert config_from_dict(AppearanceConfig, world["appearance"]) == recipe
    assert config_from_dict(RobotsConfig, world["robots"]).count == (0, 4)


def test_metadata_without_the_record_loads(policy):
    assert "world" not in json.loads(policy.metadata_path.read_text())
    assert load_metadata(policy.metadata_path).world is None


def test_the_record_is_a_plain_copy(world_policy):
    meta = load_metadata(world_policy.with_suffix(".json"))
    assert meta.world == clean_world()
    meta.world["robots"]["count"][1] = 7  # the caller's copy
    assert meta.raw["world"]["robots"]["count"] == [0, 0]


@pytest.mark.parametrize(
    ("record", "message"),
    [
        ([1, 2], "'world' must be an object of objects"),
        ("clean", "'world' must be an object of objects"),
        ({"robots": [0, 4]}, "'world' must be an object of objects .*; 'robots' is"),
        ({"robots": {"count": [0]}}, r"'world' robots.count must be a finite number or a \[low"),
        ({"robots": {"count": [0, 1, 2]}}, "'world' robots.count must be"),
        ({"robots": {"count": [0, "4"]}}, "'world' robots.count must be"),
        ({"robots": {"count": [0, True]}}, "'world' robots.count must be"),
        ({"robots": {"radius": None}}, "'world' robots.radius must be"),
        ({"robots": {"radius": "0.1"}}, "'world' robots.radius must be"),
        ({"robots": {"count": [[0, 1], 2]}}, "'world' robots.count must be"),
        ({"appearance": {"gain": [1.0, float("nan")]}}, "'world' appearance.gain must be"),
        ({"appearance": {"gain": [1.0, float("inf")]}}, "'world' appearance.gain must be"),
        ({"appearance": {"gain": [1.0, 10**400]}}, "'world' appearance.gain must be"),
        ({"appearance": {"gain": {"low": 1.0}}}, "'world' appearance.gain must be"),
    ],
)
def test_a_bad_record_is_one_policy_file_error(world_policy, record, message, helpers):
    helpers.assert_record_rejected(world_policy, "world", record, message)
