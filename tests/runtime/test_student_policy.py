"""A DAgger student through ONNX and HeadController: the same actions as in PyTorch, with the
vector built by the runtime from the head angles, pose, its error and the proposal; and one
clear error for inputs that do not fit the policy."""

from __future__ import annotations

import math

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnxruntime")

from activevision.agents.student import StudentNetwork  # noqa: E402
from activevision.envs import ActiveVisionEnv, EnvConfig  # noqa: E402
from activevision.envs.observations import flatten_vectors, vector_keys, vector_sizes  # noqa: E402
from activevision.experiments.policies import LearnedPolicy, OnnxPolicy  # noqa: E402
from activevision.export import export_onnx, policy_metadata  # noqa: E402
from activevision.runtime import HeadController  # noqa: E402
from activevision.runtime.goal_evidence import (  # noqa: E402
    GoalEvidence,
    GoalFrame,
    greedy_actions,
    offset_count,
    policy_actions,
)

KIND = "image+head+pose+proposal"


def exported(
    tmp_path,
    observation: str = KIND,
    history: int = 2,
    act_by: str = "action",
    goal_frame: GoalFrame = "body",
):
    config = EnvConfig(
        observation=observation, action_history=history, prior_error_range=(0.0, 1.0)
    )
    keys = vector_keys(config)
    torch.manual_seed(0)
    env = ActiveVisionEnv(config)
    views = env.sim.localisation.grid.views
    goals = offset_count(views) if goal_frame == "camera" else len(views)
    network = StudentNetwork(9, sum(vector_sizes(config, 9).values()), n_goals=goals).eval()
    metadata = policy_metadata(env.sim.actions, config.camera)
    metadata.update(observation=observation, vector_keys=list(keys), action_history=history)
    if act_by == "goal":
        metadata.update(
            act_by="goal",
            goal_views_deg=np.degrees(views).tolist(),
            goal_frame=goal_frame,
        )
    paths = export_onnx(network, tmp_path / "policy.onnx", metadata)
    return network, paths, config, keys


@pytest.mark.parametrize(
    ("act_by", "goal_frame"), [("action", "body"), ("goal", "body"), ("goal", "camera")]
)
def test_onnx_student_plays_like_pytorch(tmp_path, act_by, goal_frame):
    network, paths, config, keys = exported(tmp_path, act_by=act_by, goal_frame=goal_frame)
    evidence = None
    if act_by == "goal":
        grid = ActiveVisionEnv(config).sim.localisation.grid
        views = grid.views
        table = ActiveVisionEnv(config).sim.actions
        evidence = GoalEvidence(1, views, table, frame=goal_frame)
    torch_policy = LearnedPolicy(network, vector_keys=keys, goal_evidence=evidence)
    onnx_policy = OnnxPolicy(paths.model_path)
    env_a, env_b = ActiveVisionEnv(config), ActiveVisionEnv(config)
    decisions = 0
    for seed in range(6):
        obs_a, info_a = env_a.reset(seed=seed)
        obs_b, info_b = env_b.reset(seed=seed)
        onnx_policy.reset(info_b, np.random.default_rng(0))
        torch_policy.reset(info_a, np.random.default_rng(0))
        for _ in range(20):
            a, b = torch_policy.act(obs_a, info_a), onnx_policy.act(obs_b, info_b)
            assert a == b
            decisions += 1
            obs_a, _, done, _, info_a = env_a.step(a)
            obs_b, _, _, _, info_b = env_b.step(b)
            if done:
                break
    assert decisions >= 30


def test_controller_names_the_inputs_it_needs(tmp_path):
    _, paths, _, _ = exported(tmp_path)
    controller = HeadController(paths.model_path)
    assert controller.inputs == ("pose", "pose_error", "proposal")
    frame = np.zeros((120, 160), np.uint8)
    with pytest.raises(ValueError, match="needs pose"):
        controller.act(frame, 0.1, 0.3)
    with pytest.raises(ValueError, match="proposal"):
        controller.act(frame, 0.1, 0.3, pose=(0.0, 0.0, 0.0), pose_error=0.0, proposal=(1.0,))
    command = controller.act(
        frame, 0.1, 0.3, pose=(1.0, -0.5, 2.0), pose_error=0.3, proposal=(math.nan, math.nan)
    )
    assert 0 <= command.action < 9


def test_controller_clips_its_vector_as_the_env_clips_observations(tmp_path):
    """The env clips a prior pose or error scale beyond 10 to the observation space's bound;
    the controller feeds the network the same vector."""
    _, paths, _, _ = exported(tmp_path)
    controller = HeadController(paths.model_path)
    env = ActiveVisionEnv(
        observation="image+head+pose+proposal", action_history=2, prior_error_range=(12.0, 30.0)
    )
    obs, info = env.reset(seed=0)
    assert obs["pose_error"][0] == 10.0  # the error is 12 m or more
    proposal = tuple(obs["proposal"][:2]) if obs["proposal"][4] else (math.nan, math.nan)
    pan, tilt = info["head"]
    controller.act(
        obs["image"][0], pan, tilt, pose=tuple(info["prior_pose"]),
        pose_error=info["prior_error"], proposal=proposal,
    )  # fmt: skip
    keys = vector_keys(env.config)
    np.testing.assert_allclose(controller._vector[0], flatten_vectors(obs, keys), rtol=0, atol=1e-6)


def test_an_unexpected_input_names_what_the_policy_was_trained_on(tmp_path):
    _, paths, _, _ = exported(tmp_path)
    controller = HeadController(paths.model_path)
    given = {"pose": (0.0, 0.0, 0.0), "pose_error": 0.1, "proposal": (0.1, 0.3)}
    with pytest.raises(ValueError) as error:
        controller.act(np.zeros((120, 160), np.uint8), 0.1, 0.3, **given, belief=(1, 1, 1))
    trained = "image, head, pose, pose_error, proposal, actions"
    assert str(error.value).endswith(f"takes no belief; it was trained on {trained}")


@pytest.mark.parametrize(
    ("given", "message"),
    [
        ({"pose_error": -0.5}, r"pose_error must be standard deviations >= 0 .*got \[-0\.5\]"),
        ({"pose_error": True}, "pose_error must be a number, got True"),
        ({"proposal": (45.0, 20.0)}, r"proposal pan must be radians within \+-pi, got 45 \(deg"),
        ({"proposal": (0.2, 40.0)}, r"proposal tilt must be radians within \+-pi, got 40"),
        ({"proposal": (True, 0.3)}, "proposal pan must be a number of radians, got True"),
        ({"pose": (1.0, "2", 0.0)}, r"pose must be 3 numbers, got \(1\.0, '2', 0\.0\)"),
        ({"pose": (1, 2, True)}, r"pose must be 3 numbers, got \(1, 2, True\)"),
        # was clipped to 10 m, silently: a corner of the field the robot is not in
        (
            {"pose": (3000.0, -1500.0, 0.3)},
            r"pose x, y must be metres .*within \+-50\), got \(3000, -1500\) \(millimetres\?\)",
        ),
    ],
    ids=[
        "negative-error",
        "bool-error",
        "proposal-degrees",
        "tilt-degrees",
        "bool",
        "str",
        "bool-in-list",
        "pose-millimetres",
    ],
)
def test_nonsense_inputs_are_refused_by_name(tmp_path, given, message):
    """What a robot gets wrong (a negative standard deviation, degrees for radians, a flag
    or a string for a number) is one ValueError naming the value, not a silent decision."""
    _, paths, _, _ = exported(tmp_path)
    controller = HeadController(paths.model_path)
    inputs = {"pose": (0.5, 0.2, 0.3), "pose_error": 0.1, "proposal": (0.2, 0.3)} | given
    with pytest.raises(ValueError, match=message):
        controller.act(np.zeros((120, 160), np.uint8), 0.1, 0.3, **inputs)


def test_image_policy_refuses_a_pose(tmp_path):
    _, paths, _, _ = exported(tmp_path, "image+head", history=0)
    controller = HeadController(paths.model_path)
    assert controller.inputs == ()
    with pytest.raises(ValueError, match="takes no pose"):
        controller.act(np.zeros((120, 160), np.uint8), 0.0, 0.3, pose=(0.0, 0.0, 0.0))
    controller.act(np.zeros((120, 160), np.uint8), 0.0, 0.3)


def test_goal_evidence_sums_log_probabilities_and_moves_greedily():
    views = np.radians([[-30.0, 20.0], [30.0, 20.0], [0.0, 45.0]])
    table = np.radians([[0, 0], [3, 0], [-3, 0], [0, -3], [0, 3]])
    evidence = GoalEvidence(2, views, table)
    heads = np.zeros((2, 2)) + np.radians([0.0, 20.0])
    outputs = np.zeros((2, 5))  # the action head, ignored while the goal head speaks

    def act(goal_logits, slots):
        return policy_actions(
            outputs[: len(slots)], goal_logits, heads[slots], None, evidence, slots
        )

    # slot 0: view 1 a little better; slot 1: view 0 much better
    first = act(np.array([[0.0, 0.5, -5.0], [3.0, 0.0, -5.0]]), np.arange(2))
    assert list(first) == [1, 2]  # pan left (+) towards +30, pan right towards -30
    # a frame that favours view 0 a little does not turn slot 0 around...
    assert act(np.array([[0.4, 0.0, -5.0]]), np.array([0]))[0] == 1
    # ...but lasting evidence does; log-softmax sums, not raw logits
    for _ in range(3):
        action = act(np.array([[2.0, 0.0, -5.0]]), np.array([0]))[0]
    assert action == 2
    # without goal logits: the action head's argmax; a continuous policy's clipped output
    assert list(policy_actions(np.array([[0, 3, 1, 0, 0.0]]), None, heads[:1])) == [1]
    np.testing.assert_array_equal(
        policy_actions(np.array([[2.0, -0.5]]), None, heads[:1], np.radians([10, 10])),
        [[1.0, -0.5]],
    )
    evidence.reset()
    assert not evidence.evidence.any()
    assert list(greedy_actions(heads, views[[2, 2]], table)) == [4, 4]  # tilt down towards 45


def test_switch_margin_keeps_the_goal_until_another_view_leads_by_it():
    """Hand-computed: views 0 and 1 equally likely, so log-softmax differences are the
    logit differences. With a 1-nat margin the goal moves to view 1 only once its summed
    evidence leads by 1 nat; without one, at the first frame that favours it."""
    views = np.radians([[-30.0, 20.0], [30.0, 20.0]])
    table = np.radians([[0, 0], [3, 0], [-3, 0]])
    sticky, plain = GoalEvidence(1, views, table, 1.0), GoalEvidence(1, views, table)
    slot, head = np.array([0]), np.zeros((1, 2))
    frames = [[0.5, 0.0], [0.0, 0.4], [0.0, 0.4], [0.0, 0.4], [0.0, 0.4]]
    goals = []
    for frame in frames:  # 1 where the goal is view 1 (pan +30)
        goals.append(
            [int(e.target(np.array([frame]), slot, head)[0, 0] > 0) for e in (sticky, plain)]
        )
    # summed lead of view 1: -0.5, -0.1, 0.3, 0.7, 1.1
    assert [g for g, _ in goals] == [0, 0, 0, 0, 1]
    assert [g for _, g in goals] == [0, 0, 1, 1, 1]
    sticky.reset()
    assert sticky.current[0] == -1  # a new episode takes the best view at once
    assert sticky.target(np.array([[0.0, 0.1]]), slot, head)[0, 0] > 0
    with pytest.raises(ValueError, match="switch_margin"):
        GoalEvidence(1, views, table, -1.0)


def test_policy_json_carries_the_switch_margin(tmp_path):
    from activevision.runtime import PolicyFileError

    _, paths = continuous_export(tmp_path / "a", act_by="goal", goal_switch_margin=2.5)
    assert HeadController(paths.model_path).metadata.goal_switch_margin == 2.5
    with pytest.raises(PolicyFileError, match="goal_switch_margin"):
        _, paths = continuous_export(tmp_path / "b", act_by="goal", goal_switch_margin=-1)
        HeadController(paths.model_path)


def test_policy_json_names_the_goal_frame_its_output_fits(tmp_path):
    # a body-frame network (40 goal logits) described as camera-frame (133): one clear error
    from activevision.runtime import PolicyFileError

    _, paths = continuous_export(tmp_path / "a", act_by="goal", goal_frame="camera")
    with pytest.raises(PolicyFileError, match=r"goal_frame 'camera'.*133 logits"):
        HeadController(paths.model_path)
    with pytest.raises(PolicyFileError, match="'goal_frame' must be one of"):
        continuous_export(tmp_path / "b", act_by="goal", goal_frame="world")


def continuous_export(tmp_path, act_by: str = "action", **metadata_changes):
    config = EnvConfig(observation="image+head", action_type="continuous")
    torch.manual_seed(1)
    network = StudentNetwork(2, 2, n_goals=40, continuous=True).eval()
    env = ActiveVisionEnv(config)
    metadata = policy_metadata(env.sim.actions, config.camera)
    metadata.update(
        observation="image+head",
        vector_keys=["head"],
        action_type="continuous",
        max_move_deg=[10.0, 6.0],
    )
    if act_by == "goal":
        grid = env.sim.localisation.grid
        metadata.update(act_by="goal", goal_views_deg=np.degrees(grid.views).tolist())
    metadata.update(metadata_changes)
    return network, export_onnx(network, tmp_path / "policy.onnx", metadata)


def test_continuous_controller_moves_by_the_output_times_max_move(tmp_path):
    network, paths = continuous_export(tmp_path)
    controller = HeadController(paths.model_path)
    assert controller.continuous
    frame = np.random.default_rng(0).integers(0, 256, (120, 160), dtype=np.uint8)
    pan, tilt = 0.2, 0.6
    command = controller.act(frame, pan, tilt)
    with torch.inference_mode():
        move = network(torch.from_numpy(frame[None, None]), torch.tensor([[pan, tilt]])).numpy()[0]
    want = move * np.radians([10.0, 6.0])  # hand-computed: output x max_move per axis
    assert command.action == -1
    assert command.d_pan == pytest.approx(want[0], abs=1e-5)
    assert command.d_tilt == pytest.approx(want[1], abs=1e-5)
    assert command.target_pan == pytest.approx(pan + want[0], abs=1e-5)
    # a head at its pan limit: the target is clipped, the move is the policy's
    limit = controller.metadata.head_limits.pan_max
    clipped = controller.act(frame, limit, tilt)
    assert clipped.target_pan <= limit + 1e-12


def test_continuous_goal_evidence_moves_straight_towards_the_best_view(tmp_path):
    _, paths = continuous_export(tmp_path, act_by="goal")
    controller = HeadController(paths.model_path)
    frame = np.zeros((120, 160), np.uint8)
    command = controller.act(frame, 0.0, 0.5)
    best = controller.metadata.goal_views[int(np.argmax(controller.last_goal_logits))]
    reach = np.radians([10.0, 6.0])
    want = np.clip(best - [0.0, 0.5], -reach, reach)  # straight there, each axis capped
    assert (command.d_pan, command.d_tilt) == pytest.approx(tuple(want), abs=1e-9)


def test_continuous_metadata_must_say_how_far_a_move_goes(tmp_path):
    from activevision.runtime import PolicyFileError

    with pytest.raises(ValueError, match="max_move_deg"):
        continuous_export(tmp_path, max_move_deg=None)
    _, paths = continuous_export(tmp_path)
    text = paths.metadata_path.read_text()
    paths.metadata_path.write_text(text.replace('"max_move_deg": [', '"max_move_deg": [500, '))
    with pytest.raises(PolicyFileError, match="'max_move_deg' must be"):
        HeadController(paths.model_path, verify_checksum=False)
    paths.metadata_path.write_text(
        text.replace('"action_type": "continuous"', '"action_type": "x"')
    )
    with pytest.raises(PolicyFileError, match="'action_type' must be"):
        HeadController(paths.model_path)
    # a discrete policy.json beside a continuous graph: the output does not fit
    paths.metadata_path.write_text(
        text.replace('"action_type": "continuous"', '"action_type": "discrete"')
    )
    with pytest.raises(PolicyFileError, match="output shape"):
        HeadController(paths.model_path)


@pytest.mark.parametrize("action_type", ["discrete", "continuous"])
def test_a_continuous_policy_plays_matches_at_the_match_head_speed(tmp_path, action_type):
    """In a match, the continuous policy's commanded head angles are followed at the match's
    head speed: the discrete 3-deg move that ends closest, or a move of up to 3 deg per axis."""
    from activevision.envs.match.config import MatchConfig
    from activevision.envs.match.vector import ActiveVisionMatchVectorEnv
    from activevision.experiments.match_methods import OnnxMatchPolicy, move_towards

    _, paths = continuous_export(tmp_path)
    config = MatchConfig(ticks=3, action_type=action_type, max_move_deg=(3.0, 3.0))
    env = ActiveVisionMatchVectorEnv(2, config)
    obs, info = env.reset(seed=0)
    policy = OnnxMatchPolicy(config, paths.model_path)
    policy.reset(2, np.random.default_rng(0))
    actions = policy.act(obs, info)
    for i in range(2):
        command = HeadController(paths.model_path).act(obs[i, -1], *info["head"][i])
        target = np.array([[command.target_pan, command.target_tilt]])
        want = move_towards(info["head"][i : i + 1], target, config)[0]
        np.testing.assert_array_equal(actions[i], want)
    env.step(actions)  # the env accepts them
    env.close()


def test_onnx_continuous_goal_student_plays_like_pytorch(tmp_path):
    """The shipped policy's kind (continuous moves, goal evidence read at the views' offsets
    in the camera's frame, image + head + pose + error + proposal) through ONNX and
    HeadController, which builds the vector itself: the same head targets as the PyTorch
    student on the env's observations, episode after episode (the parity test above plays
    discrete students only)."""
    from activevision.experiments.policies import HeadTarget

    config = EnvConfig(
        observation=KIND,
        action_type="continuous",
        prior_error_range=(0.0, 1.0),
        max_move_deg=(10.0, 10.0),
    )
    env = ActiveVisionEnv(config)
    views, keys = env.sim.localisation.grid.views, vector_keys(config)
    torch.manual_seed(2)
    vector = sum(vector_sizes(config, 9).values())
    network = StudentNetwork(2, vector, n_goals=offset_count(views), continuous=True).eval()
    metadata = policy_metadata(env.sim.actions, config.camera)
    metadata.update(
        observation=KIND,
        vector_keys=list(keys),
        action_type="continuous",
        max_move_deg=[10.0, 10.0],
        act_by="goal",
        goal_views_deg=np.degrees(views).tolist(),
        goal_frame="camera",
    )
    paths = export_onnx(network, tmp_path / "policy.onnx", metadata)
    evidence = GoalEvidence(1, views, env.sim.actions, frame="camera")
    torch_policy = LearnedPolicy(
        network, vector_keys=keys, goal_evidence=evidence, max_move=config.max_move
    )
    onnx_policy = OnnxPolicy(paths.model_path)
    limits = onnx_policy.controller.metadata.head_limits
    envs = ActiveVisionEnv(config), ActiveVisionEnv(config)
    decisions = 0
    for seed in range(5):
        (obs_a, info_a), (obs_b, info_b) = (e.reset(seed=seed) for e in envs)
        torch_policy.reset(info_a, np.random.default_rng(0))
        onnx_policy.reset(info_b, np.random.default_rng(0))
        for _ in range(20):
            a, b = torch_policy.act(obs_a, info_a), onnx_policy.act(obs_b, info_b)
            assert isinstance(a, HeadTarget) and isinstance(b, HeadTarget)
            assert limits.clip(a.pan, a.tilt) == pytest.approx((b.pan, b.tilt), abs=1e-5)
            decisions += 1
            obs_a, _, done, _, info_a = envs[0].jump_head(a.pan, a.tilt)
            obs_b, _, _, _, info_b = envs[1].jump_head(b.pan, b.tilt)
            if done:
                break
    assert decisions >= 20


def test_a_proposal_well_outside_the_head_limits_warns_once(tmp_path):
    """A proposal planned by the robot's own code in its own convention (tilt positive up)
    lies where the policy was never shown one (best_viewpoint plans within the head limits):
    one HeadAngleWarning naming it, as for the head angles; a proposal within the limits, or
    none found, says nothing."""
    import warnings

    from activevision.runtime import HeadAngleWarning

    _, paths, _, _ = exported(tmp_path)
    controller = HeadController(paths.model_path)
    frame = np.zeros((120, 160), np.uint8)
    inputs = {"pose": (0.5, 0.2, 0.3), "pose_error": 0.1}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        controller.act(frame, 0.1, 0.3, **inputs, proposal=(-1.5, 1.1))
        controller.act(frame, 0.1, 0.3, **inputs, proposal=(math.nan, math.nan))
    with pytest.warns(HeadAngleWarning) as caught:
        controller.act(frame, 0.1, 0.3, **inputs, proposal=(0.2, -0.4))
    assert len(caught) == 1 and caught[0].filename == __file__
    assert "proposal tilt -22.9 deg lies outside the tilt limits" in str(caught[0].message)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # once per controller
        controller.act(frame, 0.1, 0.3, **inputs, proposal=(0.2, -0.4))
