"""Figures are written in the format their file's suffix names, by both writers (a figure
and an RGB array), atomically: no temporary file is left beside them; the same figure is the
same bytes (no creation date, no random SVG ids, no temporary file's name)."""

from __future__ import annotations

import os

import numpy as np
import pytest

from activevision.figures.canvas import (
    FIGURE_FORMATS,
    figure_format,
    new_figure,
    save_figure,
    save_gif,
    save_rgb,
)

#: How each format's file begins.
MAGIC = {
    "png": [b"\x89PNG"],
    "pdf": [b"%PDF"],
    "svg": [b"<?xml"],
    "eps": [b"%!PS-Adobe"],
    "ps": [b"%!PS-Adobe"],
    "jpeg": [b"\xff\xd8\xff"],
    "tiff": [b"II*\x00", b"MM\x00*"],
    "webp": [b"RIFF"],
}


def test_every_suffix_has_a_known_file_format():
    assert set(FIGURE_FORMATS.values()) == set(MAGIC)


@pytest.mark.parametrize("suffix", sorted(FIGURE_FORMATS))
def test_both_writers_write_every_format_the_suffix_names(tmp_path, suffix):
    fig = new_figure(figsize=(2, 1.5))
    ax = fig.add_subplot()
    ax.imshow(np.arange(12).reshape(3, 4))
    ax.plot([0, 3], [0, 2])
    rgb = (np.arange(40 * 60 * 3) % 251).astype(np.uint8).reshape(40, 60, 3)
    for name, write in [
        ("figure", lambda p: save_figure(fig, p, dpi=50)),
        ("rgb", lambda p: save_rgb(rgb, p)),
    ]:
        path = tmp_path / f"{name}.{suffix}"
        write(path)
        head = path.read_bytes()[:16]
        assert any(head.startswith(m) for m in MAGIC[FIGURE_FORMATS[suffix]]), (name, head)
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"figure.{suffix}", f"rgb.{suffix}"]


def test_a_path_without_suffix_is_png_and_others_are_refused(tmp_path):
    assert figure_format(tmp_path / "plain") == "png"
    assert figure_format(tmp_path / "x.PDF") == "pdf"
    assert figure_format(tmp_path / "x.tif") == "tiff"
    for suffix in ("txt", "pgf", "raw", "gif"):
        with pytest.raises(ValueError, match=rf"not \.{suffix}"):
            figure_format(tmp_path / f"x.{suffix}")


@pytest.mark.parametrize("suffix", sorted(FIGURE_FORMATS))
def test_the_same_figure_is_the_same_bytes_in_every_format(tmp_path, suffix, monkeypatch):
    """matplotlib writes the time into PDF, SVG and PostScript, salts SVG ids with a random
    UUID and titles PostScript with the file's name (here a random temporary one) unless
    told otherwise: two writes under other names in other folders must still be equal."""
    # a shell that sets SOURCE_DATE_EPOCH (reproducible-build tooling) dates PostScript
    # itself: this test is of the package's own pinning
    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
    fig = new_figure(figsize=(2, 1.5))
    ax = fig.add_subplot()
    ax.imshow(np.arange(12).reshape(3, 4))
    ax.plot([0, 3], [0, 2])
    ax.set_title("same")
    rgb = (np.arange(40 * 60 * 3) % 251).astype(np.uint8).reshape(40, 60, 3)
    for name, write in [
        ("figure", lambda p: save_figure(fig, p, dpi=50)),
        ("rgb", lambda p: save_rgb(rgb, p)),
    ]:
        first, second = tmp_path / f"{name}.{suffix}", tmp_path / "other" / f"x.{suffix}"
        write(first)
        write(second)
        data = first.read_bytes()
        assert data == second.read_bytes(), name
        assert b"CreationDate (" not in data and b"<dc:date>" not in data
        if FIGURE_FORMATS[suffix] in ("ps", "eps"):
            assert b"%%CreationDate: Thu Jan 01 00:00:00 1970" in data and b".tmp" not in data
    assert "SOURCE_DATE_EPOCH" not in os.environ


@pytest.mark.parametrize("suffix", ["ps", "eps"])
def test_postscript_is_dated_without_touching_the_environment(tmp_path, suffix, monkeypatch):
    # The date was pinned by setting SOURCE_DATE_EPOCH for the write: any other thread saw
    # the process's environment change. Now the environment is never written, and a user's
    # own SOURCE_DATE_EPOCH still dates the file.
    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)  # not the shell's own
    seen = []
    monkeypatch.setattr(os, "putenv", lambda *a: seen.append(a))
    monkeypatch.setattr(os, "unsetenv", lambda *a: seen.append(a))
    fig = new_figure(figsize=(2, 1.5))
    fig.add_subplot().plot([0, 1])
    save_figure(fig, tmp_path / f"a.{suffix}", dpi=50)
    assert seen == []
    assert b"%%CreationDate: Thu Jan 01 00:00:00 1970\n" in (tmp_path / f"a.{suffix}").read_bytes()
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "86400")
    save_figure(fig, tmp_path / f"b.{suffix}", dpi=50)
    assert b"%%CreationDate: Fri Jan 02 00:00:00 1970" in (tmp_path / f"b.{suffix}").read_bytes()


def _frames(count: int = 2, shape: tuple[int, ...] = (4, 6, 3)) -> list[np.ndarray]:
    return [np.full(shape, 40 * i, dtype=np.uint8) for i in range(count)]


def test_save_gif_writes_a_looping_gif_of_every_frame(tmp_path):
    from PIL import Image

    save_gif(_frames(3), tmp_path / "a.gif", fps=4)
    save_gif(iter(_frames(3)), tmp_path / "b.gif", fps=4.0)
    assert (tmp_path / "a.gif").read_bytes() == (tmp_path / "b.gif").read_bytes()
    with Image.open(tmp_path / "a.gif") as gif:
        assert (gif.n_frames, gif.info["duration"], gif.info["loop"]) == (3, 250, 0)


@pytest.mark.parametrize(
    ("frames", "fps", "error", "match"),
    [
        ([], 2, ValueError, r"frames: expects at least one frame, got none"),
        (_frames(), 0, ValueError, r"fps: expects a finite positive number, got 0"),
        (_frames(), -2.0, ValueError, r"fps: expects a finite positive number, got -2\.0"),
        (_frames(), float("nan"), ValueError, r"fps: expects a finite positive number, got nan"),
        (_frames(), float("inf"), ValueError, r"fps: expects a finite positive number"),
        (_frames(), "2", TypeError, r"fps: expects a positive number, got '2'"),
        (_frames(), True, TypeError, r"fps: expects a positive number, got True"),
        (_frames() + _frames(1, (5, 6, 3)), 2, ValueError, r"frames\[2\]: .* of one shape"),
        (_frames(1, (4, 6)), 2, ValueError, r"frames\[0\]: expects an \(H, W, 3\) uint8"),
        (_frames(1, (4, 6, 4)), 2, ValueError, r"frames\[0\]: expects an \(H, W, 3\) uint8"),
        (_frames(1, (0, 6, 3)), 2, ValueError, r"frames\[0\]: expects an \(H, W, 3\) uint8"),
        ([np.zeros((4, 6, 3))], 2, ValueError, r"frames\[0\]: .* got shape \(4, 6, 3\) of float64"),
        ([[[[0, 0, 0]]]], 2, TypeError, r"frames\[0\]: expects a numpy array, got list"),
    ],
)
def test_save_gif_refuses_bad_frames_or_fps_before_writing(tmp_path, frames, fps, error, match):
    with pytest.raises(error, match=match):
        save_gif(frames, tmp_path / "a.gif", fps=fps)
    assert list(tmp_path.iterdir()) == []
