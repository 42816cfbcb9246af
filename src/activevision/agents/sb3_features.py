"""The DAgger student's trunk as a Stable-Baselines3 features extractor, and its actors
turned back into :class:`~activevision.agents.student.StudentNetwork` s.

Every SB3 learner here (SAC, TD3, PPO) sees the observation through
:class:`StudentFeatures`: the paper's CNN on a 2 x 2-averaged image, plus an MLP on the Dict
observation's vectors, fused to 256 features. Its actor has no hidden layer of its own
(``net_arch`` ``pi=[]``), so the actor is exactly a ``StudentNetwork``: trunk, then one
linear layer squashed to [-1, 1] (tanh for SAC and TD3; PPO's Gaussian mean, clipped as
SB3 clips it). :func:`actor_network` copies those weights into one, so an SB3 run writes
the same policy files, validates with the same batched episodes and exports to the same
torch-free ONNX runtime as a DAgger run.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn

from activevision.agents.student import StudentNetwork

IMAGE_KEY = "image"  #: the Dict observation's image (``envs.observations.IMAGE_KEY``)


class StudentFeatures(BaseFeaturesExtractor):
    """(B, 256) features of SB3's preprocessed observation: a uint8 image Box (scaled to
    [0, 1] by SB3), or a Dict of that image and float vectors, concatenated in
    ``vector_keys`` order (the order ``envs.observations`` lays them out). With a Dict
    holding vectors, ``vector_keys`` must name those read (``()``: the image alone); a key
    the space lacks, or one named for a bare image, is a ValueError.

    ``normalize_images`` must be the policy's (SB3 passes that flag to its own extractors
    only): with ``policy_kwargs=dict(normalize_images=False)`` SB3 hands the uint8 image
    over unscaled, so pass ``features_extractor_kwargs=dict(normalize_images=False)`` too;
    the extractor then scales it itself, and the trunk reads [0, 1] either way (as the
    exported policy does). With ``normalize_images=False`` the image may also be a float Box
    already in [0, 1] (a user's normalising wrapper), read as it is. The first batch tells
    whether the two flags disagree (an image over 1 where SB3 should have scaled it, one of
    fractions k/255 where it should not have): a ValueError naming both, not a trunk reading
    pixels 255 times too bright or too dark."""

    def __init__(
        self,
        observation_space: gym.Space[Any],
        vector_keys: tuple[str, ...] | None = None,
        downsample: int = 2,
        normalize_images: bool = True,
    ) -> None:
        if isinstance(observation_space, gym.spaces.Dict):
            keys = sorted(k for k in observation_space.spaces if k != IMAGE_KEY)
            if IMAGE_KEY not in observation_space.spaces:
                raise ValueError(f"need a Dict observation with an {IMAGE_KEY!r} key, got {keys}")
            # a Dict's vectors were dropped without a word when no vector_keys were given
            # (the policy saw the image alone), and a key the space lacks was a bare KeyError
            if vector_keys is None and keys:
                raise ValueError(
                    f"vector_keys: the Dict observation holds the vectors {keys}; name those the"
                    " features read, in the order they are concatenated"
                    " (envs.observations.vector_keys(config); the match's:"
                    " envs.match.observations.vector_keys(config)), or () for the image alone"
                )
            vector_keys = tuple(vector_keys or ())
            # every key of the space (the image too) fed the image's pixels to the vector MLP
            # as one more vector, and a key named twice went in twice, without a word
            if IMAGE_KEY in vector_keys or len(set(vector_keys)) != len(vector_keys):
                raise ValueError(
                    f"vector_keys: names each vector once, never the {IMAGE_KEY!r} the CNN"
                    f" reads; got {list(vector_keys)}, the Dict's vectors: {keys}"
                )
            missing = [k for k in vector_keys if k not in observation_space.spaces]
            if missing:
                raise ValueError(
                    f"vector_keys: the Dict observation has no {missing}; its vectors: {keys}"
                )
            image_space = observation_space[IMAGE_KEY]
            sizes = [math.prod(observation_space[k].shape or ()) for k in vector_keys]
        else:
            if vector_keys:
                named = list(vector_keys)
                raise ValueError(f"vector_keys: the observation is the image alone, no {named}")
            vector_keys = ()
            image_space, sizes = observation_space, []
        if image_space.shape is None or len(image_space.shape) != 3 or image_space.shape[0] != 1:
            raise ValueError(f"need a (1, H, W) image observation, got {image_space}")
        if not isinstance(normalize_images, bool):
            raise ValueError(f"normalize_images: expects True or False, got {normalize_images!r}")
        # SB3 scales only a uint8 image to [0, 1]: a float image (DtypeObservation, a
        # user's cast) reached the trunk as 0-255 and was read as if scaled, 255 times too
        # bright, without a word (and a policy trained so exports to a runtime that scales)
        uint8 = getattr(image_space, "dtype", None) == np.uint8
        if not uint8 and (normalize_images or not _unit_box(image_space)):
            raise ValueError(
                "need the env's uint8 image (SB3 scales it to [0, 1]; the trunk reads that),"
                " or with normalize_images=False a float image in [0, 1],"
                f" got dtype {getattr(image_space, 'dtype', None)}: {image_space}"
            )
        height, width = image_space.shape[1:]
        trunk = StudentNetwork(0, sum(sizes), (height, width), downsample)
        super().__init__(observation_space, features_dim=trunk.sizes[2])
        self.vector_keys = tuple(vector_keys)
        self.trunk = trunk
        self.normalize_images = normalize_images
        # a uint8 image SB3 leaves unscaled is divided here as SB3 divides it
        self._divide = uint8 and not normalize_images
        self._uint8 = uint8
        self._checked = False  # whether a batch has shown the flags agree

    def forward(self, observations: Any) -> torch.Tensor:
        if isinstance(observations, dict):
            image = observations[IMAGE_KEY]
            vector = (
                torch.cat([observations[k].flatten(1) for k in self.vector_keys], dim=1)
                if self.vector_keys
                else None
            )
        else:
            image, vector = observations, None
        if not self._checked and self._uint8:
            self._check_scale(image)
        if self._divide:
            image = image.float() / 255.0
        return self.trunk.hidden(image, vector)

    def _check_scale(self, image: torch.Tensor) -> None:
        """ValueError unless the first batch's uint8 image came as ``normalize_images``
        says: scaled by SB3 (nothing over 1) or as it was (whole numbers 0-255)."""
        if self.normalize_images and bool((image > 1.0).any()):
            raise ValueError(
                "StudentFeatures: the image came unscaled (values up to 255), as with"
                " policy_kwargs normalize_images=False: pass"
                " features_extractor_kwargs=dict(normalize_images=False) too"
            )
        if not self.normalize_images and bool((image != image.round()).any()):
            raise ValueError(
                "StudentFeatures: normalize_images=False, but the image came scaled to [0, 1]:"
                " pass policy_kwargs=dict(normalize_images=False) too"
            )
        self._checked = True


def _unit_box(space: gym.Space[Any]) -> bool:
    """Whether ``space`` is a float Box within [0, 1] (an image already normalised)."""
    return (
        isinstance(space, gym.spaces.Box)
        and np.issubdtype(space.dtype, np.floating)
        and bool(np.all(space.low >= 0) and np.all(space.high <= 1))
    )


def actor_network(model: Any, n_actions: int) -> StudentNetwork:
    """A CPU copy of an SB3 model's deterministic actor as a ``StudentNetwork``: SAC's
    ``tanh(mu)``, TD3's ``tanh(mu)``, PPO's clipped Gaussian mean (its tanh with gSDE's
    ``squash_output``; continuous) or action logits (discrete: ``n_actions`` must be the
    model's). A model whose actor is no trunk and one linear layer is a ValueError."""
    from stable_baselines3 import PPO, SAC, TD3

    if isinstance(model, SAC):
        features, head, squash = model.actor.features_extractor, model.actor.mu, "tanh"
        _check_empty(model.actor.latent_pi, "SAC")
    elif isinstance(model, TD3):
        features, head, squash = model.actor.features_extractor, model.actor.mu[0], "tanh"
        if len(model.actor.mu) != 2:
            raise ValueError("TD3's actor has hidden layers: build it with net_arch pi=[]")
    elif isinstance(model, PPO):
        policy = model.policy
        # PPO's mean is clipped to the action space, or with gSDE's squash_output=True
        # squashed by tanh (its distribution's mode): the copy took "clip" for both and
        # acted otherwise than the model whenever the mean left [-1, 1]
        squash = "tanh" if policy.squash_output else "clip"
        features, head = policy.pi_features_extractor, policy.action_net
        _check_empty(policy.mlp_extractor.policy_net, "PPO")
    else:
        raise TypeError(f"not a Stable-Baselines3 SAC, TD3 or PPO model: {type(model).__name__}")
    if isinstance(model, SAC) and model.use_sde and not isinstance(head, nn.Linear):
        # gSDE's SAC clips its mean (Hardtanh, clip_mean) before the tanh: no StudentNetwork
        raise ValueError(
            "SAC with use_sde=True clips its actor's mean (clip_mean) before the tanh, which a"
            " StudentNetwork cannot: build it without use_sde, or with clip_mean=0"
        )
    if not isinstance(features, StudentFeatures) or not isinstance(head, nn.Linear):
        raise ValueError("the model was not built with StudentFeatures and a linear actor")
    trunk = features.trunk
    continuous = isinstance(model.action_space, gym.spaces.Box)
    if not continuous and n_actions != model.action_space.n:
        # was torch's size-mismatch RuntimeError from load_state_dict
        raise ValueError(
            f"n_actions: the model acts in {model.action_space}, got n_actions={n_actions}"
        )
    network = StudentNetwork(
        2 if continuous else n_actions,
        trunk.vector_size,
        trunk.image_shape,
        trunk.downsample,
        continuous=continuous,
        squash=squash,
    )
    weights = {k: v.detach().cpu() for k, v in trunk.state_dict().items()}
    weights["logits.weight"] = head.weight.detach().cpu()
    weights["logits.bias"] = head.bias.detach().cpu()
    network.load_state_dict(weights)
    return network.eval()


def _check_empty(layers: nn.Module, name: str) -> None:
    if any(True for _ in layers.parameters()):
        raise ValueError(f"{name}'s actor has hidden layers: build it with net_arch pi=[]")


__all__ = ["StudentFeatures", "actor_network"]
