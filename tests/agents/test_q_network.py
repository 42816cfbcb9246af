import pytest
import torch
from torch import nn

from activevision.agents.q_network import QNetwork, count_parameters, feature_shape


def test_paper_network_shapes_and_parameter_count():
    network = QNetwork(n_actions=9)
    assert feature_shape(120, 160) == (64, 6, 9)
    assert network.n_features == 3456
    assert network.fc.in_features == 3456 and network.fc.out_features == 512
    assert count_parameters(network) == 1_830_857  # ~1.83 M as in the paper's CNN
    q = network(torch.zeros(4, 1, 120, 160, dtype=torch.uint8))
    assert q.shape == (4, 9) and q.dtype == torch.float32


def test_pool_before_relu_and_channels_last_change_nothing():
    torch.manual_seed(0)
    network = QNetwork(n_actions=9, stack=2)
    # the straightforward order of the paper: conv, ReLU, pool, ...
    reference = nn.Sequential(
        network.conv1,
        nn.ReLU(),
        nn.MaxPool2d(2, 2),
        network.conv2,
        nn.ReLU(),
        network.conv3,
        nn.ReLU(),
        nn.Flatten(),
        network.fc,
        nn.ReLU(),
        network.q,
    )
    obs = torch.randint(0, 256, (3, 2, 120, 160), dtype=torch.uint8)
    expected = reference(obs.float() / 255.0)
    torch.testing.assert_close(network(obs), expected, rtol=1e-5, atol=1e-5)
    network.to_channels_last()
    fast = network(obs.contiguous(memory_format=torch.channels_last))
    torch.testing.assert_close(fast, expected, rtol=1e-4, atol=1e-5)


def test_dueling_head_is_mean_centred():
    network = QNetwork(n_actions=5, image_shape=(60, 80), dueling=True)
    obs = torch.randint(0, 256, (2, 1, 60, 80), dtype=torch.uint8)
    hidden = network.features(obs)
    q = network(obs)
    torch.testing.assert_close(q.mean(dim=1, keepdim=True), network.value(hidden))
    assert q.shape == (2, 5)


def test_auxiliary_head_shares_the_features_and_leaves_q_alone():
    torch.manual_seed(0)
    network = QNetwork(n_actions=5, image_shape=(60, 80), aux_outputs=2)
    obs = torch.randint(0, 256, (3, 1, 60, 80), dtype=torch.uint8)
    q, aux = network.forward_with_aux(obs)
    torch.testing.assert_close(q, network(obs))
    torch.testing.assert_close(aux, network.aux(network.features(obs)))
    assert aux.shape == (3, 2)
    with pytest.raises(ValueError, match="auxiliary head"):
        QNetwork(n_actions=5, image_shape=(60, 80)).forward_with_aux(obs)


@pytest.mark.parametrize("frames", [1, 4])
def test_channels_last_stores_every_convolution_as_module_to_does(frames):
    # Module.to(memory_format=channels_last) is the reference. A rewrite with .contiguous
    # left conv1's weight of one input channel (grey frames) in its NCHW strides, which
    # oneDNN ran 3x slower in training (and to other numbers), unseen from 2026-12-01.
    network = QNetwork(n_actions=9, stack=frames)
    reference = QNetwork(n_actions=9, stack=frames)
    network.to_channels_last()
    for conv, ref in zip(
        (network.conv1, network.conv2, network.conv3),
        (reference.conv1, reference.conv2, reference.conv3),
        strict=True,
    ):
        ref.to(memory_format=torch.channels_last)
        assert conv.weight.stride() == ref.weight.stride()
        assert conv.weight.is_contiguous(memory_format=torch.channels_last)
