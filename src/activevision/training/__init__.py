"""Training runs: configuration, the DDQN + prioritised-replay loop, checkpoints, metrics, plots.

Typical use::

    from activevision.training import TrainConfig, Trainer, load_policy, plot_run

    config = TrainConfig(env_kwargs={"frame_stack": 1}, total_timesteps=30_000)
    Trainer(config, "runs/paper").train()      # or train(config, "runs/paper")
    policy = load_policy("runs/paper")          # QNetwork, eval mode
    plot_run("runs/paper")                      # training.png and one PNG per curve
"""

from activevision.training.checkpoint import CheckpointError
from activevision.training.config import (
    TrainConfig,
    apply_overrides,
    load_config,
    preset,
    save_config,
)
from activevision.training.plots import plot_run
from activevision.training.trainer import Trainer, load_policy, make_env, resume, train

__all__ = [
    "CheckpointError",
    "TrainConfig",
    "Trainer",
    "apply_overrides",
    "load_config",
    "load_policy",
    "make_env",
    "plot_run",
    "preset",
    "resume",
    "save_config",
    "train",
]
