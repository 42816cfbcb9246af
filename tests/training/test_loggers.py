"""The logger protocol: what the trainer hands its loggers, and the CSV and TensorBoard backends."""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping

import pytest

from activevision.training.aux_targets import goal_offset
from activevision.training.config import TrainConfig
from activevision.training.loggers import (
    EPISODE_TAGS,
    VALIDATION_TAGS,
    CsvLogger,
    LogPosition,
    TensorBoardLogger,
    default_loggers,
)
from activevision.training.metrics import (
    EPISODE_FIELDS,
    EPOCH_FIELDS,
    TENSORBOARD_TAGS,
    CsvLog,
    read_csv_columns,
)
from activevision.training.runs import resume, train
from activevision.training.trainer import Trainer
from activevision.training.validation import EVALUATION_FIELDS


def tiny_config(**changes) -> TrainConfig:
    values = dict(
        seed=3,
        total_timesteps=120,
        epoch_steps=60,
        batch_size=8,
        buffer_size=1000,
        learning_starts=20,
        target_update_interval=50,
        checkpoint_interval=60,
        eval_interval=40,
        eval_episodes=2,
        tensorboard=False,
        progress_bar=False,
        num_threads=1,
        env_id="unused",
    )
    values.update(changes)
    return TrainConfig().replace(**values)


class RecordingLogger:
    """A logger of one's own: keeps every call."""

    def __init__(self) -> None:
        self.calls: list[tuple] = []

    def start(self, resume: LogPosition | None) -> None:
        self.calls.append(("start", resume))

    def record_epoch(self, row: Mapping[str, float], step: int) -> None:
        self.calls.append(("epoch", dict(row), step))

    def record_episode(self, record: Mapping[str, float], step: int) -> None:
        self.calls.append(("episode", dict(record), step))

    def record_validation(self, row: Mapping[str, float], step: int) -> None:
        self.calls.append(("validation", dict(row), step))

    def flush(self) -> None:
        self.calls.append(("flush",))

    def close(self) -> None:
        self.calls.append(("close",))

    def records(self, kind: str) -> list[dict]:
        return [call[1] for call in self.calls if call[0] == kind]


def csv_rows(path) -> list[dict[str, float]]:
    with open(path, newline="") as file:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(file)]


def same_rows(recorded: list[dict], written: list[dict]) -> bool:
    def plain(row):  # NaN == NaN for this comparison
        return {k: ("nan" if math.isnan(float(v)) else float(v)) for k, v in row.items()}

    return [plain(r) for r in recorded] == [plain(r) for r in written]


def test_a_custom_logger_receives_every_record_the_csv_logs_get(tmp_path, fake_env_factory):
    recorder = RecordingLogger()
    epochs = train(
        tiny_config(), tmp_path, fake_env_factory, loggers=[CsvLogger(tmp_path), recorder]
    )
    assert recorder.calls[0] == ("start", None)  # a fresh run
    assert recorder.calls[-2:] == [("flush",), ("close",)]
    assert recorder.records("epoch") == epochs
    assert same_rows(recorder.records("epoch"), csv_rows(tmp_path / "metrics.csv"))
    assert same_rows(recorder.records("episode"), csv_rows(tmp_path / "episodes.csv"))
    assert same_rows(recorder.records("validation"), csv_rows(tmp_path / "evaluations.csv"))
    assert [r["step"] for r in recorder.records("validation")] == [40, 80, 120]
    assert len(recorder.records("episode")) >= 120 // 20
    for kind, record, step in (c for c in recorder.calls if len(c) == 3):
        assert step == record["step"], kind  # each record comes with its step


def test_given_loggers_replace_the_default_ones(tmp_path, fake_env_factory):
    recorder = RecordingLogger()
    train(tiny_config(tensorboard=True), tmp_path, fake_env_factory, loggers=[recorder])
    assert recorder.records("epoch")
    assert not (tmp_path / "metrics.csv").exists()
    assert not (tmp_path / "tensorboard").exists()
    assert (tmp_path / "policy.safetensors").exists()  # the rest of the run is unchanged


def test_default_loggers_follow_the_tensorboard_switch(tmp_path):
    kinds = [type(x) for x in default_loggers(tiny_config(tensorboard=True), tmp_path)]
    assert kinds == [CsvLogger, TensorBoardLogger]
    assert [type(x) for x in default_loggers(tiny_config(), tmp_path)] == [CsvLogger]


def test_resume_starts_loggers_at_the_checkpoint(tmp_path, fake_env_factory):
    first = Trainer(tiny_config(), tmp_path, fake_env_factory)
    first.train(steps=60)
    episodes = first.episode
    for _ in range(30):  # lost in a crash: the logs hold rows the resumed run must forget
        first._env_step()
    first.validate()
    first.close()

    recorder = RecordingLogger()
    resume(tmp_path, fake_env_factory, loggers=[CsvLogger(tmp_path), recorder])
    assert recorder.calls[0] == ("start", LogPosition(60, 1, episodes, 1))
    assert [r["step"] for r in recorder.records("epoch")] == [120]
    assert [r["step"] for r in recorder.records("validation")] == [80, 120]
    assert len(csv_rows(tmp_path / "metrics.csv")) == 2
    assert [r["step"] for r in csv_rows(tmp_path / "evaluations.csv")] == [40, 80, 120]
    assert len(csv_rows(tmp_path / "episodes.csv")) == episodes + len(recorder.records("episode"))


def epoch_row(step: int, **changes: float) -> dict[str, float]:
    row = {name: float(i) for i, name in enumerate(EPOCH_FIELDS)}
    return {**row, "step": step, **changes}


def episode_row(episode: int, step: int) -> dict[str, float]:
    return {**{name: 0.5 for name in EPISODE_FIELDS}, "episode": episode, "step": step}


def validation_row(step: int) -> dict[str, float]:
    return {**{name: 0.25 for name in EVALUATION_FIELDS}, "step": step, "best": 1}


def test_csv_logger_writes_the_three_logs_and_truncates_on_resume(tmp_path):
    logger = CsvLogger(tmp_path)
    with pytest.raises(RuntimeError, match="start"):
        logger.record_epoch(epoch_row(1), 1)
    logger.start(None)
    for name, fields in [
        ("metrics.csv", EPOCH_FIELDS),
        ("episodes.csv", EPISODE_FIELDS),
        ("evaluations.csv", EVALUATION_FIELDS),
    ]:
        assert (tmp_path / name).read_text().splitlines() == [",".join(fields)]
    for step in (1, 2, 3):
        logger.record_epoch(epoch_row(step), step)
        logger.record_episode(episode_row(step, step), step)
        logger.record_validation(validation_row(step), step)
    logger.close()
    assert [r["step"] for r in csv_rows(tmp_path / "metrics.csv")] == [1, 2, 3]
    assert csv_rows(tmp_path / "episodes.csv")[1] == episode_row(2, 2)
    assert csv_rows(tmp_path / "evaluations.csv")[2] == validation_row(3)

    again = CsvLogger(tmp_path)
    again.start(LogPosition(step=2, epochs=2, episodes=1, validations=0))
    assert [r["step"] for r in csv_rows(tmp_path / "metrics.csv")] == [1, 2]
    assert [r["step"] for r in csv_rows(tmp_path / "episodes.csv")] == [1]
    assert csv_rows(tmp_path / "evaluations.csv") == []
    CsvLogger(tmp_path).start(None)  # a fresh run: headers only
    assert csv_rows(tmp_path / "metrics.csv") == []


def scalars(log_dir) -> dict[str, list[tuple[int, float]]]:
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    events = EventAccumulator(str(log_dir))
    events.Reload()
    return {
        tag: [(e.step, e.value) for e in events.Scalars(tag)] for tag in events.Tags()["scalars"]
    }


def test_tensorboard_logger_keeps_the_tags_and_purges_on_resume(tmp_path):
    logger = TensorBoardLogger(tmp_path / "tb")
    logger.start(None)
    assert not (tmp_path / "tb").exists()  # the writer is made at the first record
    for step in (10, 20, 30):
        logger.record_epoch(epoch_row(step, loss=math.nan if step == 20 else 0.5), step)
        logger.record_episode(episode_row(step, step), step)
        logger.record_validation(validation_row(step), step)
    logger.flush()
    logger.close()
    found = scalars(tmp_path / "tb")
    # an episodic run's validation rows carry no match columns: those tags are not written
    match_tags = {"eval/position_rmse", "eval/ball_in_view"}
    expected = {*TENSORBOARD_TAGS.values(), *EPISODE_TAGS.values(), *VALIDATION_TAGS.values()}
    assert set(found) == expected - match_tags
    assert set(EPISODE_TAGS.values()) == {"charts/episodic_return", "charts/episodic_length"}
    assert set(VALIDATION_TAGS.values()) == {
        "eval/success_rate",
        "eval/mean_episodic_return",
        *match_tags,
    }
    assert found["losses/td_loss"] == [(10, 0.5), (30, 0.5)]  # NaN is left out
    assert found["charts/SPS"] == [
        (s, float(EPOCH_FIELDS.index("steps_per_s"))) for s in (10, 20, 30)
    ]
    assert found["charts/episodic_length"] == [(10, 0.5), (20, 0.5), (30, 0.5)]
    assert found["eval/success_rate"] == [(10, 0.25), (20, 0.25), (30, 0.25)]

    # a checkpoint at step 20 holds what was logged at step 20 (its CSV rows too): a resume
    # from it drops step 30 only and logs on from there (step 20 was dropped and never
    # logged again)
    resumed = TensorBoardLogger(tmp_path / "tb")
    resumed.start(LogPosition(step=20, epochs=2, episodes=2, validations=2))
    resumed.record_epoch(epoch_row(30, epsilon=9.0), 30)
    resumed.close()
    epsilon = scalars(tmp_path / "tb")["charts/epsilon"]
    first = float(EPOCH_FIELDS.index("epsilon"))
    assert epsilon == [(10, first), (20, first), (30, 9.0)]
    assert scalars(tmp_path / "tb")["eval/success_rate"] == [(10, 0.25), (20, 0.25)]


def test_a_fresh_start_drops_the_tensorboard_curves_of_an_earlier_attempt(tmp_path):
    # train --out RUN --overwrite kept the older attempt's events: two runs' curves in one
    earlier = TensorBoardLogger(tmp_path / "tb")
    earlier.start(None)
    earlier.record_epoch(epoch_row(10, epsilon=7.0), 10)
    earlier.close()
    notes = tmp_path / "tb" / "notes.txt"  # not TensorBoard's: left alone
    notes.write_text("mine")
    again = TensorBoardLogger(tmp_path / "tb")
    again.start(None)
    again.record_epoch(epoch_row(20, epsilon=9.0), 20)
    again.close()
    assert scalars(tmp_path / "tb")["charts/epsilon"] == [(20, 9.0)]
    assert notes.read_text() == "mine"


def test_a_training_run_writes_todays_tensorboard_tags(tmp_path, fake_env_factory):
    train(tiny_config(tensorboard=True), tmp_path, fake_env_factory, aux_target=goal_offset)
    found = scalars(tmp_path / "tensorboard")
    allowed = {*TENSORBOARD_TAGS.values(), *EPISODE_TAGS.values(), *VALIDATION_TAGS.values()}
    assert set(found) <= allowed
    assert {"charts/episodic_return", "eval/success_rate", "charts/epsilon"} <= set(found)
    assert [step for step, _ in found["charts/epsilon"]] == [60, 120]
    assert [step for step, _ in found["eval/mean_episodic_return"]] == [40, 80, 120]


@pytest.mark.parametrize(
    ("preset_name", "loss_tag", "chart_tags"),
    [
        ("paper", "losses/td_loss", {"charts/epsilon", "charts/per_beta"}),
        ("quickstart", "losses/imitation_loss", {"charts/teacher_share"}),
        ("sac_head", "losses/critic_loss", set()),
        ("ppo_head", "losses/loss", set()),
    ],
)
def test_each_learner_s_epoch_tags_name_what_it_logs(tmp_path, preset_name, loss_tag, chart_tags):
    # every run wrote DDQN's tags: a DAgger run's imitation loss as losses/td_loss and its
    # teacher's share as charts/epsilon, an SB3 learner's unused 0s as epsilon and PER beta
    from activevision.training.presets import preset

    config = preset(preset_name).replace(**{"run.tensorboard": True})
    (logger,) = [g for g in default_loggers(config, tmp_path) if isinstance(g, TensorBoardLogger)]
    logger.start(None)
    logger.record_epoch(epoch_row(10), 10)
    logger.close()
    found = scalars(tmp_path / "tensorboard")
    common = {"charts/success_rate", "charts/success_duration", "charts/ball_loss_duration"}
    common |= {"charts/mean_episodic_return", "charts/episodes", "charts/SPS"}
    assert set(found) == common | {loss_tag} | chart_tags
    assert found[loss_tag] == [(10, float(EPOCH_FIELDS.index("loss")))]
    if "charts/teacher_share" in chart_tags:
        assert found["charts/teacher_share"] == [(10, float(EPOCH_FIELDS.index("epsilon")))]


def test_a_match_runs_validation_goes_to_its_own_columns_and_tags(tmp_path):
    from activevision.training.validation import MATCH_EVALUATION_FIELDS

    row = {"step": 12, "episodes": 3, "position_rmse": 0.08, "ball_in_view": 0.3}
    row |= {"episode_reward": -5.0, "best": 1}
    csv_logger = CsvLogger(tmp_path, MATCH_EVALUATION_FIELDS)
    csv_logger.start(None)
    csv_logger.record_validation(row, 12)
    lines = (tmp_path / "evaluations.csv").read_text().splitlines()
    assert lines == [",".join(MATCH_EVALUATION_FIELDS), "12,3,0.08,0.3,-5.0,1"]
    logger = TensorBoardLogger(tmp_path / "tb")
    logger.start(None)
    logger.record_validation(row, 12)
    logger.close()
    found = scalars(tmp_path / "tb")
    assert set(found) == {"eval/position_rmse", "eval/ball_in_view", "eval/mean_episodic_return"}
    assert found["eval/position_rmse"] == [(12, pytest.approx(0.08))]


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("epoch,step\n1,300\n2\n", "line 3 has fewer cells than its header"),
        ("epoch,step\n1,300,7\n", "line 2 has more cells than its header"),
        ("epoch,step\n1,300\n2,x\n", "line 3, column 'step': 'x' is not a number"),
    ],
)
def test_a_log_cut_short_or_edited_is_named_by_line(tmp_path, text, needle):
    # a short row said "float() argument must be a string or a real number, not 'NoneType'"
    path = tmp_path / "metrics.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match=f"^{path}.*{needle}"):
        read_csv_columns(path)
    path.write_text("epoch,step\n1,300\n2,\n")
    assert read_csv_columns(path)["epoch"] == [1.0, 2.0]
    assert read_csv_columns(path)["step"][0] == 300.0 and math.isnan(
        read_csv_columns(path)["step"][1]
    )


def test_a_log_without_its_header_or_a_column_asked_for_is_named(tmp_path):
    """A log is made with its header: an empty one was read as a log of no rows yet."""
    path = tmp_path / "metrics.csv"
    path.write_text("")
    with pytest.raises(ValueError, match=f"^{path} is empty \\(no header row\\)"):
        read_csv_columns(path)
    path.write_text("epoch,step\n")
    assert read_csv_columns(path, ("step", "epoch")) == {}
    with pytest.raises(ValueError, match=f"^{path} has no 'loss' column"):
        read_csv_columns(path, ("epoch", "loss"))


def test_a_new_log_starts_with_its_header_alone(tmp_path):
    log = CsvLog(tmp_path / "m.csv", ["epoch", "step"])
    assert (tmp_path / "m.csv").read_bytes() == b"epoch,step\r\n"
    log.append({"epoch": 1, "step": 30})
    assert CsvLog(tmp_path / "m.csv", ["epoch", "step"]).rows() == [{"epoch": "1", "step": "30"}]


def test_a_log_cut_inside_its_last_cell_is_refused_or_read_without_it_while_live(tmp_path):
    """CsvLog writes whole rows, each with its end of line: a last line without one was cut
    (``0.12`` of ``0.1234``, read as a value), or is being written by a run still training
    (``live``: left out, with a warning)."""
    path = tmp_path / "metrics.csv"
    log = CsvLog(path, ["epoch", "step"])
    log.append({"epoch": 1, "step": 0.1234})
    path.write_bytes(path.read_bytes() + b"2,0.12")
    with pytest.raises(ValueError, match=f"^{path} line 3 has no end of line"):
        read_csv_columns(path)
    with pytest.warns(UserWarning, match="last line has no end of line"):
        assert read_csv_columns(path, live=True) == {"epoch": [1.0], "step": [0.1234]}
