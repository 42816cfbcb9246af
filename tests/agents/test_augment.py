import numpy as np
import pytest

from activevision.agents.augment import random_shifts


def test_random_shifts_crop_the_edge_padded_image_at_the_drawn_offsets():
    images = np.random.default_rng(0).integers(0, 256, size=(16, 2, 7, 9), dtype=np.uint8)
    shifted = random_shifts(images, 3, np.random.default_rng(1))
    top, left = np.random.default_rng(1).integers(0, 7, size=(2, 16))  # the same draws
    assert shifted.shape == images.shape and shifted.dtype == np.uint8
    for i in range(16):  # one image at a time, by hand
        for c in range(2):
            padded = np.pad(images[i, c], 3, mode="edge")
            crop = padded[top[i] : top[i] + 7, left[i] : left[i] + 9]
            np.testing.assert_array_equal(shifted[i, c], crop)
    assert len({(t, l) for t, l in zip(top, left, strict=True)}) > 1  # the shifts differ


def test_a_shift_moves_content_and_repeats_the_border():
    image = np.arange(20, dtype=np.uint8).reshape(1, 1, 4, 5)

    class Fixed:  # offsets (top, left) = (0, 2): content moves down 1 row and left 1 column
        def integers(self, low, high, size):
            return np.array([[0], [2]])

    shifted = random_shifts(image, 1, Fixed())[0, 0]
    expected = np.array(
        [[1, 2, 3, 4, 4], [1, 2, 3, 4, 4], [6, 7, 8, 9, 9], [11, 12, 13, 14, 14]], dtype=np.uint8
    )
    np.testing.assert_array_equal(shifted, expected)


def test_no_shift_and_bad_input():
    images = np.zeros((2, 1, 4, 4), np.uint8)
    assert random_shifts(images, 0, np.random.default_rng(0)) is images
    with pytest.raises(ValueError, match="B, C, H, W"):
        random_shifts(images[0], 2, np.random.default_rng(0))
    with pytest.raises(ValueError, match="max_shift"):
        random_shifts(images, -1, np.random.default_rng(0))
