"""Off-screen figures without pyplot: a :class:`~matplotlib.figure.Figure` on its own Agg
canvas, so drawing never touches the user's backend or pyplot's global figures."""

from __future__ import annotations

import io
import math
import numbers
import os
import re
import textwrap
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, BinaryIO

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from activevision.io import atomic_path


def new_figure(**kwargs: Any) -> Figure:
    """A :class:`Figure` (``figsize``, ``layout``, ... as for ``Figure``) drawn by Agg."""
    fig = Figure(**kwargs)
    FigureCanvasAgg(fig)
    return fig


def figure_to_rgb(fig: Figure) -> np.ndarray:
    """The figure rendered as an (H, W, 3) uint8 RGB array."""
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()


#: Characters a line of a legend's label is cut to, widest first, where a label does not fit
#: the figure's width in one column.
_LABEL_LINES = (60, 40, 30, 20, 10)


def fit_legend(
    fig: Figure, handles: Sequence[Any], labels: Sequence[str], columns: int, **kwargs: Any
) -> tuple[int, list[str]]:
    """The most columns, up to ``columns``, and the labels in which
    ``fig.legend(handles, labels, ncol=..., **kwargs)`` is no wider than the figure: a label
    too wide for one column is broken into lines (long method names ran past the figure's
    edge). The legend itself is for the caller to place; ``columns`` and ``labels`` come
    back as they are where they fit."""
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]

    def fits(ncol: int, names: list[str]) -> bool:
        legend = fig.legend(handles, names, ncol=ncol, **kwargs)
        width = legend.get_window_extent(renderer).width
        legend.remove()
        return bool(width <= fig.bbox.width)

    names = list(labels)
    for ncol in range(max(1, columns), 0, -1):
        if fits(ncol, names):
            return ncol, names
    for chars in _LABEL_LINES:
        names = [textwrap.fill(label, chars) for label in labels]
        if fits(1, names):
            break
    return 1, names


#: The format a figure is written in, by its file's suffix: those both writers below handle
#: with matplotlib's own dependencies (not .pgf, which needs LaTeX, nor raw pixel dumps; GIF
#: is an animation's, :func:`save_gif`).
FIGURE_FORMATS = {
    "png": "png",
    "pdf": "pdf",
    "svg": "svg",
    "eps": "eps",
    "ps": "ps",
    "jpg": "jpeg",
    "jpeg": "jpeg",
    "tif": "tiff",
    "tiff": "tiff",
    "webp": "webp",
}


def figure_format(path: str | os.PathLike[str]) -> str:
    """The format a figure at ``path`` is written in, named by its suffix (PNG when it has
    none). ValueError naming the path when no format has that suffix (a ``.pdf`` must not
    hold a PNG)."""
    suffix = Path(path).suffix.lower().removeprefix(".")
    if not suffix:
        return "png"
    if suffix not in FIGURE_FORMATS:
        names = ", ".join(f".{name}" for name in FIGURE_FORMATS)
        raise ValueError(f"{path}: a figure is written as one of {names}; not .{suffix}")
    return FIGURE_FORMATS[suffix]


#: Metadata that leaves out the creation date matplotlib writes by default (the same figure
#: is then the same bytes at any time), by format; PNG and Pillow's formats write none.
_NO_DATE: dict[str, dict[str, Any]] = {"pdf": {"CreationDate": None}, "svg": {"Date": None}}
#: PostScript's date line, which no metadata key leaves out: it is set to the epoch after
#: writing (as matplotlib writes it under SOURCE_DATE_EPOCH=0; setting that variable here
#: would change the process's environment under any other thread).
_PS_DATE = re.compile(rb"^%%CreationDate: [^\r\n]*", re.MULTILINE)
_PS_EPOCH = b"%%CreationDate: Thu Jan 01 00:00:00 1970"


def _write_same_bytes(
    path: str | os.PathLike[str], write: Callable[[BinaryIO, str, dict[str, Any] | None], None]
) -> None:
    """Write ``path`` atomically with ``write(file, format, metadata)``, in the format its
    suffix names (:func:`figure_format`), so that the same figure is the same bytes in any
    process and at any time: no creation date (PDF, SVG: by metadata; PostScript: its date
    line, unless the user's SOURCE_DATE_EPOCH sets it), and SVG ids hashed with a fixed salt
    (matplotlib salts them with a random UUID per process by default). An open file, not the
    temporary's name, which PostScript would write as its title."""
    file_format = figure_format(path)
    with (
        atomic_path(path) as tmp,
        tmp.open("wb") as f,
        matplotlib.rc_context({"svg.hashsalt": "activevision"}),
    ):
        if file_format not in ("ps", "eps") or "SOURCE_DATE_EPOCH" in os.environ:
            write(f, file_format, _NO_DATE.get(file_format))  # None: the writer's own
            return
        buffer = io.BytesIO()
        write(buffer, file_format, None)
        f.write(_PS_DATE.sub(_PS_EPOCH, buffer.getvalue(), count=1))


def save_figure(fig: Figure, path: str | os.PathLike[str], dpi: float) -> None:
    """Write the figure atomically, in the format its suffix names (:func:`figure_format`),
    the same bytes for the same figure (no dates, no random ids)."""
    _write_same_bytes(
        path, lambda f, fmt, metadata: fig.savefig(f, dpi=dpi, format=fmt, metadata=metadata)
    )


def save_rgb(rgb: np.ndarray, path: str | os.PathLike[str]) -> None:
    """Write an RGB array atomically, in the format its suffix names (:func:`figure_format`),
    the same bytes for the same array (as :func:`save_figure`)."""
    from matplotlib.image import imsave

    _write_same_bytes(path, lambda f, fmt, metadata: imsave(f, rgb, format=fmt, metadata=metadata))


def check_fps(fps: object) -> float:
    """``fps`` as a float, if a finite positive number: a ValueError naming it otherwise
    (0 was a ZeroDivisionError, a negative or NaN a GIF of nonsense durations)."""
    if isinstance(fps, bool) or not isinstance(fps, numbers.Real):
        raise TypeError(f"fps: expects a positive number, got {fps!r}")
    if not math.isfinite(fps) or fps <= 0:
        raise ValueError(f"fps: expects a finite positive number, got {fps!r}")
    return float(fps)


def _check_frames(frames: Sequence[np.ndarray]) -> None:
    """TypeError unless every frame is an array, ValueError unless there is one at least,
    each (H, W, 3) uint8 with H, W > 0 and all of one shape (an empty list was an
    IndexError, other frames Pillow's errors or a GIF of mixed sizes), naming the frame."""
    if len(frames) == 0:
        raise ValueError("frames: expects at least one frame, got none")
    first = frames[0]
    for index, frame in enumerate(frames):
        if not isinstance(frame, np.ndarray):
            raise TypeError(f"frames[{index}]: expects a numpy array, got {type(frame).__name__}")
        shape = frame.shape
        if len(shape) != 3 or shape[2] != 3 or 0 in shape or frame.dtype != np.uint8:
            raise ValueError(
                f"frames[{index}]: expects an (H, W, 3) uint8 RGB array, "
                f"got shape {shape} of {frame.dtype}"
            )
        if shape != first.shape:
            raise ValueError(
                f"frames[{index}]: expects every frame of one shape, got {shape} "
                f"after {first.shape}"
            )


def save_gif(frames: Sequence[np.ndarray], path: str | os.PathLike[str], fps: float) -> None:
    """Write RGB frames (H, W, 3) uint8, all of one shape, as a looping animated GIF shown at
    ``fps`` (a positive number) frames a second, atomically (Pillow, matplotlib's own
    dependency). Bad frames or fps are refused before anything is written."""
    from PIL import Image

    fps = check_fps(fps)
    frames = list(frames)  # an iterator of frames, as was taken, is checked and saved once
    _check_frames(frames)
    images = [Image.fromarray(f) for f in frames]
    with atomic_path(path) as tmp:
        images[0].save(
            tmp,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            duration=int(1000 / fps),
            loop=0,
        )
