"""The paper's Q-network: a small CNN from one grayscale camera image to one Q-value per action.

Architecture (paper, Section "Training Process and Details", Fig. CNN), 'valid' padding as in
TensorFlow / Stable-Baselines v2, for a (stack, 120, 160) uint8 input:

| layer                          | output (C, H, W) | parameters |
|--------------------------------|------------------|-----------:|
| input / 255                    | (stack, 120, 160)|          0 |
| conv 32 @ 5x5, stride 2, ReLU  | (32, 58, 78)     |        832 |
| max-pool 2x2, stride 2         | (32, 29, 39)     |          0 |
| conv 64 @ 3x3, stride 2, ReLU  | (64, 14, 19)     |     18,496 |
| conv 64 @ 3x3, stride 2, ReLU  | (64, 6, 9)       |     36,928 |
| flatten                        | 3456             |          0 |
| fully connected 512, ReLU      | 512              |  1,769,984 |
| fully connected n_actions      | 9                |      4,617 |

1,830,857 parameters for stack=1 and 9 actions.

Two exact rewrites make it cheaper on a CPU without changing what it computes:

* max-pool is applied *before* the first ReLU: ``relu(maxpool(x)) == maxpool(relu(x))`` because
  ReLU is monotonic, and the ReLU then runs on a quarter of the values;
* the convolutions may run in channels-last memory format (``QNetwork.to_channels_last``),
  which oneDNN executes faster on x86 CPUs (see ``bench/train.py``).
"""

from __future__ import annotations

import torch
from torch import nn
from torch.nn import functional as F

#: Image height and width the paper feeds to the network (160 x 120 grayscale).
PAPER_IMAGE_SHAPE: tuple[int, int] = (120, 160)


def conv_output_size(size: int, kernel: int, stride: int) -> int:
    """Output length of a 'valid' (unpadded) convolution or pooling along one axis."""
    return (size - kernel) // stride + 1


def feature_shape(height: int, width: int) -> tuple[int, int, int]:
    """(C, H, W) of the convolutional features for an input image of ``height`` x ``width``."""
    h, w = height, width
    for kernel, stride in ((5, 2), (2, 2), (3, 2), (3, 2)):  # conv1, pool, conv2, conv3
        h, w = conv_output_size(h, kernel, stride), conv_output_size(w, kernel, stride)
    if h < 1 or w < 1:
        raise ValueError(f"image {height}x{width} is too small for the paper's CNN")
    return 64, h, w


class QNetwork(nn.Module):
    """Q(s, ·) for a batch of uint8 images of shape (B, stack, H, W).

    Args:
        n_actions: number of discrete actions (the paper's head controller has 9).
        stack: number of stacked frames, the input's channel dimension (1 in the paper).
        image_shape: (height, width) of each frame; the paper uses (120, 160).
        dueling: if True, split the head into a state value and action advantages
            (Wang et al. 2016), Q = V + A - mean(A). Off in the paper.
        aux_outputs: size of a second, linear head on the hidden units trained on an
            auxiliary task (:meth:`forward_with_aux`); 0 (the paper) adds none. It never
            changes the Q-values.
    """

    def __init__(
        self,
        n_actions: int,
        stack: int = 1,
        image_shape: tuple[int, int] = PAPER_IMAGE_SHAPE,
        dueling: bool = False,
        aux_outputs: int = 0,
    ) -> None:
        super().__init__()
        self.n_actions = int(n_actions)
        self.stack = int(stack)
        self.image_shape = (int(image_shape[0]), int(image_shape[1]))
        self.dueling = bool(dueling)

        self.conv1 = nn.Conv2d(self.stack, 32, kernel_size=5, stride=2)
        self.conv2 = nn.Conv2d(32, 64, kernel_size=3, stride=2)
        self.conv3 = nn.Conv2d(64, 64, kernel_size=3, stride=2)
        channels, height, width = feature_shape(*self.image_shape)
        self.n_features = channels * height * width
        self.fc = nn.Linear(self.n_features, 512)
        if self.dueling:
            self.value = nn.Linear(512, 1)
            self.advantage = nn.Linear(512, self.n_actions)
        else:
            self.q = nn.Linear(512, self.n_actions)
        self.aux_outputs = int(aux_outputs)
        self.aux = nn.Linear(512, self.aux_outputs) if self.aux_outputs else None

    def features(self, obs: torch.Tensor) -> torch.Tensor:
        """The 512 hidden units for a batch of uint8 (or already [0, 1]-scaled float) images."""
        x = obs.float() * (1.0 / 255.0) if obs.dtype == torch.uint8 else obs
        x = F.relu(F.max_pool2d(self.conv1(x), kernel_size=2, stride=2))  # pool, then ReLU
        x = F.relu(self.conv2(x))
        x = F.relu(self.conv3(x))
        # flatten in (C, H, W) order whatever the memory format, so weights are layout-free
        x = x.contiguous().flatten(1)
        return F.relu(self.fc(x))

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        """Q-values, shape (B, n_actions)."""
        return self._q_values(self.features(obs))

    def forward_with_aux(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Q-values and the auxiliary head's outputs (B, aux_outputs) from one pass."""
        if self.aux is None:
            raise ValueError("this QNetwork has no auxiliary head (aux_outputs=0)")
        hidden = self.features(obs)
        return self._q_values(hidden), self.aux(hidden)

    def _q_values(self, hidden: torch.Tensor) -> torch.Tensor:
        # nn.Module calls are typed as returning Any: the results are tensors
        if not self.dueling:
            q: torch.Tensor = self.q(hidden)
            return q
        advantage: torch.Tensor = self.advantage(hidden)
        value: torch.Tensor = self.value(hidden)
        return value + advantage - advantage.mean(dim=1, keepdim=True)

    def to_channels_last(self) -> QNetwork:
        """Store the convolution weights channels-last (NHWC), which oneDNN runs faster."""
        for conv in (self.conv1, self.conv2, self.conv3):
            # what Module.to(memory_format=...) does: only the 4-D weight changes layout.
            # .to, not .contiguous: a weight of one input channel (conv1, grey frames) counts
            # as channels-last already for .contiguous and kept its NCHW strides, which sent
            # training to a path 3x slower (and other numbers) from 2026-12-01 to 12-04
            conv.weight.data = conv.weight.data.to(memory_format=torch.channels_last)
        return self


def count_parameters(module: nn.Module) -> int:
    """Number of trainable parameters."""
    return sum(p.numel() for p in module.parameters() if p.requires_grad)
