"""Every matplotlib figure of the package, one module per figure kind, fed with plain data
(arrays, dataclasses, dicts, CSV paths), never with an env or a trainer:

* :mod:`~activevision.figures.canvas` — off-screen Agg figures: new, to RGB, to PNG.
* :mod:`~activevision.figures.topview` — the field's top view on an ``Axes`` (field,
  robot, ball, camera footprints, landmarks coloured by type).
* :mod:`~activevision.figures.scene` — the camera image beside the top view (``env.render``,
  ``activevision render``) and the best-viewpoint search (``activevision viewpoints``).
* :mod:`~activevision.figures.episode` — the qualitative episode figure and its GIF.
* :mod:`~activevision.figures.training` — a run's training curves.
* :mod:`~activevision.figures.compare` — success vs localisation error.
* :mod:`~activevision.figures.sweep` — success rate vs step over a sweep's grid points.
* :mod:`~activevision.figures.robustness` — success per perturbation of the robustness suite.

**Layer.** ``figures`` is a low layer: it imports only :mod:`activevision.geometry` and
:mod:`activevision.io` (beside numpy, matplotlib and Pillow), so every layer above geometry
may draw with it — ``env.render()`` included (``envs.view`` gathers a slot's data and hands
it to :func:`~activevision.figures.scene.view_figure`), and ``env.render()`` stays the same
picture as ``activevision render``. What a figure shows is computed in its own layer
(tracing an episode in ``experiments``, reading a run's CSVs in ``training``, the viewpoint
search in ``envs.view``); only the drawing is here.

**Backend.** Figures are :class:`matplotlib.figure.Figure` objects on their own
``FigureCanvasAgg``: no pyplot, no global figure, no ``matplotlib.use``. Calling them (or
``env.render()``) never changes the user's backend or touches their pyplot figures; only the
``activevision`` command picks a backend (``MPLBACKEND=Agg`` in :func:`activevision.cli.main`).
Importing this package imports no matplotlib; its modules do.
"""
