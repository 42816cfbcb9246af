"""Training configuration: one typed, nested, frozen config per component, paper defaults.

Sources, noted at each field: "P" = the paper's hyper-parameter table; "SB2" =
Stable-Baselines v2 ``DQN`` defaults, which the paper used for everything the table leaves
out; "R" = the authors' code release (see ``shared/REFERENCE.md``). Each field's type and
range are checked where it is declared (:func:`activevision.typecheck.in_range`), so a bad
value fails when the config is built, naming its dotted path.

``config.json`` holds :meth:`TrainConfig.to_dict`; :func:`load_config` reads it back to an
equal object, and also reads the flat format of activevision 0.1 (``learning_rate`` at the
top, ``env_kwargs``), converting it on the fly.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import os
import typing
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from activevision.envs.config import MAX_VECTOR_ENVS, EnvConfig
from activevision.envs.match.config import MatchConfig
from activevision.io import loads_json, read_json, write_text
from activevision.registration import MATCH_ENV_ID
from activevision.runtime.goal_evidence import GoalFrame
from activevision.typecheck import check_dataclass_fields, config_from_dict, config_to_dict
from activevision.typecheck import in_range as _range

_FRACTION = _range(0.0, 1.0)
_POSITIVE = _range(0, low_open=True)
_AT_LEAST_1 = _range(1)
_AT_LEAST_0 = _range(0)
#: the most torch threads a run may ask for (RunConfig.num_threads): more than any CPU has
#: cores; 100,000 was a segmentation fault
MAX_THREADS = 1024
#: Upper bounds of the sizes a run allocates arrays or layers by: far beyond any run of this
#: package (presets: 256, 1,000,000, 64, 256), yet small enough that a typo (10**12) is
#: refused naming its key, not a numpy "Maximum allowed dimension exceeded" or MemoryError.
MAX_BATCH_SIZE = 65_536  #: LearnerConfig.batch_size: images per minibatch
MAX_N_STEP = 1000  #: LearnerConfig.n_step: rewards per target, gathered per minibatch row
MAX_AUGMENT_SHIFT = 64  #: LearnerConfig.augment_shift: px each image is padded by
MAX_BUFFER_SIZE = 100_000_000  #: ReplayConfig.buffer_size, DaggerConfig.dataset_size
MAX_NUM_ENVS = 4096  #: DaggerConfig.num_envs, Sb3Config.num_envs: environments at once
MAX_ROLLOUT_STEPS = 100_000  #: Sb3Config.n_steps: PPO's rollout per env
MAX_HIDDEN = 8192  #: Sb3Config.critic_hidden: width of (hidden x hidden) layers


@dataclass(frozen=True)
class LearnerConfig:
    """Double DQN: its optimiser, targets and update schedule."""

    learning_rate: float = field(default=5e-4, metadata=_POSITIVE)  #: Adam, constant (P)
    gamma: float = field(default=0.99, metadata=_FRACTION)  #: discount (P)
    #: rewards summed per target: 1 the paper's one-step DDQN, 3 Rainbow's (no better:
    #: docs/evaluation.md)
    n_step: int = field(default=1, metadata=_range(1, MAX_N_STEP))
    batch_size: int = field(default=32, metadata=_range(1, MAX_BATCH_SIZE))  #: minibatch (P)
    learning_starts: int = field(default=1000, metadata=_AT_LEAST_0)  #: steps before updates (SB2)
    train_freq: int = field(default=1, metadata=_AT_LEAST_1)  #: env steps per update round (SB2)
    gradient_steps: int = field(default=1, metadata=_AT_LEAST_1)  #: updates per round (SB2)
    #: environment steps between target-network syncs (P)
    target_update_interval: int = field(default=10_000, metadata=_AT_LEAST_1)
    max_grad_norm: float = field(default=10.0, metadata=_POSITIVE)  #: per-tensor clip (SB2)
    dueling: bool = False  #: dueling Q head (not in the paper)
    #: DrQ random shift of replay images by up to this many pixels (0: none, the paper)
    augment_shift: int = field(default=0, metadata=_range(0, MAX_AUGMENT_SHIFT))
    #: weight of an auxiliary head regressing the goal view's (pan, tilt) offset from the
    #: image (MSE, rad; 0: none, the paper). Training only: the policy acts on the image.
    aux_goal_weight: float = field(default=0.0, metadata=_AT_LEAST_0)

    def __post_init__(self) -> None:
        check_dataclass_fields(self)


@dataclass(frozen=True)
class ExplorationConfig:
    """Epsilon-greedy, annealed linearly (SB2 LinearSchedule)."""

    initial: float = field(default=1.0, metadata=_FRACTION)  #: P
    final: float = field(default=0.02, metadata=_FRACTION)  #: P
    #: fraction of the run over which epsilon decays (SB2; R: 0.85)
    fraction: float = field(default=0.1, metadata=_FRACTION)

    def __post_init__(self) -> None:
        check_dataclass_fields(self)


@dataclass(frozen=True)
class ReplayConfig:
    """Prioritised experience replay (Schaul et al. 2016)."""

    #: transitions (P)
    buffer_size: int = field(default=1_000_000, metadata=_range(1, MAX_BUFFER_SIZE))
    alpha: float = field(default=0.6, metadata=_FRACTION)  #: prioritisation exponent (P)
    #: initial importance-sampling exponent, annealed to 1 over the run (P; SB2)
    beta0: float = field(default=0.4, metadata=_FRACTION)
    eps: float = field(default=1e-6, metadata=_POSITIVE)  #: added to |td error| (SB2)

    def __post_init__(self) -> None:
        check_dataclass_fields(self)


@dataclass(frozen=True)
class RunConfig:
    """Length, logging, validation, checkpoints and hardware of a run."""

    total_timesteps: int = field(default=30_000, metadata=_AT_LEAST_1)  #: env steps (R)
    epoch_steps: int = field(default=300, metadata=_AT_LEAST_1)  #: steps per metrics row (P)
    #: steps between greedy validations that keep the best weights (0: none, as in the
    #: paper; SB3 EvalCallback's eval_freq)
    eval_interval: int = field(default=0, metadata=_AT_LEAST_0)
    eval_episodes: int = field(default=100, metadata=_AT_LEAST_1)  #: fixed-seed episodes each
    #: validation plays the episodes of `activevision evaluate --seed eval_seed`; keep it
    #: apart from the seed of the test figures (0)
    eval_seed: int = field(default=1000, metadata=_AT_LEAST_0)
    #: steps between checkpoints, a multiple of epoch_steps (0: only at the end)
    checkpoint_interval: int = field(default=3000, metadata=_AT_LEAST_0)
    keep_checkpoints: int = field(default=2, metadata=_AT_LEAST_1)  #: newest ones kept
    #: torch threads (0: one a core); at most MAX_THREADS: PyTorch's OpenMP pool crashes the
    #: process (a segmentation fault, no error) when it cannot start the threads asked for
    num_threads: int = field(default=0, metadata=_range(0, MAX_THREADS))
    device: str = "auto"  #: "auto" (cuda if available, else cpu), "cpu", "cuda[:n]", "mps"
    tensorboard: bool = True  #: also write TensorBoard events
    progress_bar: bool = True  #: tqdm bar (only when stderr is a terminal)

    def __post_init__(self) -> None:
        check_dataclass_fields(self)
        if self.checkpoint_interval % self.epoch_steps:
            raise ValueError(
                f"RunConfig.checkpoint_interval: must be a multiple of epoch_steps"
                f" ({self.epoch_steps}), got {self.checkpoint_interval}"
            )
        if not (self.device == "auto" or self.device.split(":")[0] in ("cpu", "cuda", "mps")):
            raise ValueError(
                f"RunConfig.device: must be 'auto', 'cpu', 'cuda[:n]' or 'mps', got {self.device!r}"
            )


@dataclass(frozen=True)
class DaggerConfig:
    """DAgger (Ross et al. 2011) with the simulator's oracle as the privileged teacher
    ("Learning by Cheating", Chen et al. 2019) on the episodes, and the ``entropy_track``
    planner (nothing privileged) on the match: not in the paper, values tuned here (T).
    The student's optimiser takes ``learner.learning_rate``, ``learner.batch_size`` and
    ``learner.max_grad_norm``."""

    #: episodes rolled out at once (T)
    num_envs: int = field(default=64, metadata=_range(1, MAX_NUM_ENVS))
    #: probability that the teacher's action is executed at the start (1: behaviour cloning
    #: first), decayed linearly to 0 over ``teacher_fraction`` of the run (Ross et al.) (T)
    teacher_initial: float = field(default=1.0, metadata=_FRACTION)
    teacher_fraction: float = field(default=0.25, metadata=_FRACTION)
    #: gradient updates after each round of ``num_envs`` episodes (T)
    updates_per_rollout: int = field(default=16, metadata=_AT_LEAST_1)
    #: labelled states kept (oldest dropped); states, not images: images are rendered for
    #: each minibatch, so a million states take ~200 MB
    dataset_size: int = field(default=1_000_000, metadata=_range(1, MAX_BUFFER_SIZE))
    downsample: int = field(default=2, metadata=_range(1, 4))  #: image average-pool factor (T)
    #: weight of the goal-view classification head (40 classes; 0: none) (T)
    goal_class_weight: float = field(default=0.5, metadata=_AT_LEAST_0)
    #: how the student acts: "action", the argmax of its action head; "goal", greedy moves
    #: towards the view its goal head supports most, evidence summed over the episode
    #: (``runtime.goal_evidence``: ends the swinging between two views) (T)
    act_by: typing.Literal["action", "goal"] = "goal"
    #: with act_by "goal": another view becomes the goal only when its summed evidence
    #: leads the current goal's by this many nats (hysteresis; 0: always the best) (T)
    switch_margin: float = field(default=0.0, metadata=_range(0.0, 1000.0))
    #: what the goal head names (``runtime.goal_evidence.GoalFrame``): "body", the 40 views
    #: (head angles); "camera", the goal's offset from where the head points now, which an
    #: image shows without the head angles (7 x 19 offsets, soft bilinear labels), read
    #: back as views with the head's angles when acting (docs/learned-head-control.md) (T)
    goal_frame: GoalFrame = "body"
    #: each minibatch draws its states' prior poses again at their episodes' error scales,
    #: with Algorithm 1's proposal from them (an augmentation: the student cannot recognise
    #: a stored episode by its one prior draw, and so learns what a prior of that error
    #: tells; docs/learned-head-control.md) (T)
    redraw_prior: bool = False
    #: each minibatch draws its states' looks again from ``env.appearance`` (every factor,
    #: the pattern key and, with ``neutral_share``, whether the state is seen clean; its head
    #: move and frame counter stay): the teacher's label does not depend on the look, so
    #: every state is learned under many appearances instead of the one it was visited in
    #: (docs/randomised-world.md) (T)
    redraw_look: bool = False
    #: a run directory (its newest policy) or a policy file whose student weights this run
    #: starts from instead of a random initialisation: fine-tuning, e.g. a clean-world
    #: policy in the randomised world. Its network and inputs must be this run's (checked
    #: against the file's metadata); None: random weights (T)
    init_from: str | None = None
    #: on the match env: the teacher, the planner ``entropy_track``
    #: (``envs.match.heads.EntropyTrackTeacher``) or ``glance_track`` (``GlanceTrackTeacher``)
    match_teacher: typing.Literal["entropy_track", "glance_track"] = "entropy_track"
    #: the glance_track teacher, while it tracks the ball: Algorithm 1 among the views that
    #: keep the ball this many degrees inside the image (from half the vertical field of
    #: view, 22.6 for the default camera: the ball centred, as the glance_track strategy) (T)
    glance_track_margin_deg: float = field(default=90.0, metadata=_range(0.0, 90.0))
    #: on the match env: the entropy_track teacher keeps the ball this many degrees inside the
    #: image (docs/match.md) (T)
    track_margin_deg: float = field(default=5.0, metadata=_range(0.0, 29.0))

    def __post_init__(self) -> None:
        check_dataclass_fields(self)
        if self.act_by == "goal" and not self.goal_class_weight > 0:
            raise ValueError("DaggerConfig.act_by: 'goal' needs goal_class_weight > 0")
        if self.goal_frame == "camera" and not self.goal_class_weight > 0:
            raise ValueError("DaggerConfig.goal_frame: 'camera' needs goal_class_weight > 0")


@dataclass(frozen=True)
class Sb3Config:
    """Stable-Baselines3's learners (``algo`` "sac", "td3", "ppo"): what ``learner`` and
    ``replay`` do not set. They take ``learner.learning_rate``, ``gamma`` and
    ``batch_size``; PPO ``max_grad_norm``; SAC and TD3 ``learning_starts``, ``train_freq``,
    ``gradient_steps`` and ``replay.buffer_size`` (SB3's uniform replay: it has no
    prioritised one); nothing else of ``learner``, ``replay`` or ``exploration`` (a
    ``--set`` of it is refused). "S": SB3's default; "T": tuned here."""

    #: environments stepped together (SB3 DummyVecEnv; PPO collects n_steps from each) (T)
    num_envs: int = field(default=4, metadata=_range(1, MAX_NUM_ENVS))
    tau: float = field(default=0.005, metadata=_FRACTION)  #: SAC/TD3 target update rate (S)
    #: TD3: std of the Gaussian exploration noise on the action (fraction of the range) (S)
    action_noise: float = field(default=0.1, metadata=_AT_LEAST_0)
    #: PPO rollout per env (T)
    n_steps: int = field(default=256, metadata=_range(1, MAX_ROLLOUT_STEPS))
    n_epochs: int = field(default=4, metadata=_AT_LEAST_1)  #: PPO epochs per rollout (T)
    gae_lambda: float = field(default=0.95, metadata=_FRACTION)  #: PPO (S)
    clip_range: float = field(default=0.2, metadata=_POSITIVE)  #: PPO (S)
    ent_coef: float = field(default=0.0, metadata=_AT_LEAST_0)  #: PPO entropy bonus (S)
    #: image average-pool factor of the shared CNN (the DAgger student's trunk) (T)
    downsample: int = field(default=2, metadata=_range(1, 4))
    #: hidden layer of the critic (and PPO's value head) after the CNN trunk (S: 256, 256)
    critic_hidden: int = field(default=256, metadata=_range(1, MAX_HIDDEN))

    def __post_init__(self) -> None:
        check_dataclass_fields(self)


#: Stable-Baselines3's learners (``training.sb3_learners``)
SB3_ALGORITHMS = ("sac", "td3", "ppo")
#: SB3 keeps each transition's image twice (observation and next): 19 KB each at 160 x 120
SB3_MAX_BUFFER = 200_000

Algorithm = typing.Literal["ddqn", "dagger", "sac", "td3", "ppo"]


@dataclass(frozen=True)
class TrainConfig:
    """Everything a training run depends on; saved as ``config.json`` beside each run."""

    #: seed of every generator of the run (network init, exploration, env resets, replay)
    seed: int = field(default=0, metadata=_range(0, 2**63 - 1))
    #: Gymnasium id of the environment; ``env`` configures ActiveVision-v0 (other envs are
    #: made with ``gymnasium.make(env_id)``, or handed to the Trainer by a factory)
    env_id: str = "ActiveVision-v0"
    env: EnvConfig = field(default_factory=EnvConfig)
    #: configures ActiveVisionMatch-v0 when ``env_id`` names it
    match: MatchConfig = field(default_factory=MatchConfig)
    learner: LearnerConfig = field(default_factory=LearnerConfig)
    exploration: ExplorationConfig = field(default_factory=ExplorationConfig)
    replay: ReplayConfig = field(default_factory=ReplayConfig)
    run: RunConfig = field(default_factory=RunConfig)
    #: "ddqn": the paper's DDQN + PER; "dagger": imitation of the oracle (``dagger``);
    #: "sac", "td3", "ppo": Stable-Baselines3's (``sb3``; continuous actions, PPO also
    #: discrete)
    algo: Algorithm = "ddqn"
    dagger: DaggerConfig = field(default_factory=DaggerConfig)
    sb3: Sb3Config = field(default_factory=Sb3Config)

    @property
    def on_match(self) -> bool:
        """A run on the match env (DDQN or the match student): its episodes are matches,
        which have no success; validation scores them as ``activevision match`` does."""
        return self.env_id == MATCH_ENV_ID

    @property
    def match_student(self) -> bool:
        """DAgger on the match env: a student of the match planner."""
        return self.algo == "dagger" and self.on_match

    def __post_init__(self) -> None:
        check_dataclass_fields(self)
        # Gymnasium's "module:id" names the same env; this package registers its envs on
        # import, so the bare id is the one every check below and later compares
        given = self.env_id
        object.__setattr__(self, "env_id", given.removeprefix("activevision:"))
        if not self.env_id.strip():  # "activevision:" or blanks name no env either
            raise ValueError(f"TrainConfig.env_id: must not be empty, got {given!r}")
        if self.algo == "dagger" and self.env_id not in ("ActiveVision-v0", MATCH_ENV_ID):
            raise ValueError(
                f"TrainConfig.algo: 'dagger' trains on ActiveVision-v0 (the oracle teaches) or"
                f" {MATCH_ENV_ID} (the entropy_track planner teaches), not {self.env_id!r}"
            )
        if self.match_student:
            self._check_match_dagger()
        if self.dagger.redraw_prior and not (
            self.algo == "dagger"
            and not self.match_student
            and self.env.observes_prior
            and self.env.prior_error_range is not None
        ):
            # without prior_error_range the prior is the believed pose the goal was planned
            # from: drawing it again would break the link the student should learn
            raise ValueError(
                "TrainConfig.dagger.redraw_prior: draws the prior pose of DAgger's episodic"
                " states again at their drawn error; it needs algo='dagger' on"
                " ActiveVision-v0 with a prior pose in env.observation ('image+head+pose...')"
                " and env.prior_error_range"
            )
        appearance = self.env.appearance
        if self.dagger.redraw_look and not (
            self.algo == "dagger"
            and not self.match_student
            and appearance.enabled
            and appearance.neutral_share < 1.0
        ):
            raise ValueError(
                "TrainConfig.dagger.redraw_look: draws the looks of DAgger's episodic states"
                " again; it needs algo='dagger' on ActiveVision-v0 with a randomised"
                " env.appearance, not every episode neutral (e.g. --preset"
                " dagger_robust_continuous)"
            )
        if self.algo == "dagger" and self.env.frame_stack != 1:
            raise ValueError("TrainConfig.algo: 'dagger' takes env.frame_stack=1")
        if self.algo == "ddqn" and self.learner.batch_size > self.replay.buffer_size:
            # the learner updates only once the buffer holds a minibatch: a smaller buffer
            # never does, and the run played to its end without one update (loss nan)
            raise ValueError(
                f"TrainConfig.learner.batch_size: DDQN draws its minibatches from the replay"
                f" buffer, so at most replay.buffer_size ({self.replay.buffer_size}), got"
                f" {self.learner.batch_size}"
            )
        # the run's own world: on the match these were "need a Discrete action space, got
        # Box(...)" and "need a uint8 Box observation space, got Dict(...)" from the trainer
        section, world = ("match", self.match) if self.on_match else ("env", self.env)
        others = "algo='dagger'" if self.on_match else "algo='dagger', 'sac', 'td3' or 'ppo'"
        if self.algo == "ddqn" and world.action_type == "continuous":
            raise ValueError(
                f"TrainConfig.{section}.action_type: DDQN learns discrete actions; train"
                f" continuous head control with {others}"
            )
        if self.algo in SB3_ALGORITHMS:
            self._check_sb3()
        if self.algo == "ddqn" and world.observation != "image":
            raise ValueError(
                f"TrainConfig.{section}.observation: the DDQN learner takes images only; train"
                f" Dict observations with {others}"
            )

    def _check_match_dagger(self) -> None:
        if self.match.observation != "image+head+belief":
            raise ValueError(
                "TrainConfig.match.observation: the match student needs what its teacher"
                " plans from, 'image+head+belief'"
            )
        if self.match.appearance.enabled:
            raise ValueError(
                "TrainConfig.match.appearance: the match student trains in the clean world"
                " (its dataset re-renders states without their looks)"
            )
        if self.dagger.act_by != "action":
            raise ValueError(
                "TrainConfig.dagger.act_by: a match student acts by its action head ('action');"
                " its teacher names no goal view"
            )
        if self.dagger.goal_frame != "body":
            raise ValueError(
                "TrainConfig.dagger.goal_frame: a match student has no goal view to name in"
                " the camera's frame ('body')"
            )
        if self.run.eval_interval and self.run.eval_episodes > MAX_VECTOR_ENVS:
            # else refused by the vector env at the first validation, mid-run
            raise ValueError(
                f"TrainConfig.run.eval_episodes: a match student's validation plays its matches"
                f" together in one vector env, at most {MAX_VECTOR_ENVS}, got"
                f" {self.run.eval_episodes}"
            )

    def _check_sb3(self) -> None:
        if self.env_id != "ActiveVision-v0":
            raise ValueError(f"TrainConfig.algo: {self.algo!r} trains on ActiveVision-v0")
        if self.env.frame_stack != 1:
            raise ValueError(f"TrainConfig.algo: {self.algo!r} takes env.frame_stack=1")
        if self.algo in ("sac", "td3") and self.env.action_type != "continuous":
            raise ValueError(f"TrainConfig.algo: {self.algo!r} needs env.action_type='continuous'")
        if self.algo in ("sac", "td3") and self.replay.buffer_size > SB3_MAX_BUFFER:
            raise ValueError(
                f"TrainConfig.replay.buffer_size: {self.algo!r} keeps every image twice"
                f" (~40 KB a transition); at most {SB3_MAX_BUFFER}, got"
                f" {self.replay.buffer_size} (e.g. --set replay.buffer_size=50000)"
            )

    def replace(self, **changes: Any) -> TrainConfig:
        """A copy with some values changed, by dotted path or unique field name:
        ``config.replace(**{"learner.learning_rate": 1e-3, "total_timesteps": 600})``."""
        return with_values(self, changes)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON values (nested objects per section)."""
        return config_to_dict(self)

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> TrainConfig:
        """Build from :meth:`to_dict`'s output, or from the flat format of activevision 0.1;
        unknown keys or bad values raise ValueError naming the key."""
        # not a mapping (a config.json holding a list or null): config_from_dict's message,
        # not a TypeError of the legacy check
        legacy = isinstance(values, Mapping) and any(
            key in _LEGACY_KEYS or key == "env_kwargs" for key in values
        )
        if legacy:
            values = _from_legacy(values)
        return config_from_dict(cls, values)


SECTIONS = ("env", "learner", "exploration", "replay", "run", "dagger", "sb3")
#: sections set by their full dotted path only (``match.detection.near``): their
#: leaf names repeat the episodic env's (``step_deg``, ``observation``)
PATH_ONLY_SECTIONS = ("match",)


def field_paths() -> dict[str, str]:
    """Every settable key: dotted path -> itself, plus each unique leaf name -> its path
    (``learning_rate`` -> ``learner.learning_rate``). Fields of a section's nested configs
    are settable one by one by their full path (``env.camera.hfov``), or whole as an object
    (``env.camera={"hfov": 1.2}``, the other fields taking their defaults)."""
    paths = {
        f.name: f.name
        for f in dataclasses.fields(TrainConfig)
        if f.name not in SECTIONS + PATH_ONLY_SECTIONS
    }
    leaves: dict[str, list[str]] = {}
    hints = typing.get_type_hints(TrainConfig)
    for section in SECTIONS:
        section_hints = typing.get_type_hints(hints[section])
        for f in dataclasses.fields(hints[section]):
            path = f"{section}.{f.name}"
            paths[path] = path
            leaves.setdefault(f.name, []).append(path)
            paths.update({p: p for p in _nested_paths(path, section_hints[f.name])})
    hints_match = hints["match"]
    paths.update({p: p for p in _nested_paths("match", hints_match)})
    for leaf, found in leaves.items():
        if len(found) == 1 and leaf not in paths:
            paths[leaf] = found[0]
    for old, new in _LEGACY_KEYS.items():
        paths.setdefault(old, new)
    return paths


def config_path(key: str, paths: dict[str, str] | None = None) -> str:
    """The field a ``--set``/``--grid`` key names: its full dotted path (``learning_rate`` ->
    ``learner.learning_rate``), or the key itself where it names none (the config's own
    check refuses it). ``paths``: :func:`field_paths`, when the caller has it already."""
    key = key.strip()
    return (field_paths() if paths is None else paths).get(key) or _env_alias(key) or key


def _nested_paths(path: str, hint: Any) -> list[str]:
    """The dotted paths of the fields inside a nested config dataclass ``hint`` (none for a
    plain value): ``env.camera`` -> ``env.camera.width``, ``env.camera.hfov``, ..."""
    if not (isinstance(hint, type) and dataclasses.is_dataclass(hint)):
        return []
    hints = typing.get_type_hints(hint)
    found = []
    for f in dataclasses.fields(hint):
        found.append(f"{path}.{f.name}")
        found.extend(_nested_paths(f"{path}.{f.name}", hints[f.name]))
    return found


def with_values(config: TrainConfig, changes: Mapping[str, Any]) -> TrainConfig:
    """``config`` with values set by key (see :func:`field_paths`); ValueError names an
    unknown key, a bad value, or a key the resulting run's ``algo`` and env never read
    (``dagger.*`` on a DDQN run...: it would sit in config.json, unused)."""
    paths = field_paths()
    nested = config_to_dict(config)
    env_id = next(
        (v for k, v in changes.items() if paths.get(k.strip()) == "env_id"), config.env_id
    )
    algo = next((v for k, v in changes.items() if paths.get(k.strip()) == "algo"), config.algo)
    resolved: dict[str, str] = {}  # each key as given -> its full path
    for key, value in changes.items():
        path = paths.get(key.strip()) or _env_alias(key.strip())
        if path is None and key.strip() in SECTIONS + PATH_ONLY_SECTIONS:
            # was "unknown TrainConfig key 'env'", though env is one
            raise ValueError(
                f"TrainConfig key {key.strip()!r} is a section: set its fields one by one"
                f" ({key.strip()}.FIELD=VALUE)"
            )
        if path is None:
            twins = sorted(p for p in set(paths.values()) if p.endswith("." + key.strip()))
            if len(twins) == 1:
                raise ValueError(f"TrainConfig key {key!r}: give its full path, {twins[0]}")
            if twins:
                raise ValueError(
                    f"TrainConfig key {key!r} names several fields; give its full path:"
                    f" {', '.join(twins)}"
                )
            raise ValueError(f"unknown TrainConfig key {key!r}")
        twin = next((k for k, p in resolved.items() if p == path), None)
        if twin is not None:  # the later one was taken silently
            raise ValueError(f"keys {twin!r} and {key.strip()!r} both set {path}: give it once")
        _refuse_unread(key.strip(), path, algo, env_id, paths)
        resolved[key.strip()] = path
        *parents, leaf = path.split(".")
        target = nested
        for part in parents:
            target = target[part]
        target[leaf] = value
    result = config_from_dict(TrainConfig, nested)
    for key, path in resolved.items():  # what the whole result decides (its DAgger teacher)
        unread = _unread_given(result, path)
        if unread:
            raise ValueError(f"{_named(key, path)} is never read by this run: {unread}")
    return result


def _refuse_unread(
    key: str, path: str, algo: object, env_id: object, paths: Mapping[str, str]
) -> None:
    """ValueError where a run of ``algo`` on ``env_id`` never reads ``key`` (at ``path``):
    the run would store it in config.json and never use it."""
    on_match = str(env_id).removeprefix("activevision:") == MATCH_ENV_ID
    if path.startswith("match.") and not on_match:
        raise ValueError(
            f"{key!r} sets the match env's config, which this run never reads: it trains on"
            f" {env_id}, not {MATCH_ENV_ID} (set env_id={MATCH_ENV_ID}, or use a match preset"
            " such as match_dagger)"
        )
    if on_match and path.startswith("env."):  # the episodic env's field, short name or full
        twin = "match." + path.removeprefix("env.")
        instead = f"set {twin} (full path)" if twin in paths else "the match has no such setting"
        raise ValueError(
            f"{key!r} sets {path}, the episodic env's field; this run trains on"
            f" {MATCH_ENV_ID}: {instead}"
        )
    unread = _unread_by(algo, path, on_match)
    if unread:
        raise ValueError(f"{_named(key, path)} is never read by an algo={algo!r} run: {unread}")


def _named(key: str, path: str) -> str:
    """A key as given, with its full path where it was a short name."""
    return repr(path) if key == path else f"{key!r} ({path})"


#: What DAgger's student takes of ``learner`` (``DaggerConfig``'s docstring); the rest of
#: ``learner``, ``exploration`` and ``replay`` configure DDQN (and SB3's) learners only.
_DAGGER_LEARNER_KEYS = ("learner.learning_rate", "learner.batch_size", "learner.max_grad_norm")
#: What each Stable-Baselines3 learner takes of ``learner``, ``replay`` and ``sb3``
#: (``training.sb3_learners._algorithm``, and ``make_vec_env``'s ``sb3.num_envs``); none
#: takes anything of ``exploration`` (DDQN's epsilon-greedy), nor the prioritised replay's
#: ``replay.alpha``, ``beta0`` and ``eps`` (SB3's replay is uniform).
_OFF_POLICY_LEARNER_KEYS = (
    "learning_rate",
    "gamma",
    "batch_size",
    "learning_starts",
    "train_freq",
    "gradient_steps",
)  # SAC's and TD3's
_SB3_KEYS: dict[str, dict[str, tuple[str, ...]]] = {
    "sac": {
        "learner": _OFF_POLICY_LEARNER_KEYS,
        "replay": ("buffer_size",),
        "sb3": ("num_envs", "tau", "downsample", "critic_hidden"),
    },
    "td3": {
        "learner": _OFF_POLICY_LEARNER_KEYS,
        "replay": ("buffer_size",),
        "sb3": ("num_envs", "tau", "action_noise", "downsample", "critic_hidden"),
    },
    "ppo": {
        "learner": ("learning_rate", "gamma", "batch_size", "max_grad_norm"),
        "replay": (),  # on-policy: it learns from its rollouts
        "sb3": (
            "num_envs",
            "n_steps",
            "n_epochs",
            "gae_lambda",
            "clip_range",
            "ent_coef",
            "downsample",
            "critic_hidden",
        ),
    },
}
#: Why an SB3 learner takes nothing (or only some) of a section
_SB3_WHY = {
    "exploration": " (DDQN's epsilon-greedy; SB3's learners explore by their own policies)",
    "replay": " (SB3's replay is uniform, not prioritised)",
    "ppo.replay": " (it learns from its rollouts: no replay buffer)",
}
#: ``dagger`` keys that only the match student (DAgger on ActiveVisionMatch-v0,
#: ``training.match_dagger``) reads: its teacher, the match planner
_MATCH_DAGGER_KEYS = ("match_teacher", "glance_track_margin_deg", "track_margin_deg")
#: ``dagger`` keys that only DAgger on the episodes (``training.dagger.DaggerTrainer``)
#: reads: the goal head and the goal evidence it acts by, and the minibatches' redrawn
#: priors and looks. (``act_by`` and ``goal_frame`` a match run reads too: it must keep them
#: at "action" and "body", which a switch to the match from an episodic config needs to set.)
_EPISODIC_DAGGER_KEYS = ("goal_class_weight", "switch_margin", "redraw_prior", "redraw_look")


def _unread_by(algo: object, path: str, on_match: bool = False) -> str:
    """Why a run of ``algo`` (on the match env if ``on_match``) never reads the config value
    at dotted ``path`` ("" when it does): ``dagger.*`` is DAgger's (the match teacher's keys
    the match student's only, the goal head's and the redrawn minibatches' the episodic
    student's only), ``sb3.*`` Stable-Baselines3's, a DAgger run reads of ``learner`` only
    its optimiser's values and nothing of ``exploration`` or ``replay``, and each SB3
    learner reads what ``training.sb3_learners`` passes it (:data:`_SB3_KEYS`)."""
    section, _, leaf = path.partition(".")
    if algo not in typing.get_args(Algorithm):
        return ""  # the algo's own check names it
    if section == "dagger" and algo != "dagger":
        return (
            "only DAgger runs read dagger.* (--algo dagger, or a DAgger preset such as quickstart)"
        )
    if section == "dagger" and on_match and leaf in _EPISODIC_DAGGER_KEYS:
        return (
            f"this run trains the match student ({MATCH_ENV_ID}), and only DAgger on"
            " ActiveVision-v0 reads it (the match student has no goal head, nor episodes'"
            " priors and looks to draw again)"
        )
    if section == "dagger" and not on_match and leaf in _MATCH_DAGGER_KEYS:
        return (
            f"only the match student reads it (its teacher; DAgger on {MATCH_ENV_ID}, e.g."
            " --preset match_dagger), and this run trains on ActiveVision-v0"
        )
    if section == "sb3" and algo not in SB3_ALGORITHMS:
        return f"only Stable-Baselines3's read sb3.* (--algo {', '.join(SB3_ALGORITHMS)})"
    if algo == "dagger" and section in ("learner", "exploration", "replay"):
        if path in _DAGGER_LEARNER_KEYS:
            return ""
        return (
            "DAgger's student takes only learner.learning_rate, learner.batch_size and"
            " learner.max_grad_norm (the rest configures DDQN's learner, its exploration and"
            " its replay buffer)"
        )
    if algo in _SB3_KEYS and section in ("learner", "exploration", "replay", "sb3"):
        keys = _SB3_KEYS[str(algo)].get(section, ())
        if leaf in keys:
            return ""
        name, why = str(algo).upper(), _SB3_WHY.get(f"{algo}.{section}", _SB3_WHY.get(section, ""))
        if not keys:
            return f"{name} takes nothing of {section}.*{why}"
        listed = ", ".join(keys[:-1]) + f" and {keys[-1]}" if len(keys) > 1 else keys[0]
        return f"{name} takes of {section}.* only {listed}{why}"
    return ""


def _unread_given(config: TrainConfig, path: str) -> str:
    """Why ``config``'s run never reads the value at ``path`` because of another of its
    values ("" when it does): the prior pose's settings where the observation has no prior
    pose, continuous moves' size with discrete actions and the discrete moves' step and set
    with continuous ones, the success tolerance where success is by landmarks, validation's
    episodes where the run never validates, and a DAgger key that one match teacher, or one
    way of acting, reads and the run's does not (``_unread_by`` has the algo's and the
    env's). The match's moves likewise (``match.step_deg``, ``match.max_move_deg``)."""
    unread = (
        _unread_env(config.env, path)
        or _unread_match(config.match, path)
        or _unread_run(config.run, path)
    )
    if unread or config.algo != "dagger":
        return unread
    dag = config.dagger
    if path == "dagger.switch_margin" and dag.act_by != "goal":
        return (
            "only a student acting by its goal head reads it (the goal evidence's hysteresis,"
            " dagger.act_by=goal); this one acts by its action head"
        )
    teacher_margins = {
        "dagger.glance_track_margin_deg": "glance_track",
        "dagger.track_margin_deg": "entropy_track",
    }
    teacher = teacher_margins.get(path)
    if teacher is not None and dag.match_teacher != teacher:
        return (
            f"only the {teacher} teacher reads it (dagger.match_teacher={teacher}); this run's"
            f" teacher is {dag.match_teacher}"
        )
    return ""


#: the episodic env's settings of the prior pose, which only a Dict observation with the
#: prior pose (``EnvConfig.observes_prior``) draws (``envs.simulation``)
_PRIOR_KEYS = ("env.prior_error_range", "env.prior_exact_share", "env.prior_grid")


def _unread_env(env: EnvConfig, path: str) -> str:
    """Why a run on ``env`` (ActiveVision-v0) never reads the ``env`` value at ``path``
    because of another of its values ("" when it does)."""
    if path in _PRIOR_KEYS and not env.observes_prior:
        return (
            "only an observation with a prior pose reads it (env.observation='image+head+pose'"
            f" or 'image+head+pose+proposal'); this run observes {env.observation!r}"
        )
    if path == "env.prior_exact_share" and env.prior_error_range is None:
        return (
            "it is the share of exact priors among those drawn with env.prior_error_range,"
            " which this run does not set (its prior is the believed pose)"
        )
    if path == "env.max_move_deg" and env.action_type != "continuous":
        return (
            "only continuous moves are scaled by it (env.action_type=continuous); this run's"
            " discrete moves are env.step_deg"
        )
    if path in ("env.step_deg", "env.action_set") and env.action_type == "continuous":
        return (
            "only discrete moves read it (the table of the actions' moves); this run's"
            " continuous moves are scaled by env.max_move_deg"
        )
    if path == "env.success_tolerance_deg" and env.success_mode != "tolerance":
        return (
            "only env.success_mode=tolerance ends an episode by it; this run's success is"
            f" {env.success_mode!r} (every landmark of the goal view in view)"
        )
    return ""


def _unread_match(match: MatchConfig, path: str) -> str:
    """Why a run on the match (ActiveVisionMatch-v0) never reads the ``match`` value at
    ``path`` because of how its head moves ("" when it does): the 8-way moves' step with
    continuous moves, and the continuous moves' size with discrete ones. (A run on another
    env is refused any ``match.*`` key before this.)"""
    if path == "match.step_deg" and match.action_type == "continuous":
        return (
            "only discrete moves read it (the step of the 8-way moves); this run's continuous"
            " moves are scaled by match.max_move_deg"
        )
    if path == "match.max_move_deg" and match.action_type != "continuous":
        return (
            "only continuous moves are scaled by it (match.action_type=continuous); this"
            " run's discrete moves are match.step_deg"
        )
    return ""


def _unread_run(run: RunConfig, path: str) -> str:
    """Why a run of ``run`` never reads the ``run`` value at ``path`` ("" when it does)."""
    if path in ("run.eval_episodes", "run.eval_seed") and not run.eval_interval:
        return (
            "only validation reads it, and this run never validates (run.eval_interval=0;"
            " set run.eval_interval=N to validate every N steps)"
        )
    return ""


def _env_alias(key: str) -> str | None:
    """``env_kwargs.step_deg`` (activevision 0.1's spelling) -> ``env.step_deg``."""
    if key.startswith("env_kwargs."):
        name = key.removeprefix("env_kwargs.")
        if name in {f.name for f in dataclasses.fields(EnvConfig)}:
            return f"env.{name}"
    return None


#: activevision 0.1's flat keys -> their dotted paths (reading old config.json, old --set)
_LEGACY_KEYS = {
    "total_timesteps": "run.total_timesteps",
    "epoch_steps": "run.epoch_steps",
    "batch_size": "learner.batch_size",
    "buffer_size": "replay.buffer_size",
    "learning_rate": "learner.learning_rate",
    "gamma": "learner.gamma",
    "n_step": "learner.n_step",
    "target_update_interval": "learner.target_update_interval",
    "exploration_initial": "exploration.initial",
    "exploration_final": "exploration.final",
    "exploration_fraction": "exploration.fraction",
    "learning_starts": "learner.learning_starts",
    "train_freq": "learner.train_freq",
    "gradient_steps": "learner.gradient_steps",
    "per_alpha": "replay.alpha",
    "per_beta0": "replay.beta0",
    "per_eps": "replay.eps",
    "max_grad_norm": "learner.max_grad_norm",
    "augment_shift": "learner.augment_shift",
    "aux_goal_weight": "learner.aux_goal_weight",
    "dueling": "learner.dueling",
    "eval_interval": "run.eval_interval",
    "eval_episodes": "run.eval_episodes",
    "eval_seed": "run.eval_seed",
    "checkpoint_interval": "run.checkpoint_interval",
    "keep_checkpoints": "run.keep_checkpoints",
    "num_threads": "run.num_threads",
    "device": "run.device",
    "tensorboard": "run.tensorboard",
    "progress_bar": "run.progress_bar",
}


def _from_legacy(values: Mapping[str, Any]) -> dict[str, Any]:
    """The nested form of an activevision 0.1 (flat) config.json."""
    nested: dict[str, Any] = {}
    for key, value in values.items():
        if key == "env_kwargs":
            if not isinstance(value, Mapping):
                raise ValueError(f"env_kwargs: expects an object, got {value!r}")
            extra = sorted(set(value) - {f.name for f in dataclasses.fields(EnvConfig)})
            if extra:
                raise ValueError(f"env_kwargs: unknown ActiveVision-v0 keyword(s) {extra}")
            nested.setdefault("env", {}).update(value)
            continue
        path = _LEGACY_KEYS.get(key, key)
        section, _, leaf = path.rpartition(".")
        (nested.setdefault(section, {}) if section else nested)[leaf] = value
    return nested


def save_config(config: TrainConfig, path: str | os.PathLike[str]) -> None:
    """Write the config as JSON atomically (a temporary file, then ``os.replace``)."""
    write_text(path, json.dumps(config.to_dict(), indent=2, sort_keys=True) + "\n")


def load_config(path: str | os.PathLike[str]) -> TrainConfig:
    """Read a config written by :func:`save_config` (ValueError on unknown or invalid keys,
    and naming a path that is no file: it was a bare "[Errno 2]" line)."""
    if not Path(path).is_file():
        raise ValueError(f"{path}: {'not a file' if Path(path).exists() else 'no such file'}")
    values = read_json(path)
    if not isinstance(values, dict):
        raise ValueError(f"{path} must hold a JSON object")
    try:
        return TrainConfig.from_dict(values)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{path}: {error}") from None


def apply_overrides(config: TrainConfig, overrides: Iterable[str]) -> TrainConfig:
    """Apply ``key=value`` strings from a command line: ``["learner.learning_rate=1e-3",
    "env.step_deg=4", "total_timesteps=600"]`` (dotted paths or unique field names).

    Values are parsed as JSON where they can be (``true``, ``3``, ``[1, 2]``), else taken as
    strings.
    """
    return with_values(config, parse_overrides(overrides))


def parse_overrides(
    overrides: Iterable[str], field_of: Callable[[str], str] | None = None
) -> dict[str, Any]:
    """``key=value`` strings as a mapping of each key to its parsed value. ValueError where
    two of them set one field, by one key or by two that name it (``learning_rate`` and
    ``learner.learning_rate``): the last was taken silently. ``field_of``: the field a key
    names (default: a TrainConfig's, :func:`config_path`)."""
    if field_of is None:
        field_of = functools.partial(config_path, paths=field_paths())
    changes: dict[str, Any] = {}
    setters: dict[str, tuple[str, str]] = {}  # each field set -> the key and item that set it
    for item in overrides:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ValueError(f"override {item!r} must look like key=value")
        named = field_of(key)
        if named in setters:
            first_key, first = setters[named]
            if first_key == key:
                raise ValueError(
                    f"override {_named(key, named)} is given twice ({first}, then {item}):"
                    " give it once"
                )
            raise ValueError(f"overrides {first} and {item} both set {named}: give it once")
        setters[named] = (key, item)
        changes[key] = override_value(key, text)
    return changes


def override_value(key: str, text: str) -> Any:
    """:func:`parse_value` of ``key``'s value, a ValueError naming ``key``."""
    try:
        return parse_value(text)
    except ValueError as error:
        raise ValueError(f"override {key.strip()!r}: {error}") from None


def parse_value(text: str) -> Any:
    """A ``--set``/``--grid`` value: its JSON value, or the text itself when it is no JSON
    (``lr=1e-3`` -> 0.001, ``device="cpu"`` and ``device=cpu`` -> ``"cpu"``)."""
    try:
        return loads_json(text)
    except json.JSONDecodeError:
        return text
    except (ValueError, RecursionError) as error:  # too many digits, or nested too deep
        shown = text if len(text) <= 40 else f"{text[:40]}..."
        raise ValueError(f"cannot read the value {shown!r}: {error}") from None
