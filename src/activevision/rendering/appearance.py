"""Randomised appearance (domain randomisation, Tobin et al. 2017): what makes a rendered frame
look like one from a real robot's camera, drawn per episode.

:class:`AppearanceConfig` gives each factor a range ``(low, high)``; every episode draws each
factor uniformly from its range with the episode's own generator. A range at its neutral
value (``(1, 1)`` for a gain, ``(0, 0)`` for the rest) switches the factor off, and with every
factor off (the default) the renderer draws exactly the paper's clean world, byte for byte.
:meth:`AppearanceConfig.randomised` switches everything on at the documented ranges.

The draw of one episode is a row of :data:`LOOK_FIELDS` (:func:`draw_looks`), whose gamma
becomes a tone curve (:func:`tone_curves`); the renderer's compiled kernels apply them
(:mod:`.kernels.looks`):

* in the scene: carpet mowing stripes and grain, painted line width and wear, a hall beyond
  the carpet (advertising boards, spectators, wall), the camera mount (height, tilt, field of
  view differ from the robot's model, which stays nominal for everything but the image);
* on the image: illumination gain and offset, vignetting, defocus blur, motion blur along
  the head's move of that step, Gaussian read noise plus signal-dependent shot noise, and
  gamma (the tone curve), in that (physical) order.

Patterns are hashed from the episode's key and ground or wall coordinates, so the carpet
does not change as the head moves; sensor noise is hashed from the key, the frame counter
and the pixel, so a frame's bytes do not depend on the batch it was rendered in.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field

import numpy as np

from activevision.typecheck import check_dataclass_fields, in_range

Range = tuple[float, float]

#: Columns of a per-camera look row (float64): the episode's draws, then per-frame values.
LOOK_FIELDS = (
    "gain",  # illumination gain
    "offset",  # illumination offset (grey levels)
    "vignetting",  # share of brightness lost in the image corners
    "read_noise",  # Gaussian noise std (grey levels)
    "shot_noise",  # shot noise: variance per grey level
    "defocus",  # Gaussian blur sigma (px)
    "motion_blur",  # exposure as a share of the step's head move
    "stripes",  # mowing stripe amplitude (grey levels)
    "stripe_width",  # m
    "grain",  # carpet grain amplitude (grey levels)
    "line_width",  # change of the painted line width (m)
    "line_wear",  # share of paint worn off in patches
    "clutter",  # contrast of the hall beyond the carpet (grey levels)
    "mount_height",  # camera height offset (m)
    "mount_tilt",  # camera tilt offset (rad, down)
    "mount_fov",  # relative change of the horizontal field of view
    "gamma",  # tone curve exponent (applied through the tone curve, :func:`tone_curves`)
    "key",  # the episode's pattern key (an integer below 2**52)
    "move_pan",  # this frame's head move (rad), for motion blur
    "move_tilt",
    "frame",  # frame counter of the episode (noise key)
)
LOOK = {name: i for i, name in enumerate(LOOK_FIELDS)}
#: Looks columns an episode draws (the rest are set per frame).
_DRAWN = LOOK_FIELDS[: LOOK["key"]]


def _bounds(low: float, high: float) -> dict[str, tuple[float, float]]:
    """Field metadata: the ends of a factor's range must lie within ``[low, high]``."""
    return {"bounds": (low, high)}


@dataclass(frozen=True)
class AppearanceConfig:
    """Ranges ``(low, high)`` of the appearance factors drawn per episode (uniform). The
    defaults are neutral: the paper's clean render. :meth:`randomised` gives the robust
    ranges (in brackets below); they are chosen to span what RoboCup venues and the usual
    KidSize cameras (Logitech C9xx class, auto-exposure) show, not measured on one venue."""

    #: illumination gain [0.55, 1.45]
    gain: Range = field(default=(1.0, 1.0), metadata=_bounds(0.05, 4.0))
    #: grey offset [-25, 25]
    offset: Range = field(default=(0.0, 0.0), metadata=_bounds(-128.0, 128.0))
    #: tone curve exponent [0.7, 1.5]
    gamma: Range = field(default=(1.0, 1.0), metadata=_bounds(0.2, 5.0))
    #: brightness lost at corners [0, 0.45]
    vignetting: Range = field(default=(0.0, 0.0), metadata=_bounds(0.0, 0.9))
    #: Gaussian noise std [0, 6]
    read_noise: Range = field(default=(0.0, 0.0), metadata=_bounds(0.0, 64.0))
    #: variance per grey level [0, 0.6]
    shot_noise: Range = field(default=(0.0, 0.0), metadata=_bounds(0.0, 16.0))
    #: Gaussian blur sigma, px [0, 1.2]
    defocus: Range = field(default=(0.0, 0.0), metadata=_bounds(0.0, 4.0))
    #: exposure as a share of the step's head move (blur length = share x move in px) [0, 0.4]
    motion_blur: Range = field(default=(0.0, 0.0), metadata=_bounds(0.0, 1.0))
    #: mowing stripe amplitude, grey [0, 12]
    stripes: Range = field(default=(0.0, 0.0), metadata=_bounds(0.0, 64.0))
    #: mowing stripe width, m (used with stripes)
    stripe_width: Range = field(default=(0.5, 1.0), metadata=_bounds(0.1, 5.0))
    #: carpet grain amplitude, grey [0, 10]
    grain: Range = field(default=(0.0, 0.0), metadata=_bounds(0.0, 64.0))
    #: line width change, m [-0.015, 0.02]
    line_width: Range = field(default=(0.0, 0.0), metadata=_bounds(-0.03, 0.05))
    #: share of paint worn off [0, 0.5]
    line_wear: Range = field(default=(0.0, 0.0), metadata=_bounds(0.0, 1.0))
    #: contrast of the hall, grey [0, 60]
    clutter: Range = field(default=(0.0, 0.0), metadata=_bounds(0.0, 128.0))
    #: camera height offset, m [-0.03, 0.03]
    mount_height: Range = field(default=(0.0, 0.0), metadata=_bounds(-0.2, 0.2))
    #: tilt offset, deg [-3, 3]
    mount_tilt_deg: Range = field(default=(0.0, 0.0), metadata=_bounds(-15.0, 15.0))
    #: relative hfov change [-0.05, 0.05]
    mount_fov: Range = field(default=(0.0, 0.0), metadata=_bounds(-0.3, 0.3))
    #: share of episodes drawn neutral (every factor off: the paper's clean render), so that
    #: training keeps seeing the nominal world; not a factor, and 0 in :meth:`randomised`
    neutral_share: float = field(default=0.0, metadata=in_range(0.0, 1.0))

    def __post_init__(self) -> None:
        check_dataclass_fields(self)
        for name in FACTORS:
            lo, hi = getattr(self, name)
            low, high = self.__dataclass_fields__[name].metadata["bounds"]
            if not low <= lo <= hi <= high:
                raise ValueError(
                    f"AppearanceConfig.{name}: must be an ordered (low, high) pair within "
                    f"[{low}, {high}], got {(lo, hi)!r}"
                )
        if self.neutral_share > 0.0 and not self.enabled:
            raise ValueError(
                "AppearanceConfig.neutral_share: the share of episodes drawn neutral among"
                " randomised ones; every factor is neutral here, so switch one on (e.g."
                " AppearanceConfig.randomised())"
            )

    @classmethod
    def randomised(cls) -> AppearanceConfig:
        """Every factor on, at the robust ranges documented beside each field."""
        return cls(
            gain=(0.55, 1.45),
            offset=(-25.0, 25.0),
            gamma=(0.7, 1.5),
            vignetting=(0.0, 0.45),
            read_noise=(0.0, 6.0),
            shot_noise=(0.0, 0.6),
            defocus=(0.0, 1.2),
            motion_blur=(0.0, 0.4),
            stripes=(0.0, 12.0),
            grain=(0.0, 10.0),
            line_width=(-0.015, 0.02),
            line_wear=(0.0, 0.5),
            clutter=(0.0, 60.0),
            mount_height=(-0.03, 0.03),
            mount_tilt_deg=(-3.0, 3.0),
            mount_fov=(-0.05, 0.05),
        )

    @functools.cached_property
    def enabled(self) -> bool:
        """Whether any factor differs from the clean render (the stripes' width alone is
        none; cached: the envs ask every step)."""
        return any(
            getattr(self, f.name) != f.default
            for f in dataclasses.fields(self)
            if f.name in FACTORS and f.name != "stripe_width"
        )

    def replace(self, **changes: Range | float) -> AppearanceConfig:
        """A copy with ``changes`` (factor name -> range, or ``neutral_share``)."""
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]


#: The appearance factors: the fields of :class:`AppearanceConfig` that are ranges (those
#: with bounds; ``neutral_share`` is not one).
FACTORS = tuple(f.name for f in dataclasses.fields(AppearanceConfig) if "bounds" in f.metadata)


def draw_looks(config: AppearanceConfig, rng: np.random.Generator) -> np.ndarray:
    """One episode's look row (len(LOOK_FIELDS),) float64 and nothing else drawn: every
    factor uniform in its range, in :data:`LOOK_FIELDS` order, then the pattern key. The
    per-frame columns start at 0. With ``neutral_share`` > 0 a first number decides whether
    the episode is neutral (then its factors are drawn all the same and set neutral, so the
    draws that follow do not depend on the decision)."""
    row: np.ndarray = draw_look_rows(config, 1, rng)[0]
    return row


def draw_look_rows(config: AppearanceConfig, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` look rows (n, len(LOOK_FIELDS)) drawn at once, as :func:`draw_looks` draws
    one, in this order: the neutral decisions, the factors row by row, the keys. With
    ``n=1`` these are :func:`draw_looks`' numbers (it is this function's one-row case)."""
    neutral = (
        rng.random(n) < config.neutral_share if config.neutral_share > 0.0 else np.zeros(n, bool)
    )
    ranges = np.array(
        [getattr(config, "mount_tilt_deg" if name == "mount_tilt" else name) for name in _DRAWN]
    )
    rows = np.zeros((n, len(LOOK_FIELDS)))
    drawn = slice(0, LOOK["key"])
    rows[:, drawn] = ranges[:, 0] + (ranges[:, 1] - ranges[:, 0]) * rng.random((n, len(_DRAWN)))
    rows[:, LOOK["mount_tilt"]] = np.radians(rows[:, LOOK["mount_tilt"]])  # stored in radians
    rows[:, LOOK["key"]] = rng.integers(0, 2**52, n).astype(np.float64)
    rows[neutral, drawn] = neutral_looks(1)[0, drawn]
    return rows


def tone_curves(rows: np.ndarray) -> np.ndarray:
    """The tone curves (N, 256) uint8 of look ``rows`` (N, len(LOOK_FIELDS)): ``255 (v /
    255) ** gamma``."""
    v = np.arange(256) / 255.0
    gamma = np.asarray(rows)[:, LOOK["gamma"], None]
    return np.asarray(np.rint(255.0 * v[None] ** gamma), dtype=np.uint8)


def identity_tone() -> np.ndarray:
    """The tone curve that changes nothing."""
    return np.arange(256, dtype=np.uint8)


def neutral_looks(n: int) -> np.ndarray:
    """(n, len(LOOK_FIELDS)) rows of the clean render."""
    rows = np.zeros((n, len(LOOK_FIELDS)))
    rows[:, LOOK["gain"]] = 1.0
    rows[:, LOOK["stripe_width"]] = 1.0
    rows[:, LOOK["gamma"]] = 1.0
    return rows
