"""The student network of DAgger: the camera image through a CNN, the robot's own vector
(head angles, prior pose, proposal, previous actions; ``envs.observations``) through an
MLP, fused, to one logit per action (or, for continuous head control, the move: 2 outputs
through tanh, a fraction of the largest move on each axis) and optionally 40 goal-view
logits.

The CNN is the paper's (``q_network``) on a ``downsample`` x ``downsample``-averaged image:
the 2 x 2 average keeps every landmark edge (lines are 5 cm, 2-7 px at 120 x 160) and
makes an update 4x cheaper, which on a CPU decides how many samples a run can learn from.

| layer (downsample 2, 120 x 160 input) | output          |
|---------------------------------------|-----------------|
| input / 255, 2 x 2 average            | (1, 60, 80)     |
| conv 32 @ 5x5 s2, max-pool 2, ReLU    | (32, 14, 19)    |
| conv 64 @ 3x3 s2, ReLU                | (64, 6, 9)      |
| conv 64 @ 3x3 s2, ReLU                | (64, 2, 4)      |
| fc image_hidden, ReLU                 | 256             |
| vector: fc 128, ReLU, fc 128, ReLU    | 128             |
| concat, fc fused_hidden, ReLU         | 256             |
| fc n_actions (and fc n_goals)         | 9 or 2 (40)     |
"""

from __future__ import annotations

import torch
from torch import nn
from torch.nn import functional as F

from activevision.agents.q_network import PAPER_IMAGE_SHAPE, feature_shape

#: the smallest image side the paper's CNN takes (conv 5 s2, pool 2, conv 3 s2, conv 3 s2)
MIN_CNN_SIDE = 31


class StudentNetwork(nn.Module):
    """Action logits (or continuous moves) for a batch of uint8 images (B, 1, H, W) and
    float vectors (B, V).

    Args:
        n_actions: discrete actions (9); with ``continuous``, the move's axes (2); 0: the
            trunk alone (:meth:`hidden`, e.g. as a Stable-Baselines3 features extractor).
        vector_size: length of the vector input (0: image only, the paper's input).
        image_shape: (H, W) of the camera image.
        downsample: average-pool factor applied to the image first (1: none).
        n_goals: size of the goal-view classification head (0: none).
        continuous: the outputs are a move in [-1, 1] per axis, squashed by ``squash``:
            ``"tanh"`` (DAgger, SAC, TD3) or ``"clip"`` (PPO's Gaussian mean, clipped to
            the action space as Stable-Baselines3 does).
    """

    def __init__(
        self,
        n_actions: int,
        vector_size: int = 0,
        image_shape: tuple[int, int] = PAPER_IMAGE_SHAPE,
        downsample: int = 2,
        n_goals: int = 0,
        image_hidden: int = 256,
        vector_hidden: int = 128,
        fused_hidden: int = 256,
        continuous: bool = False,
        squash: str = "tanh",
    ) -> None:
        super().__init__()
        self.n_actions = int(n_actions)
        #: outputs are a head move in [-1, 1] per axis (tanh), not logits
        self.continuous = bool(continuous)
        if squash not in ("tanh", "clip"):
            raise ValueError(f"squash must be 'tanh' or 'clip', got {squash!r}")
        self.squash = squash
        self.vector_size = int(vector_size)
        self.image_shape = (int(image_shape[0]), int(image_shape[1]))
        self.downsample = int(downsample)
        self.n_goals = int(n_goals)
        self.sizes = (int(image_hidden), int(vector_hidden), int(fused_hidden))
        h, w = (s // self.downsample for s in self.image_shape)
        self.conv1 = nn.Conv2d(1, 32, kernel_size=5, stride=2)
        self.conv2 = nn.Conv2d(32, 64, kernel_size=3, stride=2)
        self.conv3 = nn.Conv2d(64, 64, kernel_size=3, stride=2)
        if self.downsample > 1 and (h < MIN_CNN_SIDE or w < MIN_CNN_SIDE):
            # "image 30x40 is too small" named neither the camera's 60x80 nor the average
            raise ValueError(
                f"image {self.image_shape[0]}x{self.image_shape[1]} averaged {self.downsample}"
                f" x {self.downsample} is {h}x{w}, too small for the paper's CNN (at least"
                f" {MIN_CNN_SIDE} px a side): use a smaller downsample"
            )
        channels, fh, fw = feature_shape(h, w)
        self.image_fc = nn.Linear(channels * fh * fw, self.sizes[0])
        fused_in = self.sizes[0]
        if self.vector_size:
            self.vector_fc1 = nn.Linear(self.vector_size, self.sizes[1])
            self.vector_fc2 = nn.Linear(self.sizes[1], self.sizes[1])
            fused_in += self.sizes[1]
        self.fused = nn.Linear(fused_in, self.sizes[2])
        self.logits = nn.Linear(self.sizes[2], self.n_actions) if self.n_actions else None
        self.goal_logits = nn.Linear(self.sizes[2], self.n_goals) if self.n_goals else None

    def hidden(self, image: torch.Tensor, vector: torch.Tensor | None = None) -> torch.Tensor:
        x = image.float() * (1.0 / 255.0) if image.dtype == torch.uint8 else image
        if self.downsample > 1:
            x = F.avg_pool2d(x, self.downsample)
        x = F.relu(F.max_pool2d(self.conv1(x), kernel_size=2, stride=2))
        x = F.relu(self.conv2(x))
        x = F.relu(self.conv3(x))
        parts = [F.relu(self.image_fc(x.flatten(1)))]
        if self.vector_size:
            if vector is None:
                raise ValueError(f"this network needs a vector input of {self.vector_size}")
            v = F.relu(self.vector_fc1(vector.float()))
            parts.append(F.relu(self.vector_fc2(v)))
        return F.relu(self.fused(torch.cat(parts, dim=1)))

    def forward(self, image: torch.Tensor, vector: torch.Tensor | None = None) -> torch.Tensor:
        """Action logits (B, n_actions), the greedy action their argmax; or with
        ``continuous`` the move (B, 2) in [-1, 1]."""
        return self.forward_with_goal(image, vector)[0]

    def forward_with_goal(
        self, image: torch.Tensor, vector: torch.Tensor | None = None
    ) -> tuple[torch.Tensor, torch.Tensor | None]:
        """Action logits (or moves) and goal-view logits (None without a goal head), one
        pass."""
        if self.logits is None:
            raise ValueError("this network is a trunk (n_actions=0): it has no action output")
        hidden = self.hidden(image, vector)
        goal = self.goal_logits(hidden) if self.goal_logits is not None else None
        out: torch.Tensor = self.logits(hidden)
        if self.continuous:
            out = torch.tanh(out) if self.squash == "tanh" else torch.clamp(out, -1.0, 1.0)
        return out, goal

    def metadata(self) -> dict[str, object]:
        """What :meth:`from_metadata` needs to rebuild this network."""
        return {
            "network": "student",
            "n_actions": self.n_actions,
            "vector_size": self.vector_size,
            "image_shape": list(self.image_shape),
            "downsample": self.downsample,
            "n_goals": self.n_goals,
            "hidden_sizes": list(self.sizes),
            "action_type": "continuous" if self.continuous else "discrete",
            "squash": self.squash,
        }

    @classmethod
    def from_metadata(cls, meta: dict) -> StudentNetwork:
        image_hidden, vector_hidden, fused_hidden = meta["hidden_sizes"]
        return cls(
            meta["n_actions"],
            meta["vector_size"],
            tuple(meta["image_shape"]),
            meta["downsample"],
            meta["n_goals"],
            image_hidden,
            vector_hidden,
            fused_hidden,
            continuous=meta.get("action_type", "discrete") == "continuous",
            squash=meta.get("squash", "tanh"),
        )
