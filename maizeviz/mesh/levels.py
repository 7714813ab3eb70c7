"""Mesh levels: fitted leaves meshed at the complexity the user chooses, with leaf measures.

A *level* is either ``K`` interpolated points between data points (K >= 0; K = 0 is the
paper's standard mesh, K = 4 its reference mesh) or a triangle budget below the standard mesh
(inverse multi-line segment splitting, :mod:`maizeviz.mesh.simplify`).
"""

from __future__ import annotations

import re
from collections import defaultdict
from dataclasses import dataclass

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.leaf.fit import Leaf
from maizeviz.leaf.nurbs import NurbsSurfaces, refine_parameters
from maizeviz.mesh import measures
from maizeviz.mesh.simplify import simplify
from maizeviz.mesh.tessellate import LeafMesh, mesh_grid
from maizeviz.progress import ProgressCallback, report

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


def parse_level(text: str) -> Level:
    """``"K4"``/``"K=4"``/``"k4"`` -> 4 interpolated points, ``"standard"``/``"std"`` -> K=0,
    ``"36"``/``"36t"`` -> a budget of 36 triangles."""
    t = str(text).strip().lower().replace(" ", "")
    if t in ("standard", "std", "s"):
        return Level(interp=0)
    m = re.fullmatch(r"k=?(\d{1,9})", t)
    if m:
        return Level(interp=int(m.group(1)))
    m = re.fullmatch(r"(\d{1,9})(t|tri|triangles)?", t)
    if m:
        return Level(triangles=int(m.group(1)))
    raise MaizevizError(f"'{text}' is not a mesh level: use K4 (4 points between data points), "
                        "standard, or a triangle count such as 36", quantity="level")


def parse_levels(text: str) -> list[Level]:
    """Comma-separated levels, e.g. ``"K4,K1,standard,36,8,4,3"``."""
    levels = [parse_level(p) for p in str(text).split(",") if p.strip()]
    if not levels:
        raise MaizevizError("give at least one mesh level", quantity="level")
    return levels


def reference_area_cm2(leaf: Leaf) -> float:
    """Area (cm2) of the leaf's reference mesh (K = 4); computed once per leaf, so a
    complexity slider does not pay for it at every rebuild."""
    if "reference_area_cm2" not in leaf.cache:
        pts, u, v = _sample(leaf.surface, REFERENCE_K)
        leaf.cache["reference_area_cm2"] = measures.area(mesh_grid(pts[0], u[0], v[0]))
    return float(leaf.cache["reference_area_cm2"])


def deviation_samples(leaf: Leaf) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The smooth surface sampled at K = 8 (computed once per leaf): points (A, B, 3) cm,
    u (A,), v (B,)."""
    if "deviation_samples" not in leaf.cache:
        pts, u, v = _sample(leaf.surface, DEVIATION_K)
        leaf.cache["deviation_samples"] = (pts[0], u[0], v[0])
    return leaf.cache["deviation_samples"]


def _sample(surfaces: NurbsSurfaces, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    u = refine_parameters(surfaces.params_u, k)
    v = refine_parameters(surfaces.params_v, k)
    return surfaces.evaluate_grid(u, v), u, v


def mesh_leaves(leaves: list[Leaf], level: Level, preserve_area: bool = True,
                progress: ProgressCallback | None = None) -> list[LeafMesh]:
    """Meshes of every leaf at one level, in the order given.

    Leaves of equal grid shape are sampled in one batch. ``progress(done, total)`` is called
    after each batch or leaf; if it returns ``False`` the work stops with
    :class:`InterruptedError`.
    """
    total = len(leaves)
    out: list[LeafMesh | None] = [None] * total
    done = 0

    def tick(n: int) -> None:
        nonlocal done
        done += n
        report(progress, done, total, "meshing")

    groups: dict[tuple[int, int], list[int]] = defaultdict(list)
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
        budget = level.triangles
        assert budget is not None                    # a level is K or a budget
        for k, i in enumerate(idx):
            g = leaves[i].grid
            target = reference_area_cm2(leaves[i]) if preserve_area else None
            try:
                out[i] = simplify(g.points, surf.params_u[k], surf.params_v[k], budget,
                                  g.tip_collapsed, target, g.plant, g.leaf)
            except ValueError as exc:                    # a budget below the coarsest mesh
                raise MaizevizError(f"{level}: plant {g.plant}, leaf {g.leaf}: {exc}",
                                    quantity="triangles") from None
            tick(1)
    return [m for m in out if m is not None]


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
        max_deviation_cm=measures.max_deviation(mesh, *deviation_samples(leaf)),
        reference_area_cm2=reference_area_cm2(leaf))
