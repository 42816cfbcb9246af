"""``evaluate`` / ``compare --strategy FILE.py:NAME``: a researcher's own episodic head
policy plays beside the built-in methods without editing the package (before, the only
way in was ``register_method`` inside the package; the README names the HeadPolicy
interface, ``match`` had ``--strategy``, the episodic commands had none)."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from activevision.cli import main

MINE = """
from activevision.experiments.policies import OraclePolicy


class Mirror(OraclePolicy):
    name = "mirror"  # the oracle under another name: the same episodes, move for move

    def __init__(self, context):
        super().__init__(context.config)


class ByHand(Mirror):
    name = "learned_by_hand"  # no learned policy, whatever its label says


class Builtin(Mirror):
    name = "scan"


def not_a_policy(context):
    return object()


class Fails(Mirror):
    name = "fails"

    def act(self, obs, info):
        return 1 // 0


class FailsOffTheTruePose(Mirror):
    name = "fails_off"

    def __init__(self, context):
        super().__init__(context)
        self.error = context.error

    def act(self, obs, info):
        return [][1] if self.error > 0 else super().act(obs, info)
"""

EXAMPLE = Path(__file__).parents[2] / "examples" / "centre_ball.py"


def _rows(path: Path) -> dict[str, dict[str, str]]:
    with path.open() as f:
        return {r["method"]: r for r in csv.DictReader(f)}


def test_evaluate_plays_your_own_policy_beside_the_built_in_ones(tmp_path):
    (tmp_path / "mine.py").write_text(MINE)
    out = tmp_path / "e"
    argv = ["evaluate", "--methods", "oracle", "--episodes", "3", "--out", str(out)]
    strategies = ["--strategy", f"{tmp_path / 'mine.py'}:Mirror", f"{EXAMPLE}:CentreBall"]
    assert main([*argv, *strategies]) == 0
    rows = _rows(out / "evaluation.csv")
    assert set(rows) == {"oracle", "mirror", "centre_ball"}
    drop = ("method",)
    assert {k: v for k, v in rows["mirror"].items() if k not in drop} == {
        k: v for k, v in rows["oracle"].items() if k not in drop
    }


def test_compare_plays_your_own_policy_at_every_error_level(tmp_path):
    (tmp_path / "mine.py").write_text(MINE)
    out = tmp_path / "c"
    argv = ["compare", "--methods", "oracle", "--episodes", "2", "--errors", "0,1"]
    argv += ["--out", str(out), "--strategy", f"{tmp_path / 'mine.py'}:Mirror"]
    assert main(argv) == 0
    with (out / "compare.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert sorted((r["error"], r["method"]) for r in rows) == [
        ("0.0", "mirror"),
        ("0.0", "oracle"),
        ("1.0", "mirror"),
        ("1.0", "oracle"),
    ]


def test_compare_plays_methods_in_the_order_given_and_refuses_a_repeat(tmp_path):
    """In the order given (not the default's: oracle before random); a method named twice
    was played once, the repeat dropped silently: refused (tests/cli/test_careless_files)."""
    out = tmp_path / "c"
    argv = ["compare", "--methods", "scan", "oracle", "random", "--episodes", "1"]
    assert main([*argv, "--errors", "0", "--out", str(out)]) == 0
    with (out / "compare.csv").open() as f:
        assert [r["method"] for r in csv.DictReader(f)] == ["scan", "oracle", "random"]
    repeat = ["compare", "--methods", "random", "oracle", "random", "--episodes", "1"]
    assert main([*repeat, "--errors", "0", "--out", str(tmp_path / "r")]) == 2
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize(
    ("command", "spec", "needle"),
    [
        ("evaluate", "mine.py", "FILE.py:NAME"),
        ("evaluate", "mine.py:Nothing", "defines no class or function Nothing"),
        ("evaluate", "mine.py:Builtin", "is a built-in method's"),
        ("evaluate", "mine.py:not_a_policy", "no reset or act method"),
        ("evaluate", "mine.py:Fails", "ZeroDivisionError"),
        ("compare", "mine.py:Fails", "ZeroDivisionError"),
    ],
)
def test_a_bad_policy_is_one_clear_line(
    tmp_path, monkeypatch, command, spec, needle, one_clear_line
):
    (tmp_path / "mine.py").write_text(MINE)
    monkeypatch.chdir(tmp_path)
    argv = [command, "--methods", "oracle", "--episodes", "1", "--out", str(tmp_path / "o")]
    if command == "compare":
        argv += ["--errors", "0"]
    assert main([*argv, "--strategy", spec]) == 2
    one_clear_line(needle)


def test_compare_names_your_policy_failing_at_a_later_level(tmp_path, capsys):
    """The trial episode plays the first level only: an exception at another level is one
    line naming the policy too, not a traceback (the progress bar's lines come before it)."""
    (tmp_path / "mine.py").write_text(MINE)
    argv = ["compare", "--methods", "oracle", "--episodes", "1", "--errors", "0,1"]
    argv += ["--out", str(tmp_path / "c")]
    assert main([*argv, "--strategy", f"{tmp_path / 'mine.py'}:FailsOffTheTruePose"]) == 2
    captured = capsys.readouterr()
    assert "Traceback" not in captured.out + captured.err
    last = captured.err.splitlines()[-1]
    assert last.startswith("activevision compare: error: --strategy fails_off: act raised"), last
    assert "IndexError: list index out of range (mine.py, line" in last


WRONG = """
from activevision.experiments.policies import HeadTarget


class Wrong:
    def __init__(self, context):
        pass

    def reset(self, info, rng):
        pass


class Beyond(Wrong):
    name = "beyond"

    def act(self, obs, info):
        return 99  # the table has 9 moves


class NanTarget(Wrong):
    name = "nan_target"

    def act(self, obs, info):
        return HeadTarget(float("nan"), 0.2)


class TextTarget(Wrong):
    name = "text_target"

    def act(self, obs, info):
        return HeadTarget("left", 0.2)
"""


@pytest.mark.parametrize(
    ("name", "needle"),
    [
        ("Beyond", "method beyond, step 0: invalid action 99: expects an integer in 0..8"),
        ("NanTarget", "method nan_target, step 0: invalid action HeadTarget(pan=nan"),
        ("TextTarget", "method text_target, step 0: invalid action HeadTarget(pan='left'"),
    ],
)
def test_a_policy_acting_wrongly_is_named_on_one_line(tmp_path, name, needle, one_clear_line):
    """As ``match`` names the strategy and tick of an invalid action: the line names the
    method and the step (it said "invalid action 99" alone, and a NaN head target "pan
    must be finite", naming neither the policy nor that it was its action)."""
    (tmp_path / "wrong.py").write_text(WRONG)
    argv = ["evaluate", "--methods", "oracle", "--episodes", "1", "--out", str(tmp_path / "e")]
    assert main([*argv, "--strategy", f"{tmp_path / 'wrong.py'}:{name}"]) == 2
    one_clear_line(needle)


def test_a_policy_of_yours_labelled_learned_is_not_timed_as_the_learned_one(tmp_path):
    """latency.json holds the learned policy's latency: a user's method labelled
    ``learned_...`` is not it (it was timed, and written as the learned policy's)."""
    (tmp_path / "mine.py").write_text(MINE)
    out = tmp_path / "e"
    argv = ["evaluate", "--methods", "oracle", "--episodes", "2", "--out", str(out)]
    assert main([*argv, "--strategy", f"{tmp_path / 'mine.py'}:ByHand"]) == 0
    assert set(_rows(out / "evaluation.csv")) == {"oracle", "learned_by_hand"}
    assert not (out / "latency.json").exists()


def test_evaluate_tries_your_policy_before_the_built_in_ones_play(tmp_path, monkeypatch):
    """As compare and match do: a mistake in your policy shows after one episode of it,
    not after every built-in method has played its episodes."""
    import activevision.experiments.evaluate as evaluation

    played: list[str] = []
    evaluate_policy = evaluation.evaluate_policy

    def recording(policy, *args, **kwargs):
        played.append(policy.name)
        return evaluate_policy(policy, *args, **kwargs)

    monkeypatch.setattr(evaluation, "evaluate_policy", recording)
    (tmp_path / "mine.py").write_text(MINE)
    argv = ["evaluate", "--methods", "oracle", "--episodes", "2", "--out", str(tmp_path / "e")]
    assert main([*argv, "--strategy", f"{tmp_path / 'mine.py'}:Fails"]) == 2
    assert played == ["fails"]
    assert not (tmp_path / "e").exists()


ENV_RECORDING = """
import json
import os

from activevision.experiments.policies import OraclePolicy


class Recorded(OraclePolicy):
    name = "recorded"

    def __init__(self, context):
        super().__init__(context.config)
        self.observation = context.config.observation
        with open(os.environ["RECORDED"], "a") as f:
            f.write(json.dumps([context.config.observation, context.config.step_deg]) + "\\n")

    def act(self, obs, info):
        if isinstance(obs, dict) != (self.observation != "image"):
            raise ValueError(f"built for {self.observation!r}, given a {type(obs).__name__}")
        return super().act(obs, info)
"""


def test_your_policy_is_built_for_the_env_the_shipped_policy_plays(tmp_path, monkeypatch):
    """With the shipped policy in the evaluation every method plays its env (its
    observation, moves): a user's policy is built with a MethodContext of that env (it was
    built for the defaults, before the switch, and given observations it was not built
    for)."""
    from activevision.envs import EnvConfig
    from activevision.experiments.policies import OnnxPolicy
    from activevision.runtime import pretrained_policy_path

    played = OnnxPolicy(pretrained_policy_path()).env_config(EnvConfig())
    assert played.observation != EnvConfig().observation  # so the difference shows
    (tmp_path / "mine.py").write_text(ENV_RECORDING)
    monkeypatch.setenv("RECORDED", str(tmp_path / "recorded.jsonl"))
    out = tmp_path / "e"
    argv = ["evaluate", "--methods", "shipped", "oracle", "--episodes", "2", "--out", str(out)]
    assert main([*argv, "--strategy", f"{tmp_path / 'mine.py'}:Recorded"]) == 0
    recorded = (tmp_path / "recorded.jsonl").read_text().splitlines()
    assert len(recorded) == 2  # the trial episode's policy, the evaluated one
    assert set(recorded) == {f'["{played.observation}", {played.step_deg}]'}
    assert set(_rows(out / "evaluation.csv")) == {"shipped", "oracle", "recorded"}


def test_runs_are_checked_against_the_env_the_shipped_policy_plays(
    trained, tmp_path, one_clear_line
):
    """``--runs`` beside the shipped policy: a run that observes another input than the
    shipped policy's env gives is one line (it was checked against the defaults, then fed
    the shipped env's observations: a traceback)."""
    out = tmp_path / "e"
    argv = ["evaluate", "--methods", "shipped", "--runs", str(trained), "--episodes", "1"]
    assert main([*argv, "--out", str(out)]) == 2
    one_clear_line(f"--runs {trained} was trained on observation 'image'", "shipped policy's")
    assert not out.exists()
