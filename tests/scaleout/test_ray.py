"""Ray scale-out end to end: a seed sweep, a worker crash survived, distributed compare."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

ray = pytest.importorskip("ray")
pytest.importorskip("ray.tune")

from activevision.envs import EnvConfig  # noqa: E402
from activevision.experiments.compare import compare, default_methods  # noqa: E402
from activevision.scaleout import compare_ray, sweep  # noqa: E402
from activevision.scaleout.sweep import CRASH_MARKER  # noqa: E402
from activevision.training import apply_overrides, preset  # noqa: E402

TINY = [
    "total_timesteps=600",
    "learning_starts=100",
    "buffer_size=1000",
    "batch_size=8",
    "checkpoint_interval=300",
    "num_threads=1",
    "target_update_interval=100",
    "tensorboard=false",
    "progress_bar=false",
]


@pytest.fixture(scope="module", autouse=True)
def local_ray():
    """One local Ray instance for the module; the scale-out functions join it."""
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
    yield
    ray.shutdown()


def _read(path: Path) -> list[dict[str, str]]:
    with path.open() as f:
        return list(csv.DictReader(f))


def test_sweep_two_seeds_aggregates(tmp_path):
    config = apply_overrides(preset("paper"), TINY)
    rows = sweep(config, [0, 1], {"learning_rate": [5e-4]}, tmp_path, verbose=0)

    trials = _read(tmp_path / "trials.csv")
    assert [t["name"] for t in trials] == [
        "seed=0,learning_rate=0.0005",
        "seed=1,learning_rate=0.0005",
    ]
    assert all(t["status"] == "TERMINATED" and t["epochs"] == "2" for t in trials)
    on_disk = _read(tmp_path / "sweep.csv")
    assert len(on_disk) == len(rows) == 2
    assert [int(r["epoch"]) for r in on_disk] == [1, 2]
    assert [int(r["step"]) for r in on_disk] == [300, 600]
    for r in on_disk:
        assert r["seeds"] == "2" and float(r["learning_rate"]) == 5e-4
        for m in ("success_rate", "episode_reward", "success_duration", "ball_loss_duration"):
            assert float(r[f"{m}_min"]) <= float(r[f"{m}_mean"]) <= float(r[f"{m}_max"])
            assert float(r[f"{m}_std"]) >= 0
    # the mean is the mean of the two seeds' own metrics.csv rows
    per_seed = [_read(Path(t["run_dir"]) / "metrics.csv") for t in trials]
    mean = (float(per_seed[0][1]["success_rate"]) + float(per_seed[1][1]["success_rate"])) / 2
    assert float(on_disk[1]["success_rate_mean"]) == pytest.approx(mean)
    assert (tmp_path / "sweep.png").stat().st_size > 0


def test_trial_survives_worker_crash(tmp_path):
    config = apply_overrides(preset("paper"), TINY)
    sweep(config, [3], {}, tmp_path, max_failures=1, verbose=0, crash_after_epoch=1)

    (trial,) = _read(tmp_path / "trials.csv")
    assert trial["status"] == "TERMINATED"
    assert trial["restarts"] == "1" and trial["sessions"] == "2"
    run_dir = Path(trial["run_dir"])
    assert (run_dir / CRASH_MARKER).read_text().startswith("crashed after epoch 1")
    # resumed from the step-300 checkpoint: every epoch logged exactly once, in order
    assert [(r["epoch"], r["step"]) for r in _read(run_dir / "metrics.csv")] == [
        ("1", "300"),
        ("2", "600"),
    ]
    assert [int(r["epoch"]) for r in _read(tmp_path / "sweep.csv")] == [1, 2]


def test_compare_ray_equals_local(tmp_path):
    config = EnvConfig()
    names = ["oracle", "entropy_jump", "random", "scan"]
    errors = [0.0, 1.0]
    methods = {k: v for k, v in default_methods(config).items() if k in names}
    local = compare(tmp_path / "local", methods, errors, 6, seed=5, config=config, progress=False)
    order = list(methods)  # the local run's method order
    distributed = compare_ray(tmp_path / "ray", order, errors, 6, seed=5, config=config, chunk=4)

    assert distributed == local
    assert (tmp_path / "ray" / "compare.csv").read_text() == (
        tmp_path / "local" / "compare.csv"
    ).read_text()
    # a finished run is skipped: nothing is recomputed, the CSV stays the same
    again = compare_ray(tmp_path / "ray", order, errors, 6, seed=5, config=config, chunk=4)
    assert again == _read(tmp_path / "ray" / "compare.csv")
