"""Render settings: the grey levels of the scene and optional photometric noise."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields


@dataclass(frozen=True)
class RenderConfig:
    """Grey levels (0-255) of the rendered scene and optional image noise.

    The defaults give every pair of neighbouring surfaces a clear contrast: bright lines
    and posts on mid-dark grass, a lighter grey floor/wall around the carpet, and a dark
    ball (lit from straight above, so it shades from ``ball_lit`` at its top to
    ``ball_shadow`` at its bottom) that stands out against both grass and lines.

    Noise and jitter are off by default; when on they are drawn from the ``numpy.random.
    Generator`` passed to :meth:`Renderer.render` (never a global RNG). They are applied to
    the rendered 8-bit image: ``(img - 128) * contrast + 128 + brightness + noise``, rounded
    and clipped to 0-255, with ``contrast ~ U(1 - contrast_jitter, 1 + contrast_jitter)`` and
    ``brightness ~ U(-brightness_jitter, brightness_jitter)`` drawn once per image and
    ``noise ~ N(0, noise_std^2)`` per pixel.
    """

    grass: float = 90.0  #: the green carpet (field and border strip)
    line: float = 230.0  #: painted lines, centre circle, penalty marks
    background: float = 160.0  #: everything off the carpet: the floor beyond it and the walls
    post: float = 245.0  #: goal posts and crossbars (flat white)
    ball_lit: float = 70.0  #: ball grey where its surface faces straight up
    ball_shadow: float = 15.0  #: ball grey where its surface faces straight down
    noise_std: float = 0.0  #: std of the Gaussian pixel noise (grey levels); 0: off
    brightness_jitter: float = 0.0  #: max |brightness offset| per image (grey levels); 0: off
    contrast_jitter: float = 0.0  #: max relative contrast change per image (e.g. 0.1); 0: off

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not isinstance(value, int | float) or not math.isfinite(value):
                raise ValueError(f"RenderConfig.{f.name} must be a finite number, got {value!r}")
        for name in ("grass", "line", "background", "post", "ball_lit", "ball_shadow"):
            value = getattr(self, name)
            if not 0 <= value <= 255:
                raise ValueError(f"RenderConfig.{name} must lie in [0, 255], got {value!r}")
        for name in ("noise_std", "brightness_jitter"):
            if getattr(self, name) < 0:
                raise ValueError(f"RenderConfig.{name} must be >= 0, got {getattr(self, name)!r}")
        if not 0 <= self.contrast_jitter < 1:
            raise ValueError(
                f"RenderConfig.contrast_jitter must lie in [0, 1), got {self.contrast_jitter!r}"
            )

    @property
    def has_noise(self) -> bool:
        """Whether any noise or jitter is switched on (then ``render`` needs an rng)."""
        return self.noise_std > 0 or self.brightness_jitter > 0 or self.contrast_jitter > 0
