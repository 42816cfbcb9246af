"""The reference learner a user would pick instead: Stable-Baselines3's PPO
(``MultiInputPolicy``) on the same Dict observations and episodes as ``--preset
dagger_prior``, for a wall-clock budget, then scored on the same fixed-seed test episodes as
``activevision compare`` (seed 0 + level, 200 episodes per error level).

    python bench/reference_ppo.py --minutes 11 --out runs/ppo_prior
    python bench/reference_ppo.py --minutes 11 --dagger runs/dagger_prior_s0   # side by side

Ends with one JSON line: per error level, success rate and goal reached of PPO (and of the
DAgger run, when given), with the ratio goal-reached(DAgger) / goal-reached(PPO).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import gymnasium as gym
import torch

import activevision  # noqa: F401  (registers ActiveVision-v0)
from activevision.cli.args import ArgumentParser, positive_float, positive_int, refused_by
from activevision.envs import EnvConfig
from activevision.experiments.compare import compare
from activevision.experiments.policies import LearnedPolicy
from activevision.training import preset

ERRORS = (0.0, 1.0, 2.0)


class PPOPolicy:
    """An SB3 model as a HeadPolicy (deterministic actions)."""

    name = "ppo"

    def __init__(self, model) -> None:  # stable_baselines3.PPO
        self.model = model

    def reset(self, info, rng) -> None:
        pass

    def act(self, obs, info) -> int:
        action, _ = self.model.predict(obs, deterministic=True)
        return int(action)


class WallClock:
    """An SB3 callback that stops training after ``seconds``."""

    def __new__(cls, seconds: float):
        from stable_baselines3.common.callbacks import BaseCallback

        class _Stop(BaseCallback):
            def _on_training_start(self) -> None:
                self.t0 = time.perf_counter()

            def _on_step(self) -> bool:
                return time.perf_counter() - self.t0 < seconds

        return _Stop()


def main() -> None:
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.logger import Logger

    parser = ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=positive_float, default=11.0)
    parser.add_argument("--episodes", type=positive_int, default=200)
    parser.add_argument("--out", type=Path, default=Path("runs/ppo_prior"))
    parser.add_argument("--dagger", type=Path, help="a DAgger run to score beside PPO")
    args = parser.parse_args()
    if args.dagger is not None and not (args.dagger / "config.json").is_file():
        parser.error(f"--dagger {args.dagger}: not a training run (no config.json)")
    if (args.out / "ppo.zip").exists():
        parser.error(f"--out {args.out} holds a ppo.zip already: name another folder")
    learned = None
    if args.dagger is not None:  # read before the minutes of training, not after them
        with refused_by(parser, "--dagger"):  # its weights truncated, garbage...
            learned = LearnedPolicy.from_run(args.dagger)

    torch.set_num_threads(2)
    env_config: EnvConfig = preset("dagger_prior").env
    vec = make_vec_env(lambda: gym.make("ActiveVision-v0", config=env_config), n_envs=8, seed=0)
    model = PPO("MultiInputPolicy", vec, n_steps=256, batch_size=256, seed=0, verbose=0)
    model.set_logger(Logger(folder=None, output_formats=[]))  # no SB3-<time> folder in /tmp
    t0 = time.perf_counter()
    model.learn(total_timesteps=10**8, callback=WallClock(args.minutes * 60))
    trained_s, steps = time.perf_counter() - t0, model.num_timesteps
    args.out.mkdir(parents=True, exist_ok=True)
    model.save(args.out / "ppo.zip")

    ppo = PPOPolicy(model)
    methods = {"ppo": lambda e: ppo}
    if learned is not None:
        methods["dagger"] = lambda e: learned
    rows = compare(args.out, methods, ERRORS, args.episodes, 0, env_config, progress=False)
    table: dict[str, dict[str, float]] = {}
    for row in rows:
        key = f"{row['method']}@{row['error']}"
        table[key] = {"success_rate": float(row["success_rate"]), "goal": float(row["success"])}
        print(
            f"{key:<12} success rate {row['success_rate']:.3f}  goal reached {row['success']:.3f}"
        )
    ratios: dict[str, float | None] = {}
    if args.dagger:
        for e in ERRORS:
            ppo, dagger = table[f"ppo@{e}"]["goal"], table[f"dagger@{e}"]["goal"]
            # None (JSON null), not inf: strict JSON has no Infinity
            ratios[str(e)] = dagger / ppo if ppo > 0 else None
            shown = f"{dagger / ppo:.2f}x" if ppo > 0 else "undefined (PPO reached none)"
            print(f"goal reached, DAgger / PPO at e = {e}: {shown}")
    else:
        print("no reference: pass --dagger RUN to score a DAgger run of the same budget beside")
    print(
        json.dumps(
            {
                "bench": "reference_ppo",
                "ppo_steps": steps,
                "ppo_train_s": trained_s,
                "results": table,
                "goal_ratio_dagger_over_ppo": ratios,
            }
        )
    )


if __name__ == "__main__":
    main()
