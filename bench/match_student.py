"""Per-decision cost of a match student (``--preset match_dagger``, exported to ONNX, through
HeadController on one thread: a 640 x 480 RGB frame in, a head command out) against its
teacher, the ``entropy_track`` planner (Algorithm 1 over 481 views from the belief, for one
robot), timed in alternating rounds on the same match states.

    python bench/match_student.py --policy runs/match_dagger/policy.onnx
    python bench/match_student.py      # an untrained student of the preset's shape (the
                                       # weights do not change the cost)

The last line is one JSON object (``student_p50_ms``, ``planner_p50_ms``, their ratio).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from activevision.cli.args import ArgumentParser, int_in, refused_by
from activevision.envs.match.config import MatchConfig
from activevision.envs.match.heads import EntropyTrackTeacher
from activevision.envs.match.vector import ActiveVisionMatchVectorEnv
from activevision.runtime import HeadController

#: what a match student takes besides the frame and head angles
STUDENT_INPUTS = ("pose", "belief", "ball")


def untrained_student(run_dir: Path) -> Path:
    """An untrained ``match_dagger`` student, exported (same network, same inputs)."""
    from activevision.export import export_run
    from activevision.training.match_dagger import MatchDaggerTrainer
    from activevision.training.presets import preset

    config = preset("match_dagger").replace(**{"run.tensorboard": False})
    trainer = MatchDaggerTrainer(config, run_dir / "run", loggers=[])
    trainer.save_checkpoint()
    trainer.close()
    return export_run(run_dir / "run").model_path


def match_student(parser: argparse.ArgumentParser, policy: Path) -> HeadController:
    """``--policy``'s controller, or one line naming it where it is not a match student's."""
    with refused_by(parser, "--policy"):
        student = HeadController(policy, num_threads=1)
    if set(student.inputs) != set(STUDENT_INPUTS):
        parser.error(
            f"--policy {policy}: not a match student (its robot inputs:"
            f" {', '.join(student.inputs) or 'none'}; a student's: {', '.join(STUDENT_INPUTS)};"
            " for episodic policies: bench/inference_inputs.py --policy)"
        )
    return student


def main() -> None:
    parser = ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--policy", type=Path, help="a match student's policy.onnx")
    parser.add_argument(
        "--states", type=int_in(20, 10**6), default=200, help="match states timed, per round"
    )
    args = parser.parse_args()
    student = None if args.policy is None else match_student(parser, args.policy)
    config = MatchConfig()
    env = ActiveVisionMatchVectorEnv(1, config)
    _, info = env.reset(seed=0)
    teacher = EntropyTrackTeacher(config)
    rng = np.random.default_rng(0)
    frames = rng.integers(0, 256, (16, 480, 640, 3), dtype=np.uint8)
    states = []
    for _ in range(args.states):  # a walk through one match, the teacher at the head
        states.append({k: v.copy() for k, v in info.items()})
        _, _, _, _, info = env.step(teacher.actions(info))
    if student is None:
        with tempfile.TemporaryDirectory() as tmp:
            student = HeadController(untrained_student(Path(tmp)), num_threads=1)

    def decide(i: int) -> None:
        s = states[i]
        cov, rel = s["belief_cov"][0], s["ball_relative"][0]
        student.act(
            frames[i % len(frames)],
            *s["head"][0],
            pose=tuple(s["belief_mean"][0]),
            belief=tuple(np.sqrt(np.diag(cov))),
            ball=(rel[0], rel[1], float(s["ball_age"][0]) * config.tick_seconds),
        )

    def plan(i: int) -> None:
        teacher.targets(states[i])

    for i in range(20):  # warm-up (compilation, onnxruntime's first runs)
        decide(i)
        plan(i)
    times: dict[str, list[float]] = {"student": [], "planner": []}
    for _ in range(5):
        for name, call in (("student", decide), ("planner", plan)):
            for i in range(len(states)):
                t0 = time.perf_counter()
                call(i)
                times[name].append(time.perf_counter() - t0)
    ms = {k: 1000 * np.array(v) for k, v in times.items()}
    for name, values in ms.items():
        print(f"{name:8s} p50 {np.median(values):.3f} ms  p99 {np.percentile(values, 99):.3f} ms")
    ratio = float(np.median(ms["student"]) / np.median(ms["planner"]))
    print(f"student / planner (median): {ratio:.2f}x")
    print(
        json.dumps(
            {
                "student_p50_ms": round(float(np.median(ms["student"])), 4),
                "student_p99_ms": round(float(np.percentile(ms["student"], 99)), 4),
                "planner_p50_ms": round(float(np.median(ms["planner"])), 4),
                "planner_p99_ms": round(float(np.percentile(ms["planner"], 99)), 4),
                "ratio_p50": round(ratio, 3),
            }
        )
    )


if __name__ == "__main__":
    main()
