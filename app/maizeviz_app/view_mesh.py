"""What the 3D view draws of a canopy, made in the worker that built or read it (no Qt here;
pyvista is imported once the view is ready).

A frame of millions of triangles stalls software OpenGL: above the view's budget
(:data:`maizeviz_app.viewport.VIEW_BUDGET`) the plants around the sampled tile are drawn at the
display level (36 triangles a leaf), and a canopy read from a mesh file is drawn within the
same budget (:mod:`maizeviz_app.mesh_file_view`), while light, tables and exports keep every
triangle.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any


def view_mesh(job, canopy, coarse: Callable[[], Any] | None, ready: threading.Event,
              from_file: bool = False):
    """The polydata the view draws of ``canopy`` (``coarse()``: the canopy at the display
    level, None when it is that level already; ``from_file``: read from a mesh file;
    ``ready``: set once pyvista is loaded, which the work waits for, checking ``job`` for a
    cancel)."""
    while not ready.wait(0.05):                 # pyvista still loading at start-up
        job.check()
    if from_file:
        from maizeviz_app.mesh_file_view import mesh_polydata

        return mesh_polydata(canopy)
    from maizeviz_app.viewport import VIEW_BUDGET, canopy_polydata, display_polydata

    if coarse is not None and canopy.n_triangles > VIEW_BUDGET:
        small = coarse()
        job.check()
        if small is not None and small.n_triangles < canopy.n_triangles:
            return display_polydata(canopy, small)
    return canopy_polydata(canopy)
