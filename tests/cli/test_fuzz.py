"""The fuzz pass of bench/fuzz_inputs.py, in CI: hostile CLI options, ``--set`` keys and env
keywords each end in one clear error naming the value (no traceback, no silent acceptance)."""

import json
import subprocess
import sys
from pathlib import Path

BENCH = Path(__file__).parents[2] / "bench" / "fuzz_inputs.py"


def test_fuzz_pass_finds_no_traceback_and_no_silent_acceptance():
    done = subprocess.run(
        [sys.executable, str(BENCH), "--seed", "1", "--cases", "150"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["cases"] > 300
    problems = {k: result[k] for k in ("tracebacks", "silent_acceptances")}
    problems["unnamed"] = result["errors_not_naming_the_value"]
    assert problems == {"tracebacks": 0, "silent_acceptances": 0, "unnamed": 0}, done.stdout
    assert done.returncode == 0
