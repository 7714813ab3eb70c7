"""What the 3D view draws of a canopy read from a mesh file, within the view's budget.

A canopy built from digitized points that is larger than
:data:`~maizeviz_app.viewport.VIEW_BUDGET` is drawn with the plants of its sample tile nearest
its centre at the level asked (up to :data:`~maizeviz_app.viewport.FINE_BUDGET` triangles) and
the others at 36 triangles a leaf, built again from their surfaces. A mesh file has no surfaces
to mesh coarser, so the plants nearest the field's centre are drawn with the file's triangles
(up to half the budget) and the others with their leaves simplified by
vertex clustering (:func:`maizeviz.mesh.cluster.cluster_triangles`: each leaf on its own,
keeping its ids) to fit the rest. Light is traced on every triangle of the file either way;
the view paints the simplified leaves per leaf, as it does the coarse plants of a built
canopy. Made in a worker thread.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyvista as pv

from maizeviz.ids import groups
from maizeviz.mesh.cluster import cell_for, cluster_triangles
from maizeviz.mesh.tessellate import triangle_areas_normals
from maizeviz_app import viewport

#: Triangles drawn of a canopy read from a file above the view's budget: the view's budget,
#: as for built canopies (779,000 triangles took 660 ms for their first frame, 260 ms for the
#: next; 308,000 left gaps of 254 to 395 ms under load).
DRAWN = viewport.VIEW_BUDGET
#: Share of those the plants drawn with the file's own triangles may take (the rest keeps
#: every leaf of the other plants drawn: clustered too coarsely, a small leaf vanishes).
FINE_SHARE = 0.5


@dataclass(frozen=True)
class Coarse:
    """Leaves simplified for drawing, as :func:`~maizeviz_app.viewport.display_polydata`
    takes them: vertices (n, 3) cm, faces (G, 3), and each face's plant, placement and
    leaf."""

    vertices: np.ndarray
    faces: np.ndarray
    face_plant: np.ndarray
    face_instance: np.ndarray
    face_leaf: np.ndarray

    @property
    def n_triangles(self) -> int:
        return len(self.faces)


def central_plants(canopy, budget: int) -> np.ndarray:
    """(P,) bool: the placements nearest the field's centre whose triangles together stay
    within ``budget`` (in order of distance; none if the nearest one alone exceeds it)."""
    x0, y0, x1, y1 = canopy.layout.bounds
    xy = np.array([(p.x, p.y) for p in canopy.layout.placements], np.float64).reshape(-1, 2)
    order = np.argsort(np.hypot(xy[:, 0] - (x0 + x1) / 2, xy[:, 1] - (y0 + y1) / 2),
                       kind="stable")
    per_plant = np.bincount(canopy.face_instance, minlength=len(xy))
    fits = np.cumsum(per_plant[order]) <= budget
    fine = np.zeros(len(xy), bool)
    fine[order[fits]] = True
    return fine


def simplified(canopy, plants: np.ndarray, triangles: int) -> Coarse:
    """The leaves of the placements ``plants`` ((P,) bool) clustered to about ``triangles``
    triangles (at most 1.1 times that)."""
    mine = np.flatnonzero(plants[canopy.face_instance])
    faces = canopy.faces[mine]
    _, group = groups(canopy.face_instance[mine], canopy.face_leaf[mine])
    area, _ = triangle_areas_normals(canopy.vertices, faces)
    cell = cell_for(float(area.sum()), triangles)
    for _ in range(4):                          # the estimate is rough: enlarge until it fits
        vertices, new, source = cluster_triangles(canopy.vertices, faces, group, cell)
        if len(new) <= 1.1 * triangles:
            break
        cell *= 1.05 * np.sqrt(len(new) / triangles)
    rows = mine[source]
    return Coarse(vertices.astype(np.float32), new, canopy.face_plant[rows],
                  canopy.face_instance[rows], canopy.face_leaf[rows])


def mesh_polydata(canopy, budget: int | None = None, drawn: int | None = None
                  ) -> pv.PolyData:
    """The view's mesh of a canopy read from a file: all of it within ``budget`` triangles
    (default :data:`~maizeviz_app.viewport.VIEW_BUDGET`, as for built canopies), else
    ``drawn`` triangles (default :data:`DRAWN`, at most ``budget``): the plants nearest the
    centre as they are and the others simplified (field data ``view_note`` says so)."""
    budget = viewport.VIEW_BUDGET if budget is None else budget
    drawn = DRAWN if drawn is None else drawn
    stalks = len(canopy.stalk_faces)
    if canopy.n_triangles + stalks <= budget:
        return viewport.canopy_polydata(canopy)
    leaf_budget = max(min(drawn, budget) - stalks, 1)
    fine = central_plants(canopy, int(FINE_SHARE * leaf_budget))
    fine_triangles = int(np.isin(canopy.face_instance, np.flatnonzero(fine)).sum())
    coarse = simplified(canopy, ~fine, max(leaf_budget - fine_triangles, 1))
    poly = viewport.display_polydata(canopy, coarse, fine)
    poly.field_data["view_note"] = [
        f"the view draws the {int(fine.sum())} plants nearest the centre with the file's "
        f"triangles and the other {int((~fine).sum())} simplified to "
        f"{coarse.n_triangles:,} triangles (light, tables and exports use every triangle)"]
    return viewport._settle(poly)
