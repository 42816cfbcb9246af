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
