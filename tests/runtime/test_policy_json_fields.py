"""Every policy.json key a reader uses is present and of its type, or the file is refused on
one line naming the file and the key; keys older exports lack keep their documented default."""

from __future__ import annotations

import json
import shutil

import pytest

from activevision.cli import main
from activevision.runtime import (
    PolicyFileError,
    PolicyMetadata,
    load_metadata,
    pretrained_policy_path,
)
from activevision.runtime.metadata import METADATA_FILENAME

SHIPPED = json.loads(pretrained_policy_path().with_name(METADATA_FILENAME).read_text())
REMOVED = object()


def edited(changes: dict) -> dict:
    values = {**SHIPPED, **changes}
    return {k: v for k, v in values.items() if v is not REMOVED}


@pytest.mark.parametrize(
    ("changes", "key"),
    [
        ({"input_name": REMOVED}, "'input_name'"),
        ({"output_name": REMOVED}, "'output_name'"),
        ({"output_name": 7}, "'output_name'"),
        ({"vector_input_name": REMOVED}, "'vector_input_name'"),
        ({"opset": REMOVED}, "'opset'"),
        ({"opset": "17"}, "'opset'"),
        ({"n_actions": REMOVED}, "'n_actions'"),
        ({"n_actions": 9.0}, "'n_actions'"),
        ({"input_dtype": "float32"}, "'input_dtype'"),
        ({"input_dtype": REMOVED}, "'input_dtype'"),
        ({"dueling": "no"}, "'dueling'"),
        ({"preprocessing": 1}, "'preprocessing'"),
        ({"observation": REMOVED}, "'observation'"),
        ({"observation": 5}, "'observation'"),
        ({"observation": "image"}, "'observation'"),  # but it takes a vector
        ({"observation": "image+head+pose+nonsense"}, "'observation' must be one of"),
        # vector inputs that are not the observation's: an env built for the observation
        # (evaluate, robustness) would feed another layout than the controller builds
        ({"vector_keys": ["head", "pose", "pose_error"]}, "'vector_keys' ['head', 'pose',"),
        ({"observation": "image+head+belief"}, "inputs of 'observation' 'image+head+belief'"),
        ({"action_history": 2}, "with 'action_history' 2: ['head', 'pose', 'pose_error',"),
        ({"vector_keys": [*SHIPPED["vector_keys"], "actions"]}, "'action_history' 0"),
        (
            {"observation": "image", "vector_keys": [], "action_history": 1},
            "'action_history' is 1 but 'observation' 'image' takes none",
        ),
        ({"step_deg": "3"}, "'step_deg'"),
        ({"step_deg": True}, "'step_deg'"),
        ({"step_deg": 5.0}, "'step_deg' 5"),  # not the table's moves
        ({"step_deg": REMOVED}, "'step_deg'"),
        ({"action_set": "6way"}, "'action_set'"),
        ({"action_set": "4way"}, "'action_table_deg' is not the 4way moves"),
        ({"action_set": REMOVED}, "'action_set'"),
        ({"training_config_sha256": "abc"}, "'training_config_sha256'"),
        # which weights were exported and theirs: export writes both, or neither
        ({"training_weights": "best"}, "'training_weights' and 'training_weights_sha256' come"),
        ({"training_weights_sha256": "ab" * 32}, "'training_weights' and 'training_weights_sha2"),
        (
            {"training_weights": "latest", "training_weights_sha256": "ab" * 32},
            "'training_weights' must be 'final', 'best' or null, got 'latest'",
        ),
        (
            {"training_weights": "final", "training_weights_sha256": "AB" * 32},
            "'training_weights_sha256' must be a SHA-256",
        ),
        (
            {"training_weights": None, "training_weights_sha256": "ab" * 32},
            "'training_weights_sha256' is given but 'training_weights' is null",
        ),
        ({"action_names": [*SHIPPED["action_names"][:-1], 8]}, "'action_names'"),
        # the controller keeps this many actions: 10**13 asked for 73 TiB (a MemoryError)
        ({"action_history": 10**13}, "'action_history' must be an integer in 0..16"),
        ({"action_history": -1}, "'action_history'"),
        # sizes no export writes (a config's camera is at most 8192 px a side, its
        # frame_stack at most 64): refused, not handed to a reader that allocates by them
        ({"image_width": 10**12, "camera": REMOVED}, "'image_width' must be at most 8192"),
        ({"image_height": 8193, "camera": REMOVED}, "'image_height' must be at most 8192"),
        ({"stack": 65}, "'stack' must be at most 64, got 65"),
        ({"stack": 10**12}, "'stack' must be at most 64"),
        (
            {"camera": {**SHIPPED["camera"], "width_px": 10**12}},
            "'camera' width_px must be at most 8192 px, got 1000000000000",
        ),
        ({"camera": {**SHIPPED["camera"], "height_px": 8193}}, "'camera' height_px must be at"),
    ],
    ids=repr,
)
def test_a_used_key_missing_or_of_the_wrong_type_is_named(changes, key):
    with pytest.raises(PolicyFileError) as error:
        PolicyMetadata.from_dict(edited(changes), source="x/policy.json")
    message = str(error.value)
    assert message.startswith("x/policy.json: ") and key in message
    assert "\n" not in message


def test_the_shipped_policy_and_older_files_load():
    meta = PolicyMetadata.from_dict(SHIPPED)
    assert (meta.step_deg, meta.action_set, meta.opset) == (3.0, "8way", 17)
    assert meta.observation == "image+head+pose+proposal"
    # shipped before policy.json recorded the weights it was exported from
    assert "training_weights" not in SHIPPED
    assert (meta.training_weights, meta.training_weights_sha256) == (None, None)
    recorded = {"training_weights": "best", "training_weights_sha256": "ab" * 32}
    meta = PolicyMetadata.from_dict(edited(recorded))
    assert (meta.training_weights, meta.training_weights_sha256) == ("best", "ab" * 32)
    meta = PolicyMetadata.from_dict(
        edited(
            {"training_weights": "final"}
            | {
                "training_weights_sha256": None  # the run had no policy.safetensors: a checkpoint's
            }
        )
    )
    assert (meta.training_weights, meta.training_weights_sha256) == ("final", None)
    # keys an older export lacks (export_onnx alone writes no moves, observation, camera or
    # world) keep their defaults
    older = edited({k: REMOVED for k in ("step_deg", "action_set", "camera", "world")})
    meta = PolicyMetadata.from_dict(older)
    assert (meta.step_deg, meta.action_set, meta.camera, meta.world) == (None, None, None, None)
    image_only = {
        k: v
        for k, v in SHIPPED.items()
        if k
        not in (
            "observation",
            "vector_keys",
            "vector_input_name",
            "act_by",
            "goal_output_name",
            "goal_views_deg",
            "goal_switch_margin",
            "goal_frame",
        )
    }
    assert PolicyMetadata.from_dict(image_only).observation == "image"


def test_sizes_at_a_configs_bounds_load_and_the_bounds_are_the_configs():
    from activevision.envs.config import MAX_FRAME_STACK
    from activevision.geometry.camera import MAX_IMAGE_SIDE
    from activevision.runtime import metadata

    assert (metadata.MAX_IMAGE_SIDE, metadata.MAX_STACK) == (MAX_IMAGE_SIDE, MAX_FRAME_STACK)
    camera = {**SHIPPED["camera"], "width_px": 8192, "height_px": 6144}
    meta = PolicyMetadata.from_dict(
        edited({"image_width": 8192, "image_height": 6144, "stack": 64, "camera": camera})
    )
    assert meta.input_shape == (64, 6144, 8192) and meta.camera.width == 8192


def test_a_command_names_the_file_and_the_key_on_one_line(tmp_path, capsys):
    """demo --policy (and match --model, evaluate's shipped) read policy.json through
    HeadController: a removed key is one line, before any episode."""
    model = tmp_path / "policy.onnx"
    shutil.copy(pretrained_policy_path(), model)
    (tmp_path / METADATA_FILENAME).write_text(json.dumps(edited({"opset": REMOVED})))
    argv = ["demo", "--policy", str(model), "--out", str(tmp_path / "demo.png")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert str(tmp_path / METADATA_FILENAME) in err and "'opset'" in err, err
    assert not (tmp_path / "demo.png").exists()


def test_a_discrete_policy_is_played_with_its_own_moves(tmp_path, helpers):
    """OnnxPolicy.env_config: action i of a 5-degree 4-way policy is its table's row i, so
    the env (demo --policy) moves 5 degrees a step in 4 ways, not the paper's 3 in 8."""
    from activevision.agents.q_network import QNetwork
    from activevision.experiments.policies import OnnxPolicy
    from activevision.export import export_onnx, policy_metadata
    from activevision.geometry import CameraConfig

    table = helpers.eight_way_table(5.0)[:5]
    metadata = {**policy_metadata(table, CameraConfig()), "step_deg": 5.0, "action_set": "4way"}
    exported = export_onnx(QNetwork(5).eval(), tmp_path / "policy.onnx", metadata)
    config = OnnxPolicy(exported.model_path).env_config()
    assert (config.step_deg, config.action_set) == (5.0, "4way")


@pytest.mark.parametrize(
    "text",
    ["[" * 100_000 + "]" * 100_000, '{"opset": ' + "9" * 5000 + "}"],
    ids=["nested too deep", "an integer of 5000 digits"],
)
def test_json_the_decoder_cannot_take_is_a_policy_file_error(tmp_path, capsys, text):
    """json.loads raises RecursionError and a plain ValueError for these, not
    JSONDecodeError: still one PolicyFileError naming the file, and one line from a command."""
    model = tmp_path / "policy.onnx"
    shutil.copy(pretrained_policy_path(), model)
    (tmp_path / METADATA_FILENAME).write_text(text)
    with pytest.raises(PolicyFileError, match=r"policy\.json is not valid JSON"):
        load_metadata(tmp_path / METADATA_FILENAME)
    argv = ["demo", "--policy", str(model), "--out", str(tmp_path / "demo.png")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err


def test_a_policy_is_played_with_the_camera_it_was_trained_for(tmp_path, helpers, capsys):
    """OnnxPolicy.env_config: a policy trained for another camera (README: Training for
    your own camera) is shown by demo --policy through that camera, not the paper's, its
    start tilts within the camera's limits; the shipped policy's env stays the paper's."""
    from activevision.agents.q_network import QNetwork
    from activevision.envs.config import EnvConfig
    from activevision.experiments.policies import OnnxPolicy
    from activevision.export import export_onnx, policy_metadata
    from activevision.geometry import CameraConfig

    camera = CameraConfig(hfov=1.2217, camera_height=0.62, tilt_min=0.5236, tilt_max=1.0472)
    metadata = policy_metadata(helpers.eight_way_table(), camera, camera=camera)
    exported = export_onnx(QNetwork(9).eval(), tmp_path / "policy.onnx", metadata)
    config = OnnxPolicy(exported.model_path).env_config()
    assert config.camera == camera
    assert config.start_tilt_range_deg == pytest.approx((30.0, 60.0), abs=1e-3)
    assert OnnxPolicy(pretrained_policy_path()).env_config().camera == EnvConfig().camera
    argv = ["demo", "--policy", str(exported.model_path), "--out", str(tmp_path / "d.png")]
    assert main(argv) == 0, capsys.readouterr().err


def test_a_key_written_twice_is_refused_naming_it_and_the_file(tmp_path):
    """json.loads kept the last of two values: a second ``"step_deg"`` added by hand was
    played, the first one dropped, unsaid."""
    path = tmp_path / METADATA_FILENAME
    text = json.dumps(SHIPPED)
    path.write_text(text[:-1] + f', "opset": {SHIPPED["opset"]}}}')
    with pytest.raises(PolicyFileError, match=f"^policy metadata {path}: duplicate key 'opset'"):
        load_metadata(path)
    path.write_text(text)
    assert load_metadata(path).opset == SHIPPED["opset"]


@pytest.mark.parametrize(
    "model_file",
    ["../../etc/passwd", "/etc/passwd", "../policy.onnx", "sub/policy.onnx"]
    + ["..", ".", "", "a\\b.onnx"],
)
def test_model_file_must_be_a_bare_file_name(tmp_path, capsys, model_file):
    """policy.json's ``model_file`` was only type-checked: a path out of the policy's folder
    (every one of these names a file that exists, but ``..`` and ``""``), an absolute one or
    one into a subfolder loaded the policy as if it named its model. The model sits beside
    its policy.json: one line naming the file and the field, from the reader, the controller
    and every command that loads a policy."""
    from activevision.runtime import HeadController

    run = tmp_path / "run"
    (run / "sub").mkdir(parents=True)
    for model in (run / "policy.onnx", tmp_path / "policy.onnx", run / "sub" / "policy.onnx"):
        shutil.copy(pretrained_policy_path(), model)
    path = run / METADATA_FILENAME
    path.write_text(json.dumps(edited({"model_file": model_file})))
    message = rf"^{path}: 'model_file' must be the model's file name, beside policy\.json \(no"
    with pytest.raises(PolicyFileError, match=message):
        load_metadata(path)
    with pytest.raises(PolicyFileError, match=message):
        HeadController(run / "policy.onnx")
    assert_commands_refuse(run / "policy.onnx", tmp_path, capsys, "'model_file' must be")


def test_a_policy_pair_renamed_together_loads(tmp_path):
    """An exported pair renamed together for the robot (``striker.onnx``, ``striker.json``,
    whose ``model_file`` still says ``policy.onnx``) loads: the controller reads the
    metadata named as the model it is given and the model's SHA-256 ties the two (a renamed
    pair was refused for a ``model_file`` of no file beside it)."""
    from activevision.runtime import HeadController

    model = tmp_path / "striker.onnx"
    shutil.copy(pretrained_policy_path(), model)
    values = edited({"model_file": "policy.onnx"})
    (tmp_path / "striker.json").write_text(json.dumps(values))
    controller = HeadController(model)
    assert controller.metadata.model_file == "policy.onnx"
    assert controller.metadata_path == tmp_path / "striker.json"
    # and the model of another export under the pair's name is still refused
    (tmp_path / "striker.json").write_text(json.dumps(edited({"model_sha256": "0" * 64})))
    with pytest.raises(PolicyFileError, match="does not match its metadata"):
        HeadController(model)


def assert_commands_refuse(model, tmp_path, capsys, message: str) -> None:
    """``demo --policy`` and ``match --model`` exit 2 with one line naming policy.json."""
    commands = [
        ["demo", "--policy", str(model), "--out", str(tmp_path / "demo.png")],
        ["match", "--matches", "1", "--ticks", "3", "--methods", "onnx_policy", "--model"]
        + [str(model), "--out", str(tmp_path / "m")],
    ]
    for argv in commands:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "Traceback" not in err, err
        assert str(model.with_name(METADATA_FILENAME)) in err and message in err, err
