"""Every ``activevision ...`` command in the README's shell blocks parses: a flag renamed or
removed in the code fails here, not in a new user's terminal."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import numpy as np
import pytest

from activevision.cli import build_parser

README = Path(__file__).resolve().parents[2] / "README.md"


def fenced_blocks(text: str, languages: tuple[str, ...]) -> list[str]:
    """The bodies of ``text``'s fenced blocks marked with one of ``languages`` ("" for
    unmarked)."""
    blocks: list[str] = []
    body: list[str] = []
    language: str | None = None  # None: outside a block
    for line in text.splitlines():
        if not line.startswith("```"):
            body.append(line)
        elif language is None:
            language, body = line[3:].strip(), []
        else:
            if language in languages:
                blocks.append("\n".join(body))
            language = None
    return blocks


def readme_commands(text: str) -> list[list[str]]:
    """The argument lists of the ``activevision`` commands of ``text``'s shell blocks, with
    their continued lines joined and comments dropped."""
    commands = []
    for block in fenced_blocks(text, ("", "bash", "sh")):
        for line in re.sub(r"\\\n\s*", " ", block).splitlines():
            if line.strip().startswith("activevision "):
                commands.append(shlex.split(line, comments=True)[1:])
    return commands


COMMANDS = readme_commands(README.read_text(encoding="utf-8"))


def test_the_readme_has_its_commands():
    # the parser above finds them: train, evaluate, match, robustness... (45 when written)
    assert len(COMMANDS) >= 40
    assert {argv[0] for argv in COMMANDS} >= {"train", "evaluate", "match", "robustness", "export"}


@pytest.mark.parametrize("argv", COMMANDS, ids=[" ".join(a)[:60] for a in COMMANDS])
def test_readme_command_parses(argv):
    build_parser().parse_args(argv)


def test_a_stale_flag_would_fail():
    text = "```bash\nactivevision evaluate --run runs/x --episods 5  # typo\n```\n"
    (argv,) = readme_commands(text)
    with pytest.raises(SystemExit):
        build_parser().parse_args(argv)
    python = "```python\nactivevision train --nope\n```\n"
    assert readme_commands(python) == []


#: The README's Python examples that run on their own (the rest need a robot: a camera,
#: a neck, its localisation).
ENV_EXAMPLES = [
    b for b in fenced_blocks(README.read_text(encoding="utf-8"), ("python",)) if "gym.make" in b
]


@pytest.mark.parametrize("example", ENV_EXAMPLES, ids=lambda b: b.split("gym.make")[1][:30])
def test_readme_env_example_runs(example):
    import gymnasium

    namespace: dict[str, object] = {"gym": gymnasium}  # one example continues another's imports
    exec(compile(example, str(README), "exec"), namespace)
    env = namespace["env"]
    obs, _ = env.reset(seed=0)  # type: ignore[attr-defined]
    assert env.observation_space.contains(obs)  # type: ignore[attr-defined]
    for name in ("env", "envs"):
        if name in namespace:
            namespace[name].close()  # type: ignore[attr-defined]


def test_the_quick_start_example_prints_the_same_every_run(capsys):
    """reset(seed=0) does not seed Gymnasium's action_space.sample(): the first example's
    random moves, and so what it prints, differed from run to run until it seeded them."""
    import gymnasium

    finals = []
    for _ in range(2):
        namespace: dict[str, object] = {"gym": gymnasium}
        exec(compile(ENV_EXAMPLES[0], str(README), "exec"), namespace)
        finals.append((capsys.readouterr().out, namespace["obs"].tobytes()))  # type: ignore[attr-defined]
        namespace["env"].close()  # type: ignore[attr-defined]
    assert finals[0] == finals[1]


def test_the_readme_has_its_env_examples():
    # the quick start, the randomised world, the match
    assert len(ENV_EXAMPLES) == 3


#: The README's Python examples for a robot: the controller in its loop, the plan it is
#: given and the camera check; they run here with stand-ins for the robot's parts.
ROBOT_EXAMPLES = [
    b for b in fenced_blocks(README.read_text(encoding="utf-8"), ("python",)) if "gym.make" not in b
]


class StandIns:
    """What the robot examples call on a robot: three camera frames, a neck that moves at
    once, a localisation, a ball lost once."""

    def __init__(self) -> None:
        self.ticks, self.pan, self.tilt, self.moves = 0, 0.0, 0.3, 0

    def is_running(self) -> bool:
        self.ticks += 1
        return self.ticks <= 3

    def ball_lost(self) -> bool:
        return self.ticks == 2

    def read(self) -> np.ndarray:
        return np.random.default_rng(self.ticks).integers(0, 256, (480, 640, 3), np.uint8)

    def joint_angles(self) -> tuple[float, float]:
        return self.pan, self.tilt

    def move_to(self, pan: float, tilt: float) -> None:
        self.pan, self.tilt, self.moves = pan, tilt, self.moves + 1

    def wait_until_reached(self) -> None:
        pass

    def pose(self) -> np.ndarray:
        return np.array([-1.0, 0.5, 0.3])

    def position_std(self) -> float:
        return 0.2


def test_the_readme_robot_examples_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The loop on the robot, the plan handed to the shipped policy and the camera check run
    as written (they were only read): with a discrete policy exported to the files they
    name, the shipped policy for the plan, and stand-ins for the robot."""
    pytest.importorskip("torch")
    pytest.importorskip("onnx")
    pytest.importorskip("onnxruntime")
    from activevision.agents.q_network import QNetwork
    from activevision.envs.actions import action_table
    from activevision.export import export_onnx, policy_metadata
    from activevision.geometry import CameraConfig
    from activevision.runtime import CameraMismatchWarning, HeadController, pretrained_policy_path

    loop, plan, camera_check = ROBOT_EXAMPLES
    monkeypatch.chdir(tmp_path)
    metadata = policy_metadata(action_table(3.0), CameraConfig(), camera=CameraConfig())
    exported = export_onnx(QNetwork(9).eval(), tmp_path / "deploy" / "policy.onnx", metadata)
    robot = StandIns()
    namespace: dict[str, object] = {"robot": robot, "camera": robot, "neck": robot}
    exec(compile(loop, str(README), "exec"), namespace)
    assert robot.moves == 3

    shipped = HeadController(pretrained_policy_path())
    assert shipped.inputs == ("pose", "pose_error", "proposal")  # as the README says
    namespace.update(controller=shipped, localisation=robot, ball_xy=np.array([0.5, -0.5]))
    exec(compile(plan, str(README), "exec"), namespace)
    assert namespace["command"].action == -1  # type: ignore[attr-defined]  # a continuous move

    for path in (exported.model_path, exported.metadata_path):
        (tmp_path / path.name).write_bytes(path.read_bytes())
    with pytest.warns(CameraMismatchWarning) as warned:
        exec(compile(camera_check, str(README), "exec"), namespace)
    assert len(warned) == 1  # one warning, listing each difference


def heading_anchor(heading: str) -> str:
    """GitHub's anchor of a Markdown heading: lower case, punctuation but ``-`` and ``_``
    dropped, spaces to ``-``."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def test_heading_anchor_is_githubs():
    assert heading_anchor("The task (`ActiveVision-v0`)") == "the-task-activevision-v0"
    assert heading_anchor("Evaluation and the paper's experiments") == (
        "evaluation-and-the-papers-experiments"
    )


def test_every_link_within_the_readme_finds_its_heading():
    text = README.read_text()
    outside = "\n".join(re.split(r"^```.*?^```", text, flags=re.S | re.M))  # no code
    anchors = {heading_anchor(h) for h in re.findall(r"^#{1,6} (.+)$", outside, flags=re.M)}
    links = set(re.findall(r"\]\(#([^)]+)\)", text))
    assert len(links) >= 15  # the contents line and the cross-references
    assert sorted(links - anchors) == []
