"""Every benchmark script has a command line: ``--help`` lists its options, and a bad value
is one line and exit code 2 before any work (``make bench`` and the README run them)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).parents[2] / "bench"
SCRIPTS = sorted(p.name for p in BENCH.glob("*.py"))

#: one bad value per script (a count of 0, a negative budget, a batch above its starts)
BAD = {
    "continuous.py": ["--runs", "/no/such/run"],
    "env.py": ["--rounds", "0"],
    "fuzz_inputs.py": ["--cases", "-1"],
    "inference.py": ["--iterations", "0"],
    "inference_inputs.py": ["--decisions", "5"],
    "match.py": ["--batches", "0"],
    "match_student.py": ["--states", "3"],
    "reference_ppo.py": ["--minutes", "-1"],
    "render.py": ["--rounds", "0"],
    "render_determinism.py": ["--cameras", "0"],
    "reproducibility.py": ["--repeats", "0"],
    "sweep.py": ["--steps", "0"],
    "train.py": ["--threads", "-3"],
    "vectorizers.py": ["--steps", "0"],
    "viewpoint.py": ["--batch", "32", "--starts", "16"],
}


def run(script: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(BENCH / script), *args], capture_output=True, text=True, timeout=120
    )


def test_every_script_has_a_bad_value_here():
    assert sorted(BAD) == SCRIPTS


@pytest.mark.parametrize("script", SCRIPTS)
def test_help_and_a_bad_value(script):
    done = run(script, "--help")
    assert done.returncode == 0 and "usage:" in done.stdout, done.stderr
    done = run(script, *BAD[script])
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and lines[-1].startswith(f"{script}: error: ")


#: a path option naming what is not there, or not the kind of policy the script times
BAD_PATHS = [
    ("inference.py", ["--run", "/no/such/run"], "--run /no/such/run: not a training run"),
    ("inference_inputs.py", ["--policy", "/no/such.onnx"], "/no/such.onnx not found"),
    ("match_student.py", ["--policy", "/no/such.onnx"], "/no/such.onnx not found"),
    ("match_student.py", ["--policy", "{shipped}"], "not a match student"),
]


@pytest.mark.parametrize(("script", "args", "named"), BAD_PATHS)
def test_a_bad_path_is_one_line(script, args, named):
    from activevision.runtime import pretrained_policy_path

    done = run(script, *(a.format(shipped=pretrained_policy_path()) for a in args))
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and lines[-1].startswith(f"{script}: error: ")
    assert named in lines[-1]


def test_continuous_writes_no_nan_into_its_json():
    """A median over no episodes (no paired episode, a policy that solves none) is JSON
    null: strict JSON (``allow_nan=False``, other languages' parsers) has no NaN."""
    import importlib.util
    import json
    import math

    spec = importlib.util.spec_from_file_location("continuous", BENCH / "continuous.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    record = {"paired": 0, "a": {"median": math.nan, "ci": [0.1, math.nan]}, "ok": True}
    text = json.dumps(module.finite(record), allow_nan=False)
    assert json.loads(text) == {"paired": 0, "a": {"median": None, "ci": [0.1, None]}, "ok": True}


def test_reproducibility_runs_leave_no_folder(tmp_path):
    """Each of bench/reproducibility.py's training processes removes its run folder (it
    left one in the temporary directory per process); here with 60 steps, not 900."""
    import os
    import sys

    sys.path.insert(0, str(BENCH))
    try:
        import reproducibility
    finally:
        sys.path.remove(str(BENCH))
    code = reproducibility.RUN.replace(
        "total_timesteps=900, learning_starts=300", "total_timesteps=60, learning_starts=30"
    )
    assert code != reproducibility.RUN
    (tmp_path / "tmp").mkdir()
    done = subprocess.run(
        [sys.executable, "-c", code, "1", "0"],
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "TMPDIR": str(tmp_path / "tmp")},
    )
    assert done.returncode == 0, done.stderr
    assert len(done.stdout.split()[-1]) == 64  # the weights' sha256
    # (torch's compile cache, torchinductor_USER, is a cache every torch process shares)
    assert not [p for p in (tmp_path / "tmp").iterdir() if not p.name.startswith("torchinductor")]
