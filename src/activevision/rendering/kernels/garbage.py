"""Test hook of the renderer: garbage in the kernels' uninitialised work memory.

The work arrays are uninitialised (``np.empty``): for each camera the setup pass writes every
entry that the row pass reads (a shape out of view gets an empty row range *and* edges no
pixel touches), and the row pass reads a shape's edges only on rows in its range, so a frame
never depends on what the memory held before, i.e. on the other frames of its batch. With
``renderer._WORK_GARBAGE_SEED`` set, the entry points fill the memory with garbage first
(:func:`fill_garbage`) and the tests check that no image changes.
"""

from __future__ import annotations

import numpy as np

from activevision.geometry.jit import cached_njit
from activevision.rendering.kernels.bundles import EDGE_PARAMS, JIT, RenderWork, SetupScratch

#: Kinds of garbage of :func:`fill_garbage`: random mixed values; an edge that takes every
#: pixel with row ranges over every row (stale data that *looks* valid is what turns a
#: missing write into wrong pixels); NaN and -1 everywhere.
GARBAGE_KINDS = 3
#: One edge (EDGE_PARAMS,) whose half-plane contains the whole image.
_ACCEPT_ALL_EDGE = (0.0, 0.0, 1e30, 0.5, 0.5, 1.0, 0.5, 0.0)


@cached_njit(**JIT)
def _xorshift(x: np.uint64) -> np.uint64:
    x ^= x << np.uint64(13)
    x ^= x >> np.uint64(7)
    x ^= x << np.uint64(17)
    return x


@cached_njit(**JIT)
def garbage_floats(arr: np.ndarray, seed: int) -> None:
    """Fill the C-contiguous float array ``arr`` with garbage of kind ``seed % GARBAGE_KINDS``
    drawn from ``seed``."""
    flat = arr.reshape(arr.size)
    kind = seed % GARBAGE_KINDS
    x = np.uint64(seed) | np.uint64(1)
    for i in range(flat.size):
        if kind == 1:
            flat[i] = _ACCEPT_ALL_EDGE[i % EDGE_PARAMS]
            continue
        if kind == 2:
            flat[i] = np.nan
            continue
        x = _xorshift(x)
        small = (np.int64(x >> np.uint64(40)) % 2001 - 1000) * 0.01  # -10 .. 10
        pick = np.int64(x & np.uint64(3))
        if pick == 0:
            flat[i] = np.nan
        elif pick == 1:
            flat[i] = 1e300 if x & np.uint64(32) else -1e300
        elif pick == 2:
            flat[i] = small * 1e4
        else:
            flat[i] = small


@cached_njit(**JIT)
def _garbage_ints(arr: np.ndarray, seed: int) -> None:
    """Fill the C-contiguous int64 array ``arr`` with garbage of kind ``seed % GARBAGE_KINDS``
    (huge, negative, plausible row, column and object indices) drawn from ``seed``."""
    flat = arr.reshape(arr.size)
    kind = seed % GARBAGE_KINDS
    x = np.uint64(seed) | np.uint64(1)
    for i in range(flat.size):
        if kind == 1:
            flat[i] = 0 if i % 2 == 0 else 1 << 20  # row ranges [0, 2^20): every row
            continue
        if kind == 2:
            flat[i] = -1
            continue
        x = _xorshift(x)
        pick = np.int64(x & np.uint64(3))
        if pick == 0:
            flat[i] = np.int64(x >> np.uint64(1))
        elif pick == 1:
            flat[i] = -1 - np.int64(x >> np.uint64(50))
        else:
            flat[i] = np.int64(x >> np.uint64(40)) % 300


@cached_njit(**JIT)
def fill_garbage(work: RenderWork, scratch: SetupScratch, value: np.ndarray, seed: int) -> None:
    """Overwrite every buffer of the :class:`.bundles.RenderWork` ``work``, the
    :class:`.bundles.SetupScratch` ``scratch`` and the row scratch ``value`` with garbage of
    kind ``seed % GARBAGE_KINDS``, as if the memory held anything at all (including another
    camera's data)."""
    k = GARBAGE_KINDS  # seed + m k: the same kind, different values per buffer
    garbage_floats(work.quad_edges, seed + k)
    _garbage_ints(work.quad_rows, seed + 2 * k)
    garbage_floats(work.ring_edges, seed + 3 * k)
    _garbage_ints(work.ring_rows, seed + 4 * k)
    garbage_floats(work.homography, seed + 5 * k)
    garbage_floats(work.ball_info, seed + 6 * k)
    _garbage_ints(work.ball_box, seed + 7 * k)
    _garbage_ints(work.object_order, seed + 8 * k)
    garbage_floats(work.ray, seed + 18 * k)
    garbage_floats(work.object_grey, seed + 19 * k)
    _garbage_ints(work.first_row, seed + 9 * k)
    _garbage_ints(work.visible_paint, seed + 10 * k)
    _garbage_ints(work.visible_count, seed + 11 * k)
    garbage_floats(scratch.rot, seed + 12 * k)
    garbage_floats(scratch.cam, seed + 13 * k)
    garbage_floats(scratch.pts, seed + 14 * k)
    garbage_floats(scratch.clip, seed + 15 * k)
    garbage_floats(scratch.keys, seed + 16 * k)
    garbage_floats(value, seed + 17 * k)
