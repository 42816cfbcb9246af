"""The DAgger student's trunk as SB3 features: what it reads of an observation space."""

import gymnasium as gym
import numpy as np
import pytest
import torch

import activevision.envs  # noqa: F401
from activevision.agents.sb3_features import StudentFeatures


def test_a_dict_observations_vectors_are_read_or_refused_never_dropped():
    # StudentFeatures(space) of an image + head angles Dict built a trunk with no vector
    # input, so an SB3 policy on it saw the image alone without a word; a key the space
    # lacked was a bare KeyError
    space = gym.make("ActiveVision-v0", observation="image+head+pose").observation_space
    with pytest.raises(ValueError, match=r"^vector_keys: the Dict observation holds the vectors"):
        StudentFeatures(space)
    with pytest.raises(ValueError, match=r"^vector_keys: the Dict observation has no \['ball'\]"):
        StudentFeatures(space, vector_keys=("head", "ball"))
    image = gym.make("ActiveVision-v0").observation_space
    with pytest.raises(ValueError, match=r"^vector_keys: the observation is the image alone"):
        StudentFeatures(image, vector_keys=("head",))
    torch.manual_seed(0)
    read = StudentFeatures(space, vector_keys=("head", "pose", "pose_error"))
    assert read.trunk.vector_size == 7
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
