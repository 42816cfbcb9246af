"""policy.json's trained camera: written by export, validated on read, compared by
HeadController with the robot's camera (one CameraMismatchWarning naming each difference)."""

from __future__ import annotations

import dataclasses
import json
import math
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from activevision.export import export_onnx, policy_metadata
from activevision.geometry import CameraConfig
from activevision.runtime import (
    CameraMismatchWarning,
    CameraModel,
    HeadController,
    load_metadata,
    pretrained_policy_path,
)

#: The camera the test policies are recorded as trained with (not the default one).
TRAINED = CameraConfig(hfov=1.1, camera_height=0.55, tilt_min=math.radians(10.0))
LIMIT_KEYS = ("pan_min", "pan_max", "tilt_min", "tilt_max")


def assert_same_camera(got: CameraModel | None, want) -> None:
    assert got is not None
    for f in dataclasses.fields(CameraModel):
        assert getattr(got, f.name) == pytest.approx(getattr(want, f.name), abs=1e-12), f.name


@pytest.fixture
def camera_policy(policy, tmp_path):
    """A copy of the session policy whose policy.json records TRAINED as its camera."""
    model = tmp_path / "policy.onnx"
    shutil.copy(policy.model_path, model)
    values = json.loads(policy.metadata_path.read_text())
    assert "camera" not in values  # exported without camera=: a file from before the record
    values["camera"] = CameraModel.of(TRAINED).to_json()
    # export writes the trained camera's range as the head limits too (they must agree)
    values["head_limits_deg"] = {k: math.degrees(getattr(TRAINED, k)) for k in LIMIT_KEYS}
    model.with_suffix(".json").write_text(json.dumps(values))
    return model


def rewrite_camera(model, **changes) -> None:
    path = model.with_suffix(".json")
    values = json.loads(path.read_text())
    values["camera"] = {**values["camera"], **changes}
    path.write_text(json.dumps(values))


# ---------------------------------------------------------------- the record
def test_record_in_degrees_and_round_trip(camera_policy):
    record = CameraModel.of(TRAINED).to_json()
    assert record == pytest.approx(
        {
            "width_px": 160,
            "height_px": 120,
            "hfov_deg": math.degrees(1.1),
            "camera_height_m": 0.55,
            "pan_min_deg": -90.0,
            "pan_max_deg": 90.0,
            "tilt_min_deg": 10.0,
            "tilt_max_deg": 65.0,
        }
    )
    assert isinstance(record["width_px"], int) and isinstance(record["height_px"], int)
    assert_same_camera(load_metadata(camera_policy.with_suffix(".json")).camera, TRAINED)
    by_degrees = CameraModel.from_degrees(160, 120, math.degrees(1.1), 0.55, (-90, 90), (10, 65))
    assert_same_camera(by_degrees, TRAINED)


def test_export_onnx_writes_the_camera(tmp_path, helpers):
    metadata = policy_metadata(helpers.eight_way_table(), TRAINED, camera=TRAINED)
    paths = export_onnx(helpers.make_network(seed=3), tmp_path, metadata, verify=False)
    assert json.loads(paths.metadata_path.read_text())["camera"]["camera_height_m"] == 0.55
    assert_same_camera(load_metadata(paths.metadata_path).camera, TRAINED)
    assert_same_camera(HeadController(paths.model_path).trained_camera, TRAINED)


def test_export_run_writes_the_runs_camera(tmp_path):
    try:
        from activevision.training import TrainConfig, apply_overrides, save_config
        from activevision.training.checkpoint import save_tensors
    except Exception as error:  # another subpackage is broken or absent
        pytest.skip(f"activevision.training not importable: {error}")
    from activevision.agents.q_network import QNetwork
    from activevision.export import export_run

    # the settings `activevision train --set env.camera.hfov=1.2 ...` applies
    config = apply_overrides(
        TrainConfig(),
        ["env.camera.hfov=1.2", "env.camera.camera_height=0.62", "env.camera.tilt_max=1.0"],
    )
    assert config.env.camera == CameraConfig(hfov=1.2, camera_height=0.62, tilt_max=1.0)
    run = tmp_path / "run"
    run.mkdir()
    save_config(config, run / "config.json")
    network = QNetwork(9).eval()
    shape = {"n_actions": 9, "stack": 1, "image_shape": [120, 160], "dueling": False}
    save_tensors(run / "policy.safetensors", network.state_dict(), shape)

    paths = export_run(run, tmp_path / "out", verify=False)
    record = json.loads(paths.metadata_path.read_text())["camera"]
    assert record["hfov_deg"] == pytest.approx(math.degrees(1.2))
    assert record["camera_height_m"] == 0.62
    assert record["tilt_max_deg"] == pytest.approx(math.degrees(1.0))
    assert_same_camera(load_metadata(paths.metadata_path).camera, config.env.camera)


def test_shipped_policy_records_the_default_camera():
    path = pretrained_policy_path()
    assert_same_camera(load_metadata(path.with_suffix(".json")).camera, CameraConfig())
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the checksum still matches; the camera is the same
        controller = HeadController(path, camera=CameraConfig(width=640, height=480))
    assert_same_camera(controller.trained_camera, CameraConfig())


def test_metadata_without_the_record_loads(policy):
    assert load_metadata(policy.metadata_path).camera is None
    robot = CameraModel.from_degrees(1280, 720, 90.0, 1.2, (-30, 30), (0, 20))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing to compare with: no warning
        controller = HeadController(policy.model_path, camera=robot)
    assert controller.trained_camera is None and controller.robot_camera == robot


@pytest.mark.parametrize("record", [[160, 120], "160x120", {"width_px": 160, "height_px": 120}])
def test_malformed_record_is_a_policy_file_error(camera_policy, record, helpers):
    message = "'camera' must be an object with keys"
    helpers.assert_record_rejected(camera_policy, "camera", record, message)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"width_px": 0}, "width must be a positive integer"),
        ({"height_px": 12.5}, "height must be a positive integer"),
        ({"width_px": True}, "width must be a positive integer"),
        ({"hfov_deg": "58"}, "hfov_deg must be a number"),
        ({"hfov_deg": 0.0}, "hfov must lie in"),
        ({"hfov_deg": 200.0}, "hfov must lie in"),
        ({"hfov_deg": float("nan")}, "hfov must be a finite number"),
        ({"hfov_deg": 10**400}, "hfov must be a finite number"),
        ({"camera_height_m": -0.5}, "camera_height must be positive"),
        ({"camera_height_m": None}, "camera_height must be a finite number"),
        ({"tilt_max_deg": 120.0}, "tilt_max = 120"),
        ({"pan_min_deg": 90.0, "pan_max_deg": -90.0}, "must be ordered"),
        ({"hfov_deg": 1.1}, r"hfov_deg must be degrees, at least 5; got 1\.1 \(radians\?\)"),
        ({"width_px": 640}, r"is 640x120 px \(aspect 5\.333\) but the policy's input is 160x120"),
        ({"height_px": 90}, r"is 160x90 px \(aspect 1\.778\) but the policy's input is 160x120"),
    ],
)
def test_invalid_value_is_a_policy_file_error(camera_policy, changes, message, helpers):
    record = {**CameraModel.of(TRAINED).to_json(), **changes}
    helpers.assert_record_rejected(camera_policy, "camera", record, f"'camera' .*{message}")


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"tilt_min_deg": 5.0}, "'camera' tilt_min_deg = 5 but 'head_limits_deg' tilt_min = 10"),
        ({"pan_max_deg": 60.0}, "'camera' pan_max_deg = 60 but 'head_limits_deg' pan_max = 90"),
        ({"pan_min_deg": -45.0}, "'camera' pan_min_deg = -45 but 'head_limits_deg' pan_min = -90"),
        ({"tilt_max_deg": 50.0}, "'camera' tilt_max_deg = 50 but 'head_limits_deg' tilt_max = 65"),
    ],
)
def test_camera_range_must_agree_with_the_head_limits(camera_policy, changes, message, helpers):
    """The recorded camera's pan/tilt range and the head limits are written from the same
    camera; a file where they disagree is refused, naming both values (it was accepted)."""
    record = {**CameraModel.of(TRAINED).to_json(), **changes}
    helpers.assert_record_rejected(camera_policy, "camera", record, message)


def test_head_limits_must_agree_with_the_camera_range(camera_policy, helpers):
    limits = {"pan_min": -90.0, "pan_max": 90.0, "tilt_min": 5.0, "tilt_max": 65.0}
    message = "'camera' tilt_min_deg = 10 but 'head_limits_deg' tilt_min = 5 degrees"
    helpers.assert_record_rejected(camera_policy, "head_limits_deg", limits, message)


def test_a_record_of_another_resolution_at_the_inputs_aspect_loads(camera_policy):
    rewrite_camera(camera_policy, width_px=640, height_px=480)  # the robot's resolution
    assert HeadController(camera_policy).trained_camera.aspect == pytest.approx(160 / 120)


def test_robot_camera_must_be_a_camera(camera_policy):
    with pytest.raises(TypeError, match="CameraModel or CameraConfig"):
        HeadController(camera_policy, camera={"hfov": 1.0})
    with pytest.raises(ValueError, match="hfov"):
        CameraModel.from_degrees(160, 120, 190.0, 0.5, (-90, 90), (5, 65))
    with pytest.raises(ValueError, match="ordered"):
        CameraModel.from_degrees(160, 120, 60.0, 0.5, (-90, 90), (65, 5))
    with pytest.raises(ValueError, match="hfov_deg must be a finite number of degrees"):
        CameraModel.from_degrees(160, 120, "70", 0.5, (-90, 90), (5, 65))
    with pytest.raises(ValueError, match=r"hfov_deg must be degrees, at least 5; got 1\.22"):
        CameraModel.from_degrees(160, 120, 1.22, 0.5, (-90, 90), (5, 65))  # radians
    with pytest.raises(ValueError, match=r"camera_height must be metres, at most 5; got 62"):
        CameraModel.from_degrees(160, 120, 60.0, 62, (-90, 90), (5, 65))  # centimetres
    with pytest.raises(ValueError, match="tilt_deg must be a finite"):
        CameraModel.from_degrees(160, 120, 60.0, 0.5, (-90, 90), (5, None))
    with pytest.raises(ValueError, match="a \\(min, max\\) pair"):
        CameraModel.from_degrees(160, 120, 60.0, 0.5, 90, (5, 65))


# ---------------------------------------------------------------- the warning
def build(camera_policy, robot) -> list[warnings.WarningMessage]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        HeadController(camera_policy, camera=robot)
    return caught


@pytest.mark.parametrize(
    "robot",
    [
        TRAINED,  # the trained camera itself
        CameraModel.of(TRAINED),
        dataclasses.replace(TRAINED, width=640, height=480),  # same 4:3, any resolution
        dataclasses.replace(TRAINED, width=320, height=240),
        dataclasses.replace(TRAINED, width=333, height=250),  # 1.332 vs 1.333
        dataclasses.replace(TRAINED, hfov=TRAINED.hfov + math.radians(0.9)),  # within 1 deg
        dataclasses.replace(TRAINED, camera_height=0.565),  # within 2 cm
        dataclasses.replace(TRAINED, tilt_max=TRAINED.tilt_max - math.radians(0.5)),
    ],
)
def test_no_warning_for_the_trained_camera(camera_policy, robot):
    assert build(camera_policy, robot) == []


@pytest.mark.parametrize(
    ("changes", "lines"),
    [
        ({"hfov": 1.2}, ["hfov: robot 68.8 deg, trained 63.0 deg"]),
        ({"camera_height": 0.62}, ["camera_height: robot 0.620 m, trained 0.550 m"]),
        (
            {"tilt_min": math.radians(2.0), "tilt_max": math.radians(60.0)},
            [
                "tilt_min: robot 2.0 deg, trained 10.0 deg",
                "tilt_max: robot 60.0 deg, trained 65.0 deg",
            ],
        ),
        (
            {"pan_min": -1.0, "pan_max": 1.0},
            [
                "pan_min: robot -57.3 deg, trained -90.0 deg",
                "pan_max: robot 57.3 deg, trained 90.0 deg",
            ],
        ),
        (
            {"width": 1280, "height": 720},
            ["aspect ratio (width/height): robot 1280x720 px = 1.778, trained 160x120 px = 1.333"],
        ),
    ],
)
def test_warning_names_each_difference(camera_policy, changes, lines):
    robot = dataclasses.replace(TRAINED, **changes)
    caught = build(camera_policy, robot)
    assert len(caught) == 1 and caught[0].category is CameraMismatchWarning
    assert issubclass(CameraMismatchWarning, UserWarning)
    assert caught[0].filename == __file__  # points at the caller's HeadController(...)
    message = str(caught[0].message)
    for line in lines:
        assert f"  - {line}" in message
    assert message.count("\n  - ") == len(lines)  # nothing else is reported
    assert "may not transfer" in message and "activevision export" in message
    # the settings that train for the robot's whole camera, at the policy's input width
    settings = message.split("activevision train ... ")[1]
    size = (160, round(160 * robot.height / robot.width))
    for name, value in (("width", size[0]), ("height", size[1])):
        assert f"--set env.camera.{name}={value} " in settings
    for name in ("hfov", "camera_height", "pan_min", "pan_max", "tilt_min", "tilt_max"):
        assert f"--set env.camera.{name}={getattr(robot, name):.9g} " in settings


def test_one_warning_for_many_differences(camera_policy):
    robot = CameraModel.from_degrees(640, 360, 90.0, 0.40, (-90, 90), (0, 45))
    caught = build(camera_policy, robot)
    assert [w.category for w in caught] == [CameraMismatchWarning]
    message = str(caught[0].message)
    assert message.count("\n  - ") == 5  # aspect, hfov, camera_height, tilt_min, tilt_max
    for name in ("aspect ratio", "hfov", "camera_height", "tilt_min", "tilt_max"):
        assert f"  - {name}" in message
    assert "  - pan_" not in message
    settings = message.split("activevision train ... ")[1]
    # the policy's input width at the robot's 16:9, not the robot's 640 x 360 (training
    # renders at the network's input size), and every field: a retrain starts from the
    # preset's camera, not the loaded policy's
    assert settings.startswith(
        "--set env.camera.width=160 --set env.camera.height=90 --set env.camera.hfov=1.57079633"
        " --set env.camera.camera_height=0.4 --set env.camera.pan_min=-1.57079633"
        " --set env.camera.pan_max=1.57079633 --set env.camera.tilt_min=0"
        " --set env.camera.tilt_max=0.785398163 (and --set env.start_tilt_range_deg=[LOW,HIGH]"
        " within the tilt limits, 0 to 45 degrees"
    )
    # a match run reads match.camera (env.* is refused there): the hint says so
    assert "as match.camera.* (--set match.camera.hfov=...)" in message


def test_the_retrain_hint_trains(tmp_path):
    """The warning's settings, given to the training config as `activevision train` gives
    them, build the robot's camera (at the policy's input width) and a valid env."""
    pytest.importorskip("torch")
    from activevision.runtime.controller import camera_mismatch_message
    from activevision.training import TrainConfig, apply_overrides

    robot = CameraModel.from_degrees(1280, 720, 70.0, 0.62, (-80, 80), (30, 60))
    message = camera_mismatch_message(Path("p.onnx"), robot, {"hfov": "..."}, 160)
    words = message.split("activevision train ... ")[1].split(" (and")[0].split()
    overrides = [w for w in words if w != "--set"]
    with pytest.raises(ValueError, match="within the camera's tilt limits, 30 to 60 degrees"):
        apply_overrides(TrainConfig(), overrides)  # the preset's 5-25 deg starts lie outside
    config = apply_overrides(TrainConfig(), [*overrides, "env.start_tilt_range_deg=[30,45]"])
    camera = config.env.camera
    assert (camera.width, camera.height) == (160, 90)
    want = dataclasses.replace(robot, width=160, height=90)
    for f in dataclasses.fields(CameraModel):  # to the hint's 9 digits
        got = getattr(CameraModel.of(camera), f.name)
        assert got == pytest.approx(getattr(want, f.name), abs=1e-8)


def test_the_retrain_hint_trains_a_neck_at_its_physical_limits():
    """CameraModel takes a neck reaching 180 degrees pan and 90 tilt; training's camera
    wants them strictly inside: the hint gives them just inside (it gave 1.57079633 > pi/2,
    which `activevision train` refused)."""
    pytest.importorskip("torch")
    from activevision.runtime.controller import camera_mismatch_message
    from activevision.training import TrainConfig, apply_overrides

    robot = CameraModel.from_degrees(640, 480, 58.0, 0.5, (-180, 180), (-90, 90))
    message = camera_mismatch_message(Path("p.onnx"), robot, {"tilt_max": "..."}, 160)
    words = message.split("activevision train ... ")[1].split(" (and")[0].split()
    camera = apply_overrides(TrainConfig(), [w for w in words if w != "--set"]).env.camera
    assert CameraModel.of(camera).differences(robot) == {}


def test_the_retrain_hint_trains_a_neck_that_does_not_pan():
    """A fixed pan (min = max) is a camera CameraModel takes; training's camera needs a
    range: the hint gives +-0.5 degrees and says so (its pan_min=0 pan_max=0 was refused)."""
    pytest.importorskip("torch")
    from activevision.runtime.controller import camera_mismatch_message
    from activevision.training import TrainConfig, apply_overrides

    robot = CameraModel.from_degrees(640, 480, 58.0, 0.5, (0, 0), (5, 65))
    message = camera_mismatch_message(Path("p.onnx"), robot, {"pan_min": "..."}, 160)
    assert "the robot's neck does not pan (pan_min = pan_max)" in message
    words = message.split("activevision train ... ")[1].split(" (and")[0].split()
    camera = apply_overrides(TrainConfig(), [w for w in words if w != "--set"]).env.camera
    assert math.degrees(camera.pan_min) == pytest.approx(-0.5)
    assert math.degrees(camera.pan_max) == pytest.approx(0.5)
    assert math.degrees(camera.tilt_max) == pytest.approx(65)


def test_warning_can_be_made_an_error(camera_policy):
    with warnings.catch_warnings():
        warnings.simplefilter("error", CameraMismatchWarning)
        with pytest.raises(CameraMismatchWarning, match="hfov"):
            HeadController(camera_policy, camera=dataclasses.replace(TRAINED, hfov=0.8))


def test_the_controller_still_acts_after_warning(camera_policy):
    robot = dataclasses.replace(TRAINED, width=640, height=360)
    with pytest.warns(CameraMismatchWarning):
        controller = HeadController(camera_policy, camera=robot)
    with pytest.warns(CameraMismatchWarning, match="stretched"):  # the frames' 16:9, once
        command = controller.act(np.zeros((360, 640, 3), np.uint8), 0.0, 0.3)
    assert 0 <= command.action < controller.n_actions


def test_frames_of_another_aspect_ratio_warn_once_without_a_camera(camera_policy):
    controller = HeadController(camera_policy)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        controller.act(np.zeros((480, 640), np.uint8), 0.0, 0.3)  # 4:3, as trained
        controller.reset()
    assert caught == []
    controller = HeadController(camera_policy)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(3):
            controller.act(np.zeros((720, 1280), np.uint8), 0.0, 0.3)
    assert [w.category for w in caught] == [CameraMismatchWarning]
    assert caught[0].filename == __file__  # points at the caller's act(...)
    assert "1280x720 px (aspect 1.778) are stretched to the policy's 160x120" in str(
        caught[0].message
    )


def test_a_later_frame_of_another_aspect_ratio_warns_once(camera_policy):
    """A camera switched to 16:9 after a 4:3 first frame: one warning, at the first 16:9
    frame (the README's promise; only the very first frame was checked)."""
    controller = HeadController(camera_policy)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        controller.act(np.zeros((480, 640), np.uint8), 0.0, 0.3)
        assert caught == []
        for _ in range(3):
            controller.act(np.zeros((360, 640), np.uint8), 0.0, 0.3)
            controller.act(np.zeros((480, 640), np.uint8), 0.0, 0.3)
    assert [w.category for w in caught] == [CameraMismatchWarning]
    assert "640x360 px (aspect 1.778)" in str(caught[0].message)
    assert caught[0].filename == __file__


def test_camera_config_of_the_trained_camera(camera_policy):
    """Views for a policy trained on another camera are planned with that camera."""
    trained = HeadController(camera_policy).trained_camera
    assert CameraConfig.of(trained) == TRAINED
    assert CameraConfig.of(TRAINED) is TRAINED
    with pytest.raises(TypeError, match="lacks"):
        CameraConfig.of(object())
