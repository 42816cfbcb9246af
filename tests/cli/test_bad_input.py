"""Bad input, as a new or hostile user types it: every case ends in exit code 2 and one line
on stderr that names the problem; no traceback, no silent acceptance, no file destroyed."""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from activevision.cli import main
from activevision.cli.args import figure_file
from activevision.training import load_policy


@pytest.fixture
def run(trained, tmp_path) -> Path:
    """A private copy of the tiny run, free to be tampered with."""
    return Path(shutil.copytree(trained, tmp_path / "run"))


# (argv with {run} and {tmp} placeholders, what the error line must name)
BAD_ARGUMENTS = [
    # the matches are played together in one vector env (at most 65,536 sub-environments):
    # refused as --matches, not by the env naming its num_envs
    (["match", "--matches", str(10**12), "--out", "{tmp}/m"], "must be an integer from 1 to 65536"),
    (
        ["quickstart", "--matches", "65537", "--out", "{tmp}/q"],
        "must be an integer from 1 to 65536",
    ),
    (["evaluate", "--episodes", "0"], "--episodes"),
    # past one seed's episode set (--seed 0's would replay --seed 1's): ran, unrefused
    (["evaluate", "--episodes", str(10**12)], "must be an integer from 1 to 1000003"),
    (["robustness", "--episodes", "1000004"], "must be an integer from 1 to 1000003"),
    (["evaluate", "--episodes", "-3"], "'-3'"),
    (["evaluate", "--episodes", "many"], "'many'"),
    (["evaluate", "--error", "-1"], "'-1'"),
    (["evaluate", "--error", "nan"], "'nan'"),
    (["evaluate", "--error", "inf"], "'inf'"),
    (["evaluate", "--error", "11"], "'11'"),  # beyond the field and a full turn
    (["evaluate", "--methods", "random", "--weights", "best"], "--run"),
    (["evaluate", "--methods", "random", "--out", "{run}/config.json"], "not a directory"),
    (["robustness", "--method", "random", "--weights", "best"], "--run"),
    (["robustness", "--method", "random", "--out", "{run}/metrics.csv"], "not a directory"),
    (["match", "--robot-speed", "0.2"], "--robots"),
    (["evaluate", "--seed", "-1"], "'-1'"),
    (["evaluate", "--methods", "nope"], "'nope'"),
    (["evaluate", "--methods", "learned"], "--run"),
    (["compare", "--error", "-1"], "--error"),
    (["compare", "--errors", "1:0:0.5"], "'1:0:0.5'"),
    (["compare", "--errors", "0:2:0"], "step"),
    (["compare", "--errors", "0,nan"], "'nan'"),
    (["compare", "--errors", "0,0"], "repeats"),
    (["compare", "--methods", "nope"], "'nope'"),
    (["compare", "--methods", "learned"], "--run"),
    (["compare", "--episodes", "0"], "--episodes"),
    (["compare", "--chunk", "0"], "--chunk"),
    # options of a compare on Ray, given without --ray: they were silently ignored
    (["compare", "--verbose", "--out", "{tmp}/c"], "--verbose applies to a compare on Ray"),
    (["compare", "--num-cpus", "2", "--address", "auto", "--out", "{tmp}/c"], "--address, --num"),
    (["compare", "--chunk", "5", "--out", "{tmp}/c"], "--chunk applies to a compare on Ray"),
    (
        ["compare", "--ray", "--num-cpus", "2", "--address", "auto", "--out", "{tmp}/c"],
        "--num-cpus sets a local Ray's CPUs",
    ),
    (["episode", "--seed", "-1", "--out", "{tmp}/e.png"], "'-1'"),
    (["episode", "--policies", "nope", "--out", "{tmp}/e.png"], "'nope'"),
    (["episode", "--policies", "learned", "--out", "{tmp}/e.png"], "--run"),
    (["demo", "--seed", "x"], "'x'"),
    (["demo", "--out", "{tmp}/d.gif"], "GIF"),  # the figure and its GIF would be one file
    (["episode", "--out", "{tmp}/e.gif"], "GIF"),
    (["episode", "--out", "{tmp}/e.GIF"], "GIF"),
    (["export", "{run}", "-o", "{tmp}/policy.json"], ".onnx"),
    (["render", "--field", "moon", "--out", "{tmp}/v.png"], "'moon'"),
    (["render", "--seed", "2147483648", "--out", "{tmp}/v.png"], "2147483648"),
    (["render"], "--out"),
    # a figure is written in the format its suffix names: a suffix no format has is refused
    (["render", "--out", "{tmp}/v.txt"], "not .txt"),
    (["viewpoints", "--out", "{tmp}/v.xyz"], "not .xyz"),
    (["demo", "--out", "{tmp}/d.txt"], "not .txt"),
    (["episode", "--out", "{tmp}/e.csv"], "not .csv"),
    (["export", "{run}", "--opset", "1"], "opset"),
    (["export", "{run}", "--opset", "999"], "opset"),
    (["export", "{tmp}/missing"], "missing"),
    (["quickstart", "--steps", "-1"], "--steps"),
    (["quickstart", "--episodes", "0"], "--episodes"),
    (["train", "--preset", "nope", "--out", "{tmp}/x"], "'nope'"),
    (["train", "--steps", "0", "--out", "{tmp}/x"], "--steps"),
    (["train", "--seed", "-1", "--out", "{tmp}/x"], "'-1'"),
    (["train"], "--out"),
    (["train", "--set", "nope=1", "--out", "{tmp}/x"], "'nope'"),
    (["train", "--set", "learning_rate", "--out", "{tmp}/x"], "key=value"),
    (["train", "--set", "learning_rate=-1", "--out", "{tmp}/x"], "learning_rate"),
    (["train", "--set", "env_kwargs.nope=1", "--out", "{tmp}/x"], "nope"),
    (["train", "--set", "env.nope=1", "--out", "{tmp}/x"], "nope"),
    (["train", "--set", "learner.gamma=2", "--out", "{tmp}/x"], "gamma"),
    (["train", "--set", 'env_kwargs.step_deg="3"', "--out", "{tmp}/x"], "step_deg"),
    (["train", "--set", "env_kwargs.field=42", "--out", "{tmp}/x"], "field"),
    (["train", "--set", 'env_kwargs.field="moon"', "--out", "{tmp}/x"], "moon"),
    (["train", "--set", "env_kwargs.frame_stack=true", "--out", "{tmp}/x"], "frame_stack"),
    (["train", "--set", "env_kwargs.ball_lost_reward=NaN", "--out", "{tmp}/x"], "ball_lost"),
    (["train", "--set", "env_kwargs.max_episode_steps=0", "--out", "{tmp}/x"], "max_episode"),
    (["train", "--set", "env_id=Nope-v0", "--steps", "30", "--out", "{tmp}/x"], "Nope-v0"),
    (["train", "--set", "device=cuda:7", "--out", "{tmp}/x"], "cuda"),
    (["train", "--set", "device=tpu", "--out", "{tmp}/x"], "device"),
    (["train", "--set", "env.appearance.neutral_share=0.5", "--out", "{tmp}/x"], "switch one on"),
    (
        [
            "train",
            *("--preset", "dagger_robust_continuous"),
            *("--set", "env.appearance.neutral_share=1", "--out", "{tmp}/x"),
        ],
        "redraw_look",
    ),
    (
        ["train", "--set", "ticks=1", "--out", "{tmp}/x"],
        "give its full path: match.kidnap.ticks, match.ticks",
    ),
    # a key the run's algo never reads: it was stored in config.json and ignored
    (
        ["train", "--set", "dagger.num_envs=8", "--out", "{tmp}/x"],
        "'dagger.num_envs' is never read by an algo='ddqn' run",
    ),
    (
        ["train", "--preset", "quickstart", "--set", "learner.gamma=0.9", "--out", "{tmp}/x"],
        "'learner.gamma' is never read by an algo='dagger' run",
    ),
    (
        ["train", "--preset", "ppo_head", "--set", "buffer_size=500", "--out", "{tmp}/x"],
        "'buffer_size' (replay.buffer_size) is never read by an algo='ppo' run",
    ),
    (
        [
            "train",
            "--preset",
            "quickstart",
            "--set",
            "match_teacher=glance_track",
            "--out",
            "{tmp}/x",
        ],
        "'match_teacher' (dagger.match_teacher) is never read by an algo='dagger' run",
    ),
    # an auxiliary goal head on the match, which has no goal view: the trainer's error told a
    # command-line user to pass Trainer(..., aux_target=f)
    (
        ["train", "--preset", "match_ddqn", "--set", "aux_goal_weight=1", "--out", "{tmp}/x"],
        "learner.aux_goal_weight=1.0 adds a head regressing the goal view's offset from the"
        " head, which only ActiveVision-v0's episodes have (goal_offset); env_id"
        " 'ActiveVisionMatch-v0' has none: leave it at 0 on this env",
    ),
    # values another setting of the run leaves unread: stored in config.json and ignored
    (
        ["train", "--set", "env.prior_error_range=[0,1]", "--out", "{tmp}/x"],
        "'env.prior_error_range' is never read by this run: only an observation with a prior"
        " pose reads it (env.observation='image+head+pose' or 'image+head+pose+proposal');"
        " this run observes 'image'",
    ),
    (
        ["train", "--preset", "dagger_head", "--set", "prior_grid=[0.5,10]"] + ["--out", "{tmp}/x"],
        "'prior_grid' (env.prior_grid) is never read by this run: only an observation with a"
        " prior pose",
    ),
    (
        ["train", "--preset", "dagger_prior", "--set", "env.prior_error_range=null"]
        + ["--set", "env.prior_exact_share=0.3", "--out", "{tmp}/x"],
        "'env.prior_exact_share' is never read by this run: it is the share of exact priors",
    ),
    (
        ["train", "--preset", "dagger_head", "--set", "max_move_deg=[5,5]", "--out", "{tmp}/x"],
        "'max_move_deg' (env.max_move_deg) is never read by this run: only continuous moves",
    ),
    (
        ["train", "--set", "eval_episodes=50", "--out", "{tmp}/x"],
        "'eval_episodes' (run.eval_episodes) is never read by this run: only validation reads"
        " it, and this run never validates (run.eval_interval=0",
    ),
    (
        ["train", "--preset", "ppo_head", "--set", "eval_interval=0"]
        + ["--set", "run.eval_seed=7", "--out", "{tmp}/x"],
        "'run.eval_seed' is never read by this run: only validation reads it",
    ),
    (["train", "--config", "{tmp}/none.json", "--out", "{tmp}/x"], "none.json"),
    (["train", "--resume", "{tmp}/missing"], "missing: not a training run (no config.json)"),
    (["train", "--resume", "{run}", "--set", "learning_rate=1e-3"], "--set"),
    (["train", "--resume", "{run}", "--seed", "3"], "--seed"),
    (["train", "--resume", "{run}", "--preset", "paper"], "--preset"),
    (["train", "--resume", "{run}", "--steps", "30"], "finished"),
    # a blank path made a folder named by spaces (an empty one was refused)
    (
        ["evaluate", "--out", " \t", "--methods", "scan", "--episodes", "1"],
        "argument --out: must not be blank, got ' \\t'",
    ),
    # an option and a --set of the same field: the option's value was taken, the --set one
    # dropped (--set total_timesteps=5000 --steps 100 trained 100 steps)
    (
        ["train", "--set", "total_timesteps=5000", "--steps", "100", "--out", "{tmp}/x"],
        "--set total_timesteps=... and --steps both set run.total_timesteps: give it with"
        " --steps alone",
    ),
    (
        ["train", "--set", "run.total_timesteps=5000", "--steps", "100", "--out", "{tmp}/x"],
        "and --steps both set run.total_timesteps",
    ),
    (["train", "--set", "seed=3", "--seed", "1", "--out", "{tmp}/x"], "and --seed both set seed"),
    (
        ["train", "--set", "algo=dagger", "--algo", "ddqn", "--out", "{tmp}/x"],
        "and --algo both set algo",
    ),
    # a sweep's trials each take one of --seeds (default 0..4)
    (["sweep", "--set", "seed=3", "--out", "{tmp}/s"], "give it with --seeds alone"),
    # --overwrite was ignored (exit 0): a resume replaces nothing
    (["train", "--resume", "{run}", "--overwrite"], "--overwrite cannot be combined with it"),
    (["train", "--out", "{run}"], "--resume"),
    (["train", "--out", "{run}/plots/x"], "inside the training run"),
    (["train", "--out", "{run}/plots/x", "--overwrite"], "inside the training run"),
    (["evaluate", "--run", "{tmp}", "--methods", "random"], "not a training run (no config.json)"),
    (["sweep", "--seeds", "3..1", "--out", "{tmp}/s"], "'3..1'"),
    (["sweep", "--grid", "learning_rate", "--out", "{tmp}/s"], "KEY=V1"),
    # one key twice swept only its last values; a --set key in the grid was replaced by it
    (
        ["sweep", "--grid", "learning_rate=1e-3", "--grid", "learning_rate=2e-3"]
        + ["--out", "{tmp}/s"],
        "--grid learning_rate and --grid learning_rate both set learner.learning_rate",
    ),
    (
        ["sweep", "--grid", "learner.learning_rate=1e-3,2e-3", "--grid", "learning_rate=3e-3"]
        + ["--out", "{tmp}/s"],
        "--grid learner.learning_rate and --grid learning_rate both set learner.learning_rate",
    ),
    (
        ["sweep", "--grid", "learning_rate=1e-3,2e-3", "--set", "learner.learning_rate=3e-3"]
        + ["--out", "{tmp}/s"],
        "--set learner.learning_rate and --grid learning_rate both set learner.learning_rate",
    ),
    (["train", "--config", "{tmp}/nope.json", "--out", "{tmp}/x"], "nope.json: no such file"),
    (["sweep", "--config", "{tmp}", "--out", "{tmp}/s"], ": not a file"),
    (["plot", "{tmp}"], "not a training run"),
    (["report", "{tmp}"], "not a training run"),
    (["nope"], "invalid choice"),
]


def test_the_episodes_bound_is_one_seeds_episode_set():
    from activevision.cli.args import MAX_EPISODES
    from activevision.envs.seeding import EPISODES_PER_SEED, episode_seed

    assert MAX_EPISODES == EPISODES_PER_SEED
    assert episode_seed(0, MAX_EPISODES - 1) < episode_seed(1, 0) == episode_seed(0, MAX_EPISODES)


def test_the_matches_bound_is_the_vector_envs():
    from activevision.cli.args import MAX_MATCHES
    from activevision.envs.config import MAX_VECTOR_ENVS

    assert MAX_MATCHES == MAX_VECTOR_ENVS


#: a run that is a file: named as the run, not as an --out nobody typed
RUN_IS_A_FILE = [
    ["evaluate", "--run", "{file}", "--methods", "random"],
    ["compare", "--run", "{file}"],
    ["episode", "--run", "{file}", "--out", "{tmp}/e.png"],
    ["robustness", "--run", "{file}"],
    ["report", "{file}"],
    ["export", "{file}"],
]


@pytest.mark.parametrize("argv", RUN_IS_A_FILE, ids=" ".join)
def test_a_run_that_is_a_file_is_named_as_the_run(tmp_path, argv, one_clear_line):
    (tmp_path / "afile").write_text("not a run")
    filled = [a.format(file=tmp_path / "afile", tmp=tmp_path) for a in argv]
    assert main(filled) == 2
    line = one_clear_line(f"{tmp_path / 'afile'}: not a training run (no config.json)")
    assert "--out" not in line


@pytest.mark.parametrize(("argv", "needle"), BAD_ARGUMENTS, ids=" ".join)
def test_bad_arguments(trained, tmp_path, capsys, argv, needle, digests, one_clear_line):
    before = digests(trained)
    filled = [a.format(run=trained, tmp=tmp_path) for a in argv]
    assert main(filled) == 2
    one_clear_line(needle.format(run=trained, tmp=tmp_path))
    assert digests(trained) == before  # nothing of the run was touched
    assert not (tmp_path / "x").exists()  # a refused training run leaves no directory


@pytest.mark.parametrize(
    "argv",
    [
        ["evaluate", "--run", "{other}", "--methods", "learned", "--episodes", "1"]
        + ["--out", "{run}/evaluation"],
        ["compare", "--run", "{other}", "--methods", "learned", "--errors", "0"]
        + ["--episodes", "1", "--out", "{run}/compare"],
        ["robustness", "--run", "{other}", "--perturbations", "clean", "--episodes", "1"]
        + ["--out", "{run}/robustness"],
        ["match", "--run", "{other}", "--methods", "learned", "--matches", "1", "--ticks", "2"]
        + ["--out", "{run}/match"],
        ["episode", "--run", "{other}", "--out", "{run}/episode.png"],
        ["export", "{other}", "-o", "{run}/policy.onnx"],
        ["export", "{other}", "-o", "{run}/exports/a.onnx"],
    ],
    ids=lambda argv: argv[0] + ("" if "-o" not in argv else argv[-1][5:]),
)
def test_results_of_one_run_are_not_written_inside_another(
    trained, tmp_path, argv, digests, one_clear_line
):
    """``evaluate --run B --out A/evaluation`` wrote B's scores where ``report A`` reads its
    own: the report showed B's learned policy as A's (so did compare, robustness, match and
    episode; export put B's model where ``A`` is read as a policy folder)."""
    other = Path(shutil.copytree(trained, tmp_path / "other"))
    before = digests(trained)
    assert main([a.format(run=trained, other=other) for a in argv]) == 2
    one_clear_line(f": results of {other} inside the training run {trained} would read as its own")
    assert digests(trained) == before


@pytest.mark.parametrize("folder", ["checkpoints", "tensorboard"])
@pytest.mark.parametrize(
    "argv",
    [
        ["robustness", "--method", "oracle", "--episodes", "1", "--perturbations", "robots-1"],
        ["evaluate", "--methods", "random", "--episodes", "1"],
        ["render"],
    ],
    ids=lambda argv: argv[0],
)
def test_the_folders_of_a_run_are_trains_alone(run, capsys, folder, argv, digests, one_clear_line):
    # rule 1 of cli/outputs.py: checkpoints/ and tensorboard/ are the run's, written by train
    # alone; --out RUN/checkpoints put robustness.csv or episodes.csv beside the checkpoints
    (run / folder).mkdir(exist_ok=True)
    before = digests(run)
    out = run / folder / ("view.png" if argv[0] == "render" else "")
    assert main([*argv, "--out", str(out)]) == 2
    one_clear_line("refusing to write", "belongs to the training run")
    assert digests(run) == before


@pytest.mark.parametrize("command", ["render", "viewpoints", "episode", "demo"])
def test_a_figure_named_as_a_folder_is_refused(tmp_path, capsys, command, one_clear_line):
    # pathlib drops the trailing slash: --out figs/ wrote a PNG file called figs
    folder = tmp_path / "figs"
    assert main([command, "--out", f"{folder}/"]) == 2
    one_clear_line("--out", "not a folder", f"{folder}/")
    assert not folder.exists()
    # a suffix alone is no suffix to Python: --out figs/.png wrote a PNG called .png
    assert main([command, "--out", f"{tmp_path}/.png"]) == 2
    one_clear_line("--out", "'.png' is a suffix alone", f"{tmp_path}/view.png")
    assert not (tmp_path / ".png").exists()
    assert figure_file(f"{tmp_path}/.hidden.png").name == ".hidden.png"  # a name and a suffix
    # no suffix, no format: --out demo (read as demo's folder) wrote a PNG file called demo
    # and demo.gif beside it
    assert main([command, "--out", str(folder)]) == 2
    one_clear_line("--out", "has no suffix", f"{folder}.png")
    assert not folder.exists() and not folder.with_suffix(".gif").exists()


# ------------------------------------------------------------ outputs never overwritten
@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["evaluate", "--run", "{run}", "--methods", "random", "--out", "{run}"], "episodes.csv"),
        (["export", "{run}", "-o", "{run}/config.onnx"], "config.json"),
        (["export", "{run}", "-o", "{run}/config.onnx", "--overwrite"], "training run"),
        (["episode", "--run", "{run}", "--out", "{run}/policy.safetensors"], "training run"),
        (["render", "--out", "{run}/config.json", "--overwrite"], "training run"),
        (["viewpoints", "--out", "{run}/metrics.csv", "--overwrite"], "metrics.csv"),
    ],
    ids=lambda v: " ".join(v) if isinstance(v, list) else v,
)
def test_run_files_are_never_overwritten(run, capsys, argv, needle, digests, one_clear_line):
    before = digests(run)
    assert main([a.format(run=run) for a in argv]) == 2
    one_clear_line(needle, "refusing")
    assert digests(run) == before


def test_named_outputs_need_overwrite(tmp_path, capsys, one_clear_line):
    picture = tmp_path / "view.png"
    picture.write_bytes(b"a photo of my robot")
    assert main(["render", "--out", str(picture)]) == 2
    one_clear_line("--overwrite")
    assert picture.read_bytes() == b"a photo of my robot"
    assert main(["render", "--out", str(picture), "--overwrite"]) == 0
    assert picture.read_bytes().startswith(b"\x89PNG")


def test_a_folder_of_other_files_is_no_place_for_a_run(tmp_path, tiny_train, one_clear_line):
    # an evaluation's episodes.csv, or a user's config.json, is not a run to start over
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "episodes.csv").write_text("my,table\n1,2\n")
    assert main([*tiny_train, "--out", str(folder)]) == 2
    one_clear_line("episodes.csv", "--overwrite")
    assert (folder / "episodes.csv").read_text() == "my,table\n1,2\n"
    assert sorted(p.name for p in folder.iterdir()) == ["episodes.csv"]


def test_a_run_that_fails_before_training_leaves_no_folder(tmp_path, tiny_train, one_clear_line):
    """A world with no start (the ball is below a camera tilted 50-60 degrees down) fails at
    the first reset: the folder it made held only config.json and empty logs, and the next
    try needed --overwrite. A folder that was there before stays."""
    argv = [*tiny_train, "--set", "env.start_tilt_range_deg=[50,60]"]
    assert main([*argv, "--out", str(tmp_path / "new")]) == 2
    one_clear_line("no start")
    assert not (tmp_path / "new").exists()
    (tmp_path / "mine").mkdir()
    assert main([*argv, "--out", str(tmp_path / "mine")]) == 2
    one_clear_line("no start")
    assert (tmp_path / "mine").is_dir()


def test_a_run_that_failed_after_playing_keeps_its_logs(
    tmp_path, tiny_train, monkeypatch, one_clear_line
):
    """A new run that played episodes and then failed before its first epoch row and
    checkpoint (here: a full disk as it logs the epoch) keeps its folder: its episodes.csv
    shows what happened (it was removed as if nothing had run)."""
    from activevision.training.loggers import CsvLogger

    def disk_full(self: CsvLogger, row: object, step: int) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(CsvLogger, "record_epoch", disk_full)
    run = tmp_path / "new"
    assert main([*tiny_train, "--out", str(run)]) == 2
    one_clear_line("No space left on device")
    with (run / "episodes.csv").open() as f:
        assert len(list(csv.DictReader(f))) >= 1


def test_evaluating_again_needs_overwrite(tmp_path, capsys, one_clear_line):
    argv = ["evaluate", "--methods", "random", "--episodes", "2", "--out", str(tmp_path / "e")]
    assert main(argv) == 0
    written = (tmp_path / "e" / "evaluation.csv").read_bytes()
    capsys.readouterr()
    assert main([*argv, "--seed", "1"]) == 2
    one_clear_line("evaluation.csv", "--overwrite")
    assert (tmp_path / "e" / "evaluation.csv").read_bytes() == written
    assert main([*argv, "--seed", "1", "--overwrite"]) == 0
    assert (tmp_path / "e" / "evaluation.csv").read_bytes() != written


def test_files_that_are_not_text_are_named(run, tmp_path, capsys, one_clear_line):
    garbage = bytes(range(128, 256))
    (tmp_path / "binary.json").write_bytes(garbage)
    assert (
        main(["train", "--config", str(tmp_path / "binary.json"), "--out", str(tmp_path / "x")])
        == 2
    )
    one_clear_line("binary.json")
    (run / "metrics.csv").write_bytes(garbage)
    assert main(["plot", str(run)]) == 2
    one_clear_line("metrics.csv")


@pytest.mark.parametrize(
    "text",
    ["[" * 100_000 + "]" * 100_000, "9" * 5000],
    ids=["nested too deep", "an integer of 5000 digits"],
)
def test_json_the_decoder_cannot_take_is_one_line(tmp_path, capsys, one_clear_line, text):
    """json.loads raises RecursionError and a plain ValueError for these, not
    JSONDecodeError: a config file (train --config, export's config.json) and a --set value
    are still refused on one line naming them, not with a traceback."""
    (tmp_path / "deep.json").write_text(text)
    out = str(tmp_path / "x")
    assert main(["train", "--config", str(tmp_path / "deep.json"), "--out", out]) == 2
    one_clear_line("deep.json", "not valid JSON")
    assert main(["train", "--steps", "300", "--out", out, "--set", f"env.step_deg={text}"]) == 2
    one_clear_line("env.step_deg")
    assert not (tmp_path / "x").exists()


def test_a_run_without_its_log_has_nothing_to_plot(run, capsys, one_clear_line):
    (run / "metrics.csv").unlink()  # checkpoints/ still mark it a run
    assert main(["plot", str(run)]) == 2
    one_clear_line("has no metrics.csv (its training log): nothing to plot")


def test_plot_of_a_config_alone_names_only_the_missing_log(tmp_path, one_clear_line):
    """A folder with a run's config.json and nothing else (a run killed at once): the
    refusal read "no config.json and metrics.csv", as if config.json were missing too."""
    (tmp_path / "config.json").write_text("{}")
    assert main(["plot", str(tmp_path)]) == 2
    line = one_clear_line("is not a training run (no metrics.csv)")
    assert "config.json" not in line
    assert main(["plot", str(tmp_path / "none")]) == 2
    one_clear_line("(no config.json and no metrics.csv)")


def test_plot_and_train_name_a_plots_folder_that_is_a_file(
    run, tmp_path, tiny_train, capsys, one_clear_line
):
    shutil.rmtree(run / "plots", ignore_errors=True)
    (run / "plots").write_text("mine")
    assert main(["plot", str(run)]) == 2
    one_clear_line(f"{run / 'plots'} is a file, not a directory")
    assert (run / "plots").read_text() == "mine"

    # train draws them too: it trained first, then failed on "[Errno 17] File exists"
    shutil.rmtree(run / "checkpoints" / "step_000000060")  # something left to train
    assert main(["train", "--resume", str(run)]) == 2
    one_clear_line(f"{run / 'plots'} is a file, not a directory")
    assert [p.name for p in (run / "checkpoints").iterdir()] == ["step_000000030"]
    fresh = tmp_path / "fresh"
    fresh.mkdir()
    (fresh / "plots").write_text("mine")
    assert main([*tiny_train, "--out", str(fresh)]) == 2
    one_clear_line(f"{fresh / 'plots'} is a file, not a directory")
    assert sorted(p.name for p in fresh.iterdir()) == ["plots"]


def test_a_run_without_weights_reads_its_newest_checkpoint_or_says_which_file_it_lacks(
    run, capsys, one_clear_line, tmp_path
):
    assert main(["export", str(run), "-o", str(tmp_path / "before.onnx")]) == 0
    (run / "policy.safetensors").unlink()
    # policy.safetensors is rewritten with every checkpoint: the newest holds the same weights
    newest = sorted((run / "checkpoints").iterdir())[-1] / "model.safetensors"
    command = [sys.executable, "-c", "from activevision.cli import main; raise SystemExit(main())"]
    argv = ["export", str(run), "-o", str(tmp_path / "after.onnx")]
    done = subprocess.run([*command, *argv], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    warning = [line for line in done.stderr.splitlines() if line.strip()]
    assert warning == [
        f"activevision export: warning: {run} has no policy.safetensors (deleted?): reading"
        f" its newest checkpoint's weights, {newest}"
    ]
    assert (tmp_path / "after.onnx").read_bytes() == (tmp_path / "before.onnx").read_bytes()
    # a library caller is pointed at its own line
    with pytest.warns(UserWarning, match="newest checkpoint") as caught:
        load_policy(run)
    assert caught[0].filename == __file__
    capsys.readouterr()
    shutil.rmtree(run / "checkpoints")
    assert main(["export", str(run), "-o", str(tmp_path / "none.onnx")]) == 2
    one_clear_line("no policy weights in", "policy.safetensors", "each checkpoint")


def test_a_run_another_process_trains_is_refused_on_one_line(tmp_path, tiny_train, one_clear_line):
    from ..training.test_run_lock import held_by_another_process

    busy = tmp_path / "busy"
    with held_by_another_process(busy) as pid:
        assert main([*tiny_train, "--out", str(busy)]) == 2
        one_clear_line(f"{busy} is being trained by another process (pid {pid})")
    assert main([*tiny_train, "--out", str(busy)]) == 0


def test_runs_of_another_image_stack_are_refused_on_one_line(
    trained, tiny_train, tmp_path, one_clear_line, capsys
):
    """A run of two stacked frames beside a run of one: its network took the comparison's
    one-frame images in the first step, a traceback ("expected input ... to have 2
    channels")."""
    stacked = tmp_path / "stacked"
    assert main([*tiny_train, "--set", "env.frame_stack=2", "--out", str(stacked)]) == 0
    capsys.readouterr()
    argv = ["evaluate", "--run", str(trained), "--runs", str(stacked), "--episodes", "1"]
    assert main([*argv, "--out", str(tmp_path / "e")]) == 2
    one_clear_line(f"--runs {stacked} was trained on frame_stack 2 against 1")
    assert not (tmp_path / "e").exists()


def test_a_refused_compare_on_ray_leaves_the_compare_csv_it_would_overwrite(
    tmp_path, one_clear_line, capsys
):
    """A compare refused before its first row keeps the compare.csv that --overwrite would
    replace (``--ray --runs`` and a --runs that is no run removed it before the refusal)."""
    out = tmp_path / "cmp"
    argv = ["compare", "--methods", "random", "--errors", "0.1", "--episodes", "1"]
    assert main([*argv, "--out", str(out)]) == 0
    before = (out / "compare.csv").read_bytes()
    capsys.readouterr()
    refused = [*argv, "--out", str(out), "--overwrite", "--ray", "--runs", str(tmp_path)]
    assert main(refused) == 2
    one_clear_line("--runs plays in this process: leave out --ray")
    assert (out / "compare.csv").read_bytes() == before
    # nor one refused after the outputs were checked: a --runs that is no run (it was
    # removed then too, and the error was a bare "[Errno 2] No such file")
    missing = tmp_path / "nope"
    assert main([*argv, "--out", str(out), "--overwrite", "--runs", str(missing)]) == 2
    one_clear_line(f"--runs {missing}: not a training run")
    assert (out / "compare.csv").read_bytes() == before


def test_compare_overwrite_stopped_before_its_end_leaves_no_older_figure(
    tmp_path, monkeypatch, capsys
):
    """--overwrite removed the older compare.csv but kept its compare.png: a compare that
    stopped before it drew its own left the older figure beside the new rows (report.md
    showed it as this compare's)."""
    import activevision.experiments.compare as comparison

    out = tmp_path / "cmp"
    argv = ["compare", "--methods", "random", "--episodes", "1", "--out", str(out)]
    assert main([*argv, "--errors", "0.1"]) == 0
    assert (out / "compare.png").is_file()
    capsys.readouterr()
    real = comparison.evaluate_policy
    calls = []

    def second_level_fails(*args, **kwargs):
        calls.append(1)
        if len(calls) > 1:
            raise ValueError("stopped")
        return real(*args, **kwargs)

    monkeypatch.setattr(comparison, "evaluate_policy", second_level_fails)
    assert main([*argv, "--errors", "0.2,0.3", "--overwrite"]) == 2
    err = capsys.readouterr().err  # the progress bar's lines, then the error
    assert err.splitlines()[-1] == "activevision compare: error: stopped", err
    rows = (out / "compare.csv").read_text().splitlines()
    assert [r.split(",")[0] for r in rows[1:]] == ["0.2"]  # the new level played, resumable
    assert not (out / "compare.png").exists()


def test_a_compare_folder_another_compare_writes_is_refused(tmp_path, one_clear_line, capsys):
    """Two compares into one folder would append their rows to one compare.csv."""
    from ..training.test_run_lock import held_by_another_process

    out = tmp_path / "cmp"
    argv = ["compare", "--methods", "random", "--errors", "0.1", "--episodes", "1"]
    with held_by_another_process(out) as pid:
        assert main([*argv, "--out", str(out)]) == 2
        one_clear_line(f"{out} is being written by another process (pid {pid})", "--out")
    assert not (out / "compare.csv").exists()
    assert main([*argv, "--out", str(out)]) == 0  # free again, and released after the run
    assert main([*argv, "--out", str(out), "--overwrite"]) == 0
    assert "wrote" in capsys.readouterr().out
    assert sorted(p.name for p in out.iterdir()) == ["compare.csv", "compare.png"]  # no .lock
    # a compare that fails before its first row leaves no folder (nor lock) behind
    failed = tmp_path / "failed"
    assert (
        main(
            [*argv[:-2], "--episodes", "1", "--runs", str(tmp_path / "none"), "--out", str(failed)]
        )
        == 2
    )
    assert not failed.exists()


def test_finished_run_resumes_to_nothing_and_says_so(run, capsys):
    assert main(["train", "--resume", str(run)]) == 0
    assert "finished" in capsys.readouterr().out


def test_run_without_checkpoint_needs_overwrite(run, capsys, tiny_train, one_clear_line):
    shutil.rmtree(run / "checkpoints")
    assert main([*tiny_train, "--out", str(run)]) == 2
    one_clear_line("--overwrite")
    assert main([*tiny_train, "--out", str(run), "--overwrite"]) == 0


def test_a_run_started_over_keeps_no_weights_of_the_earlier_attempt(
    run, capsys, tiny_train, one_clear_line
):
    # an attempt that validated, then stopped before its first checkpoint; started over
    # with --overwrite (and no validation), its best_policy was exported as the new run's
    shutil.copyfile(run / "policy.safetensors", run / "best_policy.safetensors")
    shutil.rmtree(run / "checkpoints")
    steps = tiny_train.index("--steps")
    tiny_train[steps + 1] = "30"  # a shorter run than the tiny one
    assert main([*tiny_train, "--out", str(run), "--overwrite"]) == 0
    capsys.readouterr()
    assert not (run / "best_policy.safetensors").exists()
    out = run.parent / "best.onnx"
    assert main(["export", str(run), "--weights", "best", "-o", str(out)]) == 2
    one_clear_line("best_policy.safetensors")
    assert not out.exists()


def test_a_corrupt_newest_checkpoint_names_the_older_whole_one(run, tmp_path, one_clear_line):
    # the run keeps its two newest checkpoints, but the error named only the corrupt one
    newest = latest(run)
    flip_bytes(newest / "model.safetensors")
    assert main(["train", "--resume", str(run)]) == 2
    one_clear_line("corrupt", "older checkpoint step_000000030 is whole", str(newest))
    shutil.move(newest, tmp_path / "aside")  # the advice works
    assert main(["train", "--resume", str(run)]) == 0
    # both broken: nothing to offer
    for checkpoint in (run / "checkpoints").iterdir():
        flip_bytes(checkpoint / "model.safetensors")
    assert main(["train", "--resume", str(run)]) == 2
    assert "older" not in one_clear_line("corrupt")


def test_stale_checkpoint_writes_are_cleaned_on_the_next_start(trained, tmp_path):
    run = Path(shutil.copytree(trained, tmp_path / "run"))
    stale = run / "checkpoints" / ".step_000000090.abc.tmp"
    stale.mkdir()
    (stale / "replay.npz").write_bytes(b"\0" * 1000)
    shutil.rmtree(run / "checkpoints" / "step_000000060")  # the run is at step 30 again
    assert main(["train", "--resume", str(run)]) == 0
    assert not stale.exists()


# ------------------------------------------------------------ tampered files
def flip_bytes(path: Path, count: int = 1000) -> None:
    data = bytearray(path.read_bytes())
    start = len(data) // 3
    for i in range(start, min(start + count, len(data))):
        data[i] ^= 0xFF
    path.write_bytes(bytes(data))


def latest(run: Path) -> Path:
    return sorted((run / "checkpoints").iterdir())[-1]


def rewrite_manifest(checkpoint: Path) -> None:
    """What a careful attacker does: recompute the manifest after editing a file."""
    from activevision.training.checkpoint import _file_digest

    names = sorted(p.name for p in checkpoint.iterdir() if p.name != "manifest.json")
    manifest = {n: _file_digest(checkpoint / n) for n in names}
    (checkpoint / "manifest.json").write_text(json.dumps(manifest))


def edit_state(run: Path, change: Callable[[dict], None]) -> None:
    path = latest(run) / "state.json"
    state = json.loads(path.read_text())
    change(state)
    path.write_text(json.dumps(state))
    rewrite_manifest(latest(run))


def replace_replay_array(run: Path, name: str, value) -> None:
    import numpy as np

    path = latest(run) / "replay.npz"
    with np.load(path) as archive:
        arrays = {k: archive[k] for k in archive.files}
    arrays[name] = np.asarray(value)
    with open(path, "wb") as file:
        np.savez(file, **arrays)
    rewrite_manifest(latest(run))


TAMPERS: list[tuple[str, Callable[[Path], None], list[str], str]] = [
    # (name, tamper, command, what the error names)
    (
        "policy weights",
        lambda r: flip_bytes(r / "policy.safetensors"),
        ["evaluate", "--run", "{run}", "--methods", "learned", "--episodes", "2"],
        "policy",
    ),
    (
        "policy weights, export",
        lambda r: flip_bytes(r / "policy.safetensors"),
        ["export", "{run}", "-o", "{run}/../out.onnx"],
        "policy.safetensors",
    ),
    (
        "policy weights, episode",
        lambda r: flip_bytes(r / "policy.safetensors", 10),
        ["episode", "--run", "{run}", "--out", "{run}/../e.png"],
        "policy.safetensors",
    ),
    (
        "truncated weights",
        lambda r: (r / "policy.safetensors").write_bytes(b"\x08"),
        ["export", "{run}", "-o", "{run}/../out.onnx"],
        "policy.safetensors",
    ),
    (
        "checkpoint weights",
        lambda r: flip_bytes(latest(r) / "model.safetensors"),
        ["train", "--resume", "{run}"],
        "corrupt",
    ),
    (
        "empty manifest",
        lambda r: (latest(r) / "manifest.json").write_text("{}"),
        ["train", "--resume", "{run}"],
        "manifest",
    ),
    (
        "manifest not an object",
        lambda r: (latest(r) / "manifest.json").write_text("[1]"),
        ["train", "--resume", "{run}"],
        "manifest",
    ),
    (
        "extra checkpoint file",
        lambda r: (latest(r) / "evil.pt").write_bytes(b"x"),
        ["train", "--resume", "{run}"],
        "evil.pt",
    ),
    (
        "edited config",
        lambda r: (r / "config.json").write_text(
            (r / "config.json")
            .read_text()
            .replace('"learning_rate": 0.0005', '"learning_rate": 0.1')
        ),
        ["train", "--resume", "{run}"],
        "config.json",
    ),
    (
        "edited config exported",
        lambda r: (r / "config.json").write_text(
            (r / "config.json").read_text().replace('"step_deg": 3.0', '"step_deg": 5.0')
        ),
        ["export", "{run}", "-o", "{run}/../out.onnx"],
        "changed after checkpoint",
    ),
    # evaluate, compare, robustness and match play the run's network in its config.json's world:
    # an edit after training (5-degree steps for a 3-degree policy) is refused like export's
    *[
        (
            f"edited config {argv[0]}",
            lambda r: (r / "config.json").write_text(
                (r / "config.json").read_text().replace('"step_deg": 3.0', '"step_deg": 5.0')
            ),
            argv,
            "changed after checkpoint step_000000030: playing its network",
        )
        for argv in (
            ["evaluate", "--run", "{run}", "--methods", "learned", "--episodes", "1"],
            [
                "compare",
                "--run",
                "{run}",
                "--methods",
                "learned",
                "--errors",
                "0",
                "--episodes",
                "1",
            ],
            ["robustness", "--run", "{run}", "--perturbations", "clean", "--episodes", "1"],
            [
                "match",
                "--run",
                "{run}",
                "--methods",
                "learned",
                "--matches",
                "1",
                "--ticks",
                "2",
                "--out",
                "{run}/../match",
            ],
        )
    ],
    (
        "config not JSON",
        lambda r: (r / "config.json").write_text("{"),
        ["evaluate", "--run", "{run}", "--methods", "learned"],
        "config.json",
    ),
    (
        "config with a bad env key",
        lambda r: (r / "config.json").write_text(
            (r / "config.json").read_text().replace('"env": {', '"env": {"x": 1, ')
        ),
        ["export", "{run}", "-o", "{run}/../out.onnx"],
        "'x'",
    ),
    (
        "state.json missing a key",
        lambda r: edit_state(r, lambda s: s.pop("episode_seed")),
        ["train", "--resume", "{run}"],
        "episode_seed",
    ),
    (
        "state.json wrong type",
        lambda r: edit_state(r, lambda s: s.update(step="soon")),
        ["train", "--resume", "{run}"],
        "checkpoint",
    ),
    (
        "state.json not an object",
        lambda r: ((latest(r) / "state.json").write_text("[]"), rewrite_manifest(latest(r))),
        ["train", "--resume", "{run}"],
        "JSON object",
    ),
    (
        "replay of another shape",
        lambda r: replace_replay_array(r, "shape", [500, 2, 120, 160]),
        ["train", "--resume", "{run}"],
        "obs_shape",
    ),
    (
        "replay missing an array",
        lambda r: replace_replay_array(r, "counters", [1, 2]),
        ["train", "--resume", "{run}"],
        "checkpoint",
    ),
    (
        "optimizer state of another network",
        lambda r: swap_optimizer_state(r),
        ["train", "--resume", "{run}"],
        "checkpoint",
    ),
    # a training log damaged after the checkpoint: resuming would append rows to a file
    # that reads as whole but lost rows (or has no header), so it is refused, naming the file
    (
        "metrics.csv emptied",
        lambda r: (r / "metrics.csv").write_text(""),
        ["train", "--resume", "{run}"],
        "metrics.csv does not start with its header",
    ),
    (
        "metrics.csv missing",
        lambda r: (r / "metrics.csv").unlink(),
        ["train", "--resume", "{run}"],
        "metrics.csv holds 0 whole rows where the checkpoint logged 1",
    ),
    (
        "episodes.csv cut short",
        lambda r: (r / "episodes.csv").write_bytes((r / "episodes.csv").read_bytes()[:100]),
        ["train", "--resume", "{run}"],
        "episodes.csv holds",
    ),
    (
        "episodes.csv binary",
        lambda r: (r / "episodes.csv").write_bytes(b"\xff\xfe" * 50),
        ["train", "--resume", "{run}"],
        "episodes.csv is not a CSV table",
    ),
    # weights another run trained (a student's in a DDQN run): one line naming the mismatch,
    # not a shape error deep in the first episode
    (
        "weights of another run",
        lambda r: put_student_weights(r),
        ["evaluate", "--run", "{run}", "--methods", "learned", "--episodes", "2"],
        "do not fit its config.json",
    ),
    (
        "weights of another run, robustness",
        lambda r: put_student_weights(r),
        ["robustness", "--run", "{run}", "--perturbations", "clean", "--episodes", "2"],
        "do not fit its config.json",
    ),
    (
        "compare.csv of other episodes",
        lambda r: write_compare_csv(r, episodes=50),
        [
            "compare",
            "--run",
            "{run}",
            "--methods",
            "random",
            "--errors",
            "0,0.5",
            "--episodes",
            "2",
        ],
        "50 episodes",
    ),
    (
        "evaluation.json not JSON",
        lambda r: write_file(r / "evaluation" / "evaluation.json", "{"),
        ["report", "{run}"],
        "evaluation.json",
    ),
    # report reads config.json, the logs, evaluation.json and match.csv: a damaged one is
    # named on one line, never a traceback
    (
        "evaluation.json of another shape",
        lambda r: write_file(r / "evaluation" / "evaluation.json", '{"methods": 5}'),
        ["report", "{run}"],
        "evaluation.json is damaged",
    ),
    (
        "evaluation.json a list",
        lambda r: write_file(r / "evaluation" / "evaluation.json", "[]"),
        ["report", "{run}"],
        "evaluation.json is damaged",
    ),
    (
        "match.csv of another layout",
        lambda r: write_file(r / "match" / "match.csv", "a,b\n1,2\n"),
        ["report", "{run}"],
        "match.csv has no 'method' column",
    ),
    (
        "config.json a list, report",
        lambda r: (r / "config.json").write_text("[]"),
        ["report", "{run}"],
        "config.json must hold a training run's config",
    ),
    (
        "config.json of wrong types, report",
        lambda r: (r / "config.json").write_text('{"run": 5}'),
        ["report", "{run}"],
        "config.json must hold a training run's config",
    ),
    (
        "metrics.csv binary, report",
        lambda r: (r / "metrics.csv").write_bytes(b"\xff\xfe" * 50),
        ["report", "{run}"],
        "metrics.csv is damaged",
    ),
    (
        "metrics.csv garbage",
        lambda r: (r / "metrics.csv").write_text("epoch,step\nx,y\n"),
        ["plot", "{run}"],
        "metrics.csv",
    ),
    # a log without a column the figures draw against was a KeyError traceback
    (
        "metrics.csv without its epochs",
        lambda r: (r / "metrics.csv").write_text("step,success_rate\n30,0.5\n"),
        ["plot", "{run}"],
        "metrics.csv has no 'epoch' column",
    ),
    (
        "episodes.csv without its episodes",
        lambda r: (r / "episodes.csv").write_text("step,reward\n20,1\n"),
        ["plot", "{run}"],
        "episodes.csv has no 'episode' column",
    ),
    (
        "evaluations.csv of another layout",
        lambda r: (r / "evaluations.csv").write_text("step,episodes\n30,5\n"),
        ["plot", "{run}"],
        "evaluations.csv has no 'success_rate' column",
    ),
    # an empty log, or one of another table with no rows, was drawn as "no data yet" (exit 0):
    # a log is made with its header, atomically, so an empty one was damaged, as --resume says
    *[
        (f"{name} emptied, {argv[0]}", lambda r, n=name: (r / n).write_text(""), argv, needle)
        for name in ("metrics.csv", "episodes.csv", "evaluations.csv")
        for argv, needle in (
            (["plot", "{run}"], f"{name} is empty (no header row)"),
            (["report", "{run}"], f"{name} is empty (no header row)"),
        )
        if (name, argv[0]) != ("episodes.csv", "report")  # report does not read it
        and (name, argv[0]) != ("evaluations.csv", "report")
    ],
    (
        "episodes.csv missing, plot",
        lambda r: (r / "episodes.csv").unlink(),
        ["plot", "{run}"],
        "has no episodes.csv (its training log): nothing to plot",
    ),
    (
        "metrics.csv of another table, no rows",
        lambda r: (r / "metrics.csv").write_text("hello,world\n"),
        ["plot", "{run}"],
        "metrics.csv has no 'epoch' column",
    ),
    (
        "metrics.csv of another table, report",
        lambda r: (r / "metrics.csv").write_text("hello,world\n1,2\n"),
        ["report", "{run}"],
        "metrics.csv has no 'epoch' column",
    ),
    (
        "episodes.csv of another table, no rows",
        lambda r: (r / "episodes.csv").write_text("hello,world\n"),
        ["plot", "{run}"],
        "episodes.csv has no 'episode' column",
    ),
    (
        "evaluations.csv of another table, no rows",
        lambda r: (r / "evaluations.csv").write_text("hello,world\n"),
        ["plot", "{run}"],
        "evaluations.csv has no 'step' column",
    ),
    # report left the section out of a results table emptied or cut to its header
    *[
        (
            f"{table} {name}",
            lambda r, t=table, x=text: write_file(r / t.split(".")[0] / t, x),
            ["report", "{run}"],
            needle,
        )
        for table in ("match.csv", "robustness.csv")
        for name, text, needle in (
            ("emptied", "", f"{table} is empty (no header row)"),
            ("of another table", "hello,world\n", f"{table} has no 'method' column"),
            ("cut to its header", "method,name,matches,n,seed\n", f"{table} holds no rows"),
        )
    ],
    (
        "manifest not text",
        lambda r: (latest(r) / "manifest.json").write_bytes(b"\xff\xfe" * 50),
        ["train", "--resume", "{run}"],
        "step_000000030 has no readable manifest",
    ),
]


def write_file(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


def write_compare_csv(run: Path, episodes: int) -> None:
    header = "error,episodes,seed,method,success_rate\n"
    write_file(run / "compare" / "compare.csv", header + f"0.0,{episodes},0,random,0.7\n")


def put_student_weights(run: Path) -> None:
    """A DAgger student's policy.safetensors (image + a 30-vector) in place of the run's."""
    from activevision.agents.student import StudentNetwork
    from activevision.training.policy_files import write_policy

    student = StudentNetwork(8, vector_size=30)
    write_policy(run, student.state_dict(), {**student.metadata(), "step": 60})


def swap_optimizer_state(run: Path) -> None:
    """An Adam state of a 2-parameter model: a valid file the run's network cannot use."""
    import torch

    params = [torch.nn.Parameter(torch.zeros(3)), torch.nn.Parameter(torch.zeros(2))]
    optimizer = torch.optim.Adam(params)
    sum(p.sum() for p in params).backward()
    optimizer.step()
    torch.save(optimizer.state_dict(), latest(run) / "optimizer.pt")
    rewrite_manifest(latest(run))


@pytest.mark.parametrize(
    ("tamper", "argv", "needle"), [t[1:] for t in TAMPERS], ids=[t[0] for t in TAMPERS]
)
def test_tampered_files_are_refused(
    trained, tmp_path, capsys, tamper, argv, needle, one_clear_line
):
    run = Path(shutil.copytree(trained, tmp_path / "run"))
    # an unfinished run, so resume has work to do
    shutil.rmtree(run / "checkpoints" / "step_000000060")
    tamper(run)
    assert main([a.format(run=run) for a in argv]) == 2
    one_clear_line(needle)


#: the slow commands, and the function that plays their episodes
SLOW_COMMANDS = [
    (["evaluate", "--methods", "random", "--episodes", "2"], "evaluate", "evaluate_policy"),
    (["compare", "--methods", "random", "--errors", "0"], "compare", "compare"),
    (["robustness", "--method", "random", "--perturbations", "clean"], "robustness", None),
]


@pytest.mark.parametrize(("argv", "module", "player"), SLOW_COMMANDS, ids=lambda v: str(v))
def test_an_out_that_cannot_be_written_is_refused_before_any_episode(
    monkeypatch, one_clear_line, argv, module, player
):
    import importlib

    played = []
    target = importlib.import_module(f"activevision.experiments.{module}")
    name = player or "score_perturbations"
    monkeypatch.setattr(target, name, lambda *a, **k: played.append(a))
    # /proc is a folder, but no folder can be made in it (not even by root)
    assert main([*argv, "--out", "/proc/activevision-no-such/x"]) == 2
    one_clear_line("--out /proc/activevision-no-such/x: cannot create it or write in it")
    assert played == []


@pytest.mark.parametrize("text", ["", "hello,world\n", "method,error\nrandom,0\n"])
def test_compare_replaces_no_file_it_cannot_resume_without_overwrite(
    tmp_path, monkeypatch, one_clear_line, text
):
    """A compare.csv emptied, or of another table, was read as one of no levels played and
    replaced without --overwrite; it is refused, named and left as it was, before any
    episode."""
    import activevision.experiments.compare as comparison

    played = []
    monkeypatch.setattr(comparison, "evaluate_policy", lambda *a, **k: played.append(a))
    csv_path = tmp_path / "cmp" / "compare.csv"
    write_file(csv_path, text)
    argv = ["compare", "--methods", "random", "--errors", "0", "--episodes", "1"]
    assert main([*argv, "--out", str(tmp_path / "cmp")]) == 2
    line = one_clear_line(str(csv_path), "damaged or not a file activevision wrote")
    assert ("is empty (no header row)" if not text else "has no '") in line
    assert csv_path.read_text() == text and played == []


def test_a_failed_evaluation_leaves_no_folder_behind(tmp_path, monkeypatch, one_clear_line):
    import activevision.experiments.evaluate as evaluation

    def fail(*args, **kwargs):
        raise ValueError("an episode failed")

    monkeypatch.setattr(evaluation, "evaluate_policy", fail)
    out = tmp_path / "new" / "e"
    assert main(["evaluate", "--methods", "random", "--episodes", "2", "--out", str(out)]) == 2
    one_clear_line("an episode failed")
    assert not (tmp_path / "new").exists()


def test_ctrl_c_is_one_line_and_an_interrupted_run_says_how_to_resume(
    tmp_path, tiny_train, monkeypatch, one_clear_line
):
    """Ctrl-C (KeyboardInterrupt) ends any command with one line and exit 130; ``train``
    names the way on: resume from its last checkpoint, or start over before the first."""
    from activevision.training.trainer import Trainer

    save = Trainer.save_checkpoint

    def save_then_interrupt(self):
        save(self)
        raise KeyboardInterrupt

    run = tmp_path / "run"
    monkeypatch.setattr(Trainer, "save_checkpoint", save_then_interrupt)
    assert main([*tiny_train, "--out", str(run)]) == 130
    one_clear_line(f"interrupted; `activevision train --resume {run}` continues", "step_")
    monkeypatch.setattr(Trainer, "save_checkpoint", save)
    assert main(["train", "--resume", str(run)]) == 0  # the advice works

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    fresh = tmp_path / "fresh"
    monkeypatch.setattr(Trainer, "train", interrupt)
    assert main([*tiny_train, "--out", str(fresh)]) == 130
    one_clear_line(f"before its first checkpoint; start it again with --out {fresh} --overwrite")

    monkeypatch.setattr("activevision.experiments.evaluate.run_episode", interrupt)
    out = tmp_path / "evaluation"
    assert main(["evaluate", "--methods", "scan", "--episodes", "2", "--out", str(out)]) == 130
    assert (
        one_clear_line("activevision evaluate: interrupted") == "activevision evaluate: interrupted"
    )
    assert not out.exists()  # the folder it made is removed again


MATCH_ARGV = ["match", "--matches", "2", "--ticks", "9", "--methods", "ball_track", "random"]


@pytest.mark.parametrize(
    ("argv", "last_writer", "outputs", "last_output"),
    [
        (
            MATCH_ARGV,
            "activevision.figures.match.save_gif",
            ["match.csv", "match_pareto.png", "match_error.png"],
            "match_clip.gif",
        ),
        # with --baseline: an older match_paired.csv outlived a failed first write
        (
            [*MATCH_ARGV, "--baseline", "random"],
            "activevision.io.write_csv",
            [],
            "match_paired.csv",
        ),
        (
            ["robustness", "--method", "random", "--episodes", "1", "--perturbations", "clean"],
            "activevision.figures.robustness.plot_robustness",
            ["robustness.csv"],
            "robustness.png",
        ),
        (
            ["evaluate", "--methods", "random", "--episodes", "2"],
            "activevision.io.write_json",
            ["evaluation.csv", "episodes.csv"],
            "evaluation.json",
        ),
    ],
)
def test_an_interrupt_while_writing_outputs_leaves_none_of_them(
    tmp_path, monkeypatch, one_clear_line, argv, last_writer, outputs, last_output
):
    """Ctrl-C while ``match`` wrote its figures left match.csv and two figures without the
    GIF (robustness: its CSV without the figure), a set that looked finished. An interrupted
    command leaves none of its outputs (``outputs`` written before ``last_writer`` writes
    ``last_output``), as one stopped while it played."""
    import importlib

    module_name, _, name = last_writer.rpartition(".")
    module = importlib.import_module(module_name)
    written = getattr(module, name)
    seen: list[str] = []

    def write_then_interrupt(*args, **kwargs):
        # what was written before this writer is there when the interrupt comes
        seen.extend(sorted(p.name for p in out.iterdir()))
        raise KeyboardInterrupt

    monkeypatch.setattr(module, name, write_then_interrupt)
    out = tmp_path / "new" / "out"
    assert main([*argv, "--out", str(out)]) == 130
    one_clear_line("interrupted")
    assert set(outputs) <= set(seen), seen
    assert not (tmp_path / "new").exists()  # its outputs and the folders it made are gone
    # with --overwrite, the older set goes too: not a mix of two runs' files
    monkeypatch.setattr(module, name, written)
    assert main([*argv, "--out", str(out)]) == 0
    monkeypatch.setattr(module, name, write_then_interrupt)
    assert (out / last_output).exists()
    assert main([*argv, "--out", str(out), "--overwrite"]) == 130
    assert not out.exists() or not [p for p in out.iterdir() if p.name in [*outputs, last_output]]


def test_sigterm_stops_train_as_ctrl_c_does(tmp_path, tiny_train):
    """``kill`` (SIGTERM) of a training run ended it with exit code 143 and nothing said: it
    stops as Ctrl-C does, with one line saying so and how to resume, and the shell's 143."""
    import signal
    import time

    from activevision.training.checkpoint import list_checkpoints

    run = tmp_path / "run"
    argv = list(tiny_train)
    argv[argv.index("--steps") + 1] = "1000000"  # far beyond the test: still running
    command = [sys.executable, "-m", "activevision", *argv, "--out", str(run)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not list_checkpoints(run) and process.poll() is None:
            assert time.monotonic() < deadline, "the run wrote no checkpoint in 120 s"
            time.sleep(0.2)
        assert process.poll() is None, process.communicate()
        process.send_signal(signal.SIGTERM)  # the run has started and checkpointed
        out, err = process.communicate(timeout=60)
    finally:
        process.kill()  # a no-op once it has exited
        process.wait()
    assert process.returncode == 143, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert "Traceback" not in out + err
    assert len(lines) == 1, err
    assert lines[0].startswith("activevision train: stopped by SIGTERM; ")
    assert f"`activevision train --resume {run}` continues from its last checkpoint" in lines[0]
    assert list_checkpoints(run)  # what the line offers to resume from is there


_NUMBA_LOOP = """
import math, signal, sys
from typing import NamedTuple

import numpy as np
from numba import njit

from activevision.cli import _sigterm_as_interrupt


class Out(NamedTuple):
    total: np.ndarray


@njit
def slow(n):
    total = np.zeros(1)
    for i in range(n):
        total[0] += math.sin(i)
    return Out(total)


slow(10)
print("ready", flush=True)
totals = []
try:
    with _sigterm_as_interrupt():
        while True:
            totals.append(slow(20_000_000).total[0])
except KeyboardInterrupt as stop:
    print(type(stop).__name__, flush=True)
"""


@pytest.mark.parametrize("signum", ["SIGTERM", "SIGINT"])
def test_an_interrupt_in_a_compiled_function_stops_without_a_crash(tmp_path, signum):
    """SIGTERM or Ctrl-C while a numba-compiled function ran (every tick of the match's
    entropy_track and glance_track: the viewpoint search) was a segmentation fault about
    every other time (exit code 139, the output folder left): the interrupt was raised in
    the Python code numba calls to box the function's result. It waits until that is done."""
    import signal

    script = tmp_path / "loop.py"
    script.write_text(_NUMBA_LOOP)
    # a few stops, one signal each (a second SIGTERM rightly ends the process at once, so
    # sending more to one process would fail the test whenever the first took long to stop)
    for _ in range(3):
        process = subprocess.Popen(
            [sys.executable, str(script)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        try:
            assert process.stdout is not None
            assert process.stdout.readline() == "ready\n", process.communicate()
            time.sleep(0.3)  # the loop is in its compiled calls
            process.send_signal(getattr(signal, signum))
            out, err = process.communicate(timeout=60)
        finally:
            process.kill()  # a no-op once it has exited
            process.wait()
        assert process.returncode == 0, err
        assert out.split() == ["Terminated" if signum == "SIGTERM" else "KeyboardInterrupt"], err


def test_a_size_this_machine_cannot_hold_is_one_line(
    tmp_path, monkeypatch, tiny_train, one_clear_line
):
    """A size the config takes but this machine cannot hold: numpy's MemoryError was a
    traceback; it is one line saying so, and the new run's folder goes."""

    def out_of_memory(*args, **kwargs):
        raise MemoryError("Unable to allocate 7.28 TiB for an array with shape (10**12,)")

    monkeypatch.setattr("activevision.training.train", out_of_memory)
    argv = [*tiny_train, "--out", str(tmp_path / "new")]
    assert main(argv) == 2
    one_clear_line("out of memory: Unable to allocate")
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize(
    ("setting", "named"),
    [
        ("replay.buffer_size", "ReplayConfig.buffer_size: must be in [1, 100000000]"),
        ("env.camera.width", "CameraConfig.width must be at most 8192 px"),
        ("learner.batch_size", "LearnerConfig.batch_size: must be in [1, 65536]"),
    ],
)
def test_a_huge_size_names_its_key_and_limit(
    tmp_path, tiny_train_without, one_clear_line, setting, named
):
    """``--set replay.buffer_size=10**15`` (or an image, a minibatch of that size) ended in
    numpy's "Maximum allowed dimension exceeded" or a MemoryError naming no key: it is one
    line naming the key and its limit, before any work."""
    tiny = tiny_train_without("batch_size", "buffer_size")  # the huge one alone sets them
    argv = [*tiny, "--set", f"{setting}={10**15}", "--out", str(tmp_path / "new")]
    assert main(argv) == 2
    one_clear_line(named, f"got {10**15}")
    assert not (tmp_path / "new").exists()


def test_resuming_a_run_without_checkpoint_says_how_to_start_it_again(run, one_clear_line):
    """A run killed before its first checkpoint: --resume said only "no checkpoint in
    RUN/checkpoints"."""
    shutil.rmtree(run / "checkpoints")
    assert main(["train", "--resume", str(run)]) == 2
    one_clear_line("before its first checkpoint", f"--out {run} --overwrite")
    (run / "checkpoints").write_text("")  # not a folder: not a run that stopped early
    assert main(["train", "--resume", str(run)]) == 2
    one_clear_line("checkpoints is not a directory")


@pytest.mark.parametrize(
    "argv",
    [
        ["--out", ""],  # after the tiny run's arguments
        ["train", "--resume", ""],
        ["evaluate", "--methods", "random", "--episodes", "1", "--out", ""],
        ["export", ""],
        ["report", ""],
    ],
)
def test_an_empty_path_is_refused(tmp_path, monkeypatch, tiny_train, argv, one_clear_line):
    """``Path("")`` is the current folder: ``--out "$RUN"`` with RUN unset trained into the
    folder the command ran in."""
    monkeypatch.chdir(tmp_path)
    assert main(tiny_train + argv if argv[0] == "--out" else argv) == 2
    one_clear_line("must not be empty")
    assert list(tmp_path.iterdir()) == []
