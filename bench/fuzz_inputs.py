"""Fuzz pass over the command line, the ``--set`` config keys and the env keywords.

Every input here is invalid by construction (a wrong type, a non-finite number, a value out
of range, an unknown name), so each must end in a clear error: exit code 2 and one stderr
line naming the bad value for the CLI, one ``ValueError`` naming the key for the library.
Counted and printed: deep tracebacks (an exception escaping), silent acceptances (exit 0 or
no error), errors that do not name the value. Ends with one JSON line; exits 1 if any count
is not zero. Needs no trained run: commands that read one get a tiny run made first (~10 s).

    python bench/fuzz_inputs.py [--seed 0] [--cases 400]
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import io
import json
import random
import sys
import tempfile
import time
import typing
from pathlib import Path

from activevision.cli.args import ArgumentParser, positive_int, seed

HOSTILE_NUMBERS = ["nan", "inf", "-inf", "1e309", "-1", "abc", "", "3.5", "0x10", "1_0_"]
HOSTILE_JSON = ['"3"', "true", "null", "[1]", '{"a": 1}', "NaN", "Infinity", "-1e400", '"x"']

#: option -> hostile values, per command; "{run}"/"{tmp}" are filled in.
CLI_OPTIONS: dict[str, dict[str, list[str]]] = {
    "evaluate": {
        "--episodes": ["0", "-5", "2.5", "nan", "x", "1e3"],
        "--seed": ["-1", "2147483648", "1.5", "seed"],
        "--error": ["-0.5", "nan", "inf", "-inf", "e"],
        "--methods": ["nope", "LEARNED", "learned,random", ""],
        "--weights": ["worst", ""],
    },
    "compare": {
        "--errors": ["1:0:0.5", "0:2:0", "0:2:-1", "0,nan", "a:b:c", "0:1", "0,0", "-1,0"],
        "--episodes": ["0", "-1", "x"],
        "--methods": ["nope", "shipped"],
        "--chunk": ["0", "-2"],
        "--seed": ["-3"],
    },
    "episode": {"--seed": ["-1", "x"], "--policies": ["nope"]},
    "demo": {"--seed": ["-1", "1e3"]},
    "render": {"--seed": ["-1", "x", "9999999999"], "--field": ["moon", "KIDSIZE", ""]},
    "viewpoints": {"--seed": ["-1"], "--field": ["nope"]},
    "export": {"--opset": ["1", "12", "21", "999", "x", "-17"], "--weights": ["best2"]},
    "quickstart": {"--steps": ["-1", "0", "x"], "--episodes": ["0", "-1"], "--seed": ["-1"]},
    "train": {
        "--steps": ["0", "-100", "1.5", "x"],
        "--seed": ["-1", "x", "2147483648"],
        "--preset": ["nope", "PAPER", ""],
    },
    "sweep": {"--seeds": ["3..1", "a..b", "-1", "1,1"], "--grid": ["lr", "=1", "lr="]},
}
#: what each command needs besides the fuzzed option to reach its checks
CLI_REQUIRED = {
    "episode": ["--out", "{tmp}/e.png"],
    "render": ["--out", "{tmp}/r.png"],
    "viewpoints": ["--out", "{tmp}/v.png"],
    "export": ["{run}", "-o", "{tmp}/p.onnx"],
    "train": ["--out", "{tmp}/t"],
    "sweep": ["--out", "{tmp}/s"],
    "quickstart": ["--out", "{tmp}/q"],
}


@dataclasses.dataclass
class Tally:
    cases: int = 0
    tracebacks: list[str] = dataclasses.field(default_factory=list)
    silent: list[str] = dataclasses.field(default_factory=list)
    unnamed: list[str] = dataclasses.field(default_factory=list)

    def as_dict(self) -> dict[str, int]:
        return {
            "cases": self.cases,
            "tracebacks": len(self.tracebacks),
            "silent_acceptances": len(self.silent),
            "errors_not_naming_the_value": len(self.unnamed),
        }


def run_cli(argv: list[str], needle: str, tally: Tally) -> None:
    from activevision.cli import main

    tally.cases += 1
    err, out = io.StringIO(), io.StringIO()
    label = " ".join(argv)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            code = main(argv)
    except BaseException as error:  # anything escaping main is a traceback for the user
        tally.tracebacks.append(f"{label}: {type(error).__name__}: {error}")
        return
    lines = [line for line in err.getvalue().splitlines() if line.strip()]
    if code == 0:
        tally.silent.append(label)
    elif code != 2 or len(lines) != 1 or "Traceback" in err.getvalue():
        tally.tracebacks.append(f"{label}: exit {code}, stderr {err.getvalue()!r}")
    elif needle and needle not in lines[0]:
        tally.unnamed.append(f"{label}: {lines[0]}")


def fuzz_cli(rng: random.Random, count: int, run: Path, tmp: Path, tally: Tally) -> None:
    cases = [
        (command, option, value)
        for command, options in CLI_OPTIONS.items()
        for option, values in options.items()
        for value in values
    ]
    rng.shuffle(cases)
    for command, option, value in cases[:count]:
        required = [a.format(run=run, tmp=tmp) for a in CLI_REQUIRED.get(command, [])]
        # --opt=value so that values starting with '-' stay values
        run_cli([command, *required, f"{option}={value}"], value, tally)


def _field_hostiles(hint: typing.Any) -> list[str]:
    """JSON texts of the wrong type (or non-finite) for an annotation."""
    name = getattr(hint, "__name__", str(hint))
    if hint is bool:
        return ["1", '"true"', "null", "[true]"]
    if hint is int:
        return ["1.5", '"3"', "true", "null", "NaN", "[1]"]
    if hint is float:
        return ['"0.1"', "true", "null", "NaN", "Infinity", "-Infinity", "[0.1]"]
    if hint is str:
        return ["3", "true", "null", "[]"]
    if set(typing.get_args(hint)) == {str, type(None)}:
        return ["3", "true", "[]"]  # any text may be right (a path: checked where it is used)
    if "tuple" in name or typing.get_origin(hint) is tuple:
        return ["[1]", "[1, 2, 3]", '["a", "b"]', "[NaN, 1]", "3", '"x"']
    return ["3", '"x"', "true", "[1]"]


def fuzz_config_keys(rng: random.Random, tally: Tally) -> None:
    """``--set KEY=V`` for every TrainConfig field and every env keyword, library path."""
    from activevision.training.config import SECTIONS, TrainConfig, apply_overrides
    from activevision.training.presets import preset

    hints = typing.get_type_hints(TrainConfig)
    targets: list[tuple[str, typing.Any]] = [
        (name, hint) for name, hint in hints.items() if name not in SECTIONS
    ]
    for section in SECTIONS:
        for f, hint in typing.get_type_hints(hints[section]).items():
            targets.append((f"{section}.{f}", hint))
    # each key on a run that reads it (a key the run's algo never reads is refused before
    # its value is looked at): dagger.* on a DAgger run (its match teacher's on the match),
    # sb3.* on a PPO run (tau on SAC, action_noise on TD3)
    bases = {"dagger": TrainConfig(algo="dagger"), "sb3": TrainConfig(algo="ppo")}
    match_dagger, sac, td3 = preset("match_dagger"), preset("sac_head"), preset("td3_head")
    for name in ("match_teacher", "glance_track_margin_deg", "track_margin_deg"):
        bases[f"dagger.{name}"] = match_dagger
    bases |= {"sb3.tau": sac, "sb3.action_noise": td3}
    for key, hint in targets:
        base = bases.get(key, bases.get(key.split(".")[0], TrainConfig()))
        for text in _field_hostiles(hint):
            expect_error(
                tally,
                f"--set {key}={text}",
                lambda key=key, text=text, base=base: apply_overrides(base, [f"{key}={text}"]),
                key.split(".")[-1],
            )


def expect_error(
    tally: Tally, label: str, call: typing.Callable[[], object], needle: str | None
) -> None:
    """Count one case: ``call`` must raise ValueError (TypeError counts too) whose message
    holds ``needle`` (None: any message)."""
    tally.cases += 1
    try:
        call()
    except (ValueError, TypeError) as error:
        if needle is not None and needle not in str(error):
            tally.unnamed.append(f"{label}: {error}")
    except BaseException as error:
        tally.tracebacks.append(f"{label}: {type(error).__name__}: {error}")
    else:
        tally.silent.append(label)


def fuzz_env_keywords(tally: Tally) -> None:
    """``gymnasium.make`` and the native vector env with hostile keywords."""
    import gymnasium as gym

    import activevision.envs  # noqa: F401
    from activevision.envs import ActiveVisionVectorEnv, EnvConfig

    # (max_episode_steps=-1 is Gymnasium's documented "no TimeLimit wrapper", not an error)
    hostile: dict[str, list[typing.Any]] = {"nope": [1], "max_episode_steps": [0, 2.5, "20"]}
    for f, hint in typing.get_type_hints(EnvConfig).items():
        hostile[f] = [json.loads(t) for t in _field_hostiles(hint) if t != "NaN"] + (
            [float("nan")] if hint is float else []
        )
    makers = (
        lambda kwargs: gym.make("ActiveVision-v0", **kwargs).close(),
        lambda kwargs: ActiveVisionVectorEnv(2, **kwargs).close(),
    )
    for key, values in hostile.items():
        for value in values:
            for make in makers:
                call = functools.partial(make, {key: value})
                expect_error(tally, f"env {key}={value!r}", call, key)


def fuzz_vector_actions(tally: Tally) -> None:
    """The native vector env stepped with actions of the wrong type, range or shape."""
    import numpy as np

    from activevision.envs import ActiveVisionVectorEnv

    env = ActiveVisionVectorEnv(3)
    env.reset(seed=0)
    bad_actions = [
        np.array([0.5, 0, 0]),
        np.array([True, False, True]),
        np.array([np.nan, 0, 0]),
        np.array(["a", "b", "c"]),
        np.array([9, 0, 0]),
        np.array([-1, 0, 0]),
        np.array([0, 0]),
        [[0, 0, 0]],
        None,
    ]
    for action in bad_actions:
        expect_error(tally, f"vector step {action!r}", lambda a=action: env.step(a), None)
    env.close()


def make_tiny_run(directory: Path) -> Path:
    from activevision.cli import main

    run = directory / "tiny"
    # a DAgger run: DDQN's learning_starts and buffer_size are refused there (never read)
    settings = ["batch_size=8", "epoch_steps=30", "checkpoint_interval=30", "tensorboard=false"]
    argv = ["train", "--preset", "quickstart", "--steps", "60", "--out", str(run)]
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(argv + [a for s in settings for a in ("--set", s)]) == 0
    return run


def main() -> int:
    parser = ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=seed, default=0)
    parser.add_argument("--cases", type=positive_int, default=400, help="CLI cases at most")
    args = parser.parse_args()
    rng = random.Random(args.seed)
    tally = Tally()
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        run = make_tiny_run(Path(tmp))
        fuzz_cli(rng, args.cases, run, Path(tmp), tally)
        fuzz_config_keys(rng, tally)
        fuzz_env_keywords(tally)
        fuzz_vector_actions(tally)
    for kind in ("tracebacks", "silent", "unnamed"):
        for line in getattr(tally, kind)[:20]:
            print(f"{kind}: {line}")
    result = {**tally.as_dict(), "seconds": round(time.perf_counter() - start, 1)}
    print(
        f"{result['cases']} bad inputs: {result['tracebacks']} tracebacks, "
        f"{result['silent_acceptances']} silent acceptances, "
        f"{result['errors_not_naming_the_value']} errors not naming the value"
    )
    print(json.dumps({"bench": "fuzz_inputs", **result}))
    return 0 if not (tally.tracebacks or tally.silent or tally.unnamed) else 1


if __name__ == "__main__":
    sys.exit(main())
