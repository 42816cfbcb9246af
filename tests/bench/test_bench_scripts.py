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


#: one option per script that keeps one value, with two good values
TWICE = {
    "continuous.py": ["--episodes", "1", "2"],
    "env.py": ["--rounds", "1", "2"],
    "fuzz_inputs.py": ["--cases", "1", "2"],
    "inference.py": ["--iterations", "10", "20"],
    "inference_inputs.py": ["--policy", "a.onnx", "b.onnx"],
    "match.py": ["--batches", "1", "2"],
    "match_student.py": ["--policy", "a.onnx", "b.onnx"],
    "reference_ppo.py": ["--minutes", "1.5", "2.5"],
    "render.py": ["--seconds", "1.5", "2.5"],
    "render_determinism.py": ["--seed", "1", "2"],
    "reproducibility.py": ["--repeats", "1", "2"],
    "sweep.py": ["--steps", "1", "2"],
    "train.py": ["--rounds", "1", "2"],
    "vectorizers.py": ["--steps", "1", "2"],
    "viewpoint.py": ["--repeats", "2", "3"],
}


def test_every_script_has_an_option_given_twice_here():
    assert sorted(TWICE) == SCRIPTS


@pytest.mark.parametrize("script", SCRIPTS)
def test_an_option_given_twice_is_one_line(script):
    """``python bench/render.py --seconds 1 --seconds 2`` timed 2 s a measurement, the first
    value dropped silently (a plain argparse parser): refused before any work, naming both,
    in one line as the package's commands do."""
    option, first, second = TWICE[script]
    done = run(script, option, first, option, second)
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert done.returncode == 2, done.stderr
    assert lines == [
        f"{script}: error: argument {option}: given twice ({option} {first}, then {option}"
        f" {second}): give it once (see {script} --help)"
    ]


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


@pytest.fixture(scope="module", params=["truncated", "garbage"])
def broken_run(request, tmp_path_factory) -> Path:
    """A run folder whose config.json is whole but whose policy.safetensors is not: cut
    short, or random bytes."""
    import numpy as np

    from activevision.agents.q_network import QNetwork
    from activevision.training import preset
    from activevision.training.config import save_config
    from activevision.training.policy_files import network_metadata, write_policy

    run = tmp_path_factory.mktemp("runs") / request.param
    run.mkdir()
    save_config(preset("quickstart_ddqn"), run / "config.json")
    network = QNetwork(9)
    weights = write_policy(run, network.state_dict(), network_metadata(network, 0))
    if request.param == "truncated":
        weights.write_bytes(weights.read_bytes()[:300])
    else:
        weights.write_bytes(np.random.default_rng(0).bytes(5000))
    return run


#: the scripts that read a run's weights, and how they are called with ``{run}``
READS_A_RUN = [
    ("inference.py", ["--run", "{run}", "--iterations", "10", "--warmup", "0"], "--run"),
    ("continuous.py", ["--runs", "{run}", "--episodes", "1"], "--runs"),
    # the run is read before PPO trains (--minutes would otherwise pass first)
    ("reference_ppo.py", ["--dagger", "{run}", "--minutes", "0.001", "--out", "{out}"], "--dagger"),
]


@pytest.mark.parametrize(("script", "args", "option"), READS_A_RUN)
def test_a_broken_weights_file_is_one_line(script, args, option, broken_run, tmp_path):
    """A run whose weights file is truncated or garbage: one line naming the file, exit 2
    (it was a traceback)."""
    done = run(script, *(a.format(run=broken_run, out=tmp_path / "out") for a in args))
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr, done.stderr
    assert lines[-1].startswith(f"{script}: error: {option}: ")
    assert str(broken_run / "policy.safetensors") in lines[-1]
    assert not (tmp_path / "out").exists()


def test_continuous_refuses_a_run_its_env_does_not_feed(tmp_path: Path) -> None:
    """A run that observes what the first run's env does not give (the README's command
    named an image-alone run after an image + head one) is one line and exit 2: it was a
    traceback from inside the evaluation."""
    from activevision.agents.q_network import QNetwork
    from activevision.training import preset
    from activevision.training.config import save_config
    from activevision.training.policy_files import network_metadata, write_policy

    image = tmp_path / "image"
    image.mkdir()
    save_config(preset("quickstart_ddqn"), image / "config.json")
    network = QNetwork(9)
    write_policy(image, network.state_dict(), network_metadata(network, 0))
    head = tmp_path / "head"
    head.mkdir()
    save_config(preset("dagger_head"), head / "config.json")
    done = run("continuous.py", "--runs", str(image), str(head), "--episodes", "1")
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr, done.stderr
    assert lines[-1].startswith(
        f"continuous.py: error: --runs {head} was trained on observation 'image+head'"
    )


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


def test_continuous_figure_with_no_paired_episode_says_so(tmp_path, monkeypatch):
    """With no test episode that all three policies solve (short runs, few episodes) the
    figure was three empty histograms on a y axis from -0.04 to 0.04: it now says why it is
    empty, and a table cell of no paired episode reads "-", not "nan°"."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("continuous", BENCH / "continuous.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    drawn = {}
    monkeypatch.setattr(module.plt.Figure, "savefig", lambda fig, path, dpi: drawn.update(fig=fig))
    episodes = [
        {"method": "a", "seed": 0, "success": True, "success_duration": 3},
        {"method": "b", "seed": 1, "success": True, "success_duration": 2},
        {"method": "oracle", "seed": 0, "success": True, "success_duration": 4},
    ]
    kinds = {"a": "discrete", "b": "continuous", "oracle": "discrete"}
    module.plot(episodes, ["a", "b", "oracle"], kinds, 0, tmp_path / "f.png")
    (ax,) = drawn["fig"].axes
    texts = [t.get_text() for t in ax.texts]
    assert any("no test episode that a, b and oracle all solve" in t for t in texts), texts
    assert ax.get_ylim()[0] >= 0
    assert module.cell(float("nan"), "{:14g}") == f"{'-':>14s}"
    assert module.cell(3.0, "{:14g}") == f"{3.0:14g}"


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


def test_refused_by_keeps_a_bugs_traceback():
    """``refused_by`` turns a refused file into one line, never a bug: a KeyError (not a
    ValueError, not activevision's) still raises."""
    from activevision.cli.args import ArgumentParser, refused_by
    from activevision.training.checkpoint import CheckpointError

    parser = ArgumentParser(prog="script.py")
    with pytest.raises(SystemExit) as exit_, refused_by(parser, "--run"):
        raise CheckpointError("cannot read weights from run/policy.safetensors")
    assert exit_.value.code == 2
    with pytest.raises(KeyError), refused_by(parser, "--run"):
        raise KeyError("a bug")


def test_train_prints_its_ratios_before_the_json():
    """bench/train.py prints, like every bench script, its measurements beside the
    references of the same run and their ratios (it printed the JSON line alone)."""
    sys.path.insert(0, str(BENCH))
    try:
        import train
    finally:
        sys.path.remove(str(BENCH))
    result = {
        "update_ms": 20.0,
        "reference_update_ms": 80.0,
        "reference_update_ms_tuned_allocator": 60.0,
        "speedup": 4.0,
        "speedup_tuned_allocator": 3.0,
        "env": "ActiveVision-v0",
        "env_steps_per_s": 30.0,
        "fake_env_training_steps_per_s": 40.0,
        "env_vs_fake_env_training": 0.75,
        "env_only_steps_per_s": 9000.0,
        "threads": 2,
        "paper_run_minutes_estimate": 16.7,
    }
    text = "\n".join(train.report_lines(result))
    assert "20.00 ms" in text and "80.00 ms" in text and "60.00 ms" in text
    assert "speed-up over the plain update in the same run: 4.00x (3.00x over the tuned one)" in (
        text
    )
    assert "30.0 steps/s, 0.75x the same trainer on a free fake env (40.0 steps/s)" in text
    assert not text.lstrip().startswith("{")
