"""Per-decision latency of the head controller: PyTorch eager vs onnxruntime, batch 1, 1 thread.

One decision = camera frame in -> head command out: grey conversion + area resize (the
runtime's NumPy preprocessing, for both back ends), the Q-network, argmax, target clipping.
Two camera inputs: a 640 x 480 RGB frame and a 160 x 120 grey frame (no resize).

The back ends are timed in alternating rounds, so a change in machine load hits both alike.
The paper reports 2.3 ms per inference (GTX 1060 + i7-7700HQ).

Usage::

    python bench/inference.py                    # freshly initialised paper network
    python bench/inference.py --run runs/paper   # a trained run (exported to a temp dir)
    python bench/inference.py --variants         # also compare ONNX export/session variants

The last printed line is one JSON object (``onnx_p50_ms``, ``onnx_p99_ms``, ``torch_p50_ms``...).
"""

from __future__ import annotations

import json
import os
import platform
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import onnxruntime as ort
import torch

import activevision
from activevision.agents.q_network import QNetwork
from activevision.cli.args import ArgumentParser, int_in, positive_int, refused_by
from activevision.export import export_onnx, export_run, policy_metadata
from activevision.geometry import CameraConfig
from activevision.runtime import FramePreprocessor, HeadController, robot_session_options

PAPER_MS = 2.3  #: the paper's time per inference (GTX 1060 + i7-7700HQ)


def eight_way_table(step_deg: float = 3.0) -> np.ndarray:
    """The release's 9 head moves (as activevision.envs.actions.action_table)."""
    s = np.radians(step_deg)
    d = s * np.sqrt(2) / 2
    return np.array([(0, 0), (s, 0), (-s, 0), (0, -s), (0, s), (d, -d), (d, d), (-d, -d), (-d, d)])


def camera_frames(rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Structured test frames: smooth shading, bright lines, noise (content barely matters)."""
    y, x = np.mgrid[0:480, 0:640]
    grey = 70 + 50 * (y / 480) + 8 * rng.standard_normal((480, 640))
    grey[np.abs(0.3 * x - y + 200) < 6] = 235
    grey[np.abs(x - 320 + 0.2 * y) < 5] = 235
    rgb = np.stack([0.6 * grey + 40, grey, 0.4 * grey + 30], axis=-1)
    small = grey.reshape(120, 4, 160, 4).mean(axis=(1, 3))
    return {
        "rgb640x480": np.clip(rgb, 0, 255).astype(np.uint8),
        "grey160x120": np.clip(small, 0, 255).astype(np.uint8),
    }


class TorchController:
    """The same decision as HeadController, with PyTorch eager for the network."""

    def __init__(self, network: QNetwork, table: np.ndarray, camera: CameraConfig) -> None:
        self.network = network.eval()
        self.preprocess = FramePreprocessor(*network.image_shape)
        self.table = [(float(a), float(b)) for a, b in table]
        self.camera = camera
        self.frames = np.zeros((1, 1, *network.image_shape), dtype=np.uint8)
        self.input = torch.from_numpy(self.frames)

    def act(self, frame: np.ndarray, pan: float, tilt: float) -> tuple[int, float, float]:
        self.preprocess(frame, "rgb", out=self.frames[0, -1])
        with torch.inference_mode():
            action = int(self.network(self.input).argmax())
        d_pan, d_tilt = self.table[action]
        cam = self.camera
        return (
            action,
            min(max(pan + d_pan, cam.pan_min), cam.pan_max),
            min(max(tilt + d_tilt, cam.tilt_min), cam.tilt_max),
        )


def time_calls(call: Callable[[], object], iterations: int) -> np.ndarray:
    """Wall time of each call, milliseconds."""
    times = np.empty(iterations)
    clock = time.perf_counter_ns
    for i in range(iterations):
        start = clock()
        call()
        times[i] = clock() - start
    return times / 1e6


def interleaved(
    calls: dict[str, Callable[[], object]], iterations: int, warmup: int, rounds: int
) -> dict[str, np.ndarray]:
    """Time each call ``iterations`` times, in ``rounds`` alternating blocks after warm-up."""
    for call in calls.values():
        time_calls(call, warmup)
    block = max(1, iterations // rounds)
    samples: dict[str, list[np.ndarray]] = {name: [] for name in calls}
    for _ in range(rounds):
        for name, call in calls.items():
            samples[name].append(time_calls(call, block))
    return {name: np.concatenate(parts) for name, parts in samples.items()}


def summary(times: np.ndarray) -> dict[str, float]:
    p50, p90, p99 = np.percentile(times, [50, 90, 99])
    return {
        "p50": float(p50),
        "p90": float(p90),
        "p99": float(p99),
        "min": float(times.min()),
        "mean": float(times.mean()),
    }


def variant_sessions(network: QNetwork, directory: Path) -> dict[str, ort.InferenceSession]:
    """onnxruntime sessions for export / session-option variants of the same network."""
    metadata = policy_metadata(eight_way_table(), CameraConfig())
    exports = {
        "fold,static": {},
        "nofold,static": {"fold_scaling": False},
        "fold,dynamic-batch": {"dynamic_batch": True},
    }
    sessions = {}
    for name, options in exports.items():
        path = export_onnx(network, directory / name / "policy.onnx", metadata, **options)
        sessions[f"{name},opt=all"] = ort.InferenceSession(
            str(path.model_path), robot_session_options(1), providers=["CPUExecutionProvider"]
        )
    base = directory / "fold,static" / "policy.onnx"
    levels = {
        "none": "ORT_DISABLE_ALL",
        "basic": "ORT_ENABLE_BASIC",
        "extended": "ORT_ENABLE_EXTENDED",
    }
    for name, level in levels.items():
        options = robot_session_options(1)
        options.graph_optimization_level = getattr(ort.GraphOptimizationLevel, level)
        sessions[f"fold,static,opt={name}"] = ort.InferenceSession(
            str(base), options, providers=["CPUExecutionProvider"]
        )
    spinning = ort.SessionOptions()  # robot_session_options(1) but with spinning allowed
    spinning.intra_op_num_threads = spinning.inter_op_num_threads = 1
    spinning.add_session_config_entry("session.intra_op.allow_spinning", "1")
    spinning.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    spinning.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    sessions["fold,static,opt=all,spinning"] = ort.InferenceSession(
        str(base), spinning, providers=["CPUExecutionProvider"]
    )
    return sessions


def conditions() -> dict[str, object]:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "loadavg_1min": os.getloadavg()[0],
        "torch": torch.__version__,
        "onnxruntime": ort.__version__,
        "numpy": np.__version__,
        "activevision": activevision.__version__,
    }


def main() -> None:
    parser = ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--run", type=Path, help="training run to export (default: random init)")
    parser.add_argument(
        "--iterations", type=int_in(2, 10**7), default=2000, help="timed decisions per case"
    )
    parser.add_argument("--warmup", type=int_in(0, 10**6), default=200)
    parser.add_argument(
        "--rounds", type=positive_int, default=4, help="alternating blocks per case"
    )
    parser.add_argument(
        "--variants",
        action="store_true",
        help="also time ONNX export/session variants (network only)",
    )
    args = parser.parse_args()
    if args.run is not None and not (args.run / "config.json").is_file():
        parser.error(f"--run {args.run}: not a training run (no config.json)")

    torch.set_num_threads(1)
    torch.set_num_interop_threads(1)
    rng = np.random.default_rng(0)
    before = conditions()
    with tempfile.TemporaryDirectory() as tmp:
        tmp_dir = Path(tmp)
        if args.run is not None:
            from activevision.training import load_policy

            with refused_by(parser, "--run"):  # weights truncated, garbage...
                network = load_policy(args.run)
                model_path = export_run(args.run, tmp_dir / "policy.onnx").model_path
        else:
            torch.manual_seed(0)
            network = QNetwork(9).eval()
            metadata = policy_metadata(eight_way_table(), CameraConfig())
            model_path = export_onnx(network, tmp_dir / "policy.onnx", metadata).model_path
        controller = HeadController(model_path, num_threads=1)
        if controller.metadata.vector_size:
            parser.error(
                f"--run {args.run}: its policy takes {', '.join(controller.metadata.vector_keys)}"
                " beside the image; this benchmark times image-only policies (for the others:"
                " bench/inference_inputs.py --policy)"
            )
        torch_controller = TorchController(
            network, controller.metadata.action_table, CameraConfig()
        )
        frames = camera_frames(rng)
        net_input = np.zeros((1, *controller.metadata.input_shape), dtype=np.uint8)
        torch_input = torch.from_numpy(net_input)

        def torch_network() -> None:
            with torch.inference_mode():
                network(torch_input)

        session = controller._session
        calls: dict[str, Callable[[], object]] = {}
        for name, frame in frames.items():
            calls[f"onnx/{name}"] = lambda f=frame: controller.act(f, 0.1, 0.5)
            calls[f"torch/{name}"] = lambda f=frame: torch_controller.act(f, 0.1, 0.5)
            calls[f"preprocess/{name}"] = lambda f=frame: controller.observe(f)
        calls["onnx/network-only"] = lambda: session.run(["q_values"], {"frames": net_input})
        calls["torch/network-only"] = torch_network
        if args.variants:
            for name, variant in variant_sessions(network, tmp_dir / "variants").items():
                calls[f"variant/{name}"] = lambda s=variant: s.run(None, {"frames": net_input})
        results = {
            name: summary(t)
            for name, t in interleaved(calls, args.iterations, args.warmup, args.rounds).items()
        }

    after = conditions()
    print(f"{'case':48s} {'p50 ms':>8s} {'p90 ms':>8s} {'p99 ms':>8s} {'min ms':>8s}")
    for name, stats in results.items():
        print(
            f"{name:48s} {stats['p50']:8.3f} {stats['p90']:8.3f} {stats['p99']:8.3f} "
            f"{stats['min']:8.3f}"
        )
    onnx, torch_eager = results["onnx/rgb640x480"], results["torch/rgb640x480"]
    print(
        f"paper: {PAPER_MS} ms/inference (GTX 1060); onnxruntime on one core, 640x480 RGB "
        f"frame to command: {onnx['p50']:.3f} ms median ({PAPER_MS / onnx['p50']:.1f}x "
        f"faster), PyTorch eager {torch_eager['p50']:.3f} ms"
    )
    print(
        f"onnxruntime / PyTorch eager in the same run: {onnx['p50'] / torch_eager['p50']:.2f}x"
        f" (p50), {onnx['p99'] / torch_eager['p99']:.2f}x (p99)"
    )
    print(
        f"conditions: {before['cpu']}, {before['cores']} cores, load average "
        f"{before['loadavg_1min']:.2f} -> {after['loadavg_1min']:.2f}; "
        f"{args.iterations} decisions per case after {args.warmup} warm-up"
    )
    record = {
        "onnx_p50_ms": onnx["p50"],
        "onnx_p99_ms": onnx["p99"],
        "torch_p50_ms": torch_eager["p50"],
        "torch_p99_ms": torch_eager["p99"],
        "onnx_grey160_p50_ms": results["onnx/grey160x120"]["p50"],
        "onnx_grey160_p99_ms": results["onnx/grey160x120"]["p99"],
        "torch_grey160_p50_ms": results["torch/grey160x120"]["p50"],
        "preprocess_rgb640_p50_ms": results["preprocess/rgb640x480"]["p50"],
        "onnx_network_p50_ms": results["onnx/network-only"]["p50"],
        "torch_network_p50_ms": results["torch/network-only"]["p50"],
        "paper_ms": PAPER_MS,
        "onnx_p50_over_paper": onnx["p50"] / PAPER_MS,
        "torch_p50_over_paper": torch_eager["p50"] / PAPER_MS,
        "onnx_over_torch_p50": onnx["p50"] / torch_eager["p50"],
        "onnx_over_torch_p99": onnx["p99"] / torch_eager["p99"],
        "target_met": onnx["p50"] < 0.5 and onnx["p99"] < 1.0,
        "iterations": args.iterations,
        "loadavg_1min": [before["loadavg_1min"], after["loadavg_1min"]],
        "cpu": before["cpu"],
        "versions": {k: before[k] for k in ("torch", "onnxruntime", "numpy", "activevision")},
    }
    if args.variants:
        record["variants_p50_ms"] = {
            name.removeprefix("variant/"): stats["p50"]
            for name, stats in results.items()
            if name.startswith("variant/")
        }
    print(json.dumps(record))


if __name__ == "__main__":
    main()
