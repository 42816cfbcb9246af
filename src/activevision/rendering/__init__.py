"""Fast batched rendering of the robot's head-camera image (numba), plus NumPy references.

* :class:`Renderer` / :class:`RenderConfig` — the fast anti-aliased renderer.
* :func:`render_reference` — a straightforward centre-sampled NumPy renderer (benchmark
  baseline); :func:`render_supersampled` — box-filtered ray-traced ground truth (tests).
"""

from activevision.rendering.config import RenderConfig
from activevision.rendering.reference import render_reference, render_supersampled
from activevision.rendering.renderer import Renderer

__all__ = ["RenderConfig", "Renderer", "render_reference", "render_supersampled"]
