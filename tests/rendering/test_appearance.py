"""Randomised appearance: neutral looks are the clean render byte for byte, each factor does
what it says (checked against the clean frame), and a frame's bytes depend on its own camera
and look only (not on the batch, its order, the thread path or the work memory)."""

from __future__ import annotations

import numpy as np
import pytest

import activevision.rendering.renderer as renderer_module
from activevision.geometry.occlusion import robot_cylinders
from activevision.rendering import Renderer
from activevision.rendering.appearance import (
    LOOK,
    LOOK_FIELDS,
    AppearanceConfig,
    draw_look_rows,
    draw_looks,
    neutral_looks,
    tone_curves,
)

N = 6


@pytest.fixture(scope="module")
def renderer() -> Renderer:
    return Renderer()


@pytest.fixture(scope="module")
def states():
    rng = np.random.default_rng(3)
    pose = np.column_stack(
        [rng.uniform(-3, 3, N), rng.uniform(-2, 2, N), rng.uniform(-np.pi, np.pi, N)]
    )
    pan = rng.uniform(-1.2, 1.2, N)
    tilt = rng.uniform(0.1, 0.9, N)
    bearing = pose[:, 2] + pan
    ball = pose[:, :2] + 1.5 * np.column_stack([np.cos(bearing), np.sin(bearing)])
    return pose, pan, tilt, ball


def only(name: str, value: float) -> np.ndarray:
    rows = neutral_looks(N)
    rows[:, LOOK[name]] = value
    return rows


def test_neutral_looks_are_the_clean_render(renderer, states):
    clean = renderer.render(*states)
    rows = neutral_looks(N)
    rows[:, LOOK["key"]] = 12345.0  # patterns off: the key changes nothing
    rows[:, LOOK["frame"]] = 7.0
    looked = renderer.render(*states, looks=rows, tone=tone_curves(rows))
    np.testing.assert_array_equal(looked, clean)


def test_gain_and_offset_scale_the_clean_grey(renderer, states):
    clean = renderer.render(*states).astype(float)
    rows = only("gain", 0.6)
    rows[:, LOOK["offset"]] = 10.0
    out = renderer.render(*states, looks=rows).astype(float)
    # the clean frame is rounded once, the lit one from the unrounded grey: within 1 level
    assert np.abs(out - np.clip(0.6 * clean + 10.0, 0, 255)).max() <= 1.0


def test_gamma_is_the_tone_curve_of_the_clean_frame(renderer, states):
    clean = renderer.render(*states)
    rows = only("gamma", 1.8)
    tone = tone_curves(rows)
    out = renderer.render(*states, looks=rows, tone=tone)
    np.testing.assert_array_equal(out, tone[0][clean])
    assert tone[0][128] == round(255 * (128 / 255) ** 1.8)


def test_vignetting_darkens_corners_not_the_centre(renderer, states):
    clean = renderer.render(*states).astype(float)
    out = renderer.render(*states, looks=only("vignetting", 0.5)).astype(float)
    centre = (slice(58, 62), slice(78, 82))
    assert np.abs(out[:, centre[0], centre[1]] - clean[:, centre[0], centre[1]]).max() <= 1
    kept = 1 - 0.5 * (79.5**2 + 59.5**2) / (80**2 + 60**2)  # corner pixel centre
    np.testing.assert_allclose(out[:, 0, 0], np.round(clean[:, 0, 0] * kept), atol=1)


def test_read_noise_has_its_standard_deviation(renderer, states):
    clean = renderer.render(*states).astype(float)
    out = renderer.render(*states, looks=only("read_noise", 5.0)).astype(float)
    inside = (clean > 30) & (clean < 225)  # no clipping
    diff = (out - clean)[inside]
    assert abs(diff.std() - 5.0) < 0.3 and abs(diff.mean()) < 0.2


@pytest.mark.parametrize("size", [(640, 480), (1024, 768)], ids=["vga", "xga"])
def test_noise_of_large_images_is_read_from_a_table_that_holds_them(states, size):
    # an image of at least as many pixels as the default table has numbers (2**19) gets a
    # larger one; before, 1024 x 768 read its noise beyond the table's end (a crash). Smaller
    # ones keep the default table, so their noisy frames keep their bytes.
    from activevision.geometry.camera import CameraConfig

    width, height = size
    big = Renderer(camera=CameraConfig(width=width, height=height))
    table = renderer_module.noise_table(width * height)
    if width * height < renderer_module.NOISE_TABLE_MIN:
        assert len(table) == renderer_module.NOISE_TABLE_MIN
    else:
        assert len(table) >= 2 * width * height and len(table) & (len(table) - 1) == 0
    small = renderer_module.noise_table(160 * 120)
    np.testing.assert_array_equal(table[: len(small)], small)  # the same numbers first
    pose, pan, tilt, ball = (x[:2] for x in states)
    clean = big.render(pose, pan, tilt, ball).astype(float)
    rows = only("read_noise", 5.0)[:2]
    rows[:, LOOK["key"]] = [3.0, 2.0**51]  # hashed starts far apart
    out = big.render(pose, pan, tilt, ball, looks=rows).astype(float)
    np.testing.assert_array_equal(big.render(pose, pan, tilt, ball, looks=rows), out)
    inside = (clean > 30) & (clean < 225)
    diff = (out - clean)[inside]
    assert abs(diff.std() - 5.0) < 0.1 and abs(diff.mean()) < 0.05


def test_noise_differs_between_frames_of_an_episode(renderer, states):
    a = only("read_noise", 5.0)
    b = a.copy()
    b[:, LOOK["frame"]] = 1.0
    assert (renderer.render(*states, looks=a) != renderer.render(*states, looks=b)).mean() > 0.5


@pytest.mark.parametrize("name", ["defocus", "motion_blur"])
def test_blur_smooths_and_keeps_the_mean(renderer, states, name):
    clean = renderer.render(*states).astype(float)
    rows = only(name, 1.2 if name == "defocus" else 0.5)
    rows[:, LOOK["move_pan"]] = np.radians(3.0)  # the head's move this step
    out = renderer.render(*states, looks=rows).astype(float)

    def edge_energy(img):  # blur spreads each edge: its squared steps shrink
        return (np.diff(img, axis=-1) ** 2).sum()

    assert edge_energy(out) < 0.8 * edge_energy(clean)
    assert np.abs(out.mean() - clean.mean()) < 1.0


def _box_taps(length: float) -> np.ndarray:
    """Each pixel tap's overlap with a box ``length`` px wide centred on 0."""
    r = int(np.ceil(length / 2))
    k = np.arange(-r, r + 1)
    return np.clip(np.minimum(k + 0.5, length / 2) - np.maximum(k - 0.5, -length / 2), 0, None)


@pytest.mark.parametrize(
    "name, value, move_deg, taps_x, taps_y",
    [
        # defocus sigma 1.2: a Gaussian cut at 3 px (2.5 sigma, at most 3) along both axes
        ("defocus", 1.2, 0.0, np.exp(-0.5 * (np.arange(-3, 4) / 1.2) ** 2), None),
        # smaller sigmas: 3 and 5 taps
        ("defocus", 0.3, 0.0, np.exp(-0.5 * (np.arange(-1, 2) / 0.3) ** 2), None),
        ("defocus", 0.7, 0.0, np.exp(-0.5 * (np.arange(-2, 3) / 0.7) ** 2), None),
        # motion blur: a box as long as 0.5 of the head's 3-degree pan in pixels, along x
        ("motion_blur", 0.5, 3.0, "box", np.ones(1)),
        # longer boxes along y (the head's tilt): 9 and 13 taps
        ("motion_blur", 1.0, -3.0, np.ones(1), "box"),
        ("motion_blur", 1.0, -5.0, np.ones(1), "box"),
    ],
)
def test_blur_is_the_separable_filter_of_scipy(
    renderer, states, name, value, move_deg, taps_x, taps_y
):
    """Blur against scipy's correlation of the clean frame (edges repeat the border), taps
    written out here from the documented filters: equal up to the float32 rounding of the
    kernels (a grey level either way, on a few pixels). A negative ``move_deg`` moves the
    tilt, not the pan. The cases span every tap count the kernels are compiled for."""
    ndimage = pytest.importorskip("scipy.ndimage")
    length = value * renderer.camera.focal * np.radians(abs(move_deg))
    taps_x = _box_taps(length) if isinstance(taps_x, str) else taps_x
    taps_y = taps_x if taps_y is None else taps_y
    taps_y = _box_taps(length) if isinstance(taps_y, str) else taps_y
    rows = only(name, value)
    rows[:, LOOK["move_pan" if move_deg >= 0 else "move_tilt"]] = np.radians(abs(move_deg))
    out = renderer.render(*states, looks=rows).astype(int)
    clean = renderer.render(*states).astype(float)
    ref = ndimage.correlate1d(clean, taps_x / taps_x.sum(), axis=2, mode="nearest")
    ref = ndimage.correlate1d(ref, taps_y / taps_y.sum(), axis=1, mode="nearest")
    ref = np.clip(np.floor(ref + 0.5), 0, 255).astype(int)
    assert np.abs(out - ref).max() <= 1
    assert (out != ref).mean() < 0.002


def test_motion_blur_needs_a_head_move(renderer, states):
    clean = renderer.render(*states)
    np.testing.assert_array_equal(renderer.render(*states, looks=only("motion_blur", 0.5)), clean)


@pytest.mark.parametrize(
    "name, value",
    [
        ("stripes", 15.0),
        ("grain", 10.0),
        ("line_width", 0.03),
        ("line_wear", 0.8),
        ("clutter", 50.0),
        ("mount_height", 0.05),
        ("mount_tilt", 0.05),
        ("mount_fov", 0.1),
    ],
)
def test_each_scene_factor_changes_the_frame(renderer, states, name, value):
    if name == "clutter":  # views of the horizon: the hall beyond the carpet in every one
        states = (*states[:2], np.full(N, 0.09), states[3])
    clean = renderer.render(*states)
    out = renderer.render(*states, looks=only(name, value))
    changed = (out != clean).any(axis=(1, 2))
    # every view shows the carpet; the hall only where the view has background
    shows = (clean == 160).all(axis=2).any(axis=1) if name == "clutter" else np.ones(N, bool)
    assert shows.sum() >= 2 and changed[shows].sum() >= shows.sum() - 1


def test_wider_lines_paint_more(renderer, states):
    clean = renderer.render(*states).astype(float)
    wide = renderer.render(*states, looks=only("line_width", 0.03)).astype(float)
    assert wide.sum() > clean.sum()  # lines are the brightest ground


def test_robot_cylinder_has_its_projected_width():
    r = Renderer()
    d, radius = 2.0, 0.15
    camera = np.array([-3.0, 0.8, 0.0])  # looking along +x, nothing else near
    robots = np.array([[[camera[0] + d, camera[1], 0.9, 10.0]]])
    cyl = robot_cylinders(robots, radius)
    img = r.render(camera, 0.0, r.camera.tilt_min, None, cylinders=cyl)[0]
    clean = r.render(camera, 0.0, r.camera.tilt_min, None)[0]
    rows = np.flatnonzero((img != clean).any(axis=1))
    dark = np.flatnonzero(img[rows[len(rows) // 2]] < 40)  # a row through the body
    # the silhouette spans the tangent lines: 2 f tan(asin(r / d))
    expected = 2 * r.camera.focal * radius / np.sqrt(d * d - radius * radius)
    assert abs(len(dark) - expected) <= 2
    assert abs(dark.mean() + 0.5 - r.camera.width / 2) <= 1


def random_looks(n, seed):
    rng = np.random.default_rng(seed)
    rows = np.stack([draw_looks(AppearanceConfig.randomised(), rng) for _ in range(n)])
    rows[:, LOOK["move_pan"]] = rng.uniform(-0.05, 0.05, n)
    rows[:, LOOK["frame"]] = rng.integers(0, 20, n)
    robots = np.zeros((n, 2, 4))
    robots[:, 0] = [1.0, 0.3, 0.8, 60.0]
    return rows, tone_curves(rows), robot_cylinders(robots, 0.12)


def test_a_frame_depends_on_its_camera_and_look_only(renderer, states, monkeypatch):
    pose, pan, tilt, ball = states
    rows, tone, cyl = random_looks(N, 1)
    cyl[:, :, :2] += pose[:, None, :2]  # a robot 1 m in front of each camera
    batch = renderer.render(*states, looks=rows, tone=tone, cylinders=cyl)
    for k in range(N):
        alone = renderer.render(
            pose[k],
            pan[k],
            tilt[k],
            ball[k],
            looks=rows[k : k + 1],
            tone=tone[k : k + 1],
            cylinders=cyl[k : k + 1],
        )
        np.testing.assert_array_equal(alone[0], batch[k])
    order = np.random.default_rng(0).permutation(N)
    shuffled = renderer.render(
        pose[order],
        pan[order],
        tilt[order],
        ball[order],
        looks=rows[order],
        tone=tone[order],
        cylinders=cyl[order],
    )
    np.testing.assert_array_equal(shuffled, batch[order])
    serial = Renderer(parallel=False).render(*states, looks=rows, tone=tone, cylinders=cyl)
    np.testing.assert_array_equal(serial, batch)
    for seed in (101, 102, 103):
        monkeypatch.setattr(renderer_module, "_WORK_GARBAGE_SEED", seed)
        dirty = renderer.render(*states, looks=rows, tone=tone, cylinders=cyl)
        np.testing.assert_array_equal(dirty, batch)
        dirty = Renderer(parallel=False).render(*states, looks=rows, tone=tone, cylinders=cyl)
        np.testing.assert_array_equal(dirty, batch)


def test_bad_looks_are_clear_errors(renderer, states):
    with pytest.raises(ValueError, match="looks must have shape"):
        renderer.render(*states, looks=np.zeros((N, 3)))
    with pytest.raises(ValueError, match="tone must be a uint8"):
        renderer.render(*states, looks=neutral_looks(N), tone=np.zeros((N, 256)))
    with pytest.raises(ValueError, match="cylinders"):
        renderer.render(*states, cylinders=np.zeros((N, 1, 5)))
    assert len(LOOK_FIELDS) == len(set(LOOK_FIELDS))


def test_config_ranges_are_checked():
    with pytest.raises(ValueError, match=r"AppearanceConfig\.gain"):
        AppearanceConfig(gain=(1.2, 1.0))
    with pytest.raises(ValueError, match=r"AppearanceConfig\.defocus"):
        AppearanceConfig(defocus=(0.0, 9.0))
    assert not AppearanceConfig().enabled and AppearanceConfig.randomised().enabled
    with pytest.raises(ValueError, match=r"AppearanceConfig\.neutral_share"):
        AppearanceConfig.randomised().replace(neutral_share=1.5)
    # a share of neutral episodes among none randomised: refused, not silently a no-op
    with pytest.raises(ValueError, match=r"AppearanceConfig\.neutral_share: .* switch one on"):
        AppearanceConfig(neutral_share=0.5)
    assert not AppearanceConfig(stripe_width=(0.2, 0.4)).enabled  # the width alone is no factor
    assert AppearanceConfig(mount_fov=(0.0, 0.01)).enabled


def test_looks_drawn_at_once_follow_the_documented_order_and_ranges():
    # draw_look_rows: every row's neutral decision first, then the factors row by row, then
    # the keys; draw_looks is its one-row case (the envs' bytes stay those of before)
    config = AppearanceConfig.randomised().replace(neutral_share=0.4, clutter=(10.0, 85.0))
    n = 500
    rows = draw_look_rows(config, n, np.random.default_rng(7))
    rng = np.random.default_rng(7)
    neutral = rng.random(n) < 0.4
    u = rng.random((n, LOOK["key"]))
    keys = rng.integers(0, 2**52, n)
    np.testing.assert_array_equal(rows[:, LOOK["key"]], keys.astype(float))
    lo, hi = config.clutter
    clutter = rows[:, LOOK["clutter"]]
    np.testing.assert_array_equal(clutter[~neutral], lo + (hi - lo) * u[~neutral, LOOK["clutter"]])
    np.testing.assert_array_equal(clutter[neutral], 0.0)
    tilt = rows[~neutral, LOOK["mount_tilt"]]
    np.testing.assert_allclose(tilt, np.radians(-3.0 + 6.0 * u[~neutral, LOOK["mount_tilt"]]))
    factors = slice(0, LOOK["key"])
    clean = neutral_looks(int(neutral.sum()))
    np.testing.assert_array_equal(rows[neutral][:, factors], clean[:, factors])
    assert 160 <= neutral.sum() <= 240  # 40% of 500: 200 +- 3.6 standard deviations
    np.testing.assert_array_equal(rows[:, LOOK["key"] + 1 :], 0.0)  # per-frame columns
    for seed in range(50):
        one = draw_look_rows(config, 1, np.random.default_rng(seed))[0]
        np.testing.assert_array_equal(one, draw_looks(config, np.random.default_rng(seed)))


def test_a_neutral_share_of_episodes_draws_the_clean_look_and_the_rest_as_before():
    robust = AppearanceConfig.randomised()
    mixed = robust.replace(neutral_share=0.3)
    factors = slice(0, LOOK["key"])
    neutral = 0
    for seed in range(400):
        row = draw_looks(mixed, np.random.default_rng(seed))
        rng = np.random.default_rng(seed)
        decided = rng.random() < 0.3  # the first number decides; the draws follow as before
        alone = draw_looks(robust, rng)
        assert row[LOOK["key"]] == alone[LOOK["key"]]
        if decided:
            np.testing.assert_array_equal(row[factors], neutral_looks(1)[0, factors])
            neutral += 1
        else:
            np.testing.assert_array_equal(row, alone)
    assert 90 <= neutral <= 150  # 30% of 400: 120 +- 3.3 standard deviations
