"""A canopy: every placed plant's leaf meshes in field coordinates, with ids per triangle.

Each digitized leaf is meshed once per level and then copied, rotated and moved to every place
its plant stands, so rebuilding an 81-plant canopy at a new level costs the meshing of the 9
digitized plants plus array copies.

Memory by design (a canopy of a hectare holds 40 million triangles): vertices in float64 (the
geometry every measure and the periodic field's grid are computed from; Embree gets its float32
copy), triangles as int32 vertex indices (Embree's own index format, shared with an open
field's scene), ids per triangle in the narrowest integer type holding their range (the
placement: 2 bytes up to 32,767 plants; a leaf rank: 1 byte). Built into arrays of the final
size, each plant's meshes let go as soon as its last placement is written.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass

import numpy as np

from maizeviz.canopy.layout import CanopyLayout, plant_bases
from maizeviz.errors import MaizevizError
from maizeviz.leaf.fit import Leaf
from maizeviz.memory import release
from maizeviz.mesh.levels import Level, mesh_leaves
from maizeviz.mesh.tessellate import LeafMesh
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
    faces : (F, 3) int32 (int64 beyond 2^31 - 1 vertices)
    face_instance : (F,) int16 or int32 (:func:`id_type`)
        Index of the placement (plant standing in the canopy) each triangle belongs to.
    face_plant : (F,) signed integers, as narrow as the ids allow
        Digitized plant id.
    face_leaf : (F,) signed integers, as narrow as the ids allow (int8 for ranks to 127)
        Leaf rank.
    layout : CanopyLayout
    level : str
    stalk_vertices : (S, 3) float64, stalk_faces : (G, 3) int32
        Stalk cylinders for views; not leaves, not in the leaf measures.
    leaves_per_instance : (P,) int32
    stalk_instance : (G,) int16 or int32, or None
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

    def __post_init__(self) -> None:
        # whoever builds a canopy (placed plants, a mesh file, test scenes), its arrays come
        # out in the types above: no copy where they already are
        n_inst = max(len(self.layout.placements), 1)
        fixed = {"vertices": _as(self.vertices, np.float64),
                 "faces": _as(self.faces, index_type(len(self.vertices))),
                 "face_instance": _as(self.face_instance, id_type(0, n_inst - 1)),
                 "face_plant": _as(self.face_plant, id_type_of(self.face_plant)),
                 "face_leaf": _as(self.face_leaf, id_type_of(self.face_leaf)),
                 "stalk_vertices": _as(self.stalk_vertices, np.float64),
                 "stalk_faces": _as(self.stalk_faces, index_type(len(self.stalk_vertices))),
                 "leaves_per_instance": _as(self.leaves_per_instance, np.int32)}
        if self.stalk_instance is not None:
            fixed["stalk_instance"] = _as(self.stalk_instance, id_type(0, n_inst - 1))
        for name, value in fixed.items():
            object.__setattr__(self, name, value)

    @property
    def nbytes(self) -> int:
        """Bytes held by the canopy's arrays."""
        return sum(a.nbytes for a in (self.vertices, self.faces, self.face_instance,
                                      self.face_plant, self.face_leaf, self.stalk_vertices,
                                      self.stalk_faces, self.leaves_per_instance)) + \
            (0 if self.stalk_instance is None else self.stalk_instance.nbytes)

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
        return cls(np.asarray(vertices, np.float64), np.asarray(faces),
                   np.zeros(n, np.int32), np.full(n, layout.placements[0].plant, np.int64),
                   np.asarray(leaf), layout, level, np.empty((0, 3)),
                   np.empty((0, 3), np.int32), np.array([len(np.unique(leaf))], np.int32))

    @property
    def n_plants(self) -> int:
        return len(self.layout.placements)

    @property
    def n_leaves(self) -> int:
        return int(self.leaves_per_instance.sum())


def id_type(lo: int, hi: int) -> type[np.signedinteger]:
    """The narrowest signed integer type holding every value from ``lo`` to ``hi``."""
    for t in (np.int8, np.int16, np.int32):
        info = np.iinfo(t)
        if info.min <= lo and hi <= info.max:
            return t
    return np.int64


def id_type_of(ids: np.ndarray) -> type[np.signedinteger]:
    """:func:`id_type` of the range of ``ids`` (int8 for none)."""
    a = np.asarray(ids)
    if not a.size:
        return np.int8
    return id_type(int(a.min()), int(a.max()))


def index_type(n_vertices: int) -> type[np.signedinteger]:
    """Type of vertex indices into ``n_vertices`` vertices: int32 (Embree's), int64 beyond."""
    return np.int32 if n_vertices <= np.iinfo(np.int32).max else np.int64


def _as(a: np.ndarray, dtype) -> np.ndarray:
    a = np.asarray(a)
    return a if a.dtype == dtype else a.astype(dtype)


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
    return verts, faces.astype(np.int32)


@dataclass(frozen=True)
class PlantMesh:
    """One digitized plant's leaves meshed at a level, relative to its stalk base.

    Attributes
    ----------
    vertices : (V, 3) float64, cm: x and y from the stalk base, z from the ground
    faces : (F, 3) int32, into ``vertices``
    leaf : (F,) int64, the leaf rank of each triangle
    n_leaves : int
    base : (x, y) cm, the stalk base in the field (:func:`~maizeviz.canopy.layout.plant_bases`)
    top : cm, the highest leaf insertion (:func:`plant_tops`: where its stalk mesh ends)
    """

    vertices: np.ndarray
    faces: np.ndarray
    leaf: np.ndarray
    n_leaves: int
    base: tuple[float, float]
    top: float


def plant_meshes(leaves: list[Leaf], level: Level, preserve_area: bool = True,
                 progress: ProgressCallback | None = None) -> dict[int, PlantMesh]:
    """Every plant of ``leaves`` meshed at ``level``, relative to its stalk base: what
    :func:`place_plants` copies to each place the plant stands. ``leaves`` holds whole plants
    (a plant's base is the median of its leaves' insertions); ``progress`` as in
    :func:`~maizeviz.mesh.levels.mesh_leaves`."""
    by_plant: dict[int, list[Leaf]] = defaultdict(list)
    for lf in leaves:
        by_plant[lf.grid.plant].append(lf)
    source = [lf for p in sorted(by_plant) for lf in by_plant[p]]
    meshes: list[LeafMesh | None] = list(mesh_leaves(source, level, preserve_area, progress))
    bases = plant_bases(source)
    tops = plant_tops(source)
    out = {}
    k = 0
    for p in sorted(by_plant):
        n = len(by_plant[p])
        ms = [m for m in meshes[k:k + n] if m is not None]
        meshes[k:k + n] = [None] * n                     # let each leaf's mesh go
        k += n
        offs = np.cumsum([0] + [m.points.shape[0] for m in ms])
        verts = np.concatenate([m.points for m in ms]) - [bases[p][0], bases[p][1], 0.0]
        faces = np.concatenate([m.faces + np.int32(o) for m, o in zip(ms, offs[:-1])])
        leaf_ids = np.concatenate([np.full(len(m.faces), m.leaf, np.int64) for m in ms])
        out[p] = PlantMesh(verts, faces, leaf_ids, len(ms), bases[p], tops[p])
    return out


def place_plants(plants: dict[int, PlantMesh], layout: CanopyLayout, label: str,
                 progress: ProgressCallback | None = None, keep: bool = False) -> Canopy:
    """The canopy of ``plants`` standing where ``layout`` places them: each plant's mesh
    turned by its placement's azimuth and moved to its place, with its stalk.

    The arrays are allocated at their final size and filled placement by placement; a plant's
    mesh is removed from ``plants`` after its last placement unless ``keep``. ``progress``
    counts placements.
    """
    places = layout.placements
    n_place = len(places)
    missing = sorted({p.plant for p in places} - set(plants))
    if missing:
        raise MaizevizError(f"the layout places plant(s) {', '.join(map(str, missing))}, which "
                            "the points file does not have")
    nv = np.array([len(plants[pl.plant].vertices) for pl in places], np.int64)
    nf = np.array([len(plants[pl.plant].faces) for pl in places], np.int64)
    v_at, f_at = np.concatenate([[0], np.cumsum(nv)]), np.concatenate([[0], np.cumsum(nf)])
    used = {pl.plant for pl in places}
    ranks = [r for p in used for r in (plants[p].leaf.min(initial=0), plants[p].leaf.max(initial=0))]
    vertices = np.empty((int(v_at[-1]), 3))
    faces = np.empty((int(f_at[-1]), 3), index_type(int(v_at[-1])))
    inst = np.empty(int(f_at[-1]), id_type(0, max(n_place - 1, 0)))
    plant_ids = np.empty(int(f_at[-1]), id_type(min(used), max(used)))
    leaf_ids = np.empty(int(f_at[-1]), id_type(int(min(ranks)), int(max(ranks))))
    last = {pl.plant: i for i, pl in enumerate(places)}
    sv_n, sf_n = 2 * STALK_SIDES, STALK_TRIANGLES
    stalk_vertices = np.empty((sv_n * n_place, 3))
    stalk_faces = np.empty((sf_n * n_place, 3), np.int32)
    nleaves = np.empty(n_place, np.int32)
    for i, pl in enumerate(places):
        mesh = plants[pl.plant]
        a, b = int(v_at[i]), int(v_at[i + 1])
        c, d = int(f_at[i]), int(f_at[i + 1])
        vertices[a:b] = mesh.vertices @ _rotation(pl.azimuth_deg).T + [pl.x, pl.y, 0.0]
        np.add(mesh.faces, a, out=faces[c:d], casting="unsafe")
        inst[c:d] = i
        plant_ids[c:d] = pl.plant
        leaf_ids[c:d] = mesh.leaf
        nleaves[i] = mesh.n_leaves
        sv, sf = stalk_mesh(mesh.top)
        stalk_vertices[i * sv_n:(i + 1) * sv_n] = sv + [pl.x, pl.y, 0.0]
        stalk_faces[i * sf_n:(i + 1) * sf_n] = sf + i * sv_n
        if last[pl.plant] == i and not keep:
            del plants[pl.plant]                    # its last placement: let its mesh go
        if i % 9 == 8 or i == n_place - 1:
            report(progress, i + 1, n_place, "canopy build")
    canopy = Canopy(vertices, faces, inst, plant_ids, leaf_ids, layout, label,
                    stalk_vertices, stalk_faces, nleaves)
    release()                           # the plants' meshes, freed, back to the system
    return canopy


def build_canopy(leaves: list[Leaf], layout: CanopyLayout, level: Level,
                 preserve_area: bool = True, progress: ProgressCallback | None = None) -> Canopy:
    """Place every plant of ``layout`` with its leaves meshed at ``level``.

    Parameters
    ----------
    leaves : all fitted leaves of the digitized plants (field coordinates, cm)
    progress : called as work advances (meshing, then placing); returning ``False`` cancels
        with :class:`InterruptedError` (see :mod:`maizeviz.progress`).
    """
    placed = {p.plant for p in layout.placements}
    have = {lf.grid.plant for lf in leaves}
    missing = sorted(placed - have)
    if missing:
        raise MaizevizError(f"the layout places plant(s) {', '.join(map(str, missing))}, which "
                            "the points file does not have")
    source = [lf for lf in leaves if lf.grid.plant in placed]
    n_place = len(layout.placements)
    total = len(source) + n_place
    plants = plant_meshes(source, level, preserve_area, scaled(progress, 0, total))
    return place_plants(plants, layout, level.label, scaled(progress, len(source), total))
