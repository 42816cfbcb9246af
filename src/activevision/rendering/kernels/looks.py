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

import numpy as np
from numba import njit, prange

from activevision.rendering.appearance import LOOK
from activevision.rendering.kernels.bundles import JIT, JIT_PART, Params

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
#: Worn paint keeps this share of its coverage.
WORN_KEEP = 0.2
#: Blur below these sizes (px) is not applied (it would change no pixel by more than ~1 grey).
MIN_DEFOCUS = 0.2
MIN_MOTION = 0.5


@njit(**JIT_PART)
def _cell(key: int, a: float, b: float, salt: int, mask: int) -> int:
    """Table index of the pattern cell ``(floor(a), floor(b))`` of the episode ``key``."""
    ia: int = math.floor(a)
    ib: int = math.floor(b)
    h = (ia * 0x9E3779B1 + ib * 0x85EBCA77 + key + salt * 0x27D4EB2F) & 0xFFFFFFFF
    h ^= h >> 15
    h = (h * 0x2C1B3C6D) & 0xFFFFFFFF
    h ^= h >> 12
    return h & mask


@njit(**JIT_PART)
def _hall(
    dx: float, dy: float, dz: float, ray: np.ndarray, params: Params, key: int, noise: np.ndarray
) -> float:
    """Grey offset (unit amplitude) of what the world ray ``(dx, dy, dz)`` from the camera
    meets beyond the carpet: the hall's floor (tiles), or its walls (advertising boards,
    spectators, plain wall above)."""
    mask = noise.shape[0] - 1
    px, py, pz = ray[0, 3], ray[1, 3], ray[2, 3]
    wx = params.hall_x if dx > 0.0 else -params.hall_x
    wy = params.hall_y if dy > 0.0 else -params.hall_y
    tx = (wx - px) / dx if abs(dx) > 1e-12 else 1e30
    ty = (wy - py) / dy if abs(dy) > 1e-12 else 1e30
    t = min(tx, ty)
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


@njit(**JIT_PART)
def _stripe(gx: float, width: float) -> float:
    """Mowing stripes across the field's length: +-1 in alternate bands ``width`` wide, with
    soft edges."""
    t = gx / (2.0 * width)
    f = t - math.floor(t)
    return min(max(8.0 * (abs(2.0 * f - 1.0) - 0.5), -1.0), 1.0)


@njit(**JIT)
def texture_row(
    v: float,
    value: np.ndarray,
    homography: np.ndarray,
    ray: np.ndarray,
    look: np.ndarray,
    params: Params,
    noise: np.ndarray,
) -> None:
    """Carpet stripes and grain on the carpet's share of each pixel of row centre ``v`` of
    ``value`` (W,), the hall on the rest. The share is read off the ground pass's grey
    (background -> 0, grass -> 1), so the carpet's anti-aliased border stays exact."""
    stripes = look[_STRIPES]
    grain = look[_GRAIN]
    clutter = look[_CLUTTER]
    width = look[_STRIPE_WIDTH]
    key = int(look[_KEY])
    mask = noise.shape[0] - 1
    bg = params.background
    span = params.grass - bg
    inv_span = 1.0 / span if abs(span) >= 1.0 else 0.0
    h = homography
    for i in range(value.shape[0]):
        u = i + 0.5
        share = 1.0 if inv_span == 0.0 else min(max((value[i] - bg) * inv_span, 0.0), 1.0)
        if share > 0.0 and (stripes != 0.0 or grain != 0.0):
            gz = h[2, 0] * u + h[2, 1] * v + h[2, 2]
            if gz > 0.0:
                gx = (h[0, 0] * u + h[0, 1] * v + h[0, 2]) / gz
                gy = (h[1, 0] * u + h[1, 1] * v + h[1, 2]) / gz
                tex = stripes * _stripe(gx, width)
                if grain != 0.0:
                    tex += grain * noise[_cell(key, gx / GRAIN_CELL, gy / GRAIN_CELL, 0, mask)]
                value[i] += share * tex
        if share < 1.0 and clutter != 0.0:
            dx = ray[0, 0] * u + ray[0, 1] * v + ray[0, 2]
            dy = ray[1, 0] * u + ray[1, 1] * v + ray[1, 2]
            dz = ray[2, 0] * u + ray[2, 1] * v + ray[2, 2]
            value[i] += (1.0 - share) * clutter * _hall(dx, dy, dz, ray, params, key, noise)


@njit(**JIT)
def worn_paint(
    v: float, lo: int, hi: int, paint: np.ndarray, homography: np.ndarray, look: np.ndarray,
    noise: np.ndarray,
) -> None:
    """Paint wear: columns ``[lo, hi)`` of ``paint`` (W,) keep :data:`WORN_KEEP` of their
    coverage in worn patches (ground cells of :data:`WEAR_CELL`; their share grows with the
    look's ``line_wear``)."""
    threshold = 4.0 * look[_WEAR] - 2.0  # a share ~ Phi(threshold) of the cells is worn
    key = int(look[_KEY])
    mask = noise.shape[0] - 1
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


@njit(**JIT)
def illuminate_row(v: float, value: np.ndarray, look: np.ndarray, params: Params) -> None:
    """Illumination of row centre ``v``: ``value * gain * (1 - vignetting r^2) + offset``,
    ``r`` the distance from the image centre relative to the corner's."""
    gain = look[_GAIN]
    offset = look[_OFFSET]
    vig = look[_VIGNETTING] / (params.cx * params.cx + params.cy * params.cy)
    dv = v - params.cy
    base = dv * dv
    for i in range(value.shape[0]):
        du = i + 0.5 - params.cx
        value[i] = value[i] * gain * (1.0 - vig * (base + du * du)) + offset


@njit(**JIT_PART)
def _gaussian_taps(sigma: float, taps: np.ndarray) -> int:
    """Normalised Gaussian weights of ``sigma`` into ``taps``; returns the radius."""
    radius: int = min(math.ceil(2.5 * sigma), (taps.shape[0] - 1) // 2)
    total = 0.0
    for k in range(-radius, radius + 1):
        w = math.exp(-0.5 * (k / sigma) ** 2)
        taps[k + radius] = w
        total += w
    for k in range(2 * radius + 1):
        taps[k] /= total
    return radius


@njit(**JIT)
def _blur(buf: np.ndarray, tmp: np.ndarray, sigma: float, bx: float, by: float) -> None:
    """Defocus (separable Gaussian of ``sigma`` px) and motion blur (the mean along the
    segment ``(bx, by)`` px centred on each pixel) of ``buf`` (H, W) in place; image edges
    repeat their border pixels."""
    height, width = buf.shape
    if sigma >= MIN_DEFOCUS:
        taps = np.empty(11)
        r = _gaussian_taps(sigma, taps)
        for j in range(height):
            for i in range(width):
                acc = 0.0
                for k in range(-r, r + 1):
                    acc += taps[k + r] * buf[j, min(max(i + k, 0), width - 1)]
                tmp[j, i] = acc
        for j in range(height):
            for i in range(width):
                acc = 0.0
                for k in range(-r, r + 1):
                    acc += taps[k + r] * tmp[min(max(j + k, 0), height - 1), i]
                buf[j, i] = acc
    length = math.sqrt(bx * bx + by * by)
    if length >= MIN_MOTION:
        samples = math.ceil(length) + 1
        tmp[:, :] = buf
        for j in range(height):
            for i in range(width):
                acc = 0.0
                for s in range(samples):
                    f = s / (samples - 1) - 0.5
                    jj = min(max(math.floor(j + 0.5 + f * by), 0), height - 1)
                    ii = min(max(math.floor(i + 0.5 + f * bx), 0), width - 1)
                    acc += tmp[jj, ii]
                buf[j, i] = acc / samples


@njit(**JIT)
def finish_frame(
    img: np.ndarray, look: np.ndarray, tone: np.ndarray, focal: float, noise: np.ndarray
) -> None:
    """Blur, sensor noise and tone curve of one rendered frame ``img`` (H, W) uint8, in
    place. Noise std ``sqrt(read^2 + shot * value)`` grey levels, the normal numbers read
    from ``noise`` at an offset hashed from the episode's key and the frame counter."""
    height, width = img.shape
    bx = look[_MOTION] * focal * look[_MOVE_PAN]
    by = look[_MOTION] * focal * look[_MOVE_TILT]
    read2 = look[_READ] * look[_READ]
    shot = look[_SHOT]
    buf = np.empty((height, width), dtype=np.float32)
    for j in range(height):
        for i in range(width):
            buf[j, i] = img[j, i]
    if look[_DEFOCUS] >= MIN_DEFOCUS or bx * bx + by * by >= MIN_MOTION * MIN_MOTION:
        _blur(buf, np.empty((height, width), dtype=np.float32), look[_DEFOCUS], bx, by)
    noisy = read2 > 0.0 or shot > 0.0
    mask = noise.shape[0] - 1
    start = _cell(int(look[_KEY]), look[_FRAME], 0.0, 6, mask)
    for j in range(height):
        for i in range(width):
            value = buf[j, i]
            if noisy:
                std = math.sqrt(read2 + shot * max(value, 0.0))
                value += std * noise[(start + j * width + i) & mask]
            img[j, i] = tone[min(max(int(value + 0.5), 0), 255)]


@njit(cache=True, fastmath=True, nogil=True, parallel=True)
def finish_kernel(
    images: np.ndarray, rows: np.ndarray, tone: np.ndarray, focal: float, noise: np.ndarray
) -> None:
    """:func:`finish_frame` for every frame of ``images`` (N, H, W), on the numba threads
    (``focal``: the nominal focal length, px, that turns head moves into motion blur)."""
    for n in prange(images.shape[0]):
        finish_frame(images[n], rows[n], tone[n], focal, noise)


@njit(**JIT)
def finish_kernel_serial(
    images: np.ndarray, rows: np.ndarray, tone: np.ndarray, focal: float, noise: np.ndarray
) -> None:
    """:func:`finish_kernel` on the calling thread."""
    for n in range(images.shape[0]):
        finish_frame(images[n], rows[n], tone[n], focal, noise)
