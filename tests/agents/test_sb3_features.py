"""The DAgger student's trunk as SB3 features: what it reads of an observation space."""

import gymnasium as gym
import numpy as np
import pytest
import torch
from stable_baselines3 import PPO, SAC

import activevision.envs  # noqa: F401
from activevision.agents.sb3_features import StudentFeatures, actor_network
from activevision.envs.match.observations import vector_keys as match_vector_keys


def test_a_dict_observations_vectors_are_read_or_refused_never_dropped():
    # StudentFeatures(space) of an image + head angles Dict built a trunk with no vector
    # input, so an SB3 policy on it saw the image alone without a word; a key the space
    # lacked was a bare KeyError
    space = gym.make("ActiveVision-v0", observation="image+head+pose").observation_space
    with pytest.raises(ValueError, match=r"^vector_keys: the Dict observation holds the vectors"):
        StudentFeatures(space)
    with pytest.raises(ValueError, match=r"^vector_keys: the Dict observation has no \['ball'\]"):
        StudentFeatures(space, vector_keys=("head", "ball"))
    # every key of the space, the image too: its pixels went to the vector MLP; a key
    # named twice went in twice
    for named in (tuple(space.spaces), ("head", "pose", "head")):
        with pytest.raises(ValueError, match=r"^vector_keys: names each vector once, never"):
            StudentFeatures(space, vector_keys=named)
    image = gym.make("ActiveVision-v0").observation_space
    with pytest.raises(ValueError, match=r"^vector_keys: the observation is the image alone"):
        StudentFeatures(image, vector_keys=("head",))
    torch.manual_seed(0)
    read = StudentFeatures(space, vector_keys=("head", "pose", "pose_error"))
    assert read.trunk.vector_size == 7
    # the match's Dict: the message named envs.observations.vector_keys alone, whose
    # EnvConfig a MatchConfig is not (an AttributeError on action_history)
    match = gym.make("ActiveVisionMatch-v0", observation="image+head+belief")
    with pytest.raises(ValueError, match=r"the match's: envs\.match\.observations\.vector_keys"):
        StudentFeatures(match.observation_space)
    keys = match_vector_keys(match.unwrapped.config)
    assert StudentFeatures(match.observation_space, vector_keys=keys).trunk.vector_size == 12
    alone = StudentFeatures(space, vector_keys=())  # the image alone, asked for
    assert alone.trunk.vector_size == 0
    assert StudentFeatures(image).trunk.vector_size == 0
    obs = {k: torch.as_tensor(np.asarray(v)[None]) for k, v in space.sample().items()}
    obs["image"] = obs["image"].float() / 255
    assert read(obs).shape == (1, read.features_dim)


def test_a_float_image_is_refused_not_read_255_times_too_bright():
    # SB3 scales a uint8 image to [0, 1]; behind DtypeObservation(env, float32) the image
    # reached the trunk as 0-255, which it reads as scaled, without a word
    env = gym.wrappers.DtypeObservation(gym.make("ActiveVision-v0"), np.float32)
    with pytest.raises(ValueError, match=r"^need the env's uint8 image .* got dtype float32"):
        StudentFeatures(env.observation_space)
    space = gym.make("ActiveVision-v0", observation="image+head").observation_space
    floats = gym.spaces.Dict(
        {**space.spaces, "image": gym.spaces.Box(0, 255, (1, 120, 160), np.float32)}
    )
    with pytest.raises(ValueError, match=r"^need the env's uint8 image"):
        StudentFeatures(floats, vector_keys=("head",))


def _student_model(algo: type, env: gym.Env, policy_kwargs: dict | None = None, **kwargs):
    policy_kwargs = {
        "features_extractor_class": StudentFeatures,
        "net_arch": {"pi": [], "vf": []} if algo is PPO else {"pi": [], "qf": [8]},
        **(policy_kwargs or {}),
    }
    extra = {"n_steps": 8, "batch_size": 8} if algo is PPO else {"buffer_size": 10}
    return algo("CnnPolicy", env, policy_kwargs=policy_kwargs, seed=0, **extra, **kwargs)


def test_ppo_with_squashed_gsde_copies_as_its_tanh_not_a_clip():
    # PPO(use_sde=True, squash_output=True) acts tanh(mean); the copy clipped the mean, and
    # so acted otherwise wherever the mean left [-1, 1], without a word
    env = gym.make("ActiveVision-v0", action_type="continuous")
    for squash in (False, True):
        model = _student_model(PPO, env, use_sde=True, policy_kwargs={"squash_output": squash})
        with torch.no_grad():  # means well beyond [-1, 1], where tanh and clip part
            model.policy.action_net.weight.mul_(200)
        actor = actor_network(model, n_actions=2)
        assert actor.squash == ("tanh" if squash else "clip")
        for seed in range(3):
            obs, _ = env.reset(seed=seed)
            want, _ = model.predict(obs, deterministic=True)
            with torch.inference_mode():
                got = actor(torch.from_numpy(obs[None])).numpy()[0]
            np.testing.assert_allclose(got, want, atol=1e-5)
            assert np.abs(got).max() < 1 if squash else np.abs(got).max() == 1


def test_actors_that_are_no_student_network_are_refused_naming_why():
    env = gym.make("ActiveVision-v0", action_type="continuous")
    # gSDE's SAC clips its mean before the tanh: it said "not built with StudentFeatures"
    sde = _student_model(SAC, env, use_sde=True)
    with pytest.raises(ValueError, match=r"^SAC with use_sde=True clips its actor's mean"):
        actor_network(sde, n_actions=2)
    unclipped = _student_model(SAC, env, use_sde=True, policy_kwargs={"clip_mean": 0.0})
    obs, _ = env.reset(seed=0)
    with torch.inference_mode():
        got = actor_network(unclipped, n_actions=2)(torch.from_numpy(obs[None])).numpy()[0]
    np.testing.assert_allclose(got, unclipped.predict(obs, deterministic=True)[0], atol=1e-5)
    # a discrete model's action count: torch's size-mismatch RuntimeError before
    discrete = _student_model(PPO, gym.make("ActiveVision-v0", action_set="4way"))
    with pytest.raises(ValueError, match=r"^n_actions: the model acts in Discrete\(5\), got n_"):
        actor_network(discrete, n_actions=9)
    assert actor_network(discrete, n_actions=5).logits.out_features == 5


def test_an_image_too_small_after_its_average_names_the_camera_and_the_downsample():
    # an 80 x 60 camera at the default 2 x 2 average (and the paper's at sb3.downsample=4,
    # which the config takes) said "image 30x40 is too small", an image no one had
    space = gym.make("ActiveVision-v0", camera={"width": 80, "height": 60}).observation_space
    with pytest.raises(ValueError, match=r"^image 60x80 averaged 2 x 2 is 30x40, too small .*31"):
        StudentFeatures(space)
    assert StudentFeatures(space, downsample=1).trunk.image_shape == (60, 80)
    paper = gym.make("ActiveVision-v0").observation_space
    with pytest.raises(ValueError, match=r"^image 120x160 averaged 4 x 4 is 30x40, too small"):
        StudentFeatures(paper, downsample=4)
    assert StudentFeatures(paper, downsample=3).trunk.hidden(torch.zeros(1, 1, 120, 160)).shape


def test_normalize_images_false_reaches_the_trunk_as_the_default_does():
    """``policy_kwargs=dict(normalize_images=False)``: SB3 hands the uint8 image over
    unscaled and tells only its own extractors, so the trunk read 0-255 as if it were
    [0, 1], 255 times too bright, without a word. Passed to the extractor too, the image is
    scaled there: the very features of the default; passed to one of the two, the first
    batch is a ValueError naming the other."""
    env = gym.make("ActiveVision-v0", action_type="continuous")
    obs, _ = env.reset(seed=3)
    models = {
        "default": _student_model(PPO, env),
        "both": _student_model(
            PPO,
            env,
            {"normalize_images": False, "features_extractor_kwargs": {"normalize_images": False}},
        ),
        "policy only": _student_model(PPO, env, {"normalize_images": False}),
        "extractor only": _student_model(
            PPO, env, {"features_extractor_kwargs": {"normalize_images": False}}
        ),
    }
    weights = models["default"].policy.state_dict()
    features = {}
    for name, model in models.items():
        model.policy.load_state_dict(weights)
        policy = model.policy
        tensor = policy.obs_to_tensor(obs)[0]
        if name in ("policy only", "extractor only"):
            other = "features_extractor_kwargs" if name == "policy only" else "policy_kwargs"
            with pytest.raises(ValueError, match=rf"^StudentFeatures: .*pass {other}="):
                policy.extract_features(tensor, policy.features_extractor)
            with pytest.raises(ValueError, match=r"^StudentFeatures: "):  # and so learn()
                model.learn(8)
            continue
        with torch.no_grad():
            features[name] = policy.extract_features(tensor, policy.features_extractor)
    assert torch.equal(features["both"], features["default"])
    assert features["default"].abs().sum() > 0


def test_normalize_images_false_reads_a_float_image_already_in_0_1():
    env = gym.wrappers.TransformObservation(
        gym.make("ActiveVision-v0"),
        lambda o: (o / 255).astype(np.float32),
        gym.spaces.Box(0, 1, (1, 120, 160), np.float32),
    )
    read = StudentFeatures(env.observation_space, normalize_images=False)
    uint8 = StudentFeatures(gym.make("ActiveVision-v0").observation_space)
    read.load_state_dict(uint8.state_dict())
    image = torch.as_tensor(env.reset(seed=1)[0])[None]
    with torch.no_grad():
        assert torch.allclose(read(image), uint8(image), atol=1e-6)
    with pytest.raises(ValueError, match=r"^normalize_images: expects True or False"):
        StudentFeatures(env.observation_space, normalize_images="no")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^need the env's uint8 image"):
        StudentFeatures(env.observation_space)  # a float image with SB3's default: refused
