"""Picking in the 3D view: which triangle is under the mouse, and the picked leaf or plant
drawn highlighted.

Nothing is rendered to pick: re-rendering a frame of the canopy to read back the triangle under
the mouse costs a frame (150-700 ms on software OpenGL at K = 4). Instead each mesh the view
draws carries a cell locator (VTK's ``vtkStaticCellLocator``, built by the worker that made the
mesh, see :func:`make_pickable`), and a click casts one ray from the camera through the pixel
into it: well under a millisecond. The picked triangle's cell data say its placement, plant
and leaf.

Qt-free but for the pixel conversion, which the view does; VTK and pyvista only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyvista as pv
from vtkmodules.vtkCommonCore import reference
from vtkmodules.vtkCommonDataModel import vtkGenericCell


@dataclass(frozen=True)
class Pick:
    """What is under a pixel: the drawn triangle (``cell``), its placement (``instance``,
    from 0), digitized ``plant`` and ``leaf`` (rank from 1; 0 for a stalk), and where the ray
    met it (``point``, cm)."""

    cell: int
    instance: int
    plant: int
    leaf: int
    point: tuple[float, float, float]


def make_pickable(poly: pv.PolyData) -> pv.PolyData:
    """Build the mesh's cell locator (about 70 ms for 336,000 triangles, so in the worker that
    made the mesh), kept when the mesh's colours change later."""
    if poly.n_cells and poly.GetCellLocator() is None:
        poly.BuildCellLocator()
        poly.GetCellLocator().UseExistingSearchStructureOn()
    return poly


def ray_through(renderer, x: float, y: float) -> tuple[np.ndarray, np.ndarray]:
    """The camera ray through the display point (``x``, ``y``) (VTK's display pixels, from
    the bottom left): its points on the near and far clipping planes, cm."""
    ends = []
    for depth in (0.0, 1.0):
        renderer.SetDisplayPoint(float(x), float(y), depth)
        renderer.DisplayToWorld()
        w = np.array(renderer.GetWorldPoint(), dtype=np.float64)
        ends.append(w[:3] / (w[3] if w[3] else 1.0))
    return ends[0], ends[1]


def pick(poly: pv.PolyData | None, renderer, x: float, y: float) -> Pick | None:
    """The triangle of ``poly`` nearest the camera under the display point (``x``, ``y``),
    None if the ray meets none."""
    if poly is None or poly.n_cells == 0:
        return None
    locator = make_pickable(poly).GetCellLocator()
    p0, p1 = ray_through(renderer, x, y)
    t, where, pcoords = reference(0.0), [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    sub, cell = reference(0), reference(-1)
    if not locator.IntersectWithLine(p0, p1, 1e-6, t, where, pcoords, sub, cell,
                                     vtkGenericCell()):
        return None
    c = int(cell)
    data = poly.cell_data
    return Pick(c, int(data["instance"][c]) - 1, int(data["plant"][c]), int(data["leaf"][c]),
                (float(where[0]), float(where[1]), float(where[2])))


def part_mesh(poly: pv.PolyData, instance: int, leaf: int) -> pv.PolyData | None:
    """The drawn triangles of placement ``instance`` (from 0): its leaf ``leaf`` (rank), or
    the whole plant with ``leaf`` -1; None if none is drawn."""
    data = poly.cell_data
    mine = np.asarray(data["instance"]) == instance + 1
    if leaf >= 0:
        mine &= np.asarray(data["leaf"]) == leaf
    cells = np.flatnonzero(mine)
    if not len(cells):
        return None
    faces = poly.regular_faces[cells]
    used, inverse = np.unique(faces, return_inverse=True)
    return pv.PolyData.from_regular_faces(np.asarray(poly.points)[used],
                                          inverse.reshape(faces.shape))


def part_bounds(poly: pv.PolyData, instance: int, leaf: int = -1) -> tuple | None:
    """x0, x1, y0, y1, z0, z1 (cm) of what :func:`part_mesh` draws, None if nothing."""
    part = part_mesh(poly, instance, leaf)
    return None if part is None else tuple(float(b) for b in part.bounds)
