"""How a sun's light can be painted on the canopy without misleading: per triangle where the
rays sample every triangle, per leaf where the triangles are smaller than the ray spacing.

A sun is traced with rays on a lattice over the sample rectangle (``density`` rays per cm2 of
ground). A leaf triangle of area ``a`` whose normal makes the angle theta with the sun, under a
sun at zenith z, casts a shadow of ``a |cos theta| / cos z`` cm2 on the ground and so expects
``density * a |cos theta| / cos z`` rays. When that is well below one, most triangles of a
sunlit leaf get no ray and their class
(:func:`~maizeviz.light.results.per_leaf.triangle_light`) reads "no direct light" though the
leaf is in the sun: at K = 4 and 2 rays/cm2 the median triangle
expects 0.23 rays and 82.5 % of the triangles are classed unlit (9.8 % direct), against 26 %
unlit at 36 triangles a leaf, whose median triangle expects 12. A leaf's sunlit share (the
rays' lit area over the leaf, the quantity of the per-leaf table) stays an honest estimate at
any triangle size, so that is what is painted there.

The rule: paint triangles when the median leaf triangle expects at least :data:`MIN_RAYS`
rays (a fully lit triangle then has at most ``exp(-3)``, 5 %, chance of getting none), else
paint each leaf's share. Raising the density until every triangle gets rays would cost 13
times the rays at K = 4 (26 rays/cm2) for one picture; the numbers of the tables do not need
it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.errors import MaizevizError
from maizeviz.ids import groups
from maizeviz.light.results.direct import LightResult
from maizeviz.light.results.per_leaf import NOT_TRACED, tile_representatives
from maizeviz.mesh.tessellate import triangle_areas_normals

#: Rays the median leaf triangle must expect for the triangles to be painted one by one.
MIN_RAYS = 3.0
#: What a painting can be: each triangle's light class, or each leaf's sunlit share.
PER = ("triangles", "leaves")


@dataclass(frozen=True)
class SunPainting:
    """A sun's light as the canopy can show it.

    Attributes
    ----------
    classes : (F,) int8, each leaf triangle's light class (2 direct, 1 second class, 0 none,
        -1 not traced; :meth:`~maizeviz.light.results.direct.LightResult.triangle_light`)
    share : (F,) float32, the sunlit share of each triangle's leaf, 0 to 1 (NaN where no
        traced ray could reach the leaf)
    rays_per_triangle : the rays the median leaf triangle expects (see the module docstring)
    density : the rays per cm2 of ground traced
    per : ``"triangles"`` or ``"leaves"``, what is honest to paint (the rule above)
    """

    classes: np.ndarray
    share: np.ndarray
    rays_per_triangle: float
    density: float
    per: str

    def chosen(self, asked: str = "auto") -> str:
        """What to paint when the user asks ``asked`` (``auto``, ``triangles`` or
        ``leaves``)."""
        if asked == "auto":
            return self.per
        if asked not in PER:
            raise ValueError(f"paint per {asked!r}: one of auto, {', '.join(PER)}")
        return asked

    def note(self, per: str | None = None) -> str:
        """One line saying what is painted and why."""
        per = per or self.per
        why = (f"the median leaf triangle expects {self.rays_per_triangle:.2g} rays at "
               f"{self.density:.3g} rays/cm²")
        if per == "leaves":
            return (f"each leaf painted with its sunlit share: {why}, too few to class each "
                    "triangle")
        if self.rays_per_triangle < MIN_RAYS:
            return (f"each triangle painted with its light class though {why}: many sunlit "
                    "triangles get no ray and read unlit")
        return f"each triangle painted with its light class ({why})"


def expected_rays(canopy: Canopy, result: LightResult) -> np.ndarray:
    """(F,) float64, the rays each leaf triangle expects: its shadow on the ground times the
    ray density (see the module docstring)."""
    area, normals = triangle_areas_normals(canopy.vertices, canopy.faces)
    return _expected(result, area, normals)


def _expected(result: LightResult, area: np.ndarray, normals: np.ndarray) -> np.ndarray:
    s = np.asarray(result.direction, dtype=np.float64)
    return result.density_per_cm2 * area * np.abs(normals @ s) / max(abs(s[2]), 1e-9)


def leaf_sunlit_share(canopy: Canopy, result: LightResult,
                      classes: np.ndarray | None = None) -> np.ndarray:
    """(F,) float32: for each leaf triangle, the sunlit share of its leaf, the sunlit area of
    :func:`~maizeviz.light.results.per_leaf.leaf_light` (sampled toward the sun, else ray
    count x footprint / |cos theta|, over the leaf's triangles, its plant's copies in a
    tile-periodic field together) over the
    leaf's area that traced rays could reach, capped at 1; NaN for a leaf no traced ray could
    reach.
    ``classes``: the triangles' classes when already made (their -1 marks untraced)."""
    if result.first_hits is None:
        raise MaizevizError("hit classes were not traced")
    classes = result.triangle_light(canopy) if classes is None else classes
    area, normals = triangle_areas_normals(canopy.vertices, canopy.faces)
    return _share(canopy, result, classes, area, normals)


def _share(canopy: Canopy, result: LightResult, classes: np.ndarray, area: np.ndarray,
           normals: np.ndarray) -> np.ndarray:
    nf = canopy.n_triangles
    if nf == 0:
        return np.zeros(0, np.float32)
    assert result.first_hits is not None
    if result.triangle_sunlit_cm2 is not None:         # sampled: the leaf tables' own
        tri_sunlit = np.asarray(result.triangle_sunlit_cm2[:nf], dtype=np.float64)
    else:
        s = np.asarray(result.direction, dtype=np.float64)
        lit = result.ray_area_cm2 * s[2] / np.maximum(np.abs(normals @ s), 1e-6)
        tri_sunlit = np.asarray(result.first_hits[:nf], dtype=np.float64) * lit
    rep = tile_representatives(canopy.layout, result.rect, result.periodic)
    inst = canopy.face_instance.astype(np.int64)
    owner, rank = rep[inst], np.asarray(canopy.face_leaf, np.int64)
    # a leaf's triangles lie together: find the runs, and the leaves among the runs' (owner,
    # leaf) pairs (a sort of thousands of runs, not of millions of triangles)
    starts = np.flatnonzero(np.r_[True, (owner[1:] != owner[:-1]) | (rank[1:] != rank[:-1])
                                  | (inst[1:] != inst[:-1])])
    _, run_leaf = groups(owner[starts], rank[starts])
    leaf = np.repeat(run_leaf, np.diff(np.r_[starts, nf]))
    n = int(run_leaf.max()) + 1
    sunlit = np.bincount(leaf, weights=tri_sunlit, minlength=n)
    traced = np.bincount(leaf, weights=np.where(classes >= 0, area, 0.0), minlength=n)
    # the copies of a plant share their light: the leaf's area is one copy's
    pairs, _ = groups(run_leaf, inst[starts])
    copies = np.bincount(pairs[:, 0], minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(traced > 0, np.minimum(sunlit / (traced / copies), 1.0), np.nan)
    return share[leaf].astype(np.float32)


def sun_painting(canopy: Canopy, result: LightResult) -> SunPainting:
    """How to paint ``result`` (a sun traced with hit classes) on ``canopy``."""
    if result.first_hits is None:
        raise MaizevizError("hit classes were not traced")
    classes = result.triangle_light(canopy)
    area, normals = triangle_areas_normals(canopy.vertices, canopy.faces)
    share = _share(canopy, result, classes, area, normals)
    rays = _expected(result, area, normals)[classes != NOT_TRACED]
    median = float(np.median(rays)) if len(rays) else 0.0
    return SunPainting(classes, share, median, float(result.density_per_cm2),
                       "triangles" if median >= MIN_RAYS else "leaves")
