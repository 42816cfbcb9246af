"""Fast batched rendering of the robot's head-camera image (numba), plus NumPy references."""

from activevision.rendering.config import RenderConfig
from activevision.rendering.renderer import Renderer

__all__ = ["RenderConfig", "Renderer"]
