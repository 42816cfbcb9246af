"""Picture of the best-viewpoint search (Algorithm 1): every candidate footprint shaded by
the entropy its landmarks leave, the winner in red, candidates hiding the ball hatched."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Polygon

from activevision.io import atomic_path
from activevision.localisation import ViewpointStatus, best_viewpoint, candidate_footprints
from activevision.rendering.topview import draw_field, draw_landmarks, draw_robot


def plot_viewpoint_search(sim, i: int, out_png: str | Path, max_distance: float = 4.0) -> None:
    """Top view of slot ``i`` of an :class:`~activevision.envs.simulation.EpisodeBatch`."""
    cfg, loc = sim.cfg, sim.localisation
    pose, ball = sim.believed_pose[i], sim.ball[i]
    result = best_viewpoint(
        pose,
        loc.ukf.initial_cov,
        ball,
        sim.landmarks,
        cfg.camera,
        grid=loc.grid,
        ukf=loc.ukf,
        ball_radius=cfg.field.ball_radius,
    )
    entropies = np.asarray(result.entropies).reshape(-1)
    shows_ball = np.asarray(result.ball_visible).reshape(-1)
    polys = candidate_footprints(pose, loc.grid, cfg.camera, max_distance)

    fig, ax = plt.subplots(figsize=(8, 5.6))
    draw_field(ax, cfg.field)
    cmap = plt.get_cmap("viridis")
    lo, hi = entropies.min(), entropies.max()
    norm = plt.Normalize(lo, hi if hi > lo else lo + 1)
    # Low-entropy (better) candidates on top, so the interesting ones stay visible.
    for k in np.argsort(-entropies):
        ax.add_patch(
            Polygon(
                polys[k],
                closed=True,
                fc=cmap(norm(entropies[k])),
                ec="k",
                lw=0.3,
                alpha=0.35,
                hatch=None if shows_ball[k] else "//",
                zorder=2,
            )
        )
    if result.status == ViewpointStatus.OK:
        ax.add_patch(
            Polygon(polys[result.index], closed=True, fill=False, ec="red", lw=2.5, zorder=6)
        )
        draw_landmarks(ax, sim.landmarks, result.landmark_ids)
    draw_robot(ax, pose, ball, cfg.field.ball_radius)
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=ax, fraction=0.03, pad=0.01, label="entropy ½ ln|2πeΣ| after update")
    status = (
        f"best: pan {np.degrees(result.pan):+.0f}°, tilt {np.degrees(result.tilt):.0f}°, "
        f"H = {result.entropy:.2f}"
        if result.status == ViewpointStatus.OK
        else "no viewpoint shows the ball"
    )
    ax.set_title(
        f"{len(polys)} candidate viewpoints (hatched: ball not in view); {status}", fontsize=10
    )
    fig.tight_layout()
    with atomic_path(out_png) as tmp:
        fig.savefig(tmp, dpi=120, format="png")
    plt.close(fig)
