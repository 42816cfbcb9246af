"""Scale-out on Ray: seed/grid sweeps of training runs on Ray Tune and the
localisation-error comparison as Ray tasks.

Ray is an optional extra (``pip install activevision[ray]``): this package imports it only
inside the functions that need it, and nothing else in :mod:`activevision` imports it.

Typical use::

    from activevision.scaleout import compare_ray, sweep
    from activevision.training import preset

    sweep(preset("paper"), seeds=range(10), grid={"learning_rate": [5e-4, 1e-3]},
          out_dir="runs/sweep")                       # local Ray, one CPU per trial
    compare_ray("runs/compare", ["oracle", "random"], [0.0, 1.0], 100, 0)   # local Ray too

Either joins a running cluster instead with ``address="auto"`` (or ``"ray://head:10001"``);
without one, ``"auto"`` raises ``ConnectionError``.
"""

from activevision.scaleout.compare import compare_ray
from activevision.scaleout.ray_session import RAY_INSTALL_HINT, ray_session, require_ray
from activevision.scaleout.sweep import aggregate, plot_sweep, sweep

__all__ = [
    "RAY_INSTALL_HINT",
    "aggregate",
    "compare_ray",
    "plot_sweep",
    "ray_session",
    "require_ray",
    "sweep",
]
