import dataclasses
import json
import subprocess
import sys

import pytest

from activevision.envs import EnvConfig
from activevision.geometry import CameraConfig, FieldSpec
from activevision.training.config import (
    LearnerConfig,
    RunConfig,
    TrainConfig,
    apply_overrides,
    field_paths,
    load_config,
    save_config,
)
from activevision.training.presets import PRESET_NAMES, preset, scaled_intervals


def test_paper_defaults_and_release_preset():
    config = TrainConfig()
    learner, replay, exploration = config.learner, config.replay, config.exploration
    assert (learner.batch_size, replay.buffer_size, learner.learning_rate) == (32, 1_000_000, 5e-4)
    assert (learner.gamma, learner.target_update_interval) == (0.99, 10_000)
    assert (exploration.initial, exploration.final) == (1.0, 0.02)
    assert (replay.alpha, replay.beta0, replay.eps) == (0.6, 0.4, 1e-6)
    assert (learner.learning_starts, exploration.fraction) == (1000, 0.1)
    assert config.env == EnvConfig() and config.run.total_timesteps == 30_000
    assert preset("paper") == config
    release = preset("release")
    assert (release.learner.learning_starts, release.exploration.fraction) == (500, 0.85)
    with pytest.raises(ValueError, match="nope"):
        preset("nope")


@pytest.mark.parametrize("name, factor", [("data4x", 4), ("data8x", 8)])
def test_more_episodes_keep_the_papers_update_budget(name, factor):
    paper, more = preset("paper"), preset(name)

    def updates(c):
        return (c.run.total_timesteps - c.learner.learning_starts) // c.learner.train_freq

    assert more.run.total_timesteps == factor * paper.run.total_timesteps
    assert updates(more) == updates(paper)  # 29,000 gradient updates each
    assert more.learner.target_update_interval // more.learner.train_freq == (
        paper.learner.target_update_interval
    )
    assert more.learner.learning_starts // more.learner.train_freq == paper.learner.learning_starts
    assert more.run.eval_interval > 0  # validated, so the run's curve shows the greedy policy
    # exploration spans the same fraction of the run; the learner itself is the paper's
    for path in ("learning_rate", "gamma", "batch_size"):
        assert getattr(more.learner, path) == getattr(paper.learner, path)
    assert (more.exploration, more.replay, more.env) == (paper.exploration, paper.replay, paper.env)


def test_drq_aux_is_the_paper_run_with_two_training_aids():
    paper, drq_aux = preset("paper"), preset("drq_aux")
    assert (drq_aux.learner.augment_shift, drq_aux.learner.aux_goal_weight) == (8, 1.0)
    assert drq_aux.replace(augment_shift=0, aux_goal_weight=0.0) == paper


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_every_preset_round_trips_through_json(tmp_path, name):
    changes: dict[str, object] = {"seed": 3, "env.field": "paper2019"}
    if preset(name).env_id == "ActiveVisionMatch-v0":  # a match run refuses env.*: unread
        changes = {"seed": 3, "match.ticks": 40}
    elif preset(name).algo == "ddqn":  # DAgger takes one frame
        changes["env.frame_stack"] = 2
    config = preset(name).replace(**changes)
    save_config(config, tmp_path / "config.json")
    loaded = load_config(tmp_path / "config.json")
    assert loaded == config and isinstance(loaded.env.field, FieldSpec)
    if "env.field" in changes:
        assert loaded.env.field == FieldSpec.paper_2019()
    else:
        assert loaded.match.ticks == 40
    assert not list(tmp_path.glob(".*tmp"))  # the temporary file is gone


def test_flat_config_of_activevision_0_1_still_loads(tmp_path):
    old = {
        "seed": 4,
        "env_id": "ActiveVision-v0",
        "env_kwargs": {"field": "paper2019", "success_mode": "landmarks"},
        "learning_rate": 1e-3,
        "per_alpha": 0.5,
        "exploration_fraction": 0.85,
        "total_timesteps": 600,
        "tensorboard": False,
    }
    path = tmp_path / "config.json"
    path.write_text(json.dumps(old))
    config = load_config(path)
    assert config.seed == 4 and config.learner.learning_rate == 1e-3
    assert (config.replay.alpha, config.exploration.fraction) == (0.5, 0.85)
    assert (config.run.total_timesteps, config.run.tensorboard) == (600, False)
    assert config.env == EnvConfig(field=FieldSpec.paper_2019(), success_mode="landmarks")
    path.write_text(json.dumps({**old, "env_kwargs": {"stack": 2}}))
    with pytest.raises(ValueError, match="stack"):
        load_config(path)


@pytest.mark.parametrize(
    ("key", "value", "named"),
    [
        ("learning_rate", -1e-3, "learning_rate"),
        ("exploration_fraction", 1.5, "fraction"),
        ("exploration.fraction", float("nan"), "fraction"),
        ("gamma", -0.1, "gamma"),
        ("batch_size", 0, "batch_size"),
        ("n_step", 0, "n_step"),
        ("learning_starts", -1, "learning_starts"),
        ("per_eps", 0.0, "eps"),
        ("checkpoint_interval", 250, "checkpoint_interval"),  # not a multiple of epoch_steps
        ("batch_size", 3.5, "batch_size"),
        ("dueling", "yes", "dueling"),
        ("device", "tpu", "device"),
        ("seed", -1, "seed"),
        ("env.step_deg", "3", "step_deg"),
        ("env.frame_stack", True, "frame_stack"),
        ("env.field", 42, "field"),
        ("env_id", "", "env_id"),
        ("learner", 3, "learner"),
    ],
)
def test_invalid_values_name_the_key(key, value, named):
    with pytest.raises(ValueError, match=named):
        TrainConfig().replace(**{key: value})


def test_each_section_checks_its_own_fields():
    with pytest.raises(ValueError, match=r"LearnerConfig\.gamma: must be in \[0.0, 1.0\]"):
        LearnerConfig(gamma=2.0)
    with pytest.raises(ValueError, match=r"RunConfig\.total_timesteps: must be >= 1"):
        RunConfig(total_timesteps=0)


def test_unknown_keys_name_the_key(tmp_path):
    path = tmp_path / "config.json"
    path.write_text(json.dumps({"learner": {"learning_rate": 1e-3, "lerning_rate": 1e-3}}))
    expected = r"TrainConfig\.learner: unknown key\(s\) \['lerning_rate'\]"
    with pytest.raises(ValueError, match=expected):
        load_config(path)


def test_cli_overrides_by_path_leaf_and_old_name():
    config = apply_overrides(
        TrainConfig(),
        [
            "learner.learning_rate=1e-3",
            "dueling=true",
            "env_id=Other-v1",
            "env.step_deg=4",
            "env_kwargs.frame_stack=2",
            "per_alpha=0.5",
            "total_timesteps=600",
        ],
    )
    assert config.learner.learning_rate == 1e-3 and config.learner.dueling
    assert config.env_id == "Other-v1" and config.replay.alpha == 0.5
    assert (config.env.step_deg, config.env.frame_stack, config.run.total_timesteps) == (4, 2, 600)
    with pytest.raises(ValueError, match="bogus"):
        apply_overrides(config, ["bogus=1"])
    with pytest.raises(ValueError, match="total_timesteps"):
        apply_overrides(config, ["total_timesteps=-5"])


def test_cli_overrides_of_a_nested_config_field():
    """``--set env.camera.hfov=1.2`` changes that field and keeps the others (train for a
    team's own camera)."""
    base = apply_overrides(TrainConfig(), ["env.camera.camera_height=0.6"])
    config = apply_overrides(
        base, ["env.camera.hfov=1.2", "env.camera.tilt_max=1.0", "env.field.ball_radius=0.1"]
    )
    assert config.env.camera == CameraConfig(hfov=1.2, camera_height=0.6, tilt_max=1.0)
    assert config.env.field.ball_radius == 0.1
    assert load_config_round_trip(config) == config
    whole = apply_overrides(base, ['env.camera={"hfov": 1.2}'])  # a whole object: defaults
    assert whole.env.camera == CameraConfig(hfov=1.2)
    with pytest.raises(ValueError, match=r"unknown TrainConfig key 'env\.camera\.fov'"):
        apply_overrides(config, ["env.camera.fov=1.2"])
    for section in ("env", "learner", "match"):  # was "unknown TrainConfig key 'env'"
        with pytest.raises(ValueError, match=rf"key '{section}' is a section: set its fields"):
            apply_overrides(config, [f'{section}={{"step_deg": 4}}'])
    with pytest.raises(ValueError, match="hfov"):
        apply_overrides(config, ["env.camera.hfov=4"])
    # a field name that several configs have: the paths to choose from
    with pytest.raises(ValueError, match=r"'neutral_share' names several fields; give its full"):
        apply_overrides(config, ["neutral_share=0.5"])
    with pytest.raises(ValueError, match=r"env\.appearance\.neutral_share, match\.appearance"):
        apply_overrides(config, ["neutral_share=0.5"])


def load_config_round_trip(config: TrainConfig) -> TrainConfig:
    return TrainConfig.from_dict(json.loads(json.dumps(config.to_dict())))


def test_every_field_has_a_key_and_a_source_comment():
    paths = field_paths()
    for section in ("env", "learner", "exploration", "replay", "run"):
        cls = type(getattr(TrainConfig(), section))
        for f in dataclasses.fields(cls):
            assert paths[f"{section}.{f.name}"] == f"{section}.{f.name}"


def test_presets_load_without_torch():
    code = (
        "import sys\n"
        "from activevision.training.presets import PRESET_NAMES, preset\n"
        "[preset(n) for n in PRESET_NAMES]\n"
        "assert 'torch' not in sys.modules, 'torch imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)


def test_the_module_prefixed_env_id_is_the_env_itself():
    """Gymnasium's "activevision:ActiveVisionMatch-v0" trained a match student, but every
    later check (match --run's detector, export, plots, the report) compared the bare id
    and took the run for an episodic one."""
    config = apply_overrides(preset("match_dagger"), ["env_id=activevision:ActiveVisionMatch-v0"])
    assert config.env_id == "ActiveVisionMatch-v0" and config.match_student
    assert TrainConfig.from_dict(config.to_dict()) == config
    episodic = TrainConfig(env_id="activevision:ActiveVision-v0")
    assert episodic.env_id == "ActiveVision-v0"


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("match.action_type", "continuous", "TrainConfig.match.action_type: DDQN learns discrete"),
        ("match.observation", "image+head", "TrainConfig.match.observation: the DDQN learner"),
    ],
)
def test_a_ddqn_run_on_the_match_refuses_what_it_cannot_learn_from(key, value, message):
    # the trainer's "need a Discrete action space, got Box(-1.0, 1.0, (2,), float32)" named
    # no setting; the episodic env's section said what to do
    with pytest.raises(ValueError, match=rf"^{message}.* with algo='dagger'$"):
        apply_overrides(preset("match_ddqn"), [f"{key}={value}"])
    if key == "match.action_type":  # the match student learns continuous moves
        assert (
            apply_overrides(preset("match_dagger"), [f"{key}={value}"]).match.action_type == value
        )
    # the match run never reads its env section: a Dict there is no reason to refuse it
    ddqn = preset("match_ddqn").to_dict()
    ddqn["env"]["observation"] = "image+head"
    assert TrainConfig.from_dict(ddqn).env.observation == "image+head"


def test_num_threads_is_bounded():
    # 100,000 torch threads was a segmentation fault of the whole process, no error line
    with pytest.raises(ValueError, match=r"RunConfig\.num_threads: must be in \[0, 1024\]"):
        TrainConfig().replace(**{"run.num_threads": 100_000})
    assert TrainConfig().replace(**{"run.num_threads": 1024}).run.num_threads == 1024


@pytest.mark.parametrize(
    ("key", "message"),
    [
        ("env.camera.width", r"CameraConfig\.width must be at most 8192 px"),
        ("env.camera.height", r"CameraConfig\.height must be at most 8192 px"),
        ("match.camera.width", r"CameraConfig\.width must be at most 8192 px"),
        ("env.frame_stack", r"EnvConfig\.frame_stack: must be an integer in \[1, 64\]"),
        ("learner.batch_size", r"LearnerConfig\.batch_size: must be in \[1, 65536\]"),
        ("learner.n_step", r"LearnerConfig\.n_step: must be in \[1, 1000\]"),
        ("learner.augment_shift", r"LearnerConfig\.augment_shift: must be in \[0, 64\]"),
        ("replay.buffer_size", r"ReplayConfig\.buffer_size: must be in \[1, 100000000\]"),
        ("dagger.num_envs", r"DaggerConfig\.num_envs: must be in \[1, 4096\]"),
        ("dagger.dataset_size", r"DaggerConfig\.dataset_size: must be in \[1, 100000000\]"),
        ("sb3.num_envs", r"Sb3Config\.num_envs: must be in \[1, 4096\]"),
        ("sb3.n_steps", r"Sb3Config\.n_steps: must be in \[1, 100000\]"),
        ("sb3.critic_hidden", r"Sb3Config\.critic_hidden: must be in \[1, 8192\]"),
    ],
)
def test_sizes_are_bounded_naming_the_key_and_the_limit(key, message):
    """``--set env.camera.width=10**12`` (or a buffer, batch... of that size) ended in numpy's
    "Maximum allowed dimension exceeded", a MemoryError or torch's allocation traceback,
    naming no key; the config refuses it, naming the field and its limit."""
    bases = {"match": "match_ddqn", "dagger": "quickstart", "sb3": "ppo_head"}
    base = preset(bases.get(key.split(".")[0], "paper"))  # a run that reads the key
    with pytest.raises(ValueError, match=message + r".*got 1000000000000"):
        apply_overrides(base, [f"{key}={10**12}"])


def test_sizes_at_their_limits_are_taken():
    config = apply_overrides(
        TrainConfig(),
        [
            "env.camera.width=8192",
            "env.camera.height=6144",
            "env.frame_stack=64",
            "learner.batch_size=65536",
            "replay.buffer_size=100000000",
        ],
    )
    assert (config.env.camera.width, config.env.camera.height) == (8192, 6144)
    assert config.replay.buffer_size == 100_000_000 and config.learner.batch_size == 65_536
    dagger = apply_overrides(preset("quickstart"), ["dagger.num_envs=4096"])
    assert dagger.dagger.num_envs == 4096
    assert apply_overrides(preset("ppo_head"), ["sb3.critic_hidden=8192"]).sb3.critic_hidden == 8192


@pytest.mark.parametrize(
    ("base", "setting", "message"),
    [
        (
            "paper",
            "dagger.num_envs=8",
            r"'dagger\.num_envs' is never read by an algo='ddqn' run: only DAgger runs",
        ),
        (  # a unique leaf name: the key as given and its path
            "paper",
            "updates_per_rollout=2",
            r"'updates_per_rollout' \(dagger\.updates_per_rollout\) is never read by an"
            r" algo='ddqn' run",
        ),
        ("match_ddqn", "dagger.track_margin_deg=3", r"algo='ddqn' run: only DAgger"),
        ("sac_head", "dagger.switch_margin=1", r"algo='sac' run: only DAgger runs"),
        ("paper", "sb3.tau=0.01", r"'sb3\.tau' is never read by an algo='ddqn' run"),
        ("quickstart", "sb3.n_steps=32", r"algo='dagger' run: only Stable-Baselines3's"),
        ("quickstart", "learner.gamma=0.9", r"'learner\.gamma' is never read by an algo='dagger'"),
        ("quickstart", "learning_starts=10", r"\(learner\.learning_starts\) is never read by"),
        ("quickstart", "learner.dueling=true", r"algo='dagger' run: DAgger's student takes only"),
        ("quickstart", "exploration.final=0.1", r"'exploration\.final' is never read by"),
        ("quickstart", "replay.buffer_size=500", r"'replay\.buffer_size' is never read by"),
        ("quickstart", "per_alpha=0.5", r"'per_alpha' \(replay\.alpha\) is never read by"),
        # SB3's learners: what training.sb3_learners passes each, nothing else
        (
            "ppo_head",
            "replay.buffer_size=500",
            r"'replay\.buffer_size' is never read by an algo='ppo' run: PPO takes nothing of"
            r" replay\.\* \(it learns from its rollouts",
        ),
        ("ppo_head", "learning_starts=10", r"algo='ppo' run: PPO takes of learner\.\* only"),
        ("ppo_head", "gradient_steps=2", r"'gradient_steps' \(learner\.gradient_steps\)"),
        ("ppo_head", "sb3.tau=0.01", r"'sb3\.tau' is never read by an algo='ppo' run"),
        ("ppo_head", "sb3.action_noise=0.2", r"algo='ppo' run: PPO takes of sb3\.\* only"),
        ("sac_head", "max_grad_norm=1", r"algo='sac' run: SAC takes of learner\.\* only"),
        ("sac_head", "sb3.n_steps=32", r"'sb3\.n_steps' is never read by an algo='sac' run"),
        ("sac_head", "sb3.action_noise=0.2", r"algo='sac' run: SAC takes of sb3\.\* only"),
        ("td3_head", "sb3.clip_range=0.1", r"'sb3\.clip_range' is never read by an algo='td3'"),
        ("sac_head", "replay.alpha=0.5", r"SAC takes of replay\.\* only buffer_size"),
        ("td3_head", "per_beta0=0.5", r"'per_beta0' \(replay\.beta0\) is never read by"),
        ("sac_head", "n_step=3", r"'n_step' \(learner\.n_step\) is never read by an algo='sac'"),
        ("td3_head", "target_update_interval=5", r"algo='td3' run: TD3 takes of learner"),
        ("ppo_head", "learner.dueling=true", r"'learner\.dueling' is never read by"),
        ("sac_head", "augment_shift=4", r"\(learner\.augment_shift\) is never read by"),
        ("ppo_head", "aux_goal_weight=1", r"\(learner\.aux_goal_weight\) is never read by"),
        (
            "td3_head",
            "exploration.final=0.1",
            r"'exploration\.final' is never read by an algo='td3' run: TD3 takes nothing of"
            r" exploration\.\*",
        ),
        ("ppo_head", "exploration_fraction=0.5", r"\(exploration\.fraction\) is never read by"),
        # the match student's teacher on the episodes, the episodic student's keys on the match
        (
            "quickstart",
            "dagger.match_teacher=glance_track",
            r"'dagger\.match_teacher' is never read by an algo='dagger' run: only the match"
            r" student reads it",
        ),
        ("quickstart", "track_margin_deg=3", r"\(dagger\.track_margin_deg\) is never read by"),
        ("dagger_image", "dagger.glance_track_margin_deg=20", r"only the match student reads"),
        (
            "match_dagger",
            "dagger.switch_margin=1",
            r"'dagger\.switch_margin' is never read by an algo='dagger' run: this run trains the"
            r" match student",
        ),
        ("match_dagger", "goal_class_weight=0.5", r"\(dagger\.goal_class_weight\) is never"),
        ("match_dagger", "dagger.redraw_look=false", r"this run trains the match student"),
        ("match_dagger_glance", "redraw_prior=false", r"this run trains the match student"),
    ],
)
def test_a_key_the_runs_algo_never_reads_is_refused(base, setting, message):
    """``--set dagger.num_envs=8`` on a DDQN run (or a DDQN key on a DAgger run) was stored in
    config.json and silently ignored."""
    with pytest.raises(ValueError, match=message):
        apply_overrides(preset(base), [setting])


@pytest.mark.parametrize(
    ("base", "settings", "message"),
    [
        (
            "match_dagger",
            ["glance_track_margin_deg=20"],
            r"'glance_track_margin_deg' \(dagger\.glance_track_margin_deg\) is never read by"
            r" this run: only the glance_track teacher reads it .* teacher is entropy_track",
        ),
        (
            "match_dagger_glance",
            ["dagger.track_margin_deg=3"],
            r"only the entropy_track teacher reads it .* teacher is glance_track",
        ),
        # the other setting counts as the run ends up, whatever the order of the overrides
        (
            "match_dagger_glance",
            ["dagger.glance_track_margin_deg=20", "match_teacher=entropy_track"],
            r"only the glance_track teacher reads it",
        ),
        (
            "dagger_prior",
            ["dagger.switch_margin=1", "dagger.act_by=action"],
            r"'dagger\.switch_margin' is never read by this run: only a student acting by its"
            r" goal head reads it",
        ),
    ],
)
def test_a_key_another_setting_leaves_unread_is_refused(base, settings, message):
    """A match teacher's margin on a run with the other teacher, or the goal evidence's
    hysteresis on a student acting by its action head, was stored unread in config.json."""
    with pytest.raises(ValueError, match=message):
        apply_overrides(preset(base), settings)
    # the setting that reads it, in the same overrides, takes it
    key, _, value = settings[0].partition("=")
    readers = {
        "glance_track_margin_deg": "match_teacher=glance_track",
        "track_margin_deg": "match_teacher=entropy_track",
        "switch_margin": "dagger.act_by=goal",
    }
    config = apply_overrides(preset(base), [settings[0], readers[key.rpartition(".")[2]]])
    assert getattr(config.dagger, key.rpartition(".")[2]) == float(value)


def test_keys_the_runs_algo_reads_and_the_presets_own_are_taken():
    # the algo set in the same overrides counts, in whatever order
    config = apply_overrides(preset("paper"), ["dagger.num_envs=8", "algo=dagger"])
    assert (config.algo, config.dagger.num_envs) == ("dagger", 8)
    config = apply_overrides(preset("paper"), ["algo=ppo", "sb3.n_steps=32"])
    assert config.sb3.n_steps == 32
    # DAgger's student takes the optimiser's values; run.* is everyone's
    dagger = apply_overrides(
        preset("quickstart"),
        ["learning_rate=1e-3", "batch_size=16", "max_grad_norm=1", "run.eval_episodes=5"],
    )
    assert (dagger.learner.learning_rate, dagger.learner.batch_size) == (1e-3, 16)
    # a DAgger preset carries its dagger section on a DDQN run: not the user's, not refused
    switched = apply_overrides(preset("dagger_image"), ["algo=ddqn"])
    assert switched.algo == "ddqn" and switched.dagger == preset("dagger_image").dagger
    # each SB3 learner takes what training.sb3_learners passes it
    sac = apply_overrides(
        preset("sac_head"),
        ["learning_starts=10", "train_freq=2", "gradient_steps=2", "buffer_size=500", "tau=0.1"],
    )
    assert (sac.learner.gradient_steps, sac.replay.buffer_size, sac.sb3.tau) == (2, 500, 0.1)
    assert apply_overrides(preset("td3_head"), ["action_noise=0.3"]).sb3.action_noise == 0.3
    ppo = apply_overrides(preset("ppo_head"), ["max_grad_norm=1", "gamma=0.9", "ent_coef=0.01"])
    assert (ppo.learner.max_grad_norm, ppo.learner.gamma, ppo.sb3.ent_coef) == (1, 0.9, 0.01)
    # the match student takes its teacher's keys, and act_by / goal_frame (which it checks)
    match = apply_overrides(
        preset("match_dagger"),
        ["dagger.match_teacher=glance_track", "glance_track_margin_deg=20", "act_by=action"],
    )
    assert (match.dagger.match_teacher, match.dagger.glance_track_margin_deg) == (
        "glance_track",
        20,
    )
    assert apply_overrides(preset("match_dagger"), ["track_margin_deg=3"]).dagger.track_margin_deg
    # the env set in the same overrides counts: a switch to the match from an episodic config
    switched = apply_overrides(
        preset("paper"),
        [
            "dagger.track_margin_deg=3",
            "algo=dagger",
            "env_id=ActiveVisionMatch-v0",
            "dagger.act_by=action",
            "match.observation=image+head+belief",
        ],
    )
    assert switched.match_student and switched.dagger.track_margin_deg == 3
    # a preset's own values on another algo are not refused (sac_head's buffer on PPO)
    assert apply_overrides(preset("sac_head"), ["algo=ppo"]).replay.buffer_size == 50_000
    # a config file holds every section: loading it is not setting them
    assert TrainConfig.from_dict(preset("quickstart").to_dict()) == preset("quickstart")


def test_a_match_students_validation_fits_one_vector_env():
    """Its validation plays run.eval_episodes matches in one vector env (at most 65,536):
    more was refused at the first validation, mid-run."""
    with pytest.raises(ValueError, match=r"run\.eval_episodes: .*at most 65536, got 65537"):
        apply_overrides(preset("match_dagger"), ["eval_episodes=65537"])
    assert apply_overrides(preset("match_dagger"), ["eval_episodes=65536"])
    # on the episodes (their own batch, not the vector env), any count
    assert apply_overrides(preset("quickstart"), ["eval_episodes=65537"])
    # without validation the count is never read: refused as such
    with pytest.raises(ValueError, match=r"'eval_episodes' .* this run never validates"):
        apply_overrides(preset("match_dagger"), ["eval_episodes=65537", "eval_interval=0"])


def test_ddqn_minibatch_fits_the_replay_buffer():
    # a buffer smaller than the minibatch never held one: the run trained without an update
    with pytest.raises(ValueError, match=r"TrainConfig\.learner\.batch_size: .*at most"):
        TrainConfig().replace(**{"replay.buffer_size": 10})
    assert TrainConfig().replace(**{"replay.buffer_size": 32}).replay.buffer_size == 32


@pytest.mark.parametrize("env_id", ["activevision:", "  "])
def test_an_env_id_that_names_no_env_is_refused(env_id):
    """ "activevision:" passed the empty check before its prefix was dropped, leaving ""."""
    with pytest.raises(
        ValueError, match=rf"TrainConfig\.env_id: must not be empty, got {env_id!r}"
    ):
        TrainConfig(env_id=env_id)


@pytest.mark.parametrize("values", [None, 5, [["seed", 1]]])
def test_from_dict_of_a_non_object_names_it(values):
    """A config.json holding null or a list was a TypeError of the legacy-key check."""
    with pytest.raises(ValueError, match=r"expects an object of TrainConfig fields"):
        TrainConfig.from_dict(values)  # type: ignore[arg-type]


def test_values_another_setting_leaves_unread_are_refused_in_any_order():
    """A prior pose's settings on an observation without one, continuous moves' size with
    discrete actions and validation's episodes without validation were stored in
    config.json and never used."""
    with pytest.raises(ValueError, match=r"'env\.prior_error_range' is never read by this run"):
        apply_overrides(preset("paper"), ["env.prior_error_range=[0,1]"])
    with pytest.raises(ValueError, match="this run observes 'image\\+head'"):
        apply_overrides(preset("dagger_head"), ["prior_exact_share=0.5"])
    with pytest.raises(ValueError, match="this run does not set"):
        apply_overrides(
            preset("dagger_head"), ["observation=image+head+pose", "prior_exact_share=1"]
        )
    with pytest.raises(ValueError, match="only continuous moves are scaled by it"):
        apply_overrides(preset("dagger_image"), ["max_move_deg=[5,5]"])
    # and the discrete moves' step and set with continuous ones (sac_head's moves)
    for setting in ("env.step_deg=4", "action_set=4way"):
        key = setting.partition("=")[0]
        with pytest.raises(
            ValueError,
            match=rf"'{key}'( \(env\.action_set\))? is never read by this run: only discrete"
            r" moves read it .* continuous moves are scaled by env\.max_move_deg",
        ):
            apply_overrides(preset("sac_head"), [setting])
        with pytest.raises(ValueError, match="only discrete moves read it"):
            apply_overrides(preset("paper"), [setting, "algo=dagger", "action_type=continuous"])
    with pytest.raises(ValueError, match="this run never validates"):
        apply_overrides(preset("paper"), ["eval_seed=3"])
    with pytest.raises(ValueError, match=r"only env\.success_mode=tolerance ends an episode by"):
        apply_overrides(preset("paper"), ["success_tolerance_deg=5", "success_mode=landmarks"])
    assert apply_overrides(preset("paper"), ["success_tolerance_deg=5"])
    # the setting that makes them read, in the same overrides and in either order
    config = apply_overrides(
        preset("dagger_head"),
        [
            "prior_exact_share=0.5",
            "prior_grid=[0.5,10]",
            "env.prior_error_range=[0,2]",
            "env.observation=image+head+pose",
        ],
    )
    assert (config.env.prior_exact_share, config.env.prior_grid) == (0.5, (0.5, 10))
    config = apply_overrides(
        preset("dagger_image"), ["max_move_deg=[5,5]", "action_type=continuous"]
    )
    assert config.env.max_move_deg == (5, 5)
    config = apply_overrides(
        preset("dagger_image_continuous"), ["step_deg=4", "action_set=4way", "action_type=discrete"]
    )
    assert (config.env.step_deg, config.env.action_set) == (4, "4way")
    config = apply_overrides(preset("paper"), ["eval_episodes=7", "eval_interval=600"])
    assert (config.run.eval_episodes, config.run.eval_interval) == (7, 600)
    # what a preset carries is not refused: quickstart's prior range on the image and head
    head = apply_overrides(preset("quickstart"), ["env.observation=image+head"])
    assert head.env.prior_error_range == (0.0, 2.0)


def test_the_match_moves_another_setting_leaves_unread_are_refused():
    """``match.step_deg`` on a match run of continuous moves and ``match.max_move_deg`` on
    one of discrete moves were stored in config.json and never read (the match scales
    continuous moves by max_move_deg, and steps discrete ones by step_deg); the setting that
    makes them read, in either order, takes them, and a preset's values stay."""
    with pytest.raises(
        ValueError,
        match=r"^'match\.step_deg' is never read by this run: only discrete moves read it .*"
        r" continuous moves are scaled by match\.max_move_deg$",
    ):
        apply_overrides(preset("match_dagger_continuous"), ["match.step_deg=5"])
    with pytest.raises(ValueError, match=r"^'match\.step_deg' is never read by this run"):
        apply_overrides(
            preset("match_dagger"), ["match.step_deg=5", "match.action_type=continuous"]
        )
    for name in ("match_dagger", "match_ddqn"):
        with pytest.raises(
            ValueError,
            match=r"^'match\.max_move_deg' is never read by this run: only continuous moves are"
            r" scaled by it \(match\.action_type=continuous\); this run's discrete moves are"
            r" match\.step_deg$",
        ):
            apply_overrides(preset(name), ["match.max_move_deg=[5,5]"])
    with pytest.raises(ValueError, match=r"^'match\.max_move_deg' is never read by this run"):
        apply_overrides(
            preset("match_dagger_continuous"),
            ["match.max_move_deg=[5,5]", "match.action_type=discrete"],
        )
    # each read where the moves are of its kind, whichever comes first
    config = apply_overrides(
        preset("match_dagger"), ["match.max_move_deg=[5,5]", "match.action_type=continuous"]
    )
    assert (config.match.action_type, config.match.max_move_deg) == ("continuous", (5, 5))
    config = apply_overrides(
        preset("match_dagger_continuous"), ["match.action_type=discrete", "match.step_deg=5"]
    )
    assert (config.match.action_type, config.match.step_deg) == ("discrete", 5)
    assert apply_overrides(preset("match_ddqn"), ["match.step_deg=5"]).match.step_deg == 5
    # a preset's value of the other kind is no setting given (match_dagger's 3-degree moves)
    assert preset("match_dagger").match.max_move_deg == (3.0, 3.0)
    continuous = apply_overrides(preset("match_dagger"), ["match.action_type=continuous"])
    assert continuous.match.max_move_deg == (3.0, 3.0)


def test_a_shortened_preset_keeps_its_intervals_as_shares_of_its_run():
    """``--preset quickstart --steps 3000`` kept the 10,000-step validation interval and
    never validated; the preset's intervals scale with the run (hand-computed values)."""
    quick = preset("quickstart")  # 40,000 steps: validation every 10,000, checkpoints never
    assert scaled_intervals(quick, quick.replace(total_timesteps=3000)) == {
        "run.eval_interval": 750
    }
    assert scaled_intervals(quick, quick.replace(total_timesteps=400_000)) == {
        "run.eval_interval": 100_000
    }
    paper = preset("paper")  # 30,000 steps, checkpoints every 3,000 in 300-step epochs
    assert paper.run.eval_interval == 0
    assert scaled_intervals(paper, paper) == {}  # at its own steps: the same config
    assert scaled_intervals(paper, paper.replace(total_timesteps=15_000)) == {
        "run.checkpoint_interval": 1500
    }
    # 200 steps, rounded to a whole epoch; 450 -> 1.5 epochs, rounded up
    assert scaled_intervals(paper, paper.replace(total_timesteps=2000)) == {
        "run.checkpoint_interval": 300
    }
    assert scaled_intervals(paper, paper.replace(total_timesteps=4500)) == {
        "run.checkpoint_interval": 600
    }
    assert scaled_intervals(paper, paper.replace(total_timesteps=100)) == {
        "run.checkpoint_interval": 300
    }
    prior = preset("dagger_prior")  # 400,000: validation 100,000, checkpoints 50,000
    assert scaled_intervals(prior, prior.replace(total_timesteps=100_000)) == {
        "run.eval_interval": 25_000,
        "run.checkpoint_interval": 15_000,  # 12,500: 2.5 epochs of 5,000, rounded up
    }
    # what the user set is kept
    shorter = quick.replace(total_timesteps=3000, eval_interval=2000)
    assert scaled_intervals(quick, shorter, keep={"run.eval_interval"}) == {}


def test_config_path_names_the_field_a_key_sets():
    from activevision.training.config import config_path

    assert config_path("learning_rate") == "learner.learning_rate"  # a unique leaf name
    assert config_path(" seed ") == "seed"  # --set spaces
    assert config_path("env.camera.hfov") == "env.camera.hfov"  # a full path is itself
    assert config_path("nope") == "nope"  # no field: left to the config's own check


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (
            ["learning_rate=1e-3", "learning_rate=2e-3"],
            r"^override 'learning_rate' \(learner\.learning_rate\) is given twice"
            r" \(learning_rate=1e-3, then learning_rate=2e-3\): give it once$",
        ),
        (  # two spellings of one field: the short name and the full path
            ["learning_rate=1e-3", "learner.learning_rate=2e-3"],
            r"^overrides learning_rate=1e-3 and learner\.learning_rate=2e-3 both set"
            r" learner\.learning_rate: give it once$",
        ),
        (  # activevision 0.1's spelling and today's
            ["env_kwargs.step_deg=4", "env.step_deg=2"],
            r"both set env\.step_deg",
        ),
        (["seed=1", " seed=2"], r"override 'seed' is given twice"),
    ],
)
def test_a_field_set_twice_is_refused_naming_it(overrides, message):
    """``--set learning_rate=1e-3 --set learner.learning_rate=2e-3`` trained with the last,
    the first dropped silently."""
    with pytest.raises(ValueError, match=message):
        apply_overrides(preset("paper"), overrides)
    assert apply_overrides(preset("paper"), overrides[:1]) != preset("paper")


def test_a_field_given_twice_by_key_is_refused_naming_it():
    """``config.replace(**{"learning_rate": ..., "learner.learning_rate": ...})`` took the
    later one silently."""
    with pytest.raises(
        ValueError,
        match=r"^keys 'learning_rate' and 'learner\.learning_rate' both set"
        r" learner\.learning_rate: give it once$",
    ):
        TrainConfig().replace(**{"learning_rate": 1e-3, "learner.learning_rate": 2e-3})
    assert TrainConfig().replace(learning_rate=1e-3).learner.learning_rate == 1e-3
