"""Image augmentation for replay batches: DrQ's random shift.

Kostrikov et al. (2021, DrQ) and Yarats et al. (2021, DrQ-v2) pad each image by a few pixels,
repeating its border, and crop it back at a random offset, separately for ``obs`` and
``next_obs``; on pixel-based benchmarks this regularises the encoder when frames are few.
"""

from __future__ import annotations

import numpy as np


def random_shifts(images: np.ndarray, max_shift: int, rng: np.random.Generator) -> np.ndarray:
    """Each image of a (B, C, H, W) batch shifted by up to ``max_shift`` pixels per axis.

    One offset per image (its channels, e.g. a frame stack, move together); the border pixels
    fill what the shift uncovers. ``max_shift=0`` returns the images unchanged (and draws nothing).
    """
    if images.ndim != 4:
        raise ValueError(f"random_shifts needs (B, C, H, W) images, got shape {images.shape}")
    if max_shift < 0:
        raise ValueError(f"max_shift must be >= 0, got {max_shift}")
    if max_shift == 0:
        return images
    batch, channels, height, width = images.shape
    pad = int(max_shift)
    padded = np.pad(images, ((0, 0), (0, 0), (pad, pad), (pad, pad)), mode="edge")
    top, left = rng.integers(0, 2 * pad + 1, size=(2, batch))
    rows = (top[:, None] + np.arange(height))[:, None, :, None]  # (B, 1, H, 1)
    cols = (left[:, None] + np.arange(width))[:, None, None, :]  # (B, 1, 1, W)
    samples = np.arange(batch)[:, None, None, None]
    shifted: np.ndarray = padded[samples, np.arange(channels)[None, :, None, None], rows, cols]
    return shifted
