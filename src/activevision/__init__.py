"""activevision: learn where a humanoid soccer robot should look.

Importing the package is light: it registers the Gymnasium environments by name (so that
``gymnasium.make("activevision:ActiveVision-v0")`` works) and imports nothing else, no torch
and no numba, so the runtime head controller runs on a robot without PyTorch.
"""

from activevision.registration import register_envs

__version__ = "0.1.0"

register_envs()
