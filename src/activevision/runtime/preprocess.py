"""Camera frame -> network input: grayscale conversion and area-averaging resize (NumPy only).

The network was trained on 160 x 120 uint8 grayscale images (the paper's input). A robot's
camera gives larger frames, in colour or grey; :class:`FramePreprocessor` turns any of them
into the network's size, with no OpenCV and no per-pixel Python loops:

* **Grayscale** from colour with the ITU-R BT.601 luma weights
  ``Y = 0.299 R + 0.587 G + 0.114 B`` (what OpenCV's ``COLOR_RGB2GRAY`` and Pillow's ``"L"``
  use). ``color_order="bgr"`` reads the channels as B, G, R (OpenCV's order).
* **Resize by area averaging** (a box filter): each output pixel is the mean of the input
  area it covers.

  - When the input size is an integer multiple of the output size (640 x 480, 320 x 240,
    160 x 120, ...) every output pixel is the exact mean of an ``fy x fx`` block.
  - Otherwise the output pixel ``i`` covers the input interval ``[i * s, (i + 1) * s)`` with
    ``s = input / output`` along each axis, and input pixels are weighted by the length of
    their overlap with it (separable; OpenCV's ``INTER_AREA`` does the same for
    downscaling). Upscaling degenerates to nearest-neighbour sampling. The aspect ratio is
    not preserved: the frame is stretched to 160 x 120.

* Colour conversion and averaging are both linear, so for colour frames the sums over each
  block's rows are taken first, on integers, the luma weights applied to them, and the
  results added over the block's columns.
* Integer-multiple sizes (every usual camera mode) run in one compiled pass over the frame
  (:func:`block_mean_kernel`, numba, on the calling thread): it reads each byte once, ~2.5x
  faster than NumPy's reshape-and-reduce, which took 0.22 ms of a 0.47 ms decision for a
  640 x 480 RGB frame.
  Other sizes are plain single-threaded NumPy. No BLAS calls, which could start OpenBLAS
  worker threads on the robot.
* The result is rounded half up, ``floor(mean + 0.5)``, to uint8. For grey frames of an
  integer-multiple size this is computed in integer arithmetic and is exact.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numba import njit

ColorOrder = Literal["rgb", "bgr"]


def compiled(function: Callable[..., Any]) -> Any:
    """``function`` compiled by numba (``nogil``), its machine code cached on disk where numba
    can write (beside the package, in ``~/.cache`` or ``NUMBA_CACHE_DIR``). A read-only
    install run by a user without a writable home (a robot's service account) has no such
    place, and numba's ``cache=True`` then refuses the import ("cannot cache function ...:
    no locator available"): there the kernel is compiled afresh at each start instead, when
    the :class:`FramePreprocessor` (or :class:`~activevision.runtime.decision.OneHeadGoal`)
    is made (about a second), not in a decision."""
    try:
        return njit(cache=True, nogil=True)(function)
    except RuntimeError:
        return njit(nogil=True)(function)


#: ITU-R BT.601 luma weights for (R, G, B).
BT601_LUMA_RGB: tuple[float, float, float] = (0.299, 0.587, 0.114)


def luma_weights(color_order: ColorOrder) -> np.ndarray:
    """The BT.601 weights in the frame's channel order, as float32 of shape (3,)."""
    if color_order == "rgb":
        return np.asarray(BT601_LUMA_RGB, dtype=np.float32)
    if color_order == "bgr":
        return np.asarray(BT601_LUMA_RGB[::-1], dtype=np.float32)
    raise ValueError(f"color_order must be 'rgb' or 'bgr', got {color_order!r}")


def check_frame(frame: object) -> np.ndarray:
    """The frame as an (H, W, C) uint8 view with C in {1, 3}; ValueError naming the problem.

    Accepts (H, W) or (H, W, 1) grey and (H, W, 3) colour ``uint8`` NumPy arrays.
    """
    if not isinstance(frame, np.ndarray):
        raise ValueError(f"frame must be a numpy uint8 array, got {type(frame).__name__}")
    if frame.dtype != np.uint8:
        how = (
            "convert float images with (img * 255).round().astype(np.uint8)"
            if np.issubdtype(frame.dtype, np.floating)
            else "scale it to 8 bits first (a 16-bit image: (img >> 8).astype(np.uint8))"
            if np.issubdtype(frame.dtype, np.integer)
            else "give the camera's 8-bit image"
        )
        raise ValueError(
            f"frame must have dtype uint8 (0..255 camera pixels), got {frame.dtype}; {how}"
        )
    if frame.ndim == 2:
        frame = frame[:, :, None]
    elif frame.ndim != 3:
        raise ValueError(
            f"frame must be (H, W) grey, (H, W, 1) grey or (H, W, 3) RGB/BGR, got {frame.ndim}-D "
            f"shape {frame.shape}"
        )
    if frame.shape[2] not in (1, 3):
        how = (
            "it looks channel-first: give frame.transpose(1, 2, 0)"
            if frame.shape[0] in (1, 3, 4) and frame.shape[2] > 4
            else "drop the alpha channel of RGBA/BGRA frames first"
        )
        raise ValueError(
            f"frame must have 1 (grey) or 3 (RGB/BGR) channels last, got {frame.shape[2]}"
            f" (shape {frame.shape}); {how}"
        )
    if frame.shape[0] < 1 or frame.shape[1] < 1:
        raise ValueError(f"frame is empty, shape {frame.shape}")
    return frame


def area_weights(n_in: int, n_out: int) -> tuple[np.ndarray, np.ndarray]:
    """Taps of a 1-D area-averaging resize from ``n_in`` to ``n_out`` samples.

    Returns ``(index, weight)``, both (n_out, K): output ``i`` is
    ``sum_k weight[i, k] * input[index[i, k]]``; each row of ``weight`` sums to 1. Unused taps
    have weight 0 (and a valid index).
    """
    scale = n_in / n_out
    starts = np.arange(n_out) * scale
    ends = starts + scale
    first = np.floor(starts).astype(np.int64)
    last = np.minimum(np.ceil(ends).astype(np.int64), n_in) - 1
    taps = int((last - first).max()) + 1
    index = first[:, None] + np.arange(taps)[None, :]
    overlap = np.minimum(index + 1, ends[:, None]) - np.maximum(index, starts[:, None])
    weight = np.clip(overlap, 0.0, None) / scale
    weight[index > last[:, None]] = 0.0
    index = np.minimum(index, n_in - 1)
    weight /= weight.sum(axis=1, keepdims=True)
    return index, weight.astype(np.float32)


def round_to_uint8(values: np.ndarray, out: np.ndarray) -> np.ndarray:
    """``floor(values + 0.5)`` clipped to 0..255, written into the uint8 array ``out``."""
    values += 0.5
    np.floor(values, out=values)
    np.clip(values, 0, 255, out=values)
    out[...] = values.reshape(out.shape)
    return out


@dataclass(frozen=True)
class _ResizePlan:
    """How to bring one input size to the output size (precomputed once per input size)."""

    in_height: int
    in_width: int
    factor_y: int  #: integer block height, or 0 when the sizes are not integer multiples
    factor_x: int
    rows: tuple[np.ndarray, np.ndarray] | None  #: area taps along y (general case)
    cols: tuple[np.ndarray, np.ndarray] | None  #: area taps along x (general case)


class FramePreprocessor:
    """Turns camera frames into the network's ``(height, width)`` uint8 grey images.

    Args:
        height, width: output size (the policy's input, 120 x 160 in the paper).

    Resize plans are cached per input size, so a camera with a fixed resolution pays for
    them once.
    """

    def __init__(self, height: int, width: int) -> None:
        if height < 1 or width < 1:
            raise ValueError(f"output size must be positive, got {height} x {width}")
        self.height = int(height)
        self.width = int(width)
        self._plans: dict[tuple[int, int], _ResizePlan] = {}
        # luma weights by colour order, and scaled by a block's pixel count: made once (a
        # decision spent microseconds on each)
        self._luma = {order: luma_weights(order) for order in ("rgb", "bgr")}
        self._scales: dict[tuple[str, int, int], np.ndarray] = {}
        # compile (or load from numba's cache) now, not in the robot's first decision
        block_mean_kernel(
            np.zeros((1, 1, 3), np.uint8), 1, 1, np.ones(3, np.float32), np.empty((1, 1), np.uint8)
        )

    def __call__(
        self, frame: np.ndarray, color_order: ColorOrder = "rgb", out: np.ndarray | None = None
    ) -> np.ndarray:
        """Grey, resized ``(height, width)`` uint8 image of ``frame`` (see the module docs).

        Args:
            frame: (H, W), (H, W, 1) grey or (H, W, 3) colour uint8 array, any H and W.
            color_order: channel order of 3-channel frames, "rgb" or "bgr".
            out: optional (height, width) uint8 array to write into.
        """
        weights = self._luma.get(color_order) if isinstance(color_order, str) else None
        if weights is None:
            weights = luma_weights(color_order)  # refuses a colour order not rgb or bgr
        frame = check_frame(frame)
        if out is None:
            out = np.empty((self.height, self.width), dtype=np.uint8)
        plan = self._plan(frame.shape[0], frame.shape[1])
        channels = frame.shape[2]
        if plan.factor_y:
            scale = self._scales.get((color_order, plan.factor_y, plan.factor_x))
            if scale is None:
                scale = weights / np.float32(plan.factor_y * plan.factor_x)
                self._scales[(color_order, plan.factor_y, plan.factor_x)] = scale
            block_mean_kernel(np.ascontiguousarray(frame), plan.factor_y, plan.factor_x, scale, out)
            return out
        grey = frame[:, :, 0].astype(np.float32) if channels == 1 else _luma(frame, weights)
        return round_to_uint8(self._resample(grey, plan), out)

    # ------------------------------------------------------------------ internals
    def _plan(self, in_height: int, in_width: int) -> _ResizePlan:
        plan = self._plans.get((in_height, in_width))
        if plan is None:
            if in_height % self.height == 0 and in_width % self.width == 0:
                plan = _ResizePlan(
                    in_height,
                    in_width,
                    in_height // self.height,
                    in_width // self.width,
                    None,
                    None,
                )
            else:
                plan = _ResizePlan(
                    in_height,
                    in_width,
                    0,
                    0,
                    area_weights(in_height, self.height),
                    area_weights(in_width, self.width),
                )
            self._plans[(in_height, in_width)] = plan
        return plan

    def _resample(self, grey: np.ndarray, plan: _ResizePlan) -> np.ndarray:
        assert plan.rows is not None and plan.cols is not None
        (row_index, row_weight), (col_index, col_weight) = plan.rows, plan.cols
        rows = np.zeros((self.height, grey.shape[1]), dtype=np.float32)
        for k in range(row_index.shape[1]):  # a few taps, each a whole-image operation
            rows += row_weight[:, k, None] * grey[row_index[:, k], :]
        result = np.zeros((self.height, self.width), dtype=np.float32)
        for k in range(col_index.shape[1]):
            result += col_weight[None, :, k] * rows[:, col_index[:, k]]
        return result


def _luma(frame: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(H, W) float32 BT.601 luma of an (H, W, 3) uint8 frame."""
    grey: np.ndarray = frame[:, :, 0] * weights[0]  # float32 (H, W); no BLAS call (see above)
    grey += frame[:, :, 1] * weights[1]
    grey += frame[:, :, 2] * weights[2]
    return grey


@compiled
def block_mean_kernel(
    frame: np.ndarray, fy: int, fx: int, scale: np.ndarray, out: np.ndarray
) -> None:
    """``out`` (h, w) uint8: the means of the ``fy x fx`` blocks of ``frame`` (h fy, w fx, C)
    uint8, C-contiguous. Grey (C = 1): the exact integer mean, rounded half up. Colour
    (C = 3): the luma (``scale`` (3,) float32: the weights over ``fy fx``) of each column's
    integer sums over the block's rows, added over the block's columns, rounded half up.

    Each output row first sums its ``fy`` input rows into one integer row (a plain loop the
    compiler vectorises), then weighs the channels of each column once and adds ``fx``
    columns per output pixel."""
    height, width = out.shape
    channels = frame.shape[2]
    columns = frame.shape[1]
    rows = frame.reshape(frame.shape[0], columns * channels)
    acc = np.empty(columns * channels, dtype=np.int32)
    luma = np.empty(columns, dtype=np.float32)
    count = fy * fx
    half = np.float32(0.5)
    for i in range(height):
        first = rows[i * fy]
        for k in range(acc.shape[0]):
            acc[k] = first[k]
        for a in range(1, fy):
            src = rows[i * fy + a]
            for k in range(acc.shape[0]):
                acc[k] += src[k]
        if channels == 1:
            for j in range(width):
                total = 0
                for t in range(j * fx, (j + 1) * fx):
                    total += acc[t]
                out[i, j] = (total + count // 2) // count
            continue
        for p in range(columns):
            luma[p] = acc[3 * p] * scale[0] + acc[3 * p + 1] * scale[1] + acc[3 * p + 2] * scale[2]
        for j in range(width):
            v = half
            for t in range(j * fx, (j + 1) * fx):
                v += luma[t]
            out[i, j] = min(max(v, np.float32(0.0)), np.float32(255.0))
