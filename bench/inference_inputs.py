"""Per-decision latency of HeadController for a policy with robot inputs (head angles,
prior pose and its error, the entropy method's proposal, goal evidence) against the paper's
image-only Q-network, both through onnxruntime on one thread, timed in alternating rounds.

One decision: a 640 x 480 RGB frame in (grey conversion, area resize), the vector built from
the inputs, the network, goal evidence or argmax, target clipping.

    python bench/inference_inputs.py                       # the shipped policy
    python bench/inference_inputs.py --policy deploy/policy.onnx

The last line is one JSON object (``p50_ms``, ``p99_ms``, ``reference_p50_ms``, ratios).
"""

from __future__ import annotations

import json
import math
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from activevision.agents.q_network import QNetwork
from activevision.cli.args import ArgumentParser, int_in, refused_by
from activevision.export import export_onnx, policy_metadata
from activevision.geometry import CameraConfig
from activevision.runtime import HeadController, pretrained_policy_path

#: the robot inputs an episodic policy may take besides the frame and head angles
EXTRA = {"pose": (1.2, -0.4, 0.7), "pose_error": 0.3, "proposal": (0.35, 0.44)}


def eight_way_table(step_deg: float = 3.0) -> np.ndarray:
    s = math.radians(step_deg)
    d = s * math.sqrt(2) / 2
    moves = [(0, 0), (s, 0), (-s, 0), (0, -s), (0, s), (d, -d), (d, d), (-d, -d), (-d, d)]
    return np.asarray(moves, dtype=np.float64)


def timed(call, n: int) -> list[float]:
    out = []
    for _ in range(n):
        t0 = time.perf_counter()
        call()
        out.append(time.perf_counter() - t0)
    return out


def main() -> None:
    parser = ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--policy", type=Path, help="policy.onnx (default: the shipped one)")
    parser.add_argument(
        "--decisions", type=int_in(10, 10**7), default=3000, help="timed, in 10 rounds"
    )
    args = parser.parse_args()
    with refused_by(parser, "--policy"):
        policy = HeadController(args.policy or pretrained_policy_path(), num_threads=1)
    if not set(policy.inputs) <= set(EXTRA):
        parser.error(
            f"--policy {args.policy}: its policy takes {', '.join(policy.inputs)} (a match"
            " student: bench/match_student.py --policy)"
        )
    torch.set_num_threads(1)
    rng = np.random.default_rng(0)
    frames = rng.integers(0, 256, (16, 480, 640, 3), dtype=np.uint8)
    with tempfile.TemporaryDirectory() as tmp:
        torch.manual_seed(0)
        metadata = policy_metadata(eight_way_table(), CameraConfig())
        reference_path = export_onnx(QNetwork(9).eval(), Path(tmp) / "paper.onnx", metadata)
        reference = HeadController(reference_path.model_path, num_threads=1)
        given = {k: v for k, v in EXTRA.items() if k in policy.inputs}
        state = {"i": 0}

        def decide(controller: HeadController, kwargs: dict) -> None:
            state["i"] += 1
            controller.act(frames[state["i"] % len(frames)], 0.1, 0.5, **kwargs)

        for _ in range(200):  # warm-up
            decide(policy, given)
            decide(reference, {})
        ours: list[float] = []
        theirs: list[float] = []
        rounds = 10
        for _ in range(rounds):
            policy.reset()
            ours += timed(lambda: decide(policy, given), args.decisions // rounds)
            theirs += timed(lambda: decide(reference, {}), args.decisions // rounds)
    ms, ref = np.asarray(ours) * 1e3, np.asarray(theirs) * 1e3
    result = {
        "bench": "inference_inputs",
        "policy": str(args.policy or "shipped"),
        "inputs": list(policy.inputs),
        "act_by": policy.metadata.act_by,
        "p50_ms": float(np.percentile(ms, 50)),
        "p99_ms": float(np.percentile(ms, 99)),
        "reference_p50_ms": float(np.percentile(ref, 50)),
        "reference_p99_ms": float(np.percentile(ref, 99)),
    }
    result["p50_ratio"] = result["p50_ms"] / result["reference_p50_ms"]
    result["p99_ratio"] = result["p99_ms"] / result["reference_p99_ms"]
    print(f"policy    p50 {result['p50_ms']:.3f} ms  p99 {result['p99_ms']:.3f} ms")
    print(
        f"reference p50 {result['reference_p50_ms']:.3f} ms  p99 "
        f"{result['reference_p99_ms']:.3f} ms (the paper's image-only Q-network)"
    )
    print(f"ratio     p50 {result['p50_ratio']:.2f}x  p99 {result['p99_ratio']:.2f}x")
    print(json.dumps(result))


if __name__ == "__main__":
    main()
