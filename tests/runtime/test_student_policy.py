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
from activevision.envs.observations import vector_keys, vector_sizes  # noqa: E402
from activevision.experiments.policies import LearnedPolicy, OnnxPolicy  # noqa: E402
from activevision.export import export_onnx, policy_metadata  # noqa: E402
from activevision.runtime import HeadController  # noqa: E402
from activevision.runtime.goal_evidence import GoalEvidence, greedy_actions  # noqa: E402

KIND = "image+head+pose+proposal"


def exported(tmp_path, observation: str = KIND, history: int = 2, act_by: str = "action"):
    config = EnvConfig(
        observation=observation, action_history=history, prior_error_range=(0.0, 1.0)
    )
    keys = vector_keys(config)
    torch.manual_seed(0)
    network = StudentNetwork(9, sum(vector_sizes(config, 9).values()), n_goals=40).eval()
    env = ActiveVisionEnv(config)
    metadata = policy_metadata(env.sim.actions, config.camera)
    metadata.update(observation=observation, vector_keys=list(keys), action_history=history)
    if act_by == "goal":
        grid = env.sim.localisation.grid
        metadata.update(
            act_by="goal",
            goal_views_deg=np.degrees(grid.views).tolist(),
        )
    paths = export_onnx(network, tmp_path / "policy.onnx", metadata)
    return network, paths, config, keys


@pytest.mark.parametrize("act_by", ["action", "goal"])
def test_onnx_student_plays_like_pytorch(tmp_path, act_by):
    network, paths, config, keys = exported(tmp_path, act_by=act_by)
    evidence = None
    if act_by == "goal":
        grid = ActiveVisionEnv(config).sim.localisation.grid
        views = grid.views
        evidence = GoalEvidence(1, views, ActiveVisionEnv(config).sim.actions)
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
    # slot 0: view 1 a little better; slot 1: view 0 much better
    first = evidence.act(np.array([[0.0, 0.5, -5.0], [3.0, 0.0, -5.0]]), heads, np.arange(2))
    assert list(first) == [1, 2]  # pan left (+) towards +30, pan right towards -30
    # a frame that favours view 0 a little does not turn slot 0 around...
    assert evidence.act(np.array([[0.4, 0.0, -5.0]]), heads[:1], np.array([0]))[0] == 1
    # ...but lasting evidence does; log-softmax sums, not raw logits
    for _ in range(3):
        action = evidence.act(np.array([[2.0, 0.0, -5.0]]), heads[:1], np.array([0]))[0]
    assert action == 2
    evidence.reset()
    assert not evidence.evidence.any()
    assert list(greedy_actions(heads, views[[2, 2]], table)) == [4, 4]  # tilt down towards 45
