"""Straightforward NumPy renderers: the benchmark's baseline and the tests' ground truth.

* :func:`render_reference` — what a first renderer would do: back-project each pixel centre
  to the ground and test its distance to every painted line segment, the centre circle and
  the penalty marks (one sample per pixel, no anti-aliasing, no goals or ball). The speed
  baseline of ``bench/render.py``.
* :func:`render_supersampled` — ground truth for the fast renderer: ray-traces
  ``samples_per_axis**2`` rays per pixel on a regular grid against the full scene (ground
  paint, carpet, posts, crossbars, shaded ball) and averages them (a box filter). It uses
  the same scene description (:mod:`activevision.rendering.scene`) and the camera
  conventions of :mod:`activevision.geometry.camera`, but none of the fast renderer's maths.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from activevision.geometry.camera import (
    CameraConfig,
    camera_centre,
    pixel_to_ground,
    world_to_camera_rotation,
)
from activevision.geometry.field import FieldSpec
from activevision.geometry.landmarks import painted_lines
from activevision.rendering.config import RenderConfig
from activevision.rendering.scene import SceneArrays, build_scene

_DEFAULT_FIELD = FieldSpec()
_DEFAULT_CAMERA = CameraConfig()
_DEFAULT_CONFIG = RenderConfig()


def _cameras(
    pose: ArrayLike, pan: ArrayLike, tilt: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    pose = np.atleast_2d(np.asarray(pose, dtype=np.float64))
    n = len(pose)
    pan = np.broadcast_to(np.asarray(pan, dtype=np.float64), (n,))
    tilt = np.broadcast_to(np.asarray(tilt, dtype=np.float64), (n,))
    return pose, pan, tilt


def render_reference(
    pose: ArrayLike,
    pan: ArrayLike,
    tilt: ArrayLike,
    field: FieldSpec = _DEFAULT_FIELD,
    camera: CameraConfig = _DEFAULT_CAMERA,
    config: RenderConfig = _DEFAULT_CONFIG,
) -> np.ndarray:
    """Centre-sampled images (N, H, W) uint8 of the ground only: carpet, painted lines (by
    distance to each line segment), centre circle and penalty marks; no goals, no ball."""
    pose, pan, tilt = _cameras(pose, pan, tilt)
    h, w = camera.height, camera.width
    jj, ii = np.mgrid[0:h, 0:w]
    centres = np.stack([ii.ravel() + 0.5, jj.ravel() + 0.5], axis=1)
    segments = painted_lines(field)
    half_w2 = (field.line_width / 2) ** 2
    radius = field.centre_circle_diameter / 2
    half_w = field.line_width / 2
    bx, by = field.carpet_half_extent
    mark_x = field.half_length - field.penalty_mark_distance
    half_mark = field.penalty_mark_size / 2
    images = np.empty((len(pose), h, w), dtype=np.uint8)
    for n in range(len(pose)):
        xy, valid = pixel_to_ground(
            centres, pose[n : n + 1], pan[n : n + 1], tilt[n : n + 1], camera
        )
        x = np.where(valid[0], xy[0, :, 0], 1e6)
        y = np.where(valid[0], xy[0, :, 1], 1e6)
        on_line = np.zeros(len(x), dtype=bool)
        for (ax, ay), (sx, sy) in segments:
            dx, dy = sx - ax, sy - ay
            t = np.clip(((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0)
            ex = x - ax - t * dx
            ey = y - ay - t * dy
            on_line |= ex * ex + ey * ey <= half_w2
        on_line |= np.abs(np.hypot(x, y) - radius) <= half_w
        on_line |= (np.abs(np.abs(x) - mark_x) <= half_mark) & (np.abs(y) <= half_mark)
        on_carpet = (np.abs(x) <= bx) & (np.abs(y) <= by)
        grey = np.where(on_carpet, np.where(on_line, config.line, config.grass), config.background)
        images[n] = np.rint(grey).reshape(h, w)
    return images


def _rect_frames(quads: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centres (Q, 2), unit axes (Q, 2, 2) and half-extents (Q, 2) of rectangles given by
    their corners (Q, 4, 2) in order (every scene quad is a rectangle)."""
    centre = quads.mean(axis=1)
    side_a = quads[:, 1] - quads[:, 0]
    side_b = quads[:, 2] - quads[:, 1]
    len_a = np.linalg.norm(side_a, axis=1)
    len_b = np.linalg.norm(side_b, axis=1)
    axes = np.stack([side_a / len_a[:, None], side_b / len_b[:, None]], axis=1)
    return centre, axes, np.stack([len_a / 2, len_b / 2], axis=1)


def _inside_rects(p: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """Whether each point (K, 2) lies in any of the rectangles (Q, 4, 2) (boundary
    included)."""
    centre, axes, half = _rect_frames(quads)
    inside = np.zeros(len(p), dtype=bool)
    for c, (a, b), (ha, hb) in zip(centre, axes, half, strict=True):
        rel = p - c
        inside |= (np.abs(rel @ a) <= ha) & (np.abs(rel @ b) <= hb)
    return inside


def _trace(
    origin: np.ndarray,
    rays: np.ndarray,
    scene: SceneArrays,
    ball: np.ndarray | None,
    config: RenderConfig,
) -> np.ndarray:
    """Grey seen along each ray (K, 3) from ``origin`` (3,); ``ball`` (3,) centre or None."""
    k = len(rays)
    grey = np.full(k, config.background)
    # Ground: carpet, then paint on it.
    going_down = rays[:, 2] < 0
    with np.errstate(divide="ignore", invalid="ignore"):
        t_ground = np.where(going_down, -origin[2] / rays[:, 2], np.inf)
    p = origin[:2] + np.where(going_down, t_ground, 0.0)[:, None] * rays[:, :2]
    on_carpet = going_down & _inside_rects(p, scene.carpet_quad[None])
    paint = _inside_rects(p, scene.paint_quads)
    r = np.hypot(p[:, 0] - scene.ring[0], p[:, 1] - scene.ring[1])
    paint |= (r >= scene.ring[2]) & (r <= scene.ring[3])
    grey = np.where(on_carpet, np.where(paint, config.line, config.grass), grey)
    nearest = t_ground.copy()

    # Posts: vertical cylinders from z = 0 to their height.
    for px, py, pr, ph in scene.posts:
        oc = origin[:2] - (px, py)
        a = np.sum(rays[:, :2] ** 2, axis=1)
        b = 2 * rays[:, :2] @ oc
        c = oc @ oc - pr * pr
        disc = b * b - 4 * a * c
        with np.errstate(invalid="ignore", divide="ignore"):
            t = (-b - np.sqrt(disc)) / (2 * a)
        z = origin[2] + t * rays[:, 2]
        hit = (disc > 0) & (t > 0) & (z >= 0) & (z <= ph) & (t < nearest)
        nearest = np.where(hit, t, nearest)
        grey = np.where(hit, config.post, grey)
    # Crossbars: horizontal cylinders along y.
    for bx, y0, y1, bz, br in scene.crossbars:
        oc = origin[[0, 2]] - (bx, bz)
        dxz = rays[:, [0, 2]]
        a = np.sum(dxz**2, axis=1)
        b = 2 * dxz @ oc
        c = oc @ oc - br * br
        disc = b * b - 4 * a * c
        with np.errstate(invalid="ignore", divide="ignore"):
            t = (-b - np.sqrt(disc)) / (2 * a)
        y = origin[1] + t * rays[:, 1]
        hit = (disc > 0) & (t > 0) & (y >= y0) & (y <= y1) & (t < nearest)
        nearest = np.where(hit, t, nearest)
        grey = np.where(hit, config.post, grey)
    # Ball: sphere, half-Lambert lit from straight above.
    if ball is not None:
        oc = origin - ball
        a = np.sum(rays * rays, axis=1)
        b = 2 * rays @ oc
        c = oc @ oc - scene.ball_radius**2
        disc = b * b - 4 * a * c
        with np.errstate(invalid="ignore"):
            t = (-b - np.sqrt(disc)) / (2 * a)
        hit = (disc > 0) & (t > 0) & (t < nearest)
        normal_z = (origin[2] + t * rays[:, 2] - ball[2]) / scene.ball_radius
        shade = config.ball_shadow + (config.ball_lit - config.ball_shadow) * (0.5 + 0.5 * normal_z)
        grey = np.where(hit, shade, grey)
    return grey


def render_supersampled(
    pose: ArrayLike,
    pan: ArrayLike,
    tilt: ArrayLike,
    ball_xy: ArrayLike | None = None,
    field: FieldSpec = _DEFAULT_FIELD,
    camera: CameraConfig = _DEFAULT_CAMERA,
    config: RenderConfig = _DEFAULT_CONFIG,
    samples_per_axis: int = 16,
    mask: np.ndarray | None = None,
    max_rays_per_chunk: int = 100_000,
) -> np.ndarray:
    """Box-filtered ground truth: the mean grey of ``samples_per_axis**2`` rays per pixel on a
    regular grid (sample ``(a, b)`` at ``(i + (a + .5) / s, j + (b + .5) / s)``).

    Args:
        pose, pan, tilt: N cameras as for :meth:`Renderer.render`.
        ball_xy: (N, 2) ball positions, or None for no ball.
        mask: optional (N, H, W) bool; only these pixels are traced (others are NaN).

    Returns:
        (N, H, W) float64 grey levels (not rounded).
    """
    pose, pan, tilt = _cameras(pose, pan, tilt)
    n, h, w = len(pose), camera.height, camera.width
    scene = build_scene(field)
    if mask is None:
        mask = np.ones((n, h, w), dtype=bool)
    s = int(samples_per_axis)
    offsets = (np.arange(s) + 0.5) / s
    sub_u, sub_v = np.meshgrid(offsets, offsets, indexing="xy")
    sub = np.stack([sub_u.ravel(), sub_v.ravel()], axis=1)  # (S, 2)
    rotations = world_to_camera_rotation(pose[:, 2] + pan, tilt)
    centres = camera_centre(pose, camera)
    focal, cx, cy = camera.focal, w / 2, h / 2
    out = np.full((n, h, w), np.nan)
    pixels_per_chunk = max(1, max_rays_per_chunk // len(sub))
    for cam in range(n):
        jj, ii = np.nonzero(mask[cam])
        ball = None
        if ball_xy is not None:
            bxy = np.asarray(ball_xy, dtype=np.float64).reshape(n, 2)[cam]
            ball = np.array([bxy[0], bxy[1], scene.ball_radius])
        for start in range(0, len(ii), pixels_per_chunk):
            ci, cj = ii[start : start + pixels_per_chunk], jj[start : start + pixels_per_chunk]
            u = (ci[:, None] + sub[None, :, 0]).ravel()
            v = (cj[:, None] + sub[None, :, 1]).ravel()
            rays_cam = np.stack([(u - cx) / focal, (v - cy) / focal, np.ones_like(u)], axis=1)
            rays = rays_cam @ rotations[cam]  # camera -> world: R^T d
            grey = _trace(centres[cam], rays, scene, ball, config)
            out[cam, cj, ci] = grey.reshape(len(ci), len(sub)).mean(axis=1)
    return out
