"""From leaf grids to surfaces to meshes at any level, with the leaf measures.

A *level* is either ``K`` interpolated points between data points (K >= 0; K = 0 is the
paper's standard mesh, K = 4 its reference mesh) or a triangle budget below the standard mesh
(inverse multi-line segment splitting).
"""

from __future__ import annotations

import re
from collections import defaultdict
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from maizeviz.errors import LeafError, MaizevizError
from maizeviz.io.points import read_points
from maizeviz.leaf.grid import LeafGrid, build_grids
from maizeviz.leaf.nurbs import NurbsSurfaces, fit_surfaces, refine_parameters
from maizeviz.mesh import measures
from maizeviz.mesh.simplify import simplify
from maizeviz.mesh.tessellate import LeafMesh, mesh_grid

#: Interpolation count of the paper's reference mesh (four points between data points).
REFERENCE_K = 4
#: Interpolation count of the sampling used to measure deviation from the smooth surface.
DEVIATION_K = 8
#: The paper's Table 1 levels.
DEFAULT_LEVELS = "K4,K1,standard,36,8,4,3"


@dataclass(frozen=True)
class Level:
    """A mesh level: exactly one of ``interp`` (K >= 0) or ``triangles`` (N >= 1)."""

    interp: int | None = None
    triangles: int | None = None

    def __post_init__(self):
        if (self.interp is None) == (self.triangles is None):
            raise ValueError("a level is either K interpolated points or N triangles")
        if self.interp is not None and self.interp < 0:
            raise ValueError(f"K must be >= 0, got {self.interp}")
        if self.triangles is not None and self.triangles < 1:
            raise ValueError(f"a triangle budget must be >= 1, got {self.triangles}")

    @property
    def label(self) -> str:
        if self.interp == 0:
            return "standard"
        if self.interp is not None:
            return f"K={self.interp}"
        return f"{self.triangles} triangles"

    def __str__(self) -> str:
        return self.label


def parse_level(text: str) -> Level:
    """``"K4"``/``"K=4"``/``"k4"`` -> 4 interpolated points, ``"standard"``/``"std"`` -> K=0,
    ``"36"``/``"36t"`` -> a budget of 36 triangles."""
    t = text.strip().lower().replace(" ", "")
    if t in ("standard", "std", "s"):
        return Level(interp=0)
    m = re.fullmatch(r"k=?(\d+)", t)
    if m:
        return Level(interp=int(m.group(1)))
    m = re.fullmatch(r"(\d+)(t|tri|triangles)?", t)
    if m:
        return Level(triangles=int(m.group(1)))
    raise ValueError(f"'{text}' is not a mesh level: use K4 (4 points between data points), "
                     "standard, or a triangle count such as 36")


def parse_levels(text: str) -> list[Level]:
    """Comma-separated levels, e.g. ``"K4,K1,standard,36,8,4,3"``."""
    return [parse_level(p) for p in text.split(",") if p.strip()]


@dataclass(frozen=True)
class Leaf:
    """A reconstructed leaf: its point grid and the surface through it (L = 1)."""

    grid: LeafGrid
    surface: NurbsSurfaces

    @property
    def key(self) -> tuple[int, int]:
        return self.grid.key

    @cached_property
    def reference_area_cm2(self) -> float:
        """Area (cm2) of the paper's reference mesh (K = 4); computed once per leaf, so a
        complexity slider does not pay for it at every rebuild."""
        pts, u, v = _sample(self.surface, REFERENCE_K)
        return measures.area(mesh_grid(pts[0], u[0], v[0]))

    @cached_property
    def deviation_samples(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The smooth surface sampled at K = 8: points (A, B, 3) cm, u (A,), v (B,)."""
        pts, u, v = _sample(self.surface, DEVIATION_K)
        return pts[0], u[0], v[0]


def fit_leaves(grids: list[LeafGrid], degree: int = 3, method: str = "chord",
               strict: bool = False) -> tuple[list[Leaf], list[LeafError]]:
    """Fit every grid, leaves of equal shape in one batch. Order of ``grids`` is kept.

    A leaf that cannot be fitted is returned in the error list (or raised with ``strict``).
    """
    groups = defaultdict(list)
    for i, g in enumerate(grids):
        groups[g.shape].append(i)
    result: dict[int, Leaf] = {}
    errors = []
    for idx in groups.values():
        batch = [grids[i] for i in idx]
        try:
            surf = fit_surfaces(np.stack([g.points for g in batch]), degree, degree, method,
                                [g.key for g in batch])
            for k, i in enumerate(idx):
                result[i] = Leaf(grids[i], surf[k])
        except LeafError:
            for i in idx:                                   # isolate the bad leaf or leaves
                try:
                    result[i] = Leaf(grids[i], fit_surfaces(grids[i].points, degree, degree,
                                                            method, [grids[i].key]))
                except LeafError as exc:
                    if strict:
                        raise
                    errors.append(exc)
    return [result[i] for i in sorted(result)], errors


@dataclass(frozen=True)
class LeavesFromFile:
    """What :func:`read_leaves` found: fitted leaves, refused leaves, skipped lines, repairs."""

    leaves: list
    skipped: list
    problems: list
    notes: list


def read_leaves(path, strict: bool = False, degree: int = 3,
                method: str = "chord") -> LeavesFromFile:
    """Read, grid and fit a points file: the first stage of every command and of the app.

    Raises
    ------
    MaizevizError
        The file cannot be read; with ``strict``, also the first skipped line or bad leaf.
    """
    if degree < 1:
        raise MaizevizError(f"--degree must be >= 1, got {degree}")
    table = read_points(path)
    problems = [f"{table.source}: {p}" for p in table.problems]
    if strict and problems:
        raise MaizevizError(problems[0])
    grids, errors = build_grids(table, strict=strict)
    notes = [f"plant {g.plant}, leaf {g.leaf}: {n}" for g in grids for n in g.notes]
    leaves, fit_errors = fit_leaves(grids, degree, method, strict=strict)
    return LeavesFromFile(leaves, errors + fit_errors, problems, notes)


def _sample(surfaces: NurbsSurfaces, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    u = refine_parameters(surfaces.params_u, k)
    v = refine_parameters(surfaces.params_v, k)
    return surfaces.evaluate_grid(u, v), u, v


def mesh_leaves(leaves: list[Leaf], level: Level, preserve_area: bool = True,
                progress=None) -> list[LeafMesh]:
    """Meshes of every leaf at one level, in the order given.

    Leaves of equal grid shape are sampled in one batch. ``progress(done, total)`` is called
    after each batch or leaf; if it returns ``False`` the work stops with
    :class:`InterruptedError`.
    """
    total = len(leaves)
    out: list[LeafMesh | None] = [None] * total
    done = 0

    def tick(n):
        nonlocal done
        done += n
        if progress is not None and progress(done, total) is False:
            raise InterruptedError("meshing cancelled")

    groups = defaultdict(list)
    for i, leaf in enumerate(leaves):
        groups[leaf.grid.shape].append(i)
    for idx in groups.values():
        surf = _stack([leaves[i].surface for i in idx])
        if level.interp is not None:
            pts, u, v = _sample(surf, level.interp)
            for k, i in enumerate(idx):
                g = leaves[i].grid
                out[i] = mesh_grid(pts[k], u[k], v[k], level.label, g.plant, g.leaf)
            tick(len(idx))
            continue
        for k, i in enumerate(idx):
            g = leaves[i].grid
            target = leaves[i].reference_area_cm2 if preserve_area else None
            out[i] = simplify(g.points, surf.params_u[k], surf.params_v[k], level.triangles,
                              g.tip_collapsed, target, g.plant, g.leaf)
            tick(1)
    return out


def mesh_leaf(leaf: Leaf, level: Level, preserve_area: bool = True) -> LeafMesh:
    """Mesh of one leaf at one level."""
    return mesh_leaves([leaf], level, preserve_area)[0]


def _stack(surfaces: list[NurbsSurfaces]) -> NurbsSurfaces:
    if len(surfaces) == 1:
        return surfaces[0]
    s0 = surfaces[0]
    return NurbsSurfaces(s0.degree_u, s0.degree_v,
                         *(np.concatenate([getattr(s, f) for s in surfaces])
                           for f in ("knots_u", "knots_v", "control", "weights",
                                     "params_u", "params_v")))


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
    """Area, horizontal projected area and deviation from the smooth surface of a leaf mesh.

    The reference area is the paper's reference mesh (K = 4); the deviation is measured from
    the surface sampled at K = 8.
    """
    m, n = leaf.grid.shape
    return LeafMeasures(
        plant=leaf.grid.plant, leaf=leaf.grid.leaf, rows=m, cols=n, level=mesh.level,
        triangles=mesh.n_triangles, area_cm2=measures.area(mesh),
        projected_area_cm2=measures.projected_area(mesh),
        max_deviation_cm=measures.max_deviation(mesh, *leaf.deviation_samples),
        reference_area_cm2=leaf.reference_area_cm2)
