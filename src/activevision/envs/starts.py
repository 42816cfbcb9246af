"""Episode starts, drawn for many episodes at once, each from its own generator.

A start candidate is a robot pose, a head pose and 16 ball candidates 1-3 m away inside the
horizontal field of view; the first ball candidate that lies on the field and projects into
the image wins (the release's start, with fewer generator round trips). Per candidate,
every episode draws :data:`CANDIDATE_UNIFORMS` uniforms from *its own* generator in one
call, and one compiled kernel checks the candidates of all episodes together, so a batch
of episodes consumes each generator exactly as one episode alone would.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from activevision.envs.config import EnvConfig
from activevision.geometry.angles import wrap_angle
from activevision.geometry.jit import cached_njit
from activevision.geometry.kernels import (
    CameraModel,
    ball_in_image,
    camera_fields,
    camera_rotation,
)

BALL_CANDIDATES = 16  #: ball positions tried per start candidate
#: uniforms per start candidate: x, y, theta, pan, tilt, then distances and bearings
CANDIDATE_UNIFORMS = 5 + 2 * BALL_CANDIDATES


class StartGenerationError(RuntimeError):
    """No valid episode start was found within ``EnvConfig.max_start_draws`` draws."""


class BallDraw(NamedTuple):
    """Where :func:`candidate_kernel` puts the ball candidates."""

    d_lo: float  #: distance range from the robot (m)
    d_hi: float
    hfov: float  #: bearing spread around the view direction (rad)
    x_lim: float  #: the ball centre must lie within |x| <= x_lim, |y| <= y_lim
    y_lim: float
    radius: float  #: ball radius (m)


def corrupt_pose(pose: np.ndarray, error: float, rng: np.random.Generator) -> np.ndarray:
    """The release's localisation error: the position moved ``error`` m in a random
    direction, the heading turned by ``+-error`` rad (``geometry.angles.wrap_angle``'s
    ``(-pi, pi]``). A heading already in range is kept as it is, so a zero error leaves the
    pose exactly as drawn (the wrap's arithmetic would round it)."""
    direction, flip = rng.random(2)
    direction = math.pi * (2 * direction - 1)
    sign = 1.0 if flip < 0.5 else -1.0
    x, y, theta = (float(v) for v in pose)
    heading = theta + error * sign
    if not -math.pi < heading <= math.pi:
        heading = float(wrap_angle(heading))
    return np.array(
        [
            x + error * math.cos(direction),
            y + error * math.sin(direction),
            heading,
        ]
    )


def quantise_pose(poses: np.ndarray, cell_m: float, cell_deg: float) -> np.ndarray:
    """(N, 3) poses rounded to ``cell_m`` metre cells and ``cell_deg`` degree headings (0:
    that part exact); headings stay in ``wrap_angle``'s ``(-pi, pi]``."""
    out = np.array(poses, dtype=np.float64)
    if cell_m > 0:
        out[:, :2] = np.round(out[:, :2] / cell_m) * cell_m
    if cell_deg > 0:
        step = math.radians(cell_deg)
        out[:, 2] = wrap_angle(np.round(out[:, 2] / step) * step)
    return out


@cached_njit()
def candidate_kernel(
    u: np.ndarray,
    low: np.ndarray,
    high: np.ndarray,
    balls: tuple[float, ...],
    cam: tuple[float, ...],
) -> tuple[np.ndarray, np.ndarray]:
    """Start candidates from uniforms ``u`` (P, CANDIDATE_UNIFORMS); ``balls``, ``cam``: the
    fields of a :class:`BallDraw` and a ``geometry.kernels.CameraModel``.

    Returns ``(found (P,), starts (P, 7))``, rows ``(x, y, theta, pan, tilt, ball_x,
    ball_y)``: the pose and head are ``low + (high - low) * u[:5]``; ball candidate ``j``
    lies ``d_lo + (d_hi - d_lo) * u[5 + j]`` away at bearing ``theta + pan + hfov *
    (u[5 + n + j] - 0.5)``; the first one with ``|x| <= x_lim``, ``|y| <= y_lim`` and its
    centre in the image is kept.
    """
    d_lo, d_hi, hfov, x_lim, y_lim, radius = BallDraw(*balls)
    cam = CameraModel(*cam)
    p, n = u.shape[0], (u.shape[1] - 5) // 2
    found = np.zeros(p, dtype=np.bool_)
    starts = np.zeros((p, 7))
    rot = np.empty((3, 3))
    for i in range(p):
        for k in range(5):
            starts[i, k] = low[k] + (high[k] - low[k]) * u[i, k]
        x, y, theta, pan, tilt = starts[i, :5]
        camera_rotation(theta + pan, tilt, rot)
        for j in range(n):
            dist = d_lo + (d_hi - d_lo) * u[i, 5 + j]
            bearing = (theta + pan) + hfov * (u[i, 5 + n + j] - 0.5)
            bx = x + dist * math.cos(bearing)
            by = y + dist * math.sin(bearing)
            if (
                abs(bx) <= x_lim
                and abs(by) <= y_lim
                and ball_in_image(bx, by, radius, x, y, rot, cam)
            ):
                found[i] = True
                starts[i, 5], starts[i, 6] = bx, by
                break
    return found, starts


def draw_starts(rngs: Sequence[np.random.Generator], cfg: EnvConfig) -> dict[str, np.ndarray]:
    """One start per generator: ``{"pose", "believed_pose", "head", "ball"}`` arrays
    ((P, 3), (P, 3), (P, 2) pan/tilt, (P, 2)). Generator ``j`` is used for start ``j`` only:
    candidates until one has the ball in view, then the localisation error of the
    believed pose (:func:`corrupt_pose`)."""
    cam, spec = cfg.camera, cfg.field
    tilt_lo, tilt_hi = np.radians(cfg.start_tilt_range_deg)
    tilt_lo, tilt_hi = max(tilt_lo, cam.tilt_min), min(tilt_hi, cam.tilt_max)
    low = np.array([cfg.robot_x_range[0], cfg.robot_y_range[0], -np.pi, cam.pan_min, tilt_lo])
    high = np.array([cfg.robot_x_range[1], cfg.robot_y_range[1], np.pi, cam.pan_max, tilt_hi])
    r = spec.ball_radius
    d_lo, d_hi = cfg.ball_distance_range
    balls = tuple(
        BallDraw(
            float(d_lo),
            float(d_hi),
            float(cam.hfov),
            spec.half_length - r,
            spec.half_width - r,
            float(r),
        )
    )
    starts = np.zeros((len(rngs), 7))
    believed = np.zeros((len(rngs), 3))
    pending: np.ndarray = np.arange(len(rngs))
    for _ in range(cfg.max_start_draws):
        if not len(pending):
            return {
                "pose": starts[:, :3],
                "believed_pose": believed,
                "head": starts[:, 3:5],
                "ball": starts[:, 5:],
            }
        u = np.stack([rngs[j].random(CANDIDATE_UNIFORMS) for j in pending])
        found, candidates = candidate_kernel(u, low, high, balls, camera_fields(cam))
        for j, row in zip(pending[found], candidates[found], strict=True):
            starts[j] = row
            believed[j] = corrupt_pose(row[:3], cfg.localisation_error, rngs[j])
        pending = pending[~found]
    raise StartGenerationError(
        f"no start with the ball in view after {cfg.max_start_draws} draws; check "
        "EnvConfig ranges against the field and camera"
    )
