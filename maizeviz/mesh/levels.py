"""Mesh levels: fitted leaves meshed at the complexity the user chooses, with leaf measures.

A *level* is either ``K`` interpolated points between data points (K >= 0; K = 0 is the
paper's standard mesh, K = 4 its reference mesh) or a triangle budget below the standard mesh
(inverse multi-line segment splitting, :mod:`maizeviz.mesh.simplify`).
"""

from __future__ import annotations

import os
import re
from collections import defaultdict
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.mesh import measures
from maizeviz.mesh.simplify import count_triangles, simplify_many
from maizeviz.mesh.tessellate import LeafMesh, mesh_grids
from maizeviz.progress import ProgressCallback, ordered_map, report

if TYPE_CHECKING:
    # Level and parse_level are light (the app's slider reads them before its window shows);
    # the surfaces (scipy) are imported when a leaf is meshed (the measures are numpy only).
    from maizeviz.leaf.fit import Leaf
    from maizeviz.leaf.nurbs import NurbsSurfaces

#: Interpolation count of the paper's reference mesh (four points between data points).
REFERENCE_K = 4
#: Interpolation count of the sampling used to measure deviation from the smooth surface.
DEVIATION_K = 8
#: The paper's Table 1 levels.
DEFAULT_LEVELS = "K4,K1,standard,36,8,4,3"
#: The paper's Table 2 and 3 levels (canopy and light).
CANOPY_LEVELS = "K4,standard,36,4"
#: The stops of the app's complexity slider, fine to coarse, as :func:`parse_level` reads them.
COMPLEXITY_STOPS = ("K4", "K2", "K1", "standard", "36", "16", "8", "4")
#: Largest K accepted: K = 50 already gives over 100,000 triangles per digitized leaf.
MAX_INTERP = 50
#: Surface points sampled at a time when measuring many leaves (about 50 MB of work arrays).
MEASURE_POINTS = 1 << 19
#: Vertices meshed at a time (a chunk per thread): small enough for a few chunks per core.
MESH_POINTS = 1 << 16


@dataclass(frozen=True)
class Level:
    """A mesh level: exactly one of ``interp`` (K >= 0) or ``triangles`` (N >= 1)."""

    interp: int | None = None
    triangles: int | None = None

    def __post_init__(self) -> None:
        if (self.interp is None) == (self.triangles is None):
            raise MaizevizError("a level is either K interpolated points or N triangles",
                                quantity="level")
        if self.interp is not None and not 0 <= self.interp <= MAX_INTERP:
            raise MaizevizError(f"K (points between data points) must be between 0 and "
                                f"{MAX_INTERP}, got {self.interp}", quantity="interp")
        if self.triangles is not None and self.triangles < 1:
            raise MaizevizError(f"a triangle budget must be >= 1, got {self.triangles}",
                                quantity="triangles")

    @property
    def label(self) -> str:
        """Short name: ``K=4``, ``standard``, ``36 triangles``."""
        if self.interp == 0:
            return "standard"
        if self.interp is not None:
            return f"K={self.interp}"
        return f"{self.triangles} triangles"

    @property
    def description(self) -> str:
        """What the level means, in words."""
        if self.interp == 0:
            return "standard mesh (data points only)"
        if self.interp is not None:
            return f"K = {self.interp} points between data points"
        return f"at most {self.triangles} triangles per leaf"

    def variant_label(self, preserve_area: bool) -> str:
        """The label, saying when a triangle budget keeps the paper's unscaled widths."""
        if preserve_area or self.triangles is None:
            return self.label
        return f"{self.label}, widths unscaled"

    def __str__(self) -> str:
        return self.label


#: Most mesh levels compared in one run (the paper compares 7).
MAX_LEVELS = 64


def parse_level(text: str) -> Level:
    """``"K4"``/``"K=4"``/``"k4"`` -> 4 interpolated points, ``"standard"``/``"std"`` -> K=0,
    ``"36"``/``"36t"`` -> a budget of 36 triangles."""
    t = str(text).strip().lower().replace(" ", "")
    if t in ("standard", "std", "s"):
        return Level(interp=0)
    m = re.fullmatch(r"k=?(\d{1,9})", t, re.ASCII)
    if m:
        return Level(interp=int(m.group(1)))
    m = re.fullmatch(r"(\d{1,9})(t|tri|triangles)?", t, re.ASCII)
    if m:
        return Level(triangles=int(m.group(1)))
    raise MaizevizError(f"'{text}' is not a mesh level: use K4 (4 points between data points), "
                        "standard, or a triangle count such as 36", quantity="level")


def parse_levels(text: str) -> list[Level]:
    """Comma-separated levels, e.g. ``"K4,K1,standard,36,8,4,3"``: at most
    :data:`MAX_LEVELS`, none empty (``K4,,8``), none twice (``K4,K=4``): each is refused in one
    line rather than dropped or traced twice."""
    text = str(text)
    if not text.strip():
        raise MaizevizError("give at least one mesh level", quantity="level")
    if text.count(",") >= MAX_LEVELS:
        raise MaizevizError(f"{text.count(',') + 1:,} mesh levels; at most {MAX_LEVELS} are "
                            "compared in one run", quantity="level")
    levels: list[Level] = []
    items = text.split(",")
    for k, item in enumerate(items, 1):
        if not item.strip():
            raise MaizevizError(f"mesh level {k} of {len(items)} is empty; write levels "
                                "separated by single commas", quantity="level")
        level = parse_level(item)
        if level in levels:
            raise MaizevizError(f"mesh level {level.label} is given twice (items "
                                f"{levels.index(level) + 1} and {k})", quantity="level")
        levels.append(level)
    return levels


def reference_areas(leaves: list[Leaf]) -> np.ndarray:
    """Areas (L,) cm2 of the leaves' reference meshes (K = 4), leaves of equal grid shape
    sampled together, :data:`MEASURE_POINTS` surface points at a time.

    Each area is kept in ``leaf.cache["reference_area_cm2"]`` (a leaf already holding one is
    not sampled again) and is the area of :func:`~maizeviz.mesh.tessellate.mesh_grid` of the
    K = 4 samples, zero-area triangles left out.
    """
    out = np.empty(len(leaves))
    todo: dict[tuple[int, int], list[int]] = defaultdict(list)
    for i, leaf in enumerate(leaves):
        if "reference_area_cm2" in leaf.cache:
            out[i] = leaf.cache["reference_area_cm2"]
        else:
            todo[leaf.grid.shape].append(i)
    for (m, n), idx in todo.items():
        per_leaf = ((m - 1) * (REFERENCE_K + 1) + 1) * ((n - 1) * (REFERENCE_K + 1) + 1)
        for chunk in _chunks(idx, per_leaf):
            pts, _, _ = _sample(_stack([leaves[i].surface for i in chunk]), REFERENCE_K)
            for i, a in zip(chunk, measures.grid_areas(pts)):
                leaves[i].cache["reference_area_cm2"] = out[i] = float(a)
    return out


def _chunks(idx: list[int], per_leaf: int, points: int = MEASURE_POINTS) -> list[list[int]]:
    """``idx`` cut in runs of about ``points`` // ``per_leaf`` (at least 1)."""
    step = max(1, points // max(per_leaf, 1))
    return [idx[k:k + step] for k in range(0, len(idx), step)]


def _sample(surfaces: NurbsSurfaces, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from maizeviz.leaf.nurbs import refine_parameters

    u = refine_parameters(surfaces.params_u, k)
    v = refine_parameters(surfaces.params_v, k)
    return surfaces.evaluate_grid(u, v), u, v


def mesh_leaves(leaves: list[Leaf], level: Level, preserve_area: bool = True,
                progress: ProgressCallback | None = None,
                threads: int | None = None) -> list[LeafMesh]:
    """Meshes of every leaf at one level, in the order given.

    Leaves of equal grid shape are meshed together, :data:`MESH_POINTS` vertices (or
    standard-grid points, under a triangle budget) at a time, the chunks on ``threads``
    threads (default: one per core; numpy releases the interpreter's lock in its loops).
    ``progress(done, total)`` is called after each chunk; if it returns ``False`` the work
    stops with :class:`InterruptedError`.
    """
    total = len(leaves)
    out: list[LeafMesh | None] = [None] * total
    groups: dict[tuple[int, int], list[int]] = defaultdict(list)
    for i, leaf in enumerate(leaves):
        groups[leaf.grid.shape].append(i)
    k = level.interp if level.interp is not None else 0
    chunks = []
    for (m, n), group in groups.items():
        per_leaf = ((m - 1) * (k + 1) + 1) * ((n - 1) * (k + 1) + 1)
        chunks += _chunks(group, per_leaf, MESH_POINTS)
    done = 0

    def tick(j: int) -> None:
        nonlocal done
        done += len(chunks[j - 1])
        report(progress, done, total, "meshing")

    work = ordered_map(lambda idx: _mesh_chunk(leaves, idx, level, preserve_area), chunks,
                       threads or os.cpu_count() or 1, tick)
    for j, meshes in enumerate(work):             # each chunk's tick follows its results
        for i, mesh in zip(chunks[j], meshes):
            out[i] = mesh
    return [m for m in out if m is not None]


def _mesh_chunk(leaves: list[Leaf], idx: list[int], level: Level, preserve_area: bool
                ) -> list[LeafMesh]:
    """Meshes of ``leaves[i]`` for i in ``idx`` (one grid shape), in that order."""
    surf = _stack([leaves[i].surface for i in idx])
    plants = [leaves[i].grid.plant for i in idx]
    ranks = [leaves[i].grid.leaf for i in idx]
    if level.interp is not None:
        pts, u, v = _sample(surf, level.interp)
        meshes = mesh_grids(pts, u, v, level.label, plants, ranks)
    else:
        budget = level.triangles
        assert budget is not None                    # a level is K or a budget
        targets = reference_areas([leaves[i] for i in idx]) if preserve_area else None
        tips = np.array([leaves[i].grid.tip_collapsed for i in idx])
        try:
            meshes = simplify_many(np.stack([leaves[i].grid.points for i in idx]),
                                   surf.params_u, surf.params_v, budget, tips, targets,
                                   plants, ranks)
        except ValueError as exc:                    # a budget below the coarsest mesh
            first = next(leaves[i].grid for k, i in enumerate(idx)
                         if budget < count_triangles(2, 2, tips[k]))
            raise MaizevizError(f"{level}: plant {first.plant}, leaf {first.leaf}: {exc}",
                                quantity="triangles") from None
    return meshes


def mesh_leaf(leaf: Leaf, level: Level, preserve_area: bool = True) -> LeafMesh:
    """Mesh of one leaf at one level."""
    return mesh_leaves([leaf], level, preserve_area)[0]


def _stack(surfaces: list[NurbsSurfaces]) -> NurbsSurfaces:
    from maizeviz.leaf.nurbs import NurbsSurfaces

    return NurbsSurfaces.join(surfaces)


@dataclass(frozen=True)
class LeafMeasures:
    """Measures of one leaf at one level (areas in cm2, lengths in cm)."""

    plant: int
    leaf: int
    rows: int
    cols: int
    level: str
    triangles: int
    area_cm2: float
    projected_area_cm2: float
    max_deviation_cm: float
    reference_area_cm2: float

    @property
    def area_error_pct(self) -> float:
        return 100.0 * (self.area_cm2 / self.reference_area_cm2 - 1.0)

    def as_dict(self) -> dict:
        d = dict(self.__dict__)
        d["area_error_pct"] = self.area_error_pct
        return d


def measure(leaf: Leaf, mesh: LeafMesh) -> LeafMeasures:
    """Area, horizontal projected area and deviation from the smooth surface of a leaf mesh:
    :func:`measure_leaves` of one leaf."""
    return measure_leaves([leaf], [mesh])[0]


def measure_leaves(leaves: list[Leaf], meshes: list[LeafMesh],
                   progress: ProgressCallback | None = None) -> list[LeafMeasures]:
    """Area, horizontal projected area and deviation from the smooth surface of each leaf's
    mesh, many leaves at a time.

    The reference area is the paper's reference mesh (K = 4, :func:`reference_areas`, kept in
    ``leaf.cache``); the deviation is measured from the surface sampled at K = 8 to the mesh
    (:func:`~maizeviz.mesh.measures.max_deviations`). Leaves whose grids and meshes share
    shapes (at a K level, all leaves of a grid shape; under a triangle budget, those whose
    selected lines have the same counts) are measured together, :data:`MEASURE_POINTS` surface
    points at a time, so memory stays bounded whatever the number of leaves. The values are
    those of the leaf-by-leaf measure this replaced (trimesh's closest point on 18 triangles
    per surface point) to rounding: 1e-13 cm, 1e-15 relative (tests/core/test_measure_batch.py).

    Parameters
    ----------
    leaves : fitted leaves
    meshes : their meshes, ``meshes[i]`` of ``leaves[i]`` (as :func:`mesh_leaves` returns them)
    progress : ``progress(done, total)`` in leaves; returning ``False`` stops the work with
        :class:`InterruptedError`

    Returns
    -------
    One :class:`LeafMeasures` per leaf, in the order given.
    """
    if len(leaves) != len(meshes):
        raise ValueError(f"{len(leaves)} leaves but {len(meshes)} meshes")
    total = len(leaves)
    ref = reference_areas(leaves)
    area, projected = np.empty(total), np.empty(total)
    deviation = np.empty(total)
    groups: dict[tuple, list[int]] = defaultdict(list)
    for i, (leaf, mesh) in enumerate(zip(leaves, meshes)):
        groups[(leaf.grid.shape, mesh.vertices.shape[:2])].append(i)
    done = 0
    for ((m, n), _), idx in groups.items():
        per_leaf = ((m - 1) * (DEVIATION_K + 1) + 1) * ((n - 1) * (DEVIATION_K + 1) + 1)
        for chunk in _chunks(idx, per_leaf):
            part = [meshes[i] for i in chunk]
            area[chunk], projected[chunk] = measures.areas(part)
            pts, u, v = _sample(_stack([leaves[i].surface for i in chunk]), DEVIATION_K)
            deviation[chunk] = measures.max_deviations(
                np.stack([ms.vertices for ms in part]), np.stack([ms.u for ms in part]),
                np.stack([ms.v for ms in part]), pts, u, v)
            done += len(chunk)
            report(progress, done, total, "measuring")
    return [LeafMeasures(plant=leaf.grid.plant, leaf=leaf.grid.leaf, rows=leaf.grid.shape[0],
                         cols=leaf.grid.shape[1], level=mesh.level, triangles=mesh.n_triangles,
                         area_cm2=float(area[i]), projected_area_cm2=float(projected[i]),
                         max_deviation_cm=float(deviation[i]),
                         reference_area_cm2=float(ref[i]))
            for i, (leaf, mesh) in enumerate(zip(leaves, meshes))]
