"""The picture of one slot of a :class:`~activevision.envs.match.simulation.MatchBatch`:
``render()`` of the match env and of its native vector env. This module gathers the slot's
state; :mod:`activevision.figures.match` draws."""

from __future__ import annotations

import numpy as np

from activevision.envs.actions import require_reset
from activevision.envs.match.simulation import MatchBatch


def match_panel(sim: MatchBatch, i: int, image: np.ndarray) -> np.ndarray:
    """RGB array of slot ``i``: its camera ``image`` beside the match from above (the true
    robot and its view, the belief's 2-sigma ellipse, the ball, the other robots), as
    ``activevision match``'s clip draws it. ResetNeeded if the slot was never reset."""
    require_reset(sim.started, np.array([i]), "render")
    from activevision.figures.canvas import figure_to_rgb  # imports matplotlib: only here
    from activevision.figures.match import match_view

    info = {key: value[i] for key, value in sim.info_arrays().items()}
    title = f"tick {int(info['tick'])}: position error {float(info['position_error']):.2f} m"
    cfg = sim.cfg
    return figure_to_rgb(match_view(image, cfg.field, cfg.camera, info, title, cfg.robots.radius))


__all__ = ["match_panel"]
