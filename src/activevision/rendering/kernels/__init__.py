"""The numba kernels of the fast renderer, split by job:

* :mod:`.bundles` -- the typed bundles the kernels take (:class:`~.bundles.Scene`,
  :class:`~.bundles.Cameras`, :class:`~.bundles.RenderWork`, :class:`~.bundles.SetupScratch`)
  and the work memory;
* :mod:`.coverage` -- pixel coverage: the box filter, row spans, quads, ring and ball;
* :mod:`.edges` -- image edge lines of 3D polygons, frustum clipping, row ranges;
* :mod:`.camera_setup` -- the per-camera setup pass;
* :mod:`.raster` -- the row pass and the entry points :func:`~.raster.render_kernel`
  (threads) and :func:`~.raster.render_kernel_serial`;
* :mod:`.garbage` -- the test hook that fills the work memory with garbage.

How a frame is drawn
--------------------
Every straight edge in the scene (a side of a painted line, of a penalty mark, of the carpet,
the silhouette edge of a post or crossbar) is a straight line in the image too. For a 3D
segment ``A B`` in camera coordinates, the plane through the optical centre, ``A`` and ``B``
has normal ``n = A x B``; a pixel ray ``d = K^-1 (u, v, 1)`` lies on the inner side iff
``n . d > 0``, which is the image half-plane ``l . (u, v, 1) > 0`` with ``l = K^-T n``.
Scaling ``l`` so that ``(l0, l1)`` is a unit vector makes ``l . (u, v, 1)`` the signed
distance in pixels. Because this only uses rays with positive depth, the intersection of a
convex polygon's edge half-planes is *exactly* its projection, even when part of the
polygon lies behind the camera.

Anti-aliasing is an exact box filter per half-plane: projected onto the line's normal, the
unit pixel square spreads as the sum of two uniform variables of half-widths ``|l0|/2`` and
``|l1|/2`` (a trapezoid), so the covered fraction is that trapezoid's CDF at the centre's
signed distance (:func:`.coverage._halfplane_coverage`). A band between two edges that do not cross
inside the pixel covers ``F1 + F2 - 1`` of it (exact); a quad covers the product of its two
bands (exact for axis-aligned rectangles, a tiny error only at line ends). The centre circle
ring and the ball use the same formula with the signed distance to their image conics taken
to first order (``q / |grad q|``).

Work per frame: a setup pass computes, per camera, every shape's edge lines and the range of
image rows it touches (its polygon clipped to the view frustum and projected; shapes out of
view are dropped). Then each row is filled with background/grass in runs, and each shape in
range shades only the columns its edges allow (linear inequalities per row, :func:`.coverage.span`):
pixels fully inside are filled directly, per-pixel coverage is computed only for the
partly covered ones. The ring is bounded by a 16-gon around it and one inside its hole. Row
work is handed to the threads in interleaved sets (rows ``b, b + B, b + 2B, ...``) so
sky-only rows do not pile up on one thread; single frames skip the threads altogether
(``render_kernel_serial``). The painted coverages of one row combine with ``max``; posts,
crossbars and the ball are composited over the ground far-to-near (painter's order by
distance) with their coverage as alpha. Values are rounded to uint8 once per pixel.

The work memory is uninitialised (``np.empty``), yet no frame depends on what it held:
:mod:`.garbage` says why, and holds the test hook that checks it.

Goal posts are drawn as their silhouette: the quad between the two vertical generators
tangent to the sight lines from the camera (exact side edges); the bottom and top edges,
really arcs of the end circles, are straight lines moved 2/3 of the arc's sagitta towards
the camera (equal area). Crossbars likewise, around their horizontal axis. Their ends lie
inside the posts.
"""
