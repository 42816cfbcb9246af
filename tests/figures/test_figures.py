"""All drawing lives in ``activevision.figures``, a low layer that never picks a matplotlib
backend nor touches pyplot: a user's backend and figures survive env.render() and every
figure function; only the ``activevision`` command chooses Agg."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import activevision

SRC = Path(activevision.__file__).parent
#: what figures/ may import from the package: it sits just above geometry
FIGURES_MAY_IMPORT = (
    "activevision.geometry",
    "activevision.io",
    "activevision.text",
    "activevision.figures",
)


def _imports(path: Path) -> list[str]:
    names = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names.append(node.module)
    return names


def _calls_matplotlib_use(path: Path) -> bool:
    return any(
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Attribute)
        and node.func.attr == "use"
        and isinstance(node.func.value, ast.Name)
        and node.func.value.id == "matplotlib"
        for node in ast.walk(ast.parse(path.read_text(), str(path)))
    )


def test_only_figures_draw_and_nobody_picks_a_backend():
    for path in SRC.rglob("*.py"):
        rel = path.relative_to(SRC).as_posix()
        mpl = [m for m in _imports(path) if m.split(".")[0] == "matplotlib"]
        assert not mpl or rel.startswith("figures/"), f"{rel} imports {mpl}"
        assert "matplotlib.pyplot" not in mpl, f"{rel} uses pyplot"
        assert not _calls_matplotlib_use(path), f"{rel} calls matplotlib.use"


def test_figures_is_a_low_layer():
    for path in (SRC / "figures").glob("*.py"):
        own = [m for m in _imports(path) if m.split(".")[0] == "activevision"]
        bad = [m for m in own if not m.startswith(FIGURES_MAY_IMPORT)]
        assert not bad, f"figures/{path.name} imports {bad}"


_USER_SESSION = textwrap.dedent(
    """
    import csv, sys
    from pathlib import Path
    import matplotlib
    matplotlib.use("svg")  # the user's choice
    import numpy as np
    from activevision.envs import ActiveVisionEnv, EnvConfig
    from activevision.envs.simulation import EpisodeBatch
    from activevision.envs.view import viewpoint_search
    from activevision.experiments.episode_figure import trace_episode
    from activevision.experiments.policies import RandomPolicy
    from activevision.figures.compare import plot_compare
    from activevision.figures.episode import animate_episode, plot_episodes
    from activevision.figures.scene import plot_viewpoint_search
    from activevision.scaleout import plot_sweep
    from activevision.training import plot_run

    out = Path(sys.argv[1])

    def draw_everything():
        env = ActiveVisionEnv(render_mode="rgb_array")
        env.reset(seed=1)
        assert env.render().shape[-1] == 3
        sim = EpisodeBatch(EnvConfig(), 1)
        sim.reset(np.zeros(1, dtype=np.int64), [np.random.default_rng(3)])
        plot_viewpoint_search(viewpoint_search(sim, 0), out / "vp.png")
        trace = trace_episode(RandomPolicy(), 2)
        plot_episodes([trace], out / "episode.png", columns=2)
        animate_episode(trace, out / "episode.gif")
        plot_run(out / "run")
        plot_compare(out / "compare.csv", out / "compare.png")
        row = {"epoch": 1, "step": 10, "seeds": 1, "success_rate_mean": 0.5,
               "success_rate_std": 0.1}
        plot_sweep([row], out / "sweep.png")

    (out / "run").mkdir()
    (out / "run" / "episodes.csv").write_text("episode,step,reward\\n0,20,1\\n1,40,-1\\n")
    (out / "run" / "metrics.csv").write_text("epoch,step,loss,success_rate,"
        "success_duration,ball_loss_duration\\n1,40,0.5,0.2,10,3\\n")
    with (out / "compare.csv").open("w") as f:
        f.write("method,error,success_rate,success_rate_low,success_rate_high,"
                "success,success_low,success_high\\nrandom,0.0,0.5,0.4,0.6,0.2,0.1,0.3\\n")

    draw_everything()
    assert matplotlib.get_backend() == "svg", matplotlib.get_backend()
    assert "matplotlib.pyplot" not in sys.modules, "pyplot imported"

    import matplotlib.pyplot as plt  # a user with a figure open
    mine = plt.figure()
    draw_everything()
    assert matplotlib.get_backend() == "svg", matplotlib.get_backend()
    assert plt.get_fignums() == [mine.number] and plt.gcf() is mine
    print("ok")
    """
)


def _env_without_backend() -> dict[str, str]:
    return {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}


def test_user_backend_and_figures_survive_render_and_figures(tmp_path):
    done = subprocess.run(
        [sys.executable, "-c", _USER_SESSION, str(tmp_path)],
        env=_env_without_backend(),
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    for name in ("vp.png", "episode.png", "episode.gif", "compare.png", "sweep.png"):
        assert (tmp_path / name).stat().st_size > 5_000, name
    assert (tmp_path / "run" / "plots" / "training.png").stat().st_size > 5_000


def test_only_the_command_picks_agg_and_help_imports_no_matplotlib(tmp_path):
    code = textwrap.dedent(
        f"""
        import sys
        from activevision.cli import main
        assert main(["--help"]) == 0
        assert "matplotlib" not in sys.modules, "--help imported matplotlib"
        assert main(["render", "--out", {str(tmp_path / "v.png")!r}]) == 0
        import matplotlib
        assert matplotlib.get_backend().lower() == "agg", matplotlib.get_backend()
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", code], env=_env_without_backend(), capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr[-3000:]


def test_the_success_rate_panel_names_both_curves():
    """Beside the greedy validation, the training episodes' success rate (a DAgger run's
    first epochs played partly by the teacher) had no legend entry: it read as the policy's."""
    from activevision.figures.canvas import new_figure
    from activevision.figures.training import CURVES, draw_curve

    ax = new_figure().subplots()
    metrics = {"epoch": [1, 2], "step": [10, 20], "success_rate": [0.9, 0.7]}
    draw_curve(ax, CURVES[2], metrics, {"step": [20], "success_rate": [0.8]})
    assert ax.get_legend_handles_labels()[1] == ["training episodes", "greedy validation"]


def test_validation_sits_at_its_step_on_the_epoch_axis():
    """A run that ends between two epochs logs a short last epoch (`--steps 1000`: epochs at
    steps 300, 600, 900 and 1000): validation was placed by the last row's epochs per step,
    so step 750 sat at epoch 3.0, not between epochs 2 and 3; a PPO run's validation at step
    2,000 sat at epoch 1.95 beside its own epoch 1 at that step. And a run of one epoch drew
    its axis as 0.945 ... 1.050 (no two whole epochs in it)."""
    from activevision.figures.canvas import new_figure
    from activevision.figures.training import CURVES, draw_curve

    ax = new_figure().subplots()
    metrics = {"epoch": [1, 2, 3, 4], "step": [300, 600, 900, 1000]}
    metrics["success_rate"] = [0.5, 0.6, 0.7, 0.8]
    draw_curve(ax, CURVES[2], metrics, {"step": [250, 750, 1000], "success_rate": [0.6] * 3})
    (validation,) = [line for line in ax.lines if line.get_label() == "greedy validation"]
    assert validation.get_xdata() == pytest.approx([250 / 300, 2.5, 4.0])

    ax = new_figure().subplots()
    one = {"epoch": [1], "step": [3724], "success_rate": [0.76]}
    draw_curve(ax, CURVES[2], one, {"step": [1233, 3724], "success_rate": [0.7, 0.8]})
    ax.figure.canvas.draw()
    ticks = [t for t in ax.get_xticks() if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
    assert len(ticks) >= 2 and all(float(t).is_integer() for t in ticks), ticks


def test_a_match_runs_reward_panel_counts_matches():
    """A match student's reward is one value a match: its panel said "episode"."""
    from activevision.figures.canvas import new_figure
    from activevision.figures.training import CURVES, MATCH_CURVES, draw_curve

    episodes = {"episode": list(range(1, 31)), "reward": [float(i % 7) for i in range(30)]}
    for curves, word in ((MATCH_CURVES, "match"), (CURVES, "episode")):
        ax = new_figure().subplots()
        draw_curve(ax, curves[0], episodes, {})
        assert ax.get_xlabel() == word
        assert ax.get_legend_handles_labels()[1][0] == word


def test_a_short_runs_epoch_axis_counts_whole_epochs():
    """Two epochs drew ticks at epoch 1.2, 1.4, ...: an epoch is a count."""
    from activevision.figures.canvas import new_figure
    from activevision.figures.training import CURVES, draw_curve

    metrics = {"epoch": [1, 2], "step": [300, 600], "success_rate": [0.56, 0.65]}
    episodes = {"episode": [1, 2, 3], "reward": [1.0, -2.0, 0.0]}
    for curve, table in ((CURVES[2], metrics), (CURVES[0], episodes)):
        ax = new_figure().subplots()
        draw_curve(ax, curve, table, {})
        ticks = [t for t in ax.get_xticks() if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
        assert ticks and all(float(t).is_integer() for t in ticks), (curve.x, ticks)


def test_the_viewpoint_figure_shows_every_footprint_whole(tmp_path, monkeypatch):
    # a start near the carpet's edge looks beyond it: its footprints were cut at the carpet
    import numpy as np

    import activevision.figures.scene as scene
    from activevision.envs import EnvConfig
    from activevision.envs.simulation import EpisodeBatch
    from activevision.envs.view import viewpoint_search

    drawn = {}
    monkeypatch.setattr(scene, "save_figure", lambda fig, path, dpi: drawn.update(fig=fig))
    sim = EpisodeBatch(EnvConfig(), 1)
    sim.reset(np.zeros(1, dtype=np.int64), [np.random.default_rng(0)])
    search = viewpoint_search(sim, 0)
    corners = np.concatenate(search.footprints)
    carpet_x, carpet_y = search.field.carpet_half_extent
    assert np.abs(corners[:, 0]).max() > carpet_x or np.abs(corners[:, 1]).max() > carpet_y
    scene.plot_viewpoint_search(search, tmp_path / "vp.png")
    ax = drawn["fig"].axes[0]
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 < corners[:, 0].min() and corners[:, 0].max() < x1
    assert y0 < corners[:, 1].min() and corners[:, 1].max() < y1
    assert x0 <= -carpet_x and carpet_x <= x1 and y0 <= -carpet_y and carpet_y <= y1
