"""The robot's head camera: pinhole model, head limits and pure vectorised projections.

Conventions
-----------
* Robot pose ``(x, y, theta)``: position on the ground (m) and heading (rad, from +x, CCW).
* Head angles: ``pan`` (neck yaw, rad, positive to the left) and ``tilt`` (head pitch, rad,
  positive *down* from horizontal). The camera looks along yaw ``theta + pan`` and pitch
  ``-tilt``; it sits ``height`` metres above the robot's ground position (the paper's
  OP2-derived robot: torso 0.411 + neck 0.050 + camera 0.041 m).
* Camera frame (OpenCV): x right, y down, z forward. Pixel ``(u, v)``: ``u`` to the right,
  ``v`` down; pixel ``(i, j)`` (row ``j``) covers ``[i, i+1) x [j, j+1)``, so its centre is
  ``(i + 0.5, j + 0.5)`` and the principal point is the image centre.

Every function takes arrays of N cameras (``pose`` (N, 3), ``pan`` (N,), ``tilt`` (N,)) and
broadcasts; nothing loops over cameras or points in Python.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
import numpy.typing as npt

from activevision.typecheck import check_dataclass_fields

#: The widest and tallest image a CameraConfig takes (px): an 8K sensor, far beyond the
#: 160 x 120 the policies see; a larger size (a typo, 10**12) is refused naming the field,
#: not a numpy "Maximum allowed dimension exceeded" or MemoryError when rendering.
MAX_IMAGE_SIDE = 8192


@dataclass(frozen=True)
class CameraConfig:
    """Head camera and neck. Defaults: the paper's MRL-HSL robot (REFERENCE.md)."""

    width: int = 160  #: image width (px), the paper's network input
    height: int = 120  #: image height (px)
    hfov: float = 1.0123  #: horizontal field of view (rad), 58 degrees (release)
    camera_height: float = 0.50  #: camera above the ground (m)
    pan_min: float = -math.pi / 2  #: neck yaw limits (rad), paper: (-pi/2, pi/2)
    pan_max: float = math.pi / 2
    tilt_min: float = math.radians(5.0)  #: head pitch limits, down from horizontal (paper)
    tilt_max: float = math.radians(65.0)

    def __post_init__(self) -> None:
        check_dataclass_fields(self)  # types first: the comparisons below need numbers
        for name in ("width", "height"):
            value = getattr(self, name)
            if not isinstance(value, int | np.integer) or value <= 0:
                raise ValueError(f"CameraConfig.{name} must be a positive integer, got {value!r}")
            if value > MAX_IMAGE_SIDE:
                raise ValueError(
                    f"CameraConfig.{name} must be at most {MAX_IMAGE_SIDE} px, got {value!r}"
                )
        if not 0 < self.hfov < math.pi:
            raise ValueError(f"CameraConfig.hfov must lie in (0, pi) rad, got {self.hfov!r}")
        if not self.camera_height > 0:
            raise ValueError(
                f"CameraConfig.camera_height must be positive, got {self.camera_height!r}"
            )
        if not -math.pi < self.pan_min < self.pan_max < math.pi:
            raise ValueError(
                f"CameraConfig pan limits must satisfy -pi < pan_min < pan_max < pi, "
                f"got ({self.pan_min!r}, {self.pan_max!r})"
            )
        if not -math.pi / 2 < self.tilt_min < self.tilt_max < math.pi / 2:
            raise ValueError(
                f"CameraConfig tilt limits must satisfy -pi/2 < tilt_min < tilt_max < pi/2, "
                f"got ({self.tilt_min!r}, {self.tilt_max!r})"
            )

    @classmethod
    def of(cls, camera: object) -> CameraConfig:
        """The CameraConfig of any camera record with these fields as attributes, such as
        the runtime's ``CameraModel`` (``HeadController.trained_camera``): the camera to plan
        views with (``localisation.best_viewpoint``) for a policy trained on another camera."""
        if isinstance(camera, cls):
            return camera
        names = [f.name for f in fields(cls)]
        missing = [name for name in names if not hasattr(camera, name)]
        if missing:
            raise TypeError(f"a camera needs the fields {names}; {camera!r} lacks {missing}")
        return cls(**{name: getattr(camera, name) for name in names})

    @property
    def focal(self) -> float:
        """Focal length in pixels (square pixels)."""
        return (self.width / 2) / math.tan(self.hfov / 2)

    @property
    def vfov(self) -> float:
        return 2 * math.atan((self.height / 2) / self.focal)

    def intrinsics(self) -> np.ndarray:
        """The 3x3 intrinsic matrix K."""
        f = self.focal
        return np.array([[f, 0, self.width / 2], [0, f, self.height / 2], [0, 0, 1.0]])

    def differences(self, other: CameraConfig | None = None) -> str:
        """What of this camera differs from ``other`` (default: the paper's), in words and
        degrees: ``"160x90 px, hfov 70 deg"``; empty where nothing does."""
        other = other or CameraConfig()
        parts = []
        if (self.width, self.height) != (other.width, other.height):
            parts.append(f"{self.width}x{self.height} px")
        if self.hfov != other.hfov:
            parts.append(f"hfov {math.degrees(self.hfov):.3g} deg")
        if self.camera_height != other.camera_height:
            parts.append(f"height {self.camera_height:g} m")
        for axis in ("pan", "tilt"):
            low, high = getattr(self, f"{axis}_min"), getattr(self, f"{axis}_max")
            if (low, high) != (getattr(other, f"{axis}_min"), getattr(other, f"{axis}_max")):
                parts.append(f"{axis} {math.degrees(low):.3g}..{math.degrees(high):.3g} deg")
        return ", ".join(parts)


def head_in_limits(pan: npt.ArrayLike, tilt: npt.ArrayLike, cam: CameraConfig) -> np.ndarray:
    """True where the head angles lie within the (closed) limits."""
    pan, tilt = np.asarray(pan), np.asarray(tilt)
    inside: np.ndarray = (
        (pan >= cam.pan_min)
        & (pan <= cam.pan_max)
        & (tilt >= cam.tilt_min)
        & (tilt <= cam.tilt_max)
    )
    return inside


def clip_head(
    pan: npt.ArrayLike, tilt: npt.ArrayLike, cam: CameraConfig
) -> tuple[np.ndarray, np.ndarray]:
    """Head angles clipped to the limits."""
    return np.clip(pan, cam.pan_min, cam.pan_max), np.clip(tilt, cam.tilt_min, cam.tilt_max)


def world_to_camera_rotation(yaw: npt.ArrayLike, tilt: npt.ArrayLike) -> np.ndarray:
    """Rotation (..., 3, 3) whose rows are the camera's right, down and forward axes in
    world coordinates, for a camera looking along ``yaw`` and pitched ``tilt`` down."""
    yaw, tilt = np.broadcast_arrays(np.asarray(yaw, float), np.asarray(tilt, float))
    cy, sy, ct, st = np.cos(yaw), np.sin(yaw), np.cos(tilt), np.sin(tilt)
    zero = np.zeros_like(yaw)
    right = np.stack([sy, -cy, zero], axis=-1)
    down = np.stack([-cy * st, -sy * st, -ct], axis=-1)
    forward = np.stack([cy * ct, sy * ct, -st], axis=-1)
    return np.stack([right, down, forward], axis=-2)


def camera_centre(pose: npt.ArrayLike, cam: CameraConfig) -> np.ndarray:
    """Camera optical centres (..., 3) in world coordinates."""
    pose = np.asarray(pose, float)
    return np.concatenate(
        [pose[..., :2], np.full(pose.shape[:-1] + (1,), cam.camera_height)], axis=-1
    )


def project_points(
    points: npt.ArrayLike,
    pose: npt.ArrayLike,
    pan: npt.ArrayLike,
    tilt: npt.ArrayLike,
    cam: CameraConfig,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Project world points into N cameras.

    Args:
        points: (M, 3) world points (or (N, M, 3), one set per camera).
        pose: (N, 3) robot poses; pan, tilt: (N,) head angles.

    Returns:
        ``(uv, depth, in_image)``: pixel coordinates (N, M, 2), depth along the optical axis
        (N, M), and whether the point is in front of the camera and inside the image.
    """
    pose = np.atleast_2d(np.asarray(pose, float))
    rot = world_to_camera_rotation(pose[:, 2] + np.asarray(pan), np.asarray(tilt))
    rel = np.asarray(points, float) - camera_centre(pose, cam)[:, None, :]
    pc = np.einsum("nij,nmj->nmi", rot, rel)
    depth = pc[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = cam.focal * pc[..., 0] / depth + cam.width / 2
        v = cam.focal * pc[..., 1] / depth + cam.height / 2
    uv = np.stack([u, v], axis=-1)
    in_image = (depth > 0) & (u >= 0) & (u <= cam.width) & (v >= 0) & (v <= cam.height)
    return uv, depth, in_image


def ground_to_pixel_homography(
    pose: npt.ArrayLike, pan: npt.ArrayLike, tilt: npt.ArrayLike, cam: CameraConfig
) -> np.ndarray:
    """Homographies (N, 3, 3) taking ground points ``(x, y, 1)`` to homogeneous pixels
    ``(u w, v w, w)``, where ``w`` is the depth (positive in front of the camera)."""
    pose = np.atleast_2d(np.asarray(pose, float))
    rot = world_to_camera_rotation(pose[:, 2] + np.asarray(pan), np.asarray(tilt))
    t = -np.einsum("nij,nj->ni", rot, camera_centre(pose, cam))
    m = np.stack([rot[:, :, 0], rot[:, :, 1], t], axis=-1)
    homography: np.ndarray = np.einsum("ij,njk->nik", cam.intrinsics(), m)
    return homography


def pixel_to_ground_homography(
    pose: npt.ArrayLike, pan: npt.ArrayLike, tilt: npt.ArrayLike, cam: CameraConfig
) -> np.ndarray:
    """Inverse homographies (N, 3, 3): pixel ``(u, v, 1)`` to homogeneous ground points."""
    return np.linalg.inv(ground_to_pixel_homography(pose, pan, tilt, cam))


def pixel_to_ground(
    uv: npt.ArrayLike,
    pose: npt.ArrayLike,
    pan: npt.ArrayLike,
    tilt: npt.ArrayLike,
    cam: CameraConfig,
) -> tuple[np.ndarray, np.ndarray]:
    """Back-project pixels to the ground plane.

    Args:
        uv: (M, 2) pixel coordinates (or (N, M, 2)).

    Returns:
        ``(xy, valid)``: ground points (N, M, 2) and whether the pixel's ray meets the
        ground in front of the camera (False above the horizon).
    """
    pose = np.atleast_2d(np.asarray(pose, float))
    rot = world_to_camera_rotation(pose[:, 2] + np.asarray(pan), np.asarray(tilt))
    uv = np.asarray(uv, float)
    rays_cam = np.stack(
        [
            (uv[..., 0] - cam.width / 2) / cam.focal,
            (uv[..., 1] - cam.height / 2) / cam.focal,
            np.ones(uv.shape[:-1]),
        ],
        axis=-1,
    )
    rays = np.einsum(
        "nji,n...j->n...i", rot, np.broadcast_to(rays_cam, (len(pose),) + uv.shape[-2:-1] + (3,))
    )
    valid = rays[..., 2] < -1e-12
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(valid, cam.camera_height / -rays[..., 2], np.nan)
    xy = pose[:, None, :2] + scale[..., None] * rays[..., :2]
    return xy, valid


def image_halfplanes(
    pose: npt.ArrayLike, pan: npt.ArrayLike, tilt: npt.ArrayLike, cam: CameraConfig
) -> np.ndarray:
    """The image as four half-planes on the ground: (N, 4, 3) rows ``(a, b, c)`` such that
    a ground point ``(x, y)`` projects inside the image iff ``a x + b y + c >= 0`` for all
    four rows (left, right, top, bottom border). Together they also imply depth > 0."""
    g = ground_to_pixel_homography(pose, pan, tilt, cam)
    u_row, v_row, w_row = g[:, 0], g[:, 1], g[:, 2]
    return np.stack([u_row, cam.width * w_row - u_row, v_row, cam.height * w_row - v_row], axis=1)


def footprint_polygon(
    pose: npt.ArrayLike,
    pan: npt.ArrayLike,
    tilt: npt.ArrayLike,
    cam: CameraConfig,
    max_distance: float = 4.0,
    points_per_side: int = 16,
) -> np.ndarray:
    """The ground seen by each camera, up to ``max_distance`` (horizontal, from the robot).

    The image border is sampled and back-projected; rays that miss the ground (above the
    horizon) or meet it beyond ``max_distance`` are cut at ``max_distance``.

    Returns:
        (N, 4 * points_per_side, 2) polygon vertices, in order around the border.
    """
    w, h, k = cam.width, cam.height, points_per_side
    s = np.linspace(0, 1, k, endpoint=False)
    border = np.concatenate(
        [
            np.stack([s * w, np.zeros(k)], 1),
            np.stack([np.full(k, w), s * h], 1),
            np.stack([w - s * w, np.full(k, h)], 1),
            np.stack([np.zeros(k), h - s * h], 1),
        ]
    )
    pose = np.atleast_2d(np.asarray(pose, float))
    rot = world_to_camera_rotation(pose[:, 2] + np.asarray(pan), np.asarray(tilt))
    rays_cam = np.stack(
        [
            (border[:, 0] - w / 2) / cam.focal,
            (border[:, 1] - h / 2) / cam.focal,
            np.ones(len(border)),
        ],
        axis=-1,
    )
    rays = np.einsum("nji,mj->nmi", rot, rays_cam)
    horiz = np.linalg.norm(rays[..., :2], axis=-1)
    hits = rays[..., 2] < 0
    with np.errstate(divide="ignore", invalid="ignore"):
        dist = np.where(hits, cam.camera_height * horiz / -rays[..., 2], np.inf)
    dist = np.minimum(dist, max_distance)
    direction = rays[..., :2] / np.maximum(horiz, 1e-12)[..., None]
    polygon: np.ndarray = pose[:, None, :2] + dist[..., None] * direction
    return polygon
