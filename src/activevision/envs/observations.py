"""What the agent observes: the paper's camera image, or a Gymnasium ``Dict`` that adds what
a robot knows of itself (``EnvConfig.observation``).

| key        | shape            | contents                                                   |
|------------|------------------|------------------------------------------------------------|
| "image"    | (1, H, W) uint8  | the camera image (the paper's whole observation)           |
| "head"     | (2,) float32     | head joint angles (pan, tilt), rad: the robot's encoders   |
| "pose"     | (4,) float32     | the prior pose (x m, y m, cos theta, sin theta)            |
| "pose_error" | (1,) float32   | the prior's error scale e (m and rad): what a consistent   |
|            |                  | filter reports as its uncertainty; comes with "pose"       |
| "proposal" | (5,) float32     | Algorithm 1's view from the prior: (pan, tilt) rad, the    |
|            |                  | move there from the head (d_pan, d_tilt) rad, found (0/1)  |
| "actions"  | (h * A,) float32 | the last ``action_history`` actions one-hot, oldest first  |

"image+head" has image and head; "image+head+pose" adds pose; "image+head+pose+proposal"
adds proposal. ``action_history > 0`` adds actions to any of them. The prior pose is the
believed pose (the true pose corrupted as ``localisation_error`` does), or with
``prior_error_range`` one corrupted by an error drawn per episode, and is quantised to
``prior_grid``. Every entry is clipped to +-10, the spaces' bound (only a prior error over
10 m reaches it). Every vector is what a robot computes itself, so a policy trained on them
runs on a robot (:class:`activevision.runtime.HeadController` takes the same inputs).

SB3's ``MultiInputPolicy`` takes these Dict spaces; the package's networks concatenate the
vector keys in :func:`vector_keys` order (:func:`flatten_vectors`).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from gymnasium import spaces

from activevision.envs.config import EnvConfig
from activevision.envs.simulation import EpisodeBatch
from activevision.runtime.metadata import VECTOR_BOUND, VECTOR_KEY_SIZES, observation_vector_keys

IMAGE_KEY = "image"
#: Size of each vector key (``"actions"`` is per remembered action): the runtime's table,
#: so that HeadController builds exactly this layout on the robot.
VECTOR_SIZES = VECTOR_KEY_SIZES
#: Bound of every vector entry (angles in rad, positions in m, one-hots, cos/sin): entries
#: beyond it (a prior pose or error scale over 10 m) are clipped to it, as on the robot.
_VECTOR_BOUND = VECTOR_BOUND

Observation = np.ndarray | dict[str, np.ndarray]


def vector_keys(cfg: EnvConfig) -> tuple[str, ...]:
    """The Dict observation's vector keys, in the order networks concatenate them."""
    return observation_vector_keys(cfg.observation, cfg.action_history)


def observes_within(cfg: EnvConfig, given: EnvConfig) -> bool:
    """Whether a policy trained on ``cfg`` can play in an env of ``given``: both give the
    bare image, or both a Dict whose vector keys include all of ``cfg``'s."""
    if (cfg.observation == "image") != (given.observation == "image"):
        return False
    return set(vector_keys(cfg)) <= set(vector_keys(given))


def play_differences(
    trained: EnvConfig, given: EnvConfig, moves_by_target: bool = False
) -> list[str]:
    """What a policy trained on ``trained`` would meet in an env of ``given`` that its
    network does not take, or that would change what its moves or its images mean; empty
    where it can play there. Each entry names the setting and both values (``given``'s
    second). ``moves_by_target``: the policy moves by head targets (a continuous one),
    which any env takes; a discrete one's actions index its own moves."""
    differences = []
    if not observes_within(trained, given):
        if trained.observation == "image":
            why = "a network of the bare image takes no Dict"
        elif given.observation == "image":
            why = "the env gives the bare image, no vectors"
        else:
            missing = [
                f"actions (action_history {trained.action_history}: the moves it remembers)"
                if key == "actions"
                else key
                for key in vector_keys(trained)
                if key not in vector_keys(given)
            ]
            why = f"no {', '.join(missing)}"
        differences.append(
            f"observation {trained.observation!r} ({', '.join(vector_keys(trained)) or 'image'})"
            f" against {given.observation!r}: {why}"
        )
    camera, env_camera = trained.camera, given.camera
    if (camera.width, camera.height) != (env_camera.width, env_camera.height):
        differences.append(
            f"images of {camera.width}x{camera.height} px against {env_camera.width}x"
            f"{env_camera.height}"
        )
    elif camera != env_camera:  # the same size, another view of the field
        differences.append(
            f"a camera of {camera.differences(env_camera)} against {env_camera.differences(camera)}"
        )
    if trained.frame_stack != given.frame_stack:
        differences.append(f"frame_stack {trained.frame_stack} against {given.frame_stack}")
    remembered = "actions" in vector_keys(trained) and "actions" in vector_keys(given)
    if remembered and trained.action_history != given.action_history:
        differences.append(
            f"action_history {trained.action_history} against {given.action_history}"
            " (the moves it remembers)"
        )
    moves, env_moves = (trained.step_deg, trained.action_set), (given.step_deg, given.action_set)
    if not moves_by_target and moves != env_moves:
        differences.append(
            f"moves of {trained.step_deg:g} deg, {trained.action_set}, against"
            f" {given.step_deg:g} deg, {given.action_set}"
        )
    return differences


def vector_sizes(cfg: EnvConfig, n_actions: int) -> dict[str, int]:
    """Length of each vector key."""
    return {
        k: cfg.action_history * n_actions if k == "actions" else VECTOR_SIZES[k]
        for k in vector_keys(cfg)
    }


def vector_columns(cfg: EnvConfig, n_actions: int) -> dict[str, slice]:
    """Where each vector key lies in the concatenated vector (:func:`flatten_vectors`)."""
    columns, start = {}, 0
    for key, size in vector_sizes(cfg, n_actions).items():
        columns[key] = slice(start, start + size)
        start += size
    return columns


def pose_features(prior_pose: np.ndarray) -> np.ndarray:
    """(N, 4) the ``"pose"`` key of prior poses (N, 3): x, y, cos theta, sin theta."""
    theta = prior_pose[:, 2]
    return np.stack([prior_pose[:, 0], prior_pose[:, 1], np.cos(theta), np.sin(theta)], 1)


def proposal_features(proposal: np.ndarray, head: np.ndarray) -> np.ndarray:
    """(N, 5) the ``"proposal"`` key of proposals (N, 3: pan, tilt, found) seen from heads
    (N, 2): the view, the move there (zero where none was found), found."""
    found = proposal[:, 2:3]
    return np.concatenate([proposal[:, :2], (proposal[:, :2] - head) * found, found], axis=1)


def image_space(cfg: EnvConfig) -> spaces.Box:
    shape = (cfg.frame_stack, cfg.camera.height, cfg.camera.width)
    return spaces.Box(0, 255, shape, dtype=np.uint8)


def observation_space(cfg: EnvConfig, n_actions: int) -> spaces.Box | spaces.Dict:
    """The paper's image Box, or the Dict of :data:`IMAGE_KEY` and the vector keys."""
    image = image_space(cfg)
    if cfg.observation == "image":
        return image
    vectors = {
        key: spaces.Box(-_VECTOR_BOUND, _VECTOR_BOUND, (size,), dtype=np.float32)
        for key, size in vector_sizes(cfg, n_actions).items()
    }
    return spaces.Dict({IMAGE_KEY: image, **vectors})


def flatten_vectors(obs: Mapping[str, np.ndarray], keys: tuple[str, ...]) -> np.ndarray:
    """The vector keys of one or a batch of Dict observations, concatenated (float32)."""
    if not keys:
        first = np.asarray(obs[IMAGE_KEY])
        return np.zeros((*first.shape[:-3], 0), dtype=np.float32)
    return np.concatenate([np.asarray(obs[k], dtype=np.float32) for k in keys], axis=-1)


class ObservationBuilder:
    """Assembles the observations of N episode slots (the env's frames plus the slots' head,
    prior, proposal and action history)."""

    def __init__(self, cfg: EnvConfig, num_envs: int, n_actions: int) -> None:
        self.cfg = cfg
        self.keys = vector_keys(cfg)
        self.n_actions = n_actions
        self.history = np.full((num_envs, cfg.action_history), -1, dtype=np.int64)

    def start(self, slots: np.ndarray) -> None:
        """Slots ``slots`` begin new episodes: no actions remembered."""
        self.history[slots] = -1

    def record(self, actions: np.ndarray, slots: np.ndarray) -> None:
        """Slots ``slots`` took ``actions`` (one each)."""
        if self.cfg.action_history:
            self.history[slots, :-1] = self.history[slots, 1:]
            self.history[slots, -1] = actions

    def vectors(self, sim: EpisodeBatch) -> np.ndarray:
        """(N, V) float32: the vector keys of all slots, concatenated (V may be 0)."""
        parts = [self._vector(k, sim) for k in self.keys]
        if not parts:
            return np.zeros((sim.n, 0), dtype=np.float32)
        return np.concatenate(parts, axis=1)

    def batch(self, frames: np.ndarray, sim: EpisodeBatch) -> Observation:
        """Observations of all slots: ``frames`` (N, stack, H, W) and the slots' state."""
        if not self.keys:
            return frames.copy()
        obs: dict[str, np.ndarray] = {IMAGE_KEY: frames.copy()}
        for key in self.keys:
            obs[key] = self._vector(key, sim)
        return in_space_order(obs)

    def _vector(self, key: str, sim: EpisodeBatch) -> np.ndarray:
        values: np.ndarray
        if key == "head":
            values = sim.head
        elif key == "pose_error":
            values = sim.prior_error[:, None]
        elif key == "pose":
            values = pose_features(sim.prior_pose)
        elif key == "proposal":
            values = proposal_features(sim.proposal, sim.head)
        else:
            n = len(self.history)
            onehot = np.zeros((n, self.cfg.action_history, self.n_actions), dtype=np.float32)
            rows, cols = np.nonzero(self.history >= 0)
            onehot[rows, cols, self.history[rows, cols]] = 1.0
            values = onehot.reshape(n, -1)
        # inside the observation space: a prior error over 10 m (localisation_error or
        # prior_error_range) gave a pose_error and a prior pose beyond the Box's bound
        return np.clip(values, -_VECTOR_BOUND, _VECTOR_BOUND).astype(np.float32)


def in_space_order(obs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """``obs`` with its keys in the order of its ``spaces.Dict`` (sorted: Gymnasium sorts a
    Dict's keys), the order ``SyncVectorEnv`` and ``AsyncVectorEnv`` batch them in, so that
    code iterating ``obs.values()`` (a hash, a concatenation) sees every vectorizer's
    observation, and the space's own order, alike."""
    return {key: obs[key] for key in sorted(obs)}


def single(obs: Observation, i: int = 0) -> Observation:
    """Slot ``i`` of a batched observation."""
    if isinstance(obs, dict):
        return {k: v[i] for k, v in obs.items()}
    one: np.ndarray = obs[i]
    return one
