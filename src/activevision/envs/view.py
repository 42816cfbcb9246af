"""Pictures of one slot of an :class:`~activevision.envs.simulation.EpisodeBatch`: this module
reads the slot's state (and runs the viewpoint search on it) and hands plain data to
:mod:`activevision.figures.scene`, which draws. ``env.render()`` and ``activevision render``
/ ``viewpoints`` use it."""

from __future__ import annotations

import numpy as np

from activevision.envs.actions import require_reset
from activevision.envs.simulation import EpisodeBatch
from activevision.figures.canvas import figure_to_rgb
from activevision.figures.scene import ViewpointSearch, view_figure
from activevision.localisation import ViewpointStatus, best_viewpoint, candidate_footprints


def episode_panel(sim: EpisodeBatch, i: int, image: np.ndarray) -> np.ndarray:
    """RGB array of slot ``i``: the camera image beside the top view with the goal (red) and
    current (blue) views. ResetNeeded if the slot was never reset (its state is zeros)."""
    require_reset(sim.started, np.array([i]), "render")
    cfg = sim.cfg
    fig = view_figure(
        cfg.field,
        sim.landmarks,
        cfg.camera,
        image,
        sim.pose[i],
        sim.pan[i],
        sim.tilt[i],
        sim.ball[i],
        goal=(sim.goal_pan[i], sim.goal_tilt[i]),
        visible_ids=np.flatnonzero(sim.observed[i]),
        title=f"step {sim.step_count[i]}: {int((sim.observed[i] & sim.desired[i]).sum())}/"
        f"{int(sim.desired[i].sum())} goal landmarks in view",
        robots=sim.robots[i],
        robot_radius=cfg.robots.radius,
    )
    return figure_to_rgb(fig)


def viewpoint_search(sim: EpisodeBatch, i: int, max_distance: float = 4.0) -> ViewpointSearch:
    """Algorithm 1 from slot ``i``'s believed pose (start covariance), every candidate kept."""
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
    found = result.status == ViewpointStatus.OK
    return ViewpointSearch(
        field=cfg.field,
        landmarks=sim.landmarks,
        pose=pose,
        ball=ball,
        footprints=candidate_footprints(pose, loc.grid, cfg.camera, max_distance),
        entropies=np.asarray(result.entropies).reshape(-1),
        shows_ball=np.asarray(result.ball_visible).reshape(-1),
        best=result.index if found else None,
        pan=result.pan,
        tilt=result.tilt,
        entropy=result.entropy,
        landmark_ids=result.landmark_ids,
    )
