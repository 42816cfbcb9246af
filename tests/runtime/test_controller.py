"""HeadController: same decisions as PyTorch, clipped targets, frame stack, clear errors."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import torch

from activevision.runtime import HeadCommand, HeadController, PolicyFileError
from activevision.runtime import pretrained as pretrained_module
from activevision.runtime.controller import MAX_THREADS

_D = 3 * math.sqrt(2) / 2
#: The exported 9-action table in degrees (stay, 4 axis moves, 4 diagonals).
TABLE_DEG = np.array(
    [(0, 0), (3, 0), (-3, 0), (0, -3), (0, 3), (_D, -_D), (_D, _D), (-_D, -_D), (-_D, _D)]
)


def torch_q(network, stacked: np.ndarray) -> np.ndarray:
    with torch.inference_mode():
        return network(torch.from_numpy(stacked[None]))[0].numpy()


def same_decision(action: int, q_torch: np.ndarray) -> bool:
    """Equal to torch's argmax, or a tie within float noise."""
    return action == int(np.argmax(q_torch)) or q_torch.max() - q_torch[action] < 1e-4


@pytest.mark.parametrize(("width", "height"), [(160, 120), (640, 480), (320, 240), (333, 250)])
def test_decisions_match_torch_for_grey_rgb_bgr(policy, frames, helpers, width, height):
    controller = HeadController(policy.model_path)
    bgr_controller = HeadController(policy.model_path, color_order="bgr")
    for i, grey in enumerate(frames(width, height)):
        rgb = helpers.colourise(grey, seed=i)
        cases = [
            (controller, grey, "rgb"),
            (controller, grey[:, :, None], "rgb"),
            (controller, rgb, "rgb"),
            (bgr_controller, rgb[:, :, ::-1], "bgr"),
        ]
        references = np.stack([helpers.reference_preprocess(f, o)[None] for _, f, o in cases])
        with torch.inference_mode():
            q_torch = policy.network(torch.from_numpy(references)).numpy()
        for (ctrl, frame, _), q_expected in zip(cases, q_torch, strict=True):
            command = ctrl.act(frame, 0.0, 0.5)
            assert same_decision(command.action, q_expected)
            assert np.abs(ctrl.last_q_values - q_expected).max() < 0.05  # ±1 grey level at most


def test_q_values_match_torch_exactly_preprocessed(policy, frames):
    controller = HeadController(policy.model_path)
    for frame in frames(640, 480):
        q = controller.q_values(frame)
        expected = torch_q(policy.network, controller.observe(frame).copy())
        assert np.abs(q - expected).max() <= 1e-4


def biased_policy(tmp_path, helpers, action: int, stack: int = 1):
    """A network that always picks ``action`` (output weights zero, one-hot bias)."""
    network = helpers.make_network(stack=stack)
    with torch.no_grad():
        network.q.weight.zero_()
        network.q.bias.zero_()
        network.q.bias[action] = 1.0
    return helpers.export(network, tmp_path).model_path


def test_command_and_clipping_to_head_limits(tmp_path, helpers):
    pan_left_tilt_down = 6  # (+d, +d): pan left, tilt down
    controller = HeadController(biased_policy(tmp_path, helpers, pan_left_tilt_down))
    frame = np.zeros((480, 640, 3), dtype=np.uint8)
    d = math.radians(3.0) * math.sqrt(2) / 2

    command = controller.act(frame, 0.1, 0.4)
    assert isinstance(command, HeadCommand) and command.action == pan_left_tilt_down
    assert command.d_pan == pytest.approx(d) and command.d_tilt == pytest.approx(d)
    assert command.target_pan == pytest.approx(0.1 + d)
    assert command.target_tilt == pytest.approx(0.4 + d)

    command = controller.act(frame, math.radians(89.5), math.radians(64.0))
    assert command.target_pan == pytest.approx(math.pi / 2)
    assert command.target_tilt == pytest.approx(math.radians(65.0))
    with pytest.warns(UserWarning, match="outside the pan limits"):  # HeadAngleWarning
        command = controller.act(frame, 3.0, -1.0)  # outside the limits already: clipped in
    assert command.target_pan == pytest.approx(math.pi / 2)
    assert command.target_tilt == pytest.approx(math.radians(5.0))


def test_targets_stay_within_the_robots_own_limits_too(tmp_path, helpers):
    """Given the robot's camera, whose neck reaches less than the policy's limits (pan +-60
    deg, tilt 0 to 60 against +-90 and 5 to 65), the targets stay within both: they were
    clipped to the policy's alone, commanding 61 deg from a neck that stops at 60, though the
    README promises targets "already clipped to the limits"."""
    from activevision.runtime import CameraModel

    model = biased_policy(tmp_path, helpers, 6)  # (+d, +d): pan left, tilt down
    robot = CameraModel.from_degrees(640, 480, 58.0, 0.5, (-60, 60), (0, 60))
    controller = HeadController(model, camera=robot)
    frame = np.zeros((480, 640, 3), dtype=np.uint8)
    d = math.radians(3.0) * math.sqrt(2) / 2
    command = controller.act(frame, math.radians(59.0), math.radians(59.0))
    assert command.d_pan == pytest.approx(d) and command.d_tilt == pytest.approx(d)  # its move
    assert command.target_pan == pytest.approx(math.radians(60.0))
    assert command.target_tilt == pytest.approx(math.radians(60.0))
    command = controller.act(frame, 0.1, 0.4)  # inside both: the plain sum
    assert (command.target_pan, command.target_tilt) == pytest.approx((0.1 + d, 0.4 + d))
    # the robot's neck reaches further than the policy's limits: the policy's still bound it
    wide = CameraModel.from_degrees(640, 480, 58.0, 0.5, (-120, 120), (0, 80))
    command = HeadController(model, camera=wide).act(frame, math.radians(89.5), 1.13)
    assert command.target_pan == pytest.approx(math.pi / 2)
    assert command.target_tilt == pytest.approx(math.radians(65.0))


def test_frame_stack_and_reset(tmp_path, frames, helpers):
    network = helpers.make_network(stack=3, seed=3)
    controller = HeadController(helpers.export(network, tmp_path).model_path)
    images = frames(160, 120)
    stacked = controller.observe(images[0]).copy()
    assert all(np.array_equal(s, images[0]) for s in stacked)  # first frame fills the stack
    controller.observe(images[1])
    q = controller.q_values(images[2])
    assert np.abs(q - torch_q(network, images[:3].copy())).max() <= 1e-4  # oldest first
    np.testing.assert_array_equal(controller.observe(images[3]), images[1:4])
    controller.reset()
    assert all(np.array_equal(s, images[1]) for s in controller.observe(images[1]))


def test_bad_frame_leaves_stack_untouched(tmp_path, frames, helpers):
    controller = HeadController(helpers.export(helpers.make_network(stack=2), tmp_path).model_path)
    images = frames(160, 120)
    before = controller.observe(images[0]).copy()
    with pytest.raises(ValueError, match="dtype uint8"):
        controller.act(images[1].astype(np.float32), 0.0, 0.3)
    np.testing.assert_array_equal(controller.observe(images[0]), before)


@pytest.mark.parametrize(
    "frame",
    [
        np.zeros((480, 640, 3), dtype=np.float32),
        np.zeros((480, 640, 4), dtype=np.uint8),
        np.zeros(640, dtype=np.uint8),
    ],
    ids=["float", "4-channel", "1-D"],
)
def test_bad_frames(policy, frame):
    with pytest.raises(ValueError, match="frame"):
        HeadController(policy.model_path).act(frame, 0.0, 0.3)


def test_bad_arguments(policy):
    controller = HeadController(policy.model_path)
    frame = np.zeros((120, 160), dtype=np.uint8)
    with pytest.raises(ValueError, match="pan"):
        controller.act(frame, float("nan"), 0.3)
    with pytest.raises(ValueError, match="tilt"):
        controller.act(frame, 0.0, "up")
    with pytest.raises(ValueError, match=r"pan must be radians within \+-pi, got 45 \(degrees\?\)"):
        controller.act(frame, 45.0, 0.3)
    with pytest.raises(ValueError, match="tilt must be radians"):
        controller.act(frame, 0.0, -30.0)
    with pytest.raises(ValueError, match="pan must be a number of radians, got True"):
        controller.act(frame, True, 0.3)  # float(True) is 1 rad
    with pytest.raises(ValueError, match=r"tilt must be a number of radians, got '0\.3'"):
        controller.act(frame, 0.0, "0.3")
    with pytest.raises(ValueError, match="num_threads"):
        HeadController(policy.model_path, num_threads=0)
    # 100,000 hung starting threads; 2**40 was a PolicyFileError calling the model invalid
    for threads in (MAX_THREADS + 1, 2**40, 2.0):
        with pytest.raises(ValueError, match=rf"num_threads must be .* up to {MAX_THREADS}"):
            HeadController(policy.model_path, num_threads=threads)  # type: ignore[arg-type]
    assert HeadController(policy.model_path, num_threads=np.int64(1)).act(frame, 0.0, 0.3)
    with pytest.raises(ValueError, match="color_order"):
        HeadController(policy.model_path, color_order="rgba")
    for path in (None, 3, b"policy.onnx"):
        with pytest.raises(PolicyFileError, match=r"model_path: expects the path .* got"):
            HeadController(path)  # type: ignore[arg-type]


@pytest.fixture
def policy_copy(policy, tmp_path):
    model = tmp_path / "policy.onnx"
    shutil.copy(policy.model_path, model)
    shutil.copy(policy.metadata_path, tmp_path / "policy.json")
    return model


def test_missing_files(policy_copy):
    with pytest.raises(PolicyFileError, match="not found"):
        HeadController(policy_copy.with_name("nope.onnx"))
    # a folder stands for its policy.onnx
    assert HeadController(policy_copy.parent).model_path == policy_copy
    empty_run = policy_copy.parent / "empty_run"
    empty_run.mkdir()
    with pytest.raises(PolicyFileError, match=r"not found .*activevision export RUN_DIR"):
        HeadController(empty_run)
    policy_copy.with_suffix(".json").unlink()
    with pytest.raises(PolicyFileError, match=r"policy\.json not found"):
        HeadController(policy_copy)


def test_metadata_given_for_the_model_is_named(policy_copy):
    """policy.json passed where policy.onnx is meant: one line saying so, not a checksum
    mismatch blaming another export (or, unchecked, an invalid ONNX model)."""
    metadata = policy_copy.with_suffix(".json")
    for verify in (True, False):
        with pytest.raises(PolicyFileError, match=r"policy\.json is the policy's metadata; pass"):
            HeadController(metadata, verify_checksum=verify)


def test_corrupt_model(policy_copy):
    policy_copy.write_bytes(policy_copy.read_bytes()[:5000])  # truncated
    with pytest.raises(PolicyFileError, match="does not match its metadata"):
        HeadController(policy_copy)
    with pytest.raises(PolicyFileError, match="not a valid ONNX model"):
        HeadController(policy_copy, verify_checksum=False)


def test_corrupt_metadata(policy_copy):
    meta_path = policy_copy.with_suffix(".json")
    meta_path.write_text(meta_path.read_text()[:100])
    with pytest.raises(PolicyFileError, match="not valid JSON"):
        HeadController(policy_copy)
    meta_path.write_text("[1, 2]")
    with pytest.raises(PolicyFileError, match="JSON object"):
        HeadController(policy_copy)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"stack": 2}, "input shape"),
        ({"image_width": 320}, "input shape"),
        ({"n_actions": 5}, "n_actions"),
        (
            {"action_table_deg": [[0, 0]] * 5, "n_actions": 5, "action_names": ["stay"] * 5},
            "5 actions",
        ),
        ({"action_table_deg": [[0, 0]] * 5, "n_actions": 5}, "one name per action"),
        ({"input_name": "image"}, "no input 'image'"),
        ({"format_version": 99}, "format_version"),
        # True == 1 and 1.0 == 1 were read as format 1: not what an export writes
        ({"format_version": True}, "'format_version' must be an integer .*, got True"),
        ({"format_version": 1.0}, "'format_version' must be an integer .*, got 1.0"),
        ({"format_version": "1"}, "'format_version' must be an integer .*, got '1'"),
        ({"format_version": 0}, "unsupported 'format_version' 0"),
        (  # a newer export: say what to do about it
            {"format_version": 2},
            "'format_version' 2 is newer than this activevision reads \\(1\\): upgrade",
        ),
        ({"head_limits_deg": {"pan_min": 0}}, "head_limits_deg"),
        ({"model_sha256": "0" * 64}, "SHA-256"),
        ({"model_sha256": None}, "model_sha256"),
        ({"model_sha256": "abc"}, "model_sha256"),
        ({"action_table_deg": TABLE_DEG[::-1].tolist()}, "moves the head"),
        ({"action_table_deg": (TABLE_DEG * 20).tolist()}, "more than 30"),
        (
            {"head_limits_deg": {"pan_min": -720, "pan_max": 720, "tilt_min": 5, "tilt_max": 65}},
            "outside",
        ),
        (
            {"head_limits_deg": {"pan_min": -90, "pan_max": 90, "tilt_min": 5, "tilt_max": 900}},
            "outside",
        ),
        (  # float(true) is 1 degree: every command would be clipped to pan <= 1 degree
            {"head_limits_deg": {"pan_min": -90, "pan_max": True, "tilt_min": 5, "tilt_max": 65}},
            "'head_limits_deg' pan_max must be a number of degrees, got True",
        ),
        (
            {"head_limits_deg": {"pan_min": "-90", "pan_max": 90, "tilt_min": 5, "tilt_max": 65}},
            "'head_limits_deg' pan_min must be a number of degrees, got '-90'",
        ),
    ],
)
def test_metadata_mismatch(policy_copy, change, message):
    meta_path = policy_copy.with_suffix(".json")
    meta_path.write_text(json.dumps({**json.loads(meta_path.read_text()), **change}))
    with pytest.raises(PolicyFileError, match=message):
        HeadController(policy_copy)


def test_pretrained_policy_path(tmp_path, monkeypatch, policy_copy):
    monkeypatch.setattr(pretrained_module, "PRETRAINED_DIR", tmp_path / "absent")
    with pytest.raises(PolicyFileError, match="no pretrained policy"):
        pretrained_module.pretrained_policy_path()
    monkeypatch.setattr(pretrained_module, "PRETRAINED_DIR", policy_copy.parent)
    assert pretrained_module.pretrained_policy_path() == policy_copy


def test_runtime_imports_and_runs_without_torch(policy):
    script = textwrap.dedent(f"""
        import sys
        for blocked in ("torch", "gymnasium", "activevision.envs", "activevision.training"):
            sys.modules[blocked] = None  # any import of these now raises ImportError
        import numpy as np
        from activevision.runtime import HeadController
        controller = HeadController({str(policy.model_path)!r})
        command = controller.act(np.zeros((480, 640, 3), np.uint8), 0.0, 0.3)
        # numba (the frame resize) is allowed, and with it whatever numba loads (scipy)
        loaded = [m for m in ("onnx", "matplotlib") if m in sys.modules]
        print(command.action, loaded)
    """)
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    action, loaded = result.stdout.split(maxsplit=1)
    assert 0 <= int(action) < 9 and loaded.strip() == "[]"


def test_runtime_runs_where_numba_cannot_write_its_cache(policy, frames, helpers):
    """A read-only install run by a user without a writable home (a robot's service
    account): numba has nowhere to put the frame resize's on-disk cache and refused the
    import, "RuntimeError: cannot cache function 'block_mean_kernel': no locator available"
    (seen as user nobody with HOME=/nonexistent). The kernel is compiled afresh instead, and
    the controller decides as anywhere else."""
    frame = helpers.colourise(frames(640, 480)[0], seed=1)
    np.save(policy.model_path.parent / "frame.npy", frame)
    script = textwrap.dedent(f"""
        from numba.core import caching
        impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl  # numba >= 0.61 / older
        impl._locator_classes = []  # no place numba may write its cache
        import numpy as np
        from activevision.runtime import HeadController
        controller = HeadController({str(policy.model_path)!r})
        frame = np.load({str(policy.model_path.parent / "frame.npy")!r})
        print(list(controller.q_values(frame)))
    """)
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    here = HeadController(policy.model_path).q_values(frame)
    np.testing.assert_array_equal(np.array(eval(result.stdout)), here)


def test_missing_onnxruntime_names_the_extra(policy):
    script = textwrap.dedent(f"""
        import sys
        sys.modules["onnxruntime"] = None
        from activevision.runtime import HeadController
        try:
            HeadController({str(policy.model_path)!r})
        except ImportError as error:
            print(error)
    """)
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    assert "activevision[runtime]" in result.stdout


def test_runtime_action_names_are_the_envs():
    from activevision.envs.actions import ACTION_NAMES_8WAY
    from activevision.runtime.metadata import STANDARD_ACTION_NAMES

    assert STANDARD_ACTION_NAMES == ACTION_NAMES_8WAY


def test_the_controller_s_thread_bound_is_the_training_config_s():
    from activevision.training.config import MAX_THREADS as TRAINING_MAX_THREADS

    assert MAX_THREADS == TRAINING_MAX_THREADS


def test_head_angles_well_outside_the_limits_warn_once(tmp_path, helpers):
    """A robot whose tilt is positive *up* gives -0.3 rad for a head looking 17 deg down:
    the policy (tilt limits 5..65 deg down) never saw it, and its clipped command turns the
    head the wrong way. That was silent; now one HeadAngleWarning names the angle, the limits
    and the convention. Within 5 deg of the limits (a head resting level, a joint
    overshooting) nothing is said."""
    import warnings

    from activevision.runtime import HeadAngleWarning

    controller = HeadController(biased_policy(tmp_path, helpers, 4))  # tilt down
    frame = np.zeros((120, 160), dtype=np.uint8)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        controller.act(frame, 0.0, 0.0)  # level: 5 deg above tilt_min, within the margin
        controller.act(frame, math.radians(94.9), math.radians(69.9))
    with pytest.warns(HeadAngleWarning) as caught:
        command = controller.act(frame, 0.1, -0.3)
    assert len(caught) == 1 and caught[0].filename == __file__
    message = str(caught[0].message)
    for needle in ("tilt -17.2 deg", "5 to 65 deg", "tilt positive down", "radians"):
        assert needle in message, message
    assert command.target_tilt == pytest.approx(math.radians(5.0))  # still clipped in
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # once per controller
        controller.act(frame, 2.5, -0.3)
    assert issubclass(HeadAngleWarning, UserWarning)
    with pytest.warns(HeadAngleWarning, match="pan 143.2 deg"):
        HeadController(controller.model_path).act(frame, 2.5, 0.3)
