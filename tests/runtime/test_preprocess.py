"""Grey conversion and area-averaging resize of camera frames (runtime.preprocess)."""

from __future__ import annotations

import numpy as np
import pytest

from activevision.runtime import FramePreprocessor, area_weights

prep = FramePreprocessor(120, 160)


def block_mean_half_up(grey: np.ndarray, fy: int, fx: int) -> np.ndarray:
    sums = grey.astype(np.int64).reshape(120, fy, 160, fx).sum(axis=(1, 3))
    return ((2 * sums + fy * fx) // (2 * fy * fx)).astype(np.uint8)  # floor(mean + 1/2)


@pytest.mark.parametrize(("width", "height"), [(160, 120), (320, 240), (640, 480), (480, 360)])
def test_integer_multiple_grey_is_exact_block_mean(frames, width, height):
    for frame in frames(width, height):
        expected = block_mean_half_up(frame, height // 120, width // 160)
        np.testing.assert_array_equal(prep(frame), expected)
        np.testing.assert_array_equal(prep(frame[:, :, None]), expected)  # (H, W, 1)


def test_views_of_a_larger_frame_resize_as_their_copies(helpers):
    """Crops, flips and channel-reversed views (not C-contiguous) through the compiled path."""
    big = helpers.colourise(
        np.random.default_rng(3).integers(0, 256, (500, 700), dtype=np.uint8), seed=3
    )
    for view in (big[10:490, 30:670], big[:480, :640][::-1], big[:480, :640, ::-1]):
        want = prep(np.ascontiguousarray(view))
        np.testing.assert_array_equal(prep(view), want)
        assert np.abs(want.astype(int) - helpers.reference_preprocess(view, "rgb")).max() <= 1


def test_block_mean_rounds_half_up():
    frame = np.zeros((240, 320), dtype=np.uint8)
    frame[0, 0] = 2  # block sum 2 -> mean 0.5 -> 1
    frame[0, 2] = 1  # block sum 1 -> mean 0.25 -> 0
    out = prep(frame)
    assert out[0, 0] == 1 and out[0, 1] == 0


def test_random_noise_integer_multiple_is_exact():
    frame = np.random.default_rng(1).integers(0, 256, (480, 640), dtype=np.uint8)
    np.testing.assert_array_equal(prep(frame), block_mean_half_up(frame, 4, 4))


@pytest.mark.parametrize(("width", "height"), [(160, 120), (640, 480), (320, 240), (333, 250)])
def test_colour_and_odd_sizes_match_float64_reference(frames, helpers, width, height):
    for i, grey in enumerate(frames(width, height)):
        rgb = helpers.colourise(grey, seed=i)
        bgr = np.ascontiguousarray(rgb[:, :, ::-1])
        for frame, order in ((grey, "rgb"), (rgb, "rgb"), (bgr, "bgr")):
            got = prep(frame, order).astype(int)
            want = helpers.reference_preprocess(frame, order).astype(int)
            assert np.abs(got - want).max() <= 1  # float32 vs float64 at .5 boundaries
            assert np.mean(got == want) > 0.995


def test_bgr_is_rgb_reversed(frames, helpers):
    rgb = helpers.colourise(frames(640, 480)[0])
    np.testing.assert_array_equal(prep(rgb, "rgb"), prep(rgb[:, :, ::-1], "bgr"))
    assert not np.array_equal(prep(rgb, "rgb"), prep(rgb, "bgr"))


def test_uniform_colour_gives_bt601_luma():
    frame = np.empty((250, 333, 3), dtype=np.uint8)
    frame[:] = (200, 100, 50)
    expected = int(np.floor(0.299 * 200 + 0.587 * 100 + 0.114 * 50 + 0.5))
    assert np.all(prep(frame) == expected)
    assert np.all(prep(frame[::2, ::2]) == expected)  # non-contiguous view, upscaling size


def test_area_weights_rows_sum_to_one_and_integer_case_is_box():
    for n_in, n_out in ((250, 120), (333, 160), (60, 120), (121, 120), (1080, 120)):
        index, weight = area_weights(n_in, n_out)
        np.testing.assert_allclose(weight.sum(axis=1), 1.0, rtol=1e-6)
        assert index.min() >= 0 and index.max() < n_in
    index, weight = area_weights(480, 120)
    np.testing.assert_array_equal(index, np.arange(480).reshape(120, 4))
    np.testing.assert_allclose(weight, 0.25)


def test_upscaling_is_nearest_neighbour():
    frame = np.random.default_rng(2).integers(0, 256, (60, 80), dtype=np.uint8)
    np.testing.assert_array_equal(prep(frame), np.repeat(np.repeat(frame, 2, 0), 2, 1))


def test_writes_into_out():
    out = np.zeros((120, 160), dtype=np.uint8)
    frame = np.full((480, 640), 7, dtype=np.uint8)
    assert prep(frame, out=out) is out and np.all(out == 7)


@pytest.mark.parametrize(
    ("frame", "message"),
    [
        (np.zeros((120, 160), dtype=np.float32), "dtype uint8"),
        (np.zeros((120, 160, 3), dtype=np.float64), "dtype uint8"),
        (np.zeros((120, 160, 4), dtype=np.uint8), "got 4 .* drop the alpha channel"),
        (np.zeros((3, 120, 160), dtype=np.uint8), r"channel-first: give frame\.transpose"),
        (np.zeros((120, 160), dtype=np.uint16), "16-bit image"),
        (np.zeros((120, 160), dtype=bool), "the camera's 8-bit image"),
        (np.zeros((120, 160, 2), dtype=np.uint8), "channels"),
        (np.zeros(19200, dtype=np.uint8), "1-D"),
        (np.zeros((1, 120, 160, 3), dtype=np.uint8), "4-D"),
        (np.zeros((0, 160), dtype=np.uint8), "empty"),
        ([[0, 1], [2, 3]], "numpy"),
    ],
)
def test_bad_frames_raise_value_error(frame, message):
    with pytest.raises(ValueError, match=message):
        prep(frame)


def test_bad_color_order():
    with pytest.raises(ValueError, match="color_order"):
        prep(np.zeros((120, 160, 3), dtype=np.uint8), "rgba")
