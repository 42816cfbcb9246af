"""Every ``activevision ...`` command in the shell blocks of the README and the docs pages
parses: a flag renamed or removed in the code fails here, not in a new user's terminal. Every
relative link of those pages points at a file that exists (and an anchor at a heading)."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import numpy as np
import pytest

from activevision.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


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


COMMANDS = [argv for page in PAGES for argv in readme_commands(page.read_text(encoding="utf-8"))]


def test_the_pages_have_their_commands():
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


#: The pages' Python examples that run on their own (the rest need a robot: a camera,
#: a neck, its localisation).
PYTHON_BLOCKS = [
    b for page in PAGES for b in fenced_blocks(page.read_text(encoding="utf-8"), ("python",))
]
ENV_EXAMPLES = [b for b in PYTHON_BLOCKS if "gym.make" in b]


@pytest.mark.parametrize("example", ENV_EXAMPLES, ids=lambda b: b.split("gym.make")[1][:30])
def test_readme_env_example_runs(example):
    import gymnasium

    namespace: dict[str, object] = {"gym": gymnasium}  # one example continues another's imports
    exec(compile(example, "<docs example>", "exec"), namespace)
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
        exec(compile(ENV_EXAMPLES[0], "<docs example>", "exec"), namespace)
        finals.append((capsys.readouterr().out, namespace["obs"].tobytes()))  # type: ignore[attr-defined]
        namespace["env"].close()  # type: ignore[attr-defined]
    assert finals[0] == finals[1]


def test_the_readme_has_its_env_examples():
    # the quick start, the randomised world, the match
    assert len(ENV_EXAMPLES) == 3


#: The pages' Python examples for a robot (docs/robot.md): the controller in its loop, the
#: plan it is given and the camera check; they run here with stand-ins for the robot's parts.
ROBOT_EXAMPLES = [b for b in PYTHON_BLOCKS if "gym.make" not in b]


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
    exec(compile(loop, "<docs example>", "exec"), namespace)
    assert robot.moves == 3

    shipped = HeadController(pretrained_policy_path())
    assert shipped.inputs == ("pose", "pose_error", "proposal")  # as docs/robot.md says
    namespace.update(controller=shipped, localisation=robot, ball_xy=np.array([0.5, -0.5]))
    exec(compile(plan, "<docs example>", "exec"), namespace)
    assert namespace["command"].action == -1  # type: ignore[attr-defined]  # a continuous move

    for path in (exported.model_path, exported.metadata_path):
        (tmp_path / path.name).write_bytes(path.read_bytes())
    with pytest.warns(CameraMismatchWarning) as warned:
        exec(compile(camera_check, "<docs example>", "exec"), namespace)
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


def page_anchors(page: Path) -> set[str]:
    """The anchors of ``page``'s headings (those outside its code blocks)."""
    text = page.read_text(encoding="utf-8")
    outside = "\n".join(re.split(r"^```.*?^```", text, flags=re.S | re.M))
    return {heading_anchor(h) for h in re.findall(r"^#{1,6} (.+)$", outside, flags=re.M)}


def test_the_readme_links_every_docs_page():
    links = set(re.findall(r"\]\((docs/[^)#]+\.md)\)", PAGES[0].read_text(encoding="utf-8")))
    assert links == {f"docs/{page.name}" for page in PAGES[1:]} and len(links) >= 10


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_relative_link_of_a_page_finds_its_file_and_heading(page):
    """Links to a heading (``#anchor``, ``other.md#anchor``) and to files (figures, examples,
    other pages), as GitHub resolves them: relative to the page."""
    links = re.findall(r"\]\(([^)\s]+)\)", page.read_text(encoding="utf-8"))
    broken = []
    for link in links:
        if link.startswith(("http://", "https://")):
            continue
        path, _, anchor = link.partition("#")
        target = (page.parent / path).resolve() if path else page
        if not target.is_file() or (anchor and anchor not in page_anchors(target)):
            broken.append(link)
    assert links and broken == []


def test_a_broken_link_would_fail(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("# Here\n\n[ok](#here) [gone](#there)\n")
    assert page_anchors(page) == {"here"}
