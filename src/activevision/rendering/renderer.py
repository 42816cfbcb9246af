"""The fast batched renderer of the robot's head camera (see :mod:`.kernels` for the
method)."""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import ArrayLike

from activevision.geometry.camera import CameraConfig
from activevision.geometry.field import FieldSpec
from activevision.rendering.appearance import LOOK_FIELDS, identity_tone, neutral_looks
from activevision.rendering.config import RenderConfig
from activevision.rendering.kernels import looks as looks_kernels
from activevision.rendering.kernels import raster
from activevision.rendering.kernels.bundles import Cameras, scene_bundles
from activevision.rendering.scene import build_scene
from activevision.threads import numba_threads

_DEFAULT_FIELD = FieldSpec()
_DEFAULT_CAMERA = CameraConfig()
_DEFAULT_CONFIG = RenderConfig()

#: Batches smaller than this render on the calling thread: a frame takes tens of
#: microseconds, comparable to waking the worker threads (far more when the cores are busy).
PARALLEL_MIN_BATCH = 4

#: Test hook: a non-zero seed makes the kernels fill their (uninitialised) work memory with
#: garbage before rendering. Images must not change: every value a kernel reads is written
#: for the camera first. Tests set it with ``monkeypatch``; never set in production code.
_WORK_GARBAGE_SEED = 0


def _float_array(name: str, value: ArrayLike, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` as a C-contiguous float64 array of exactly ``shape``, or a ValueError."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a numeric array of shape {shape}") from None
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} must be finite")
    return np.ascontiguousarray(arr)


def _per_camera(name: str, value: ArrayLike, n: int) -> np.ndarray:
    """A per-camera scalar: accepts shape (n,), or a scalar / shape (1,) when n == 1."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a numeric array of shape ({n},)") from None
    if n == 1 and arr.ndim == 0:
        arr = np.reshape(arr, (1,))
    return _float_array(name, arr, (n,))


class Renderer:
    """Renders what the robot's head camera sees, for many cameras per call.

    The image (``camera.height`` x ``camera.width``, uint8 grey) shows the carpet, every
    painted line at its true width, the centre circle, the penalty marks and a short centre
    mark, both goals (posts and crossbars) and the ball, anti-aliased by exact box-filter
    coverage of each pixel (see :mod:`activevision.rendering.kernels`). Greys and optional
    noise come from :class:`RenderConfig`; per-camera randomised looks (``looks``, ``tone``:
    :mod:`.appearance`) and other robots (``cylinders``) are options of :meth:`render`.

    Batches of ``PARALLEL_MIN_BATCH`` or more frames are split over the numba threads
    (``numba.set_num_threads``); smaller ones, or all with ``parallel=False``, render on the
    calling thread. Both give identical images, and a frame does not depend on the other
    frames of its batch or on earlier calls: the kernels allocate their work memory per call
    and write every value they read. A Renderer holds no mutable state.

    Example::

        r = Renderer()
        imgs = r.render(pose, pan, tilt, ball_xy)  # (N, 3), (N,), (N,), (N, 2) -> (N, H, W)
    """

    def __init__(
        self,
        field: FieldSpec = _DEFAULT_FIELD,
        camera: CameraConfig = _DEFAULT_CAMERA,
        config: RenderConfig = _DEFAULT_CONFIG,
        *,
        parallel: bool = True,
    ) -> None:
        self.field = field
        self.camera = camera
        self.config = config
        #: Whether batches of PARALLEL_MIN_BATCH or more frames use all numba threads. Turn
        #: off when the cores are busy with other work (e.g. a trainer's own threads): a
        #: parallel call waits for every thread to be scheduled, which on an oversubscribed
        #: machine can cost milliseconds, while the calling thread alone renders a frame in
        #: tens of microseconds.
        self.parallel = bool(parallel)
        self.scene = build_scene(field)
        # What the kernels see of the scene, the camera and the greys (kernels.bundles), and
        # the plain tuples of their fields the entry points are handed (numba types those in
        # C, namedtuples in Python).
        self._kernel_scene, self._kernel_params = scene_bundles(self.scene, camera, config)
        self._kernel_fields = (tuple(self._kernel_scene), tuple(self._kernel_params))
        self._noise = noise_table(camera.width * camera.height)

    @property
    def image_shape(self) -> tuple[int, int]:
        """``(height, width)`` of one image."""
        return (self.camera.height, self.camera.width)

    def render(
        self,
        pose: ArrayLike,
        pan: ArrayLike,
        tilt: ArrayLike,
        ball_xy: ArrayLike | None,
        out: np.ndarray | None = None,
        rng: np.random.Generator | None = None,
        *,
        looks: ArrayLike | None = None,
        tone: ArrayLike | None = None,
        cylinders: ArrayLike | None = None,
    ) -> np.ndarray:
        """Render N cameras.

        Args:
            pose: (N, 3) robot poses ``(x, y, theta)``, or one pose (3,) for N = 1.
            pan, tilt: (N,) head angles (rad; scalars allowed for N = 1).
            ball_xy: (N, 2) ball positions on the ground (or (2,) for N = 1); ``None``: no
                ball in any image.
            out: optional preallocated C-contiguous (N, H, W) uint8 array to render into.
            rng: numpy Generator for the noise/jitter of ``config``; required when they are
                on, unused otherwise.
            looks: (N, len(LOOK_FIELDS)) randomised appearance of each camera
                (:mod:`.appearance`: ``draw_looks`` per episode, the per-frame columns set by
                the caller); None: the clean render.
            tone: (N, 256) uint8 tone curves (``appearance.tone_curves``), with ``looks``;
                None: none.
            cylinders: (N, C, 6) vertical cylinders (other robots' bodies) per camera: x, y,
                radius, bottom z, top z (m), grey; radius 0 marks an unused slot.

        Returns:
            (N, H, W) uint8 images (``out`` when given).
        """
        pose_arr = _poses(pose)
        n = pose_arr.shape[0]
        pan_arr = _per_camera("pan", pan, n)
        tilt_arr = _per_camera("tilt", tilt, n)
        ball_arr, has_ball = _balls(ball_xy, n)
        out = _output(out, (n, *self.image_shape))
        if self.config.has_noise and not isinstance(rng, np.random.Generator):
            raise ValueError("rng must be a numpy.random.Generator when noise/jitter is on")

        scene, params = self._kernel_fields
        cameras = tuple(Cameras(pose_arr, pan_arr, tilt_arr, ball_arr, has_ball))
        looks_fields = self._looks(n, looks, tone, cylinders)
        # small batches run serially and never start numba's thread pool
        threads = numba_threads() if self.parallel and n >= PARALLEL_MIN_BATCH else 1
        garbage = _WORK_GARBAGE_SEED
        if threads == 1:
            raster.render_kernel_serial(scene, params, cameras, looks_fields, out, garbage)
        else:
            # Enough interleaved row sets per camera that every thread gets a fair share.
            row_blocks = max(1, math.ceil(4 * threads / n))
            raster.render_kernel(scene, params, cameras, looks_fields, row_blocks, out, garbage)
        if looks_fields[-1]:
            finish = looks_kernels.finish_kernel_serial
            if threads > 1:
                finish = looks_kernels.finish_kernel
            finish(out, looks_fields[0], looks_fields[1], self.camera.focal, self._noise)
        if rng is not None and self.config.has_noise:  # with noise, rng is checked above
            apply_noise(out, self.config, rng)
        return out

    def _looks(
        self,
        n: int,
        looks: ArrayLike | None,
        tone: ArrayLike | None,
        cylinders: ArrayLike | None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, bool]:
        """The kernels' :class:`~.kernels.bundles.Looks` fields of one call, checked."""
        if looks is None and tone is not None:
            raise ValueError("tone needs looks")
        cyl = _NO_CYLINDERS if cylinders is None else _cylinders(cylinders, n)
        if looks is None:
            return _NEUTRAL_ROWS, _NEUTRAL_TONE, cyl, self._noise, False
        rows = _float_array("looks", looks, (n, len(LOOK_FIELDS)))
        if tone is None:
            tone_arr = np.broadcast_to(identity_tone(), (n, 256))
        else:
            tone_arr = np.asarray(tone)
            if tone_arr.shape != (n, 256) or tone_arr.dtype != np.uint8:
                raise ValueError(f"tone must be a uint8 array of shape ({n}, 256)")
        return rows, np.ascontiguousarray(tone_arr), cyl, self._noise, True


def _cylinders(value: ArrayLike, n: int) -> np.ndarray:
    """(N, C, 6) cylinders, checked: radius >= 0, bottom <= top."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"cylinders must be a numeric array of shape ({n}, C, 6)") from None
    if arr.ndim != 3 or arr.shape[0] != n or arr.shape[2] != 6:
        raise ValueError(f"cylinders must have shape ({n}, C, 6), got {arr.shape}")
    arr = _float_array("cylinders", arr, arr.shape)
    if (arr[..., 2] < 0).any() or (arr[..., 3] > arr[..., 4]).any():
        raise ValueError("cylinders need radius >= 0 and bottom z <= top z")
    return arr


#: Entries of the noise table of every image of fewer pixels than this (640 x 480 has 307,200;
#: the default camera's image 19,200).
NOISE_TABLE_MIN = 1 << 19


@functools.lru_cache(maxsize=4)
def noise_table(pixels: int) -> np.ndarray:
    """The fixed table of standard normal numbers the looks of ``pixels``-pixel images read
    patterns and noise from. A frame's sensor noise is a contiguous run of the table from a
    hashed start, so the table must hold the frame: NOISE_TABLE_MIN entries for images of
    fewer pixels (the table every image had before larger ones were supported, so their
    frames keep their bytes), else the first power of two of at least twice ``pixels`` (room
    to place the run). Its seed never changes; a larger table begins with the same numbers."""
    size = NOISE_TABLE_MIN if pixels < NOISE_TABLE_MIN else 1 << (2 * pixels - 1).bit_length()
    return np.random.default_rng(20170320).standard_normal(size).astype(np.float32)


_NEUTRAL_ROWS = neutral_looks(1)
_NEUTRAL_TONE = identity_tone()[None]
_NO_CYLINDERS = np.zeros((1, 0, 6))


def apply_noise(images: np.ndarray, config: RenderConfig, rng: np.random.Generator) -> None:
    """Apply ``config``'s contrast jitter, brightness jitter and pixel noise in place (drawn
    from ``rng`` in that order, one contrast and brightness per image)."""
    n = images.shape[0]
    value = images.astype(np.float32)
    if config.contrast_jitter > 0:
        gain = rng.uniform(1 - config.contrast_jitter, 1 + config.contrast_jitter, (n, 1, 1))
        value = (value - 128.0) * gain.astype(np.float32) + 128.0
    if config.brightness_jitter > 0:
        value += rng.uniform(-config.brightness_jitter, config.brightness_jitter, (n, 1, 1)).astype(
            np.float32
        )
    if config.noise_std > 0:
        value += rng.normal(0.0, config.noise_std, value.shape).astype(np.float32)
    np.clip(np.rint(value), 0, 255, out=value)
    images[...] = value


def _poses(pose: ArrayLike) -> np.ndarray:
    """(N, 3) float poses from (N, 3) or one (3,) pose; ValueError naming the shape."""
    try:
        pose_arr = np.asarray(pose, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError("pose must be a numeric array of shape (N, 3) or (3,)") from None
    if pose_arr.ndim == 1:
        pose_arr = _float_array("pose", pose_arr, (3,))[None]
    n = pose_arr.shape[0] if pose_arr.ndim == 2 else -1
    if n < 1:
        raise ValueError(f"pose must have shape (N, 3) or (3,), got {pose_arr.shape}")
    return _float_array("pose", pose_arr, (n, 3))


def _balls(ball_xy: ArrayLike | None, n: int) -> tuple[np.ndarray, bool]:
    """(N, 2) ball positions and whether there is a ball (None: none in any image)."""
    if ball_xy is None:
        return np.zeros((n, 2)), False
    try:
        ball_arr = np.asarray(ball_xy, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"ball_xy must be a numeric array of shape ({n}, 2)") from None
    if n == 1 and ball_arr.shape == (2,):
        ball_arr = ball_arr[None]
    return _float_array("ball_xy", ball_arr, (n, 2)), True


def _output(out: np.ndarray | None, shape: tuple[int, int, int]) -> np.ndarray:
    """The array to render into: ``out`` checked, or a new one."""
    if out is None:
        return np.empty(shape, dtype=np.uint8)
    if not isinstance(out, np.ndarray):
        raise ValueError("out must be a numpy uint8 array")
    if out.shape != shape or out.dtype != np.uint8:
        raise ValueError(f"out must be a uint8 array of shape {shape}, got {out.dtype} {out.shape}")
    if not out.flags.c_contiguous or not out.flags.writeable:
        raise ValueError("out must be C-contiguous and writeable")
    return out
