"""Field and head-camera geometry: the world model everything else stands on (NumPy only)."""

from activevision.geometry.camera import (
    CameraConfig,
    camera_centre,
    clip_head,
    footprint_polygon,
    ground_to_pixel_homography,
    head_in_limits,
    image_halfplanes,
    pixel_to_ground,
    pixel_to_ground_homography,
    project_points,
    world_to_camera_rotation,
)
from activevision.geometry.field import (
    DEFAULT_MAX_DISTANCE,
    FieldSpec,
    LandmarkType,
    field_preset,
)
from activevision.geometry.landmarks import LandmarkSet, field_landmarks, painted_lines
from activevision.geometry.visibility import Visibility, ball_visible, visible_landmarks

__all__ = [
    "DEFAULT_MAX_DISTANCE",
    "CameraConfig",
    "FieldSpec",
    "LandmarkSet",
    "LandmarkType",
    "Visibility",
    "ball_visible",
    "camera_centre",
    "clip_head",
    "field_landmarks",
    "field_preset",
    "footprint_polygon",
    "ground_to_pixel_homography",
    "head_in_limits",
    "image_halfplanes",
    "painted_lines",
    "pixel_to_ground",
    "pixel_to_ground_homography",
    "project_points",
    "visible_landmarks",
    "world_to_camera_rotation",
]
