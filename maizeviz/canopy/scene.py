"""A canopy: every placed plant's leaf meshes in field coordinates, with ids per triangle.

Each digitized leaf is meshed once per level and then copied, rotated and moved to every place
its plant stands, so rebuilding an 81-plant canopy at a new level costs the meshing of the 9
digitized plants plus array copies.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass

import numpy as np

from maizeviz.canopy.layout import CanopyLayout, plant_bases
from maizeviz.errors import MaizevizError
from maizeviz.leaf.fit import Leaf
from maizeviz.mesh.levels import Level, mesh_leaves
from maizeviz.progress import ProgressCallback, report, scaled

STALK_RADIUS_CM = 1.2
STALK_SIDES = 8
#: Triangles of one plant's stalk (:func:`stalk_mesh`: two per side).
STALK_TRIANGLES = 2 * STALK_SIDES


def plant_tops(leaves: list[Leaf]) -> dict[int, float]:
    """Height (cm) of the highest leaf insertion of each plant: where the stalk mesh ends."""
    tops: dict[int, float] = defaultdict(float)
    for lf in leaves:
        tops[lf.grid.plant] = max(tops[lf.grid.plant], float(lf.grid.collar[2]))
    return dict(tops)


@dataclass(frozen=True)
class Canopy:
    """Triangles of a canopy at one level.

    Attributes
    ----------
    vertices : (V, 3) float64, cm
    faces : (F, 3) int64
    face_instance : (F,) int32
        Index of the placement (plant standing in the canopy) each triangle belongs to.
    face_plant : (F,) int32
        Digitized plant id.
    face_leaf : (F,) int32
        Leaf rank.
    layout : CanopyLayout
    level : str
    stalk_vertices : (S, 3) float64, stalk_faces : (G, 3) int64
        Stalk cylinders for views; not leaves, not in the leaf measures.
    leaves_per_instance : (P,) int32
    stalk_instance : (G,) int32, or None
        The placement each stalk triangle belongs to, where plants' stalks differ in size (a
        canopy read from a mesh file); None: each placement has an equal share of the stalk
        triangles, in placement order.
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_instance: np.ndarray
    face_plant: np.ndarray
    face_leaf: np.ndarray
    layout: CanopyLayout
    level: str
    stalk_vertices: np.ndarray
    stalk_faces: np.ndarray
    leaves_per_instance: np.ndarray
    stalk_instance: np.ndarray | None = None

    @property
    def n_triangles(self) -> int:
        return len(self.faces)

    @classmethod
    def from_triangles(cls, vertices: np.ndarray, faces: np.ndarray, layout: CanopyLayout,
                       face_leaf: np.ndarray | None = None, level: str = "") -> Canopy:
        """A canopy of given triangles (V, 3) cm / (F, 3), all belonging to the layout's first
        placement; for analytic test scenes and imported meshes."""
        n = len(faces)
        leaf = np.arange(1, n + 1, dtype=np.int32) if face_leaf is None else face_leaf
        return cls(np.asarray(vertices, np.float64), np.asarray(faces, np.int64),
                   np.zeros(n, np.int32), np.full(n, layout.placements[0].plant, np.int32),
                   np.asarray(leaf, np.int32), layout, level, np.empty((0, 3)),
                   np.empty((0, 3), np.int64), np.array([len(np.unique(leaf))], np.int32))

    @property
    def n_plants(self) -> int:
        return len(self.layout.placements)

    @property
    def n_leaves(self) -> int:
        return int(self.leaves_per_instance.sum())


def _rotation(deg):
    t = np.radians(deg)
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def stalk_mesh(height: float, radius: float = STALK_RADIUS_CM, sides: int = STALK_SIDES):
    """An open cylinder from z = 0 to ``height`` about the z axis: (2 sides, 3), (2 sides, 3)."""
    t = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    ring = np.column_stack([radius * np.cos(t), radius * np.sin(t), np.zeros(sides)])
    top = ring + [0, 0, height]
    verts = np.vstack([ring, top])
    i = np.arange(sides)
    j = (i + 1) % sides
    faces = np.vstack([np.column_stack([i, j, j + sides]), np.column_stack([i, j + sides, i + sides])])
    return verts, faces.astype(np.int64)


def build_canopy(leaves: list[Leaf], layout: CanopyLayout, level: Level,
                 preserve_area: bool = True, progress: ProgressCallback | None = None) -> Canopy:
    """Place every plant of ``layout`` with its leaves meshed at ``level``.

    Parameters
    ----------
    leaves : all fitted leaves of the digitized plants (field coordinates, cm)
    progress : called as work advances (meshing, then placing); returning ``False`` cancels
        with :class:`InterruptedError` (see :mod:`maizeviz.progress`).
    """
    by_plant: dict[int, list[Leaf]] = defaultdict(list)
    for lf in leaves:
        by_plant[lf.grid.plant].append(lf)
    missing = sorted({p.plant for p in layout.placements} - set(by_plant))
    if missing:
        raise MaizevizError(f"the layout places plant(s) {', '.join(map(str, missing))}, which "
                            "the points file does not have")
    used = sorted({p.plant for p in layout.placements})
    source = [lf for p in used for lf in by_plant[p]]
    n_place = len(layout.placements)
    total = len(source) + n_place

    meshes = mesh_leaves(source, level, preserve_area, scaled(progress, 0, total))
    bases = plant_bases(source)
    tops = plant_tops(source)

    # one local mesh per digitized plant, relative to its stalk base
    local = {}
    k = 0
    for p in used:
        n = len(by_plant[p])
        ms = meshes[k:k + n]
        k += n
        offs = np.cumsum([0] + [m.points.shape[0] for m in ms])
        verts = np.concatenate([m.points for m in ms]) - [bases[p][0], bases[p][1], 0.0]
        faces = np.concatenate([m.faces.astype(np.int64) + o for m, o in zip(ms, offs)])
        leaf_ids = np.concatenate([np.full(len(m.faces), m.leaf, np.int32) for m in ms])
        local[p] = (verts, faces, leaf_ids, len(ms))

    vparts, fparts, inst, plant_ids, leaf_parts, nleaves = [], [], [], [], [], []
    svparts, sfparts = [], []
    v_off = s_off = 0
    for i, pl in enumerate(layout.placements):
        verts, faces, lids, nl = local[pl.plant]
        moved = verts @ _rotation(pl.azimuth_deg).T + [pl.x, pl.y, 0.0]
        vparts.append(moved)
        fparts.append(faces + v_off)
        v_off += len(verts)
        inst.append(np.full(len(faces), i, np.int32))
        plant_ids.append(np.full(len(faces), pl.plant, np.int32))
        leaf_parts.append(lids)
        nleaves.append(nl)
        sv, sf = stalk_mesh(tops[pl.plant])
        svparts.append(sv + [pl.x, pl.y, 0.0])
        sfparts.append(sf + s_off)
        s_off += len(sv)
        if i % 9 == 8 or i == n_place - 1:
            report(progress, len(source) + i + 1, total, "canopy build")
    return Canopy(np.concatenate(vparts), np.concatenate(fparts), np.concatenate(inst),
                  np.concatenate(plant_ids), np.concatenate(leaf_parts), layout, level.label,
                  np.concatenate(svparts), np.concatenate(sfparts),
                  np.array(nleaves, dtype=np.int32))
