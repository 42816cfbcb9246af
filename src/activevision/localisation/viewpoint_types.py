"""The data of the best-viewpoint search: the candidate grid, the result of one search and of
a batch, and the localisation settings the environment and the entropy baseline share."""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from activevision.geometry.camera import CameraConfig
from activevision.localisation.config import DEFAULT_UKF, UKFConfig
from activevision.typecheck import check_dataclass_fields

#: the most angles on one axis of a :class:`ViewpointGrid` (0.01 degrees apart over 180:
#: finer than any head's encoder)
MAX_GRID_COUNT = 20_000


@dataclass(frozen=True)
class ViewpointGrid:
    """Candidate head positions: ``n_pan`` x ``n_tilt`` evenly spaced angles (rad).

    Defaults are the paper's: pan in (-90, 90) deg at 10 points and tilt in (5, 65) deg at 4
    points. The paper writes open intervals, but its code release uses the endpoints
    (-90, -70, ..., 90 and 5, 25, 45, 65 deg), and so do we. The 10-point pan grid is
    symmetric about 0 (and contains no 0). Grid order is pan-major: candidate
    ``i = i_pan * n_tilt + i_tilt``.
    """

    pan_min: float = -math.pi / 2  #: rad (paper)
    pan_max: float = math.pi / 2  #: rad (paper)
    n_pan: int = 10  #: paper
    tilt_min: float = math.radians(5.0)  #: rad, positive down (paper)
    tilt_max: float = math.radians(65.0)  #: rad (paper)
    n_tilt: int = 4  #: paper

    def __post_init__(self) -> None:
        # types first (finite angles, integer counts): a string angle was a TypeError of the
        # comparison below, a NaN one refused without its value, True taken for 1
        check_dataclass_fields(self)
        for name in ("n_pan", "n_tilt"):
            value = getattr(self, name)
            if not 1 <= value <= MAX_GRID_COUNT:
                # n_pan=10**9 was a MemoryError (or minutes of swapping) on first use, unnamed
                raise ValueError(
                    f"ViewpointGrid.{name} must be a positive integer up to {MAX_GRID_COUNT:,},"
                    f" got {value!r}"
                )
        if not (self.pan_min <= self.pan_max and self.tilt_min <= self.tilt_max):
            raise ValueError(
                "ViewpointGrid needs pan_min <= pan_max and tilt_min <= tilt_max, got pan"
                f" ({self.pan_min!r}, {self.pan_max!r}),"
                f" tilt ({self.tilt_min!r}, {self.tilt_max!r})"
            )

    def __len__(self) -> int:
        return self.n_pan * self.n_tilt

    @cached_property
    def pan_values(self) -> np.ndarray:
        """The distinct pan angles (n_pan,), from ``pan_min`` to ``pan_max``."""
        return _readonly(_even(self.pan_min, self.pan_max, self.n_pan))

    @cached_property
    def tilt_values(self) -> np.ndarray:
        """The distinct tilt angles (n_tilt,), from ``tilt_min`` to ``tilt_max``."""
        return _readonly(_even(self.tilt_min, self.tilt_max, self.n_tilt))

    @cached_property
    def pans(self) -> np.ndarray:
        """Pan of every candidate (V,), grid order."""
        return _readonly(np.repeat(self.pan_values, self.n_tilt))

    @cached_property
    def tilts(self) -> np.ndarray:
        """Tilt of every candidate (V,), grid order."""
        return _readonly(np.tile(self.tilt_values, self.n_pan))

    @cached_property
    def views(self) -> np.ndarray:
        """Every candidate as a (pan, tilt) row (V, 2), grid order: the goal-view classes of a
        DAgger student."""
        return _readonly(np.column_stack([self.pans, self.tilts]))

    def index(self, i_pan: int, i_tilt: int) -> int:
        return i_pan * self.n_tilt + i_tilt


DEFAULT_GRID = ViewpointGrid()


class ViewpointStatus(enum.Enum):
    OK = "ok"  #: a candidate shows the ball; it is the goal
    NO_VIEWPOINT_SHOWS_BALL = "no_viewpoint_shows_ball"  #: no goal (e.g. ball behind the robot)


@dataclass(frozen=True)
class ViewpointResult:
    """Outcome of Algorithm 1 for one belief. Without a goal, ``index`` is -1, ``pan``,
    ``tilt`` and ``entropy`` are NaN and ``landmark_ids`` is empty."""

    status: ViewpointStatus
    index: int  #: goal candidate in grid order
    pan: float  #: rad
    tilt: float  #: rad
    entropy: float  #: nats, of the expected posterior at the goal
    landmark_ids: tuple[int, ...]  #: landmarks the goal view shows
    entropies: np.ndarray  #: (V,) expected posterior entropy of every candidate, grid order
    ball_visible: np.ndarray  #: (V,) bool
    visible: np.ndarray  #: (V, K) bool, landmarks each candidate shows
    covariances: np.ndarray  #: (V, 3, 3) expected posterior covariances
    grid: ViewpointGrid

    @property
    def ok(self) -> bool:
        return self.status is ViewpointStatus.OK

    @property
    def entropy_grid(self) -> np.ndarray:
        """Entropies as (n_pan, n_tilt)."""
        return self.entropies.reshape(self.grid.n_pan, self.grid.n_tilt)


@dataclass(frozen=True)
class ViewpointBatch:
    """Outcome of Algorithm 1 for N beliefs; ``batch[i]`` is the :class:`ViewpointResult`
    of start ``i``. ``ok`` is False (and ``index`` -1, angles NaN) where no candidate shows
    the ball."""

    ok: np.ndarray  #: (N,) bool
    index: np.ndarray  #: (N,) int
    pan: np.ndarray  #: (N,) rad
    tilt: np.ndarray  #: (N,) rad
    entropy: np.ndarray  #: (N,)
    entropies: np.ndarray  #: (N, V)
    ball_visible: np.ndarray  #: (N, V) bool
    visible: np.ndarray  #: (N, V, K) bool
    covariances: np.ndarray  #: (N, V, 3, 3)
    grid: ViewpointGrid

    def __len__(self) -> int:
        return len(self.ok)

    def __getitem__(self, i: int) -> ViewpointResult:
        return search_result(
            self.entropies[i],
            self.ball_visible[i],
            self.visible[i],
            self.covariances[i],
            self.grid,
        )


def _even(lo: float, hi: float, n: int) -> np.ndarray:
    """``n`` evenly spaced values from ``lo`` to ``hi`` (one value: the midpoint), exactly
    mirror-symmetric about the midpoint (``np.linspace`` is not: -50 deg and 50 deg would
    differ in the last bit, breaking the pan -> -pan symmetry)."""
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    if n == 1:
        return np.array([mid])
    k = 2.0 * np.arange(n) - (n - 1)  # exact integers, symmetric about 0
    return mid + half * (k / (n - 1))


def _readonly(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


def choose_goal(
    entropies: np.ndarray, ball_visible: np.ndarray
) -> tuple[np.ndarray | np.bool_, np.ndarray]:
    """Least-entropy candidate showing the ball, first in grid order on ties (Algorithm 1,
    lines 9-12). ``entropies``, ``ball_visible``: (N, V). Returns ``(ok (N,), index (N,))``
    with ``index`` -1 where no candidate shows the ball (for one belief's (V,): a NumPy
    bool and a 0-d array)."""
    masked = np.where(ball_visible, entropies, np.inf)
    ok = ball_visible.any(axis=-1)
    return ok, np.where(ok, np.argmin(masked, axis=-1), -1)


def search_result(
    entropies: np.ndarray,
    ball_vis: np.ndarray,
    visible: np.ndarray,
    post: np.ndarray,
    grid: ViewpointGrid,
) -> ViewpointResult:
    """The :class:`ViewpointResult` of one start from its per-candidate search output."""
    ok, index = choose_goal(entropies, ball_vis)
    i = int(index)
    found = bool(ok)
    return ViewpointResult(
        status=ViewpointStatus.OK if found else ViewpointStatus.NO_VIEWPOINT_SHOWS_BALL,
        index=i,
        pan=float(grid.pans[i]) if found else math.nan,
        tilt=float(grid.tilts[i]) if found else math.nan,
        entropy=float(entropies[i]) if found else math.nan,
        landmark_ids=tuple(np.flatnonzero(visible[i]).tolist()) if found else (),
        entropies=entropies,
        ball_visible=ball_vis,
        visible=visible,
        covariances=post,
        grid=grid,
    )


@dataclass(frozen=True)
class LocalisationConfig:
    """What the environment's goal search and the entropy baseline share: the candidate grid
    and the UKF (whose ``initial_cov`` is the belief at an episode start)."""

    grid: ViewpointGrid = DEFAULT_GRID  #: 10 x 4 candidates (paper)
    ukf: UKFConfig = DEFAULT_UKF  #: sensor model and start belief

    def __post_init__(self) -> None:
        # a grid or UKF of another type failed deep in the env's constructor or first reset
        check_dataclass_fields(self)

    @classmethod
    def for_camera(cls, camera: CameraConfig, ukf: UKFConfig = DEFAULT_UKF) -> LocalisationConfig:
        """The paper's 10 x 4 candidates spread over ``camera``'s head limits (for the
        paper's camera, :data:`DEFAULT_GRID` itself), so that no goal lies beyond what the
        head can reach."""
        return cls(grid_spanning(camera), ukf)


def grid_spanning(
    camera: CameraConfig, n_pan: int = DEFAULT_GRID.n_pan, n_tilt: int = DEFAULT_GRID.n_tilt
) -> ViewpointGrid:
    """``n_pan`` x ``n_tilt`` candidates from ``camera``'s lowest to highest pan and tilt."""
    return ViewpointGrid(
        camera.pan_min, camera.pan_max, n_pan, camera.tilt_min, camera.tilt_max, n_tilt
    )


def check_grid_reachable(grid: ViewpointGrid, camera: CameraConfig) -> None:
    """ValueError when a candidate of ``grid`` lies beyond ``camera``'s head limits (a goal
    there could never be reached)."""
    if (
        grid.pan_min < camera.pan_min
        or grid.pan_max > camera.pan_max
        or grid.tilt_min < camera.tilt_min
        or grid.tilt_max > camera.tilt_max
    ):
        raise ValueError(
            f"the candidate views (pan {math.degrees(grid.pan_min):.1f} to"
            f" {math.degrees(grid.pan_max):.1f} deg, tilt {math.degrees(grid.tilt_min):.1f} to"
            f" {math.degrees(grid.tilt_max):.1f}) reach beyond the camera's head limits (pan"
            f" {math.degrees(camera.pan_min):.1f} to {math.degrees(camera.pan_max):.1f}, tilt"
            f" {math.degrees(camera.tilt_min):.1f} to {math.degrees(camera.tilt_max):.1f}):"
            " use LocalisationConfig.for_camera(camera)"
        )
