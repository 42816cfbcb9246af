"""The randomised appearance in the renderer's kernels (:mod:`activevision.rendering.appearance`
says what each factor is).

Two places:

* in the row pass (:func:`texture_row`, :func:`worn_paint`, :func:`illuminate_row`): carpet
  stripes and grain, paint wear and the hall beyond the carpet need each pixel's ground or
  wall point, which the row pass has (the pixel -> ground homography and the pixel -> ray
  matrix of the setup pass); illumination gain, offset and vignetting scale the row before it
  is rounded;
* after it, per frame (:func:`finish_frame`): defocus and motion blur need whole images, then
  sensor noise and the tone curve (gamma).

Patterns look their values up in a fixed table of standard normal numbers (``Looks.noise``)
at a hashed index: of the episode's key and a ground or wall cell for patterns (so they stay
put as the head moves), of the key, the frame counter and the pixel for sensor noise (so a
frame's bytes depend on nothing but its own camera and look).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import prange
from numba.np.unsafe.ndarray import to_fixed_tuple as _to_fixed_tuple

from activevision.geometry.jit import cached_njit
from activevision.rendering.appearance import LOOK
from activevision.rendering.kernels.bundles import JIT, JIT_PART, Params
from activevision.rendering.kernels.selects import clamp

#: numba's ``to_fixed_tuple(array, n)``: the first n values as a tuple, n a constant (to mypy
#: an intrinsic, whose Python signature is its typing function's)
to_fixed_tuple: Any = _to_fixed_tuple

_GAIN = LOOK["gain"]
_OFFSET = LOOK["offset"]
_VIGNETTING = LOOK["vignetting"]
_READ = LOOK["read_noise"]
_SHOT = LOOK["shot_noise"]
_DEFOCUS = LOOK["defocus"]
_MOTION = LOOK["motion_blur"]
_STRIPES = LOOK["stripes"]
_STRIPE_WIDTH = LOOK["stripe_width"]
_GRAIN = LOOK["grain"]
_WEAR = LOOK["line_wear"]
_CLUTTER = LOOK["clutter"]
_KEY = LOOK["key"]
_MOVE_PAN = LOOK["move_pan"]
_MOVE_TILT = LOOK["move_tilt"]
_FRAME = LOOK["frame"]
_GAMMA = LOOK["gamma"]

#: Cell sizes (m) of the patterns: carpet grain, paint wear patches, hall floor tiles,
#: advertising boards, spectators (width, height) and the wall above them.
GRAIN_CELL = 0.025
WEAR_CELL = 0.08
FLOOR_CELL = 0.5
BOARD_CELL = 1.2
SPECTATOR_CELL = (0.3, 0.4)
WALL_CELL = 3.0
#: Heights (m) on the hall's walls: boards below the first, spectators up to the second.
BOARD_TOP = 0.8
STANDS_TOP = 2.6
#: Patterns read the first PATTERN_CELLS numbers of the table (a table that stays in the
#: L1 cache: random reads from the whole one would miss it at nearly every pattern cell).
PATTERN_CELLS = 4096
#: Patterns are evaluated every KNOT pixels of a row and interpolated between.
KNOT = 8
#: Worn paint keeps this share of its coverage.
WORN_KEEP = 0.2
#: Blur below these sizes (px) is not applied (it would change no pixel by more than ~1 grey).
MIN_DEFOCUS = 0.2
MIN_MOTION = 0.5


@cached_njit(**JIT_PART)
def _cell(key: int, a: float, b: float, salt: int, mask: int) -> int:
    """Table index of the pattern cell ``(floor(a), floor(b))`` of the episode ``key``."""
    ia: int = math.floor(a)
    ib: int = math.floor(b)
    h = (ia * 0x9E3779B1 + ib * 0x85EBCA77 + key + salt * 0x27D4EB2F) & 0xFFFFFFFF
    h ^= h >> 15
    h = (h * 0x2C1B3C6D) & 0xFFFFFFFF
    h ^= h >> 12
    return h & mask


@cached_njit(**JIT_PART)
def _hall(
    dx: float, dy: float, dz: float, ray: np.ndarray, params: Params, key: int, noise: np.ndarray
) -> float:
    """Grey offset (unit amplitude) of what the world ray ``(dx, dy, dz)`` from the camera
    meets beyond the carpet: the hall's floor (tiles), or its walls (advertising boards,
    spectators, plain wall above)."""
    mask = PATTERN_CELLS - 1
    px, py, pz = ray[0, 3], ray[1, 3], ray[2, 3]
    wx = params.hall_x if dx > 0.0 else -params.hall_x
    wy = params.hall_y if dy > 0.0 else -params.hall_y
    tx = (wx - px) / dx if abs(dx) > 1e-12 else 1e30
    ty = (wy - py) / dy if abs(dy) > 1e-12 else 1e30
    t = tx if tx < ty else ty
    z = pz + t * dz
    if z < 0.0:
        tf = -pz / dz
        cell = _cell(key, (px + tf * dx) / FLOOR_CELL, (py + tf * dy) / FLOOR_CELL, 1, mask)
        return 0.25 * float(noise[cell])
    # along the wall, each wall offset so that the four do not repeat each other
    if tx < ty:
        s = py + t * dy + (1000.0 if dx > 0.0 else 2000.0)
    else:
        s = px + t * dx + (3000.0 if dy > 0.0 else 4000.0)
    if z < BOARD_TOP:
        return float(noise[_cell(key, s / BOARD_CELL, 0.0, 2, mask)])
    if z < STANDS_TOP:
        cell = _cell(key, s / SPECTATOR_CELL[0], z / SPECTATOR_CELL[1], 3, mask)
        return 0.8 * float(noise[cell])
    return 0.3 * float(noise[_cell(key, s / WALL_CELL, 0.0, 4, mask)])


@cached_njit(**JIT_PART)
def _stripe(gx: float, width: float) -> float:
    """Mowing stripes across the field's length: +-1 in alternate bands ``width`` wide, with
    soft edges."""
    t = gx / (2.0 * width)
    f = t - math.floor(t)
    return float(clamp(8.0 * (abs(2.0 * f - 1.0) - 0.5), -1.0, 1.0))


#: Rows of the knots scratch of :func:`texture_row`: the carpet's and the hall's pattern
#: values, the knots' ground coordinates (x, y; 0 where the ray misses the ground), whether
#: the ray meets the ground (1 or 0) and the grain's table index.
KNOT_ROWS = 6
CARPET, HALL, GROUND_X, GROUND_Y, ON_GROUND, GRAIN_INDEX = range(KNOT_ROWS)


@cached_njit(**JIT_PART)
def _carpet_knots(
    v: float,
    h: np.ndarray,
    stripes: float,
    grain: float,
    look: np.ndarray,
    noise: np.ndarray,
    knots: np.ndarray,
) -> None:
    """Stripes and grain at the knots of row centre ``v`` into ``knots[CARPET]`` (``h``:
    the pixel -> ground homography). A quantity at a time over the row, each knot computed
    and then selected (no branch), so that each loop vectorises."""
    n_knots = knots.shape[1]
    width = look[_STRIPE_WIDTH]
    # the homography's entries as scalars: loads from an array the loop might write would
    # keep it from vectorising
    h00, h01, h02 = h[0, 0], h[0, 1], h[0, 2]
    h10, h11, h12 = h[1, 0], h[1, 1], h[1, 2]
    h20, h21, h22 = h[2, 0], h[2, 1], h[2, 2]
    for m in range(n_knots):
        u = float(m * KNOT)
        gz = h20 * u + h21 * v + h22
        seen = gz > 0.0  # the knot's ray meets the ground
        inv_gz = 1.0 / (gz if seen else 1.0)
        gx = (h00 * u + h01 * v + h02) * inv_gz
        gy = (h10 * u + h11 * v + h12) * inv_gz
        knots[GROUND_X, m] = gx if seen else 0.0
        knots[GROUND_Y, m] = gy if seen else 0.0
        knots[ON_GROUND, m] = 1.0 if seen else 0.0
        stripe = stripes * _stripe(gx, width)
        knots[CARPET, m] = stripe if seen else 0.0
    if grain == 0.0:
        return
    # the cells first (vectorised), then the table reads on their own (a gather the
    # vectoriser cannot bound-check)
    key = int(look[_KEY])
    mask = PATTERN_CELLS - 1
    for m in range(n_knots):
        gx = knots[GROUND_X, m] / GRAIN_CELL
        knots[GRAIN_INDEX, m] = _cell(key, gx, knots[GROUND_Y, m] / GRAIN_CELL, 0, mask)
    for m in range(n_knots):
        cell = noise[int(knots[GRAIN_INDEX, m])]
        knots[CARPET, m] += knots[ON_GROUND, m] * (grain * float(cell))


@cached_njit(**JIT_PART)
def _hall_knots(
    v: float,
    ray: np.ndarray,
    clutter: float,
    look: np.ndarray,
    params: Params,
    noise: np.ndarray,
    knots: np.ndarray,
) -> None:
    """The hall's pattern at the knots of row centre ``v`` into ``knots[HALL]`` (``ray``:
    the pixel -> world ray matrix)."""
    key = int(look[_KEY])
    for m in range(knots.shape[1]):
        u = float(m * KNOT)
        dx = ray[0, 0] * u + ray[0, 1] * v + ray[0, 2]
        dy = ray[1, 0] * u + ray[1, 1] * v + ray[1, 2]
        dz = ray[2, 0] * u + ray[2, 1] * v + ray[2, 2]
        knots[HALL, m] = clutter * _hall(dx, dy, dz, ray, params, key, noise)


@cached_njit(**JIT_PART)
def _blend_knots(value: np.ndarray, params: Params, knots: np.ndarray, texture: np.ndarray) -> None:
    """Add the knots' patterns, interpolated linearly between knots (into ``texture``),
    to ``value``: the carpet's on its share of each pixel, the hall's on the rest."""
    width = value.shape[0]
    step = np.float32(1.0 / KNOT)
    half = np.float32(0.5)
    for m in range(knots.shape[1] - 1):
        c0 = np.float32(knots[CARPET, m])
        dc = (np.float32(knots[CARPET, m + 1]) - c0) * step
        h0 = np.float32(knots[HALL, m])
        dh = (np.float32(knots[HALL, m + 1]) - h0) * step
        first = m * KNOT
        for k in range(min(KNOT, width - first)):
            texture[0, first + k] = c0 + (np.float32(k) + half) * dc
            texture[1, first + k] = h0 + (np.float32(k) + half) * dh
    bg = np.float32(params.background)
    span = params.grass - params.background
    inv_span = np.float32(1.0 / span if abs(span) >= 1.0 else 0.0)
    zero = np.float32(0.0)
    one = np.float32(1.0)
    # one flat loop over the row: a segment's 8 pixels are too few to vectorise
    for i in range(width):
        share = clamp((value[i] - bg) * inv_span, zero, one)
        value[i] += share * texture[0, i] + (one - share) * texture[1, i]


@cached_njit(**JIT)
def texture_row(
    v: float,
    value: np.ndarray,
    homography: np.ndarray,
    ray: np.ndarray,
    look: np.ndarray,
    params: Params,
    noise: np.ndarray,
    knots: np.ndarray,
    texture: np.ndarray,
) -> None:
    """Carpet stripes and grain on the carpet's share of each pixel of row centre ``v`` of
    ``value`` (W,), the hall on the rest. The share is read off the ground pass's grey
    (background -> 0, grass -> 1), so the carpet's anti-aliased border stays exact.

    Patterns are evaluated every :data:`KNOT` pixels (into ``knots`` (KNOT_ROWS,
    W // KNOT + 2) float64) and interpolated linearly between (into ``texture`` (2, W)
    float32: carpet, hall): a pixel costs a few multiply-adds, not a division and a hash
    (grain cells farther than a few metres are smaller than a pixel anyway). The kernels
    index ``knots`` and ``texture`` by row and column: a view of a row would be
    reference-counted, row after row."""
    stripes = look[_STRIPES]
    grain = look[_GRAIN]
    clutter = look[_CLUTTER]
    # rows all carpet (or all beyond it) need only one of the patterns
    grass = np.float32(params.grass)
    background = np.float32(params.background)
    any_carpet = False
    any_hall = False
    for i in range(value.shape[0]):
        any_carpet |= value[i] != background
        any_hall |= value[i] != grass
    if not any_hall:
        clutter = 0.0
    if not any_carpet:
        stripes = 0.0
        grain = 0.0
    if stripes == 0.0 and grain == 0.0 and clutter == 0.0:
        return
    if stripes != 0.0 or grain != 0.0:
        _carpet_knots(v, homography, stripes, grain, look, noise, knots)
    else:
        knots[CARPET, :] = 0.0
    if clutter != 0.0:
        _hall_knots(v, ray, clutter, look, params, noise, knots)
    else:
        knots[HALL, :] = 0.0
    _blend_knots(value, params, knots, texture)


@cached_njit(**JIT)
def worn_paint(
    v: float,
    lo: int,
    hi: int,
    paint: np.ndarray,
    homography: np.ndarray,
    look: np.ndarray,
    noise: np.ndarray,
) -> None:
    """Paint wear: columns ``[lo, hi)`` of ``paint`` (W,) keep :data:`WORN_KEEP` of their
    coverage in worn patches (ground cells of :data:`WEAR_CELL`; their share grows with the
    look's ``line_wear``)."""
    threshold = 4.0 * look[_WEAR] - 2.0  # a share ~ Phi(threshold) of the cells is worn
    key = int(look[_KEY])
    mask = PATTERN_CELLS - 1
    h = homography
    for i in range(lo, hi):
        if paint[i] == 0.0:
            continue
        u = i + 0.5
        gz = h[2, 0] * u + h[2, 1] * v + h[2, 2]
        if gz <= 0.0:
            continue
        gx = (h[0, 0] * u + h[0, 1] * v + h[0, 2]) / gz
        gy = (h[1, 0] * u + h[1, 1] * v + h[1, 2]) / gz
        if noise[_cell(key, gx / WEAR_CELL, gy / WEAR_CELL, 5, mask)] < threshold:
            paint[i] *= WORN_KEEP


@cached_njit(**JIT)
def illuminate_row(v: float, value: np.ndarray, look: np.ndarray, params: Params) -> None:
    """Illumination of row centre ``v``: ``value * gain * (1 - vignetting r^2) + offset``,
    ``r`` the distance from the image centre relative to the corner's."""
    gain = np.float32(look[_GAIN])
    offset = np.float32(look[_OFFSET])
    vig = np.float32(look[_VIGNETTING] / (params.cx * params.cx + params.cy * params.cy))
    dv = v - params.cy
    base = np.float32(dv * dv)
    one = np.float32(1.0)
    # a float column counter, not float(i): int64 -> float has no vector instruction (AVX2)
    du = np.float32(0.5 - params.cx)
    for i in range(value.shape[0]):
        value[i] = value[i] * gain * (one - vig * (base + du * du)) + offset
        du += one


#: Most taps of the blur filter along one axis (defocus and motion blur convolved).
MAX_TAPS = 15


@cached_njit(**JIT_PART)
def _blur_taps(sigma: float, move: float, taps: np.ndarray) -> int:
    """The blur filter along one image axis into ``taps`` (MAX_TAPS,): a Gaussian of
    ``sigma`` px (defocus; none below MIN_DEFOCUS) convolved with a box as long as ``move``
    px (motion blur; none below MIN_MOTION). Returns the radius ``r`` (taps ``0..2r``),
    weights normalised."""
    g_r = min(math.ceil(2.5 * sigma), 3) if sigma >= MIN_DEFOCUS else 0
    length = abs(move) if abs(move) >= MIN_MOTION else 0.0
    b_r = min(math.ceil(0.5 * length - 0.5), (MAX_TAPS - 1) // 2 - g_r) if length > 0.0 else 0
    r = g_r + b_r
    taps[: 2 * r + 1] = 0.0
    for k in range(-g_r, g_r + 1):
        w = math.exp(-0.5 * (k / sigma) ** 2) if g_r > 0 else 1.0
        for b in range(-b_r, b_r + 1):
            # box of width `length` centred on 0: the end taps hold the fraction they cover
            cover = 1.0
            if b_r > 0 and abs(b) == b_r:
                cover = 0.5 * (length - (2 * b_r - 1))
            taps[k + b + r] += w * cover
    total = taps[: 2 * r + 1].sum()
    taps[: 2 * r + 1] /= total
    return r


#: The tap counts the blur kernels are compiled for: a filter of radius ``r`` runs as the
#: smallest that holds ``2r + 1`` taps, centred and padded with zeros (a zero tap adds 0 x
#: a pixel, which changes no sum). A count known when compiling unrolls the taps' loop, so
#: the pixels' loop keeps every sum in a register; over taps of unknown count it loads and
#: stores the row once a tap, 2x slower.
TAP_COUNTS = (3, 5, 7, 9, MAX_TAPS)


@cached_njit(**JIT_PART)
def _centred_taps(taps: np.ndarray, r: int) -> np.ndarray:
    """``taps[:2r + 1]`` as float32, centred in the smallest of :data:`TAP_COUNTS` that
    holds them, zero around."""
    n = MAX_TAPS
    for count in TAP_COUNTS[::-1]:
        if count >= 2 * r + 1:
            n = count
    out = np.zeros(n, dtype=np.float32)
    first = (n - 1) // 2 - r
    for k in range(2 * r + 1):
        out[first + k] = np.float32(taps[k])
    return out


@cached_njit(**JIT)
def _filter_rows_by(src: np.ndarray, dst: np.ndarray, taps: Any) -> None:
    """Rows ``m..m + H`` of ``dst`` (H + 2m, W) float32 = ``src`` (H, W) uint8 filtered
    along each row (axis 1) by ``taps`` (a tuple: its length is a constant of the compiled
    kernel), and the ``m`` rows above and below copies of the first and last (the column
    filter's padding); the row edges repeat their border pixels (each row is copied into a
    padded one, so that the filter reads every tap from one plain array). The sum runs tap
    by tap from the first."""
    height, width = src.shape
    m = (dst.shape[0] - height) // 2
    n = len(taps)
    r = n // 2
    pad = np.empty(width + 2 * r, dtype=np.float32)
    for j in range(height):
        for i in range(width):
            pad[r + i] = src[j, i]
        for i in range(r):
            pad[i] = pad[r]
            pad[r + width + i] = pad[r + width - 1]
        for i in range(width):
            acc = taps[0] * pad[i]
            for k in range(1, n):
                acc += taps[k] * pad[i + k]
            dst[m + j, i] = acc
    for j in range(m):
        for i in range(width):
            dst[j, i] = dst[m, i]
            dst[m + height + j, i] = dst[m + height - 1, i]


@cached_njit(**JIT_PART)
def _filter_column_by(rows: np.ndarray, taps: Any, row: np.ndarray, j: int) -> None:
    """``row`` (W,) float32 = row ``j`` of the image whose rows ``rows`` (H + n - 1, W)
    float32 holds padded as :func:`_filter_rows_by` writes them, filtered along the columns
    by ``taps`` (a tuple of n, as :func:`_filter_rows_by`'s). Row ``j + k`` feeds tap
    ``k``: plain offsets, no table of source rows (whose loads in the loop would keep it
    from vectorising)."""
    n = len(taps)
    for i in range(row.shape[0]):
        acc = taps[0] * rows[j, i]
        for k in range(1, n):
            acc += taps[k] * rows[j + k, i]
        row[i] = acc


@cached_njit(**JIT_PART)
def _filter_rows(src: np.ndarray, dst: np.ndarray, taps: np.ndarray) -> None:
    """:func:`_filter_rows_by` with ``taps`` (n,) float32 of :func:`_centred_taps`."""
    n = taps.shape[0]
    if n == 3:
        _filter_rows_by(src, dst, to_fixed_tuple(taps, 3))
    elif n == 5:
        _filter_rows_by(src, dst, to_fixed_tuple(taps, 5))
    elif n == 7:
        _filter_rows_by(src, dst, to_fixed_tuple(taps, 7))
    elif n == 9:
        _filter_rows_by(src, dst, to_fixed_tuple(taps, 9))
    else:
        _filter_rows_by(src, dst, to_fixed_tuple(taps, MAX_TAPS))


@cached_njit(**JIT_PART)
def _filter_column(rows: np.ndarray, taps: np.ndarray, row: np.ndarray, j: int) -> None:
    """:func:`_filter_column_by` with ``taps`` (n,) float32 of :func:`_centred_taps`."""
    n = taps.shape[0]
    if n == 3:
        _filter_column_by(rows, to_fixed_tuple(taps, 3), row, j)
    elif n == 5:
        _filter_column_by(rows, to_fixed_tuple(taps, 5), row, j)
    elif n == 7:
        _filter_column_by(rows, to_fixed_tuple(taps, 7), row, j)
    elif n == 9:
        _filter_column_by(rows, to_fixed_tuple(taps, 9), row, j)
    else:
        _filter_column_by(rows, to_fixed_tuple(taps, MAX_TAPS), row, j)


@cached_njit(**JIT_PART)
def _add_noise(row: np.ndarray, read2: float, shot: float, noise: np.ndarray, first: int) -> None:
    """Sensor noise of std ``sqrt(read2 + shot * value)`` on ``row``, its normal numbers
    ``noise[first:]`` (indexed, not sliced: a view per row would be reference-counted)."""
    zero = np.float32(0.0)
    for i in range(row.shape[0]):
        signal = row[i] if row[i] > zero else zero
        row[i] += np.float32(math.sqrt(read2 + shot * signal)) * noise[first + i]


@cached_njit(**JIT_PART)
def _store_row(
    row: np.ndarray, img: np.ndarray, j: int, tone: np.ndarray, toned: bool, levels: np.ndarray
) -> None:
    """Row ``j`` of ``img`` = ``row`` rounded to grey levels, through the ``tone`` curve if
    ``toned`` (``levels`` (W,) int32 scratch)."""
    zero = np.float32(0.0)
    top = np.float32(255.0)
    half = np.float32(0.5)
    if not toned:
        for i in range(row.shape[0]):
            img[j, i] = np.uint8(clamp(row[i] + half, zero, top))
        return
    # the levels in one vectorised loop, the table reads in a plain one (a vector gather is
    # slower than scalar reads on CPUs with the gather data sampling mitigation)
    for i in range(row.shape[0]):
        levels[i] = np.int32(clamp(row[i] + half, zero, top))
    for i in range(row.shape[0]):
        img[j, i] = tone[levels[i]]


@cached_njit(**JIT)
def finish_frame(
    img: np.ndarray, look: np.ndarray, tone: np.ndarray, focal: float, noise: np.ndarray
) -> None:
    """Blur, sensor noise and tone curve of one rendered frame ``img`` (H, W) uint8, in
    place.

    Blur is separable: along each image axis, the defocus Gaussian convolved with a box as
    long as the head's move on that axis in this step (motion blur; a diagonal move blurs a
    box, not a line). Noise std ``sqrt(read^2 + shot * value)`` grey levels, its normal
    numbers read from ``noise`` at an offset hashed from the episode's key and the frame
    counter. A frame with none of them is left as it is.

    One pass along the rows blurs them into a float image; a second pass makes each output
    row: its column blur, noise and tone at once (no more passes over the image)."""
    height, width = img.shape
    sigma = look[_DEFOCUS]
    bx = look[_MOTION] * focal * look[_MOVE_PAN]
    by = look[_MOTION] * focal * look[_MOVE_TILT]
    read2 = look[_READ] * look[_READ]
    shot = look[_SHOT]
    noisy = read2 > 0.0 or shot > 0.0
    toned = look[_GAMMA] != 1.0
    blurred = sigma >= MIN_DEFOCUS or abs(bx) >= MIN_MOTION or abs(by) >= MIN_MOTION
    if not (noisy or toned or blurred):
        return
    mask = noise.shape[0] - 1
    # a contiguous run of the table (the start leaves room for the whole frame)
    start = _cell(int(look[_KEY]), look[_FRAME], 0.0, 6, mask) % (mask + 1 - height * width)
    row = np.empty(width, dtype=np.float32)
    taps = np.empty(MAX_TAPS)
    rows_blurred = np.empty((0, width), dtype=np.float32)
    column_taps = np.empty(0, dtype=np.float32)
    if blurred:
        column_taps = _centred_taps(taps, _blur_taps(sigma, by, taps))
        rows_blurred = np.empty((height + column_taps.shape[0] - 1, width), dtype=np.float32)
        _filter_rows(img, rows_blurred, _centred_taps(taps, _blur_taps(sigma, bx, taps)))
    levels = np.empty(width, dtype=np.int32)
    for j in range(height):
        if blurred:
            _filter_column(rows_blurred, column_taps, row, j)
        else:
            for i in range(width):
                row[i] = img[j, i]
        if noisy:
            _add_noise(row, read2, shot, noise, start + j * width)
        _store_row(row, img, j, tone, toned, levels)


@cached_njit(**JIT, parallel=True)
def finish_kernel(
    images: np.ndarray, rows: np.ndarray, tone: np.ndarray, focal: float, noise: np.ndarray
) -> None:
    """:func:`finish_frame` for every frame of ``images`` (N, H, W), on the numba threads
    (``focal``: the nominal focal length, px, that turns head moves into motion blur)."""
    for n in prange(images.shape[0]):
        finish_frame(images[n], rows[n], tone[n], focal, noise)


@cached_njit(**JIT)
def finish_kernel_serial(
    images: np.ndarray, rows: np.ndarray, tone: np.ndarray, focal: float, noise: np.ndarray
) -> None:
    """:func:`finish_kernel` on the calling thread."""
    for n in range(images.shape[0]):
        finish_frame(images[n], rows[n], tone[n], focal, noise)
