"""HeadController's one-head decision (runtime/decision.py, Python floats and the input
vector built without small arrays) gives the same bytes as the batched path the trainer
and the evaluator use (GoalEvidence, policy_actions, the vector as NumPy arrays): random
inputs replayed through both, every number compared bit for bit."""

from __future__ import annotations

import math
import struct
import warnings

import numpy as np
import pytest

from activevision.runtime import HeadController, load_metadata, pretrained_policy_path
from activevision.runtime.decision import (
    OneHeadGoal,
    clipped_move,
    continuous_move,
    greedy_action,
    offset_weight_kernel,
)
from activevision.runtime.goal_evidence import (
    GoalEvidence,
    offset_axes,
    offset_weights,
    policy_actions,
)
from activevision.runtime.metadata import metadata_path_for

SHIPPED = load_metadata(metadata_path_for(pretrained_policy_path()))


def grid(pans_deg: list[float], tilts_deg: list[float]) -> np.ndarray:
    """(V, 2) views, pan-major, radians."""
    return np.radians([(p, t) for p in pans_deg for t in tilts_deg])


#: the shipped policy's 40 views, a 3 x 5 grid, and one column of views (one pan offset)
VIEW_GRIDS = {
    "shipped": SHIPPED.goal_views,
    "3x5": grid([-40.0, 0.0, 40.0], [5.0, 20.0, 35.0, 50.0, 65.0]),
    "column": grid([10.0], [5.0, 35.0, 65.0]),
}


def bits(*values: float) -> bytes:
    """The exact bytes of some floats (-0.0 and 0.0 differ)."""
    return struct.pack(f"{len(values)}d", *values)


def random_heads(rng: np.random.Generator, views: np.ndarray, n: int) -> np.ndarray:
    """(n, 2) heads: uniform over the reachable angles, on a view, and a view minus an
    offset-grid knot (so that offsets fall exactly on knots and on the clipped ends)."""
    pans, tilts = offset_axes(views)
    uniform = np.column_stack([rng.uniform(-math.pi, math.pi, n), rng.uniform(-1.2, 1.5, n)])
    on_view = views[rng.integers(0, len(views), n)]
    knot = np.column_stack([rng.choice(pans, n), rng.choice(tilts, n)])
    on_knot = views[rng.integers(0, len(views), n)] - knot
    pick = rng.integers(0, 3, n)
    return np.where((pick == 0)[:, None], uniform, np.where((pick == 1)[:, None], on_view, on_knot))


@pytest.mark.parametrize("views", list(VIEW_GRIDS), ids=str)
def test_offset_weight_kernel_gives_offset_weights_bytes(views):
    views = VIEW_GRIDS[views]
    pans, tilts = offset_axes(views)
    rng = np.random.default_rng(0)
    out = np.empty((len(views), len(pans) * len(tilts)))
    for head in random_heads(rng, views, 600):
        pan, tilt = float(head[0]), float(head[1])
        offset_weight_kernel(views, pan, tilt, pans, tilts, out)
        want = offset_weights((views - np.array([pan, tilt]))[None], pans, tilts)[0]
        assert out.tobytes() == want.tobytes()


@pytest.mark.parametrize("frame", ["body", "camera"])
@pytest.mark.parametrize("margin", [0.0, 3.0])
@pytest.mark.parametrize("views", list(VIEW_GRIDS), ids=str)
def test_one_head_goal_moves_as_policy_actions_bit_for_bit(views, frame, margin):
    """Random goal logits (float32, as the network gives them, some large) from random
    heads, with resets between episodes: the same goal, evidence, discrete action and
    continuous move, byte for byte."""
    views = VIEW_GRIDS[views]
    table = SHIPPED.action_table
    reach = (math.radians(10.0), math.radians(6.0))
    n_logits = len(offset_axes(views)[0]) * len(offset_axes(views)[1])
    n_logits = n_logits if frame == "camera" else len(views)
    rng = np.random.default_rng(len(views) + int(margin))
    batched = GoalEvidence(1, views, table, margin, frame)
    fast = OneHeadGoal(GoalEvidence(1, views, table, margin, frame))
    heads = random_heads(rng, views, 800)
    for step, head in enumerate(heads):
        if rng.random() < 0.05:
            batched.reset()
            fast.evidence.reset()
        scale = 30.0 if step % 7 == 0 else 3.0
        logits = (rng.normal(size=n_logits) * scale).astype(np.float32)
        pan, tilt = float(head[0]), float(head[1])
        heads_1 = np.array([[pan, tilt]])
        evidence_before = batched.evidence.copy(), batched.current.copy()
        want_move = policy_actions(None, logits[None], heads_1, np.array(reach), batched)[0]
        goal = fast.target(logits, pan, tilt)
        assert bits(*continuous_move(pan, tilt, goal, reach)) == want_move.tobytes()
        assert fast.evidence.evidence.tobytes() == batched.evidence.tobytes()
        assert int(fast.evidence.current[0]) == int(batched.current[0])
        # the discrete action from the same goal (the same step replayed on the batch)
        batched.evidence[:], batched.current[:] = evidence_before
        want_action = policy_actions(None, logits[None], heads_1, None, batched)[0]
        assert greedy_action(pan, tilt, goal, table) == int(want_action)


def test_clipped_move_is_policy_actions_continuous_output():
    rng = np.random.default_rng(3)
    outputs = (rng.normal(size=(500, 2)) * 2).astype(np.float32)
    outputs[:10] = [[1.0, -1.0], [0.0, -0.0], [np.nan, 0.5]] + [[1.5, -7.0]] * 7
    heads = np.zeros((1, 2))
    for row in outputs:
        want = policy_actions(row[None], None, heads, np.radians([10, 10]))[0]
        assert bits(*clipped_move(row)) == want.tobytes()


# ------------------------------------------------------------------ through HeadController
def old_vector(controller, history, pan, tilt, pose, pose_error, proposal) -> np.ndarray:
    """The vector input as HeadController built it before (NumPy arrays per part)."""
    parts = []
    for key in controller.metadata.vector_keys:
        if key == "head":
            parts.append(np.array([pan, tilt]))
        elif key == "pose":
            x, y, theta = np.asarray(pose, dtype=np.float64).reshape(3)
            parts.append(np.array([x, y, math.cos(theta), math.sin(theta)]))
        elif key == "pose_error":
            parts.append(np.asarray(pose_error, dtype=np.float64).reshape(1))
        elif key == "proposal":
            p_pan, p_tilt = float(proposal[0]), float(proposal[1])
            if math.isnan(p_pan):
                parts.append(np.zeros(5))
            else:
                parts.append(np.array([p_pan, p_tilt, p_pan - pan, p_tilt - tilt, 1.0]))
        else:
            onehot = np.zeros((len(history), controller.n_actions))
            seen = history >= 0
            onehot[np.flatnonzero(seen), history[seen]] = 1.0
            parts.append(onehot.reshape(-1))
    return np.clip(np.concatenate(parts), -10.0, 10.0).astype(np.float32)


def random_inputs(rng: np.random.Generator, inputs: tuple[str, ...]) -> dict:
    """The optional inputs of ``act`` in the forms a robot gives them: floats, ints,
    NumPy scalars and arrays, lists; errors above the vector bound; no proposal."""
    pose = [rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(-10, 10)]
    form = rng.integers(0, 4)
    given = {
        "pose": (
            tuple(pose)
            if form == 0
            else np.array(pose)
            if form == 1
            else [int(pose[0]), np.float64(pose[1]), pose[2]]
            if form == 2
            else tuple(np.float64(v) for v in pose)
        ),
        "pose_error": [float(rng.uniform(0, 15)), 0.0, 3, np.float64(0.25), [1.5]][form],
        "proposal": (
            (math.nan, math.nan)
            if rng.random() < 0.3
            else (rng.uniform(-math.pi, math.pi), rng.uniform(-1.5, 1.5))
        ),
    }
    return {k: v for k, v in given.items() if k in inputs}


def replay(controller: HeadController, steps: int, seed: int) -> int:
    """``steps`` random decisions of ``controller`` against the old path; returns the
    number of distinct moves (or goals, with goal evidence) seen: the replay must explore."""
    meta = controller.metadata
    rng = np.random.default_rng(seed)
    frames = [rng.integers(0, 256, (120, 160), dtype=np.uint8) for _ in range(3)]
    frames += [rng.integers(0, 256, (240, 320, 3), dtype=np.uint8)]
    evidence = None
    if meta.act_by == "goal":
        evidence = GoalEvidence(
            1, meta.goal_views, meta.action_table, meta.goal_switch_margin, meta.goal_frame
        )
    max_move = None if meta.max_move is None else np.asarray(meta.max_move)
    history = np.full(meta.action_history, -1, dtype=np.int64)
    seen = set()
    limits = meta.head_limits
    for step in range(steps):
        if step % 40 == 0:
            controller.reset()
            history[:] = -1
            if evidence is not None:
                evidence.reset()
        pan = rng.uniform(limits.pan_min - 0.2, limits.pan_max + 0.2)
        tilt = rng.uniform(limits.tilt_min - 0.2, limits.tilt_max + 0.2)
        pan = [pan, np.float64(pan), 0][rng.integers(0, 3)] if step % 5 == 0 else pan
        given = random_inputs(rng, controller.inputs)
        want_vector = old_vector(controller, history, float(pan), float(tilt), **given)
        command = controller.act(frames[step % len(frames)], pan, tilt, **given)
        assert controller._vector[0].tobytes() == want_vector.tobytes()
        q, goal_logits = controller.last_q_values, controller.last_goal_logits
        heads = np.array([[float(pan), float(tilt)]])
        chosen = policy_actions(
            q[None], None if goal_logits is None else goal_logits[None], heads, max_move, evidence
        )[0]
        if max_move is not None:
            action = -1
            d_pan, d_tilt = (float(v) for v in chosen * max_move)
        else:
            action = int(chosen)
            history[:-1], history[-1:] = history[1:], action
            d_pan, d_tilt = (float(v) for v in meta.action_table[action])
        target = limits.clip(float(pan) + d_pan, float(tilt) + d_tilt)
        assert command.action == action
        assert bits(*command[1:]) == bits(d_pan, d_tilt, *target)
        if evidence is not None:  # and the same evidence, to the last bit
            assert controller._evidence is not None
            assert controller._evidence.evidence.tobytes() == evidence.evidence.tobytes()
        seen.add((action, d_pan, d_tilt) if evidence is None else int(evidence.current[0]))
    return len(seen)


def test_shipped_policy_commands_are_the_batched_paths_bytes():
    controller = HeadController(pretrained_policy_path())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # heads beyond the limits warn once
        assert replay(controller, 600, seed=0) >= 3


@pytest.mark.parametrize(
    ("act_by", "action_type"),
    [("action", "discrete"), ("goal", "discrete"), ("action", "continuous")],
)
def test_student_commands_are_the_batched_paths_bytes(tmp_path, act_by, action_type):
    """Discrete students with two remembered actions (argmax, or greedy towards a goal
    named as a view) and a continuous one without goal evidence."""
    torch = pytest.importorskip("torch")
    from activevision.agents.student import StudentNetwork
    from activevision.export import export_onnx, policy_metadata
    from activevision.geometry import CameraConfig

    continuous = action_type == "continuous"
    history = 0 if continuous else 2
    keys = ["head", "pose", "pose_error", "proposal"] + (["actions"] if history else [])
    torch.manual_seed(0)
    network = StudentNetwork(
        2 if continuous else 9,
        2 + 4 + 1 + 5 + 9 * history,
        n_goals=len(SHIPPED.goal_views) if act_by == "goal" else 0,
        continuous=continuous,
    ).eval()
    metadata = policy_metadata(SHIPPED.action_table, CameraConfig())
    metadata.update(
        observation="image+head+pose+proposal", vector_keys=keys, action_history=history
    )
    if continuous:
        metadata.update(action_type="continuous", max_move_deg=[10.0, 6.0])
    if act_by == "goal":
        metadata.update(
            act_by="goal", goal_views_deg=np.degrees(SHIPPED.goal_views).tolist(), goal_frame="body"
        )
    paths = export_onnx(network, tmp_path / "policy.onnx", metadata)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert replay(HeadController(paths.model_path), 300, seed=1) >= 2
