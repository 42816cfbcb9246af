"""The shipped policy as a method of ``episode`` and ``evaluate``: without ``--run`` it plays
its own env (its observation, camera and moves), as ``demo`` plays it; beside ``--run`` it
must fit the run's env, checked before any episode (``episode --policies shipped random``
was "this policy observes 'image+head+pose+proposal'; play it on an env with that
observation (OnnxPolicy.env_config())", a class a command-line user never sees, and
``evaluate --run RUN --methods learned shipped`` said it only after every learned
episode)."""

from __future__ import annotations

import pytest

from activevision.cli import main

pytest.importorskip("onnxruntime")


def test_episode_plays_the_shipped_policy_in_its_own_env(tmp_path, capsys, monkeypatch):
    """Both policies of the figure play the shipped policy's env (as ``evaluate --methods
    shipped ...`` does), at localisation error 0."""
    from activevision.envs import EnvConfig
    from activevision.experiments import episode_figure
    from activevision.experiments.compare import config_at_error
    from activevision.experiments.policies import OnnxPolicy
    from activevision.runtime import pretrained_policy_path

    played = []
    trace = episode_figure.trace_episode

    def recorded(policy, seed, config=None):
        played.append((policy.name, config))
        return trace(policy, seed, config)

    monkeypatch.setattr(episode_figure, "trace_episode", recorded)
    out = tmp_path / "episode.png"
    argv = ["episode", "--policies", "shipped", "random", "--seed", "2", "--out", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    own = OnnxPolicy(pretrained_policy_path()).env_config(EnvConfig())
    assert own.observation != EnvConfig().observation  # so the difference shows
    assert [name for name, _ in played] == ["shipped", "random"]  # the rows' labels
    assert all(config == config_at_error(own, 0.0) for _, config in played)
    assert out.stat().st_size > 0 and out.with_suffix(".gif").stat().st_size > 0


@pytest.mark.parametrize("command", ["episode", "evaluate"])
def test_shipped_beside_a_run_of_other_inputs_is_one_line_before_any_episode(
    command, trained, tmp_path, one_clear_line
):
    out = tmp_path / ("e.png" if command == "episode" else "e")
    picked = ["--policies" if command == "episode" else "--methods", "learned", "shipped"]
    argv = [command, "--run", str(trained), *picked, "--out", str(out)]
    if command == "evaluate":
        argv += ["--episodes", "1000"]  # refused at once, not after the learned episodes
    assert main(argv) == 2
    line = one_clear_line("shipped", "observation 'image+head+pose+proposal'", str(trained))
    assert "OnnxPolicy" not in line
    assert not out.exists() and not out.with_suffix(".gif").exists()
