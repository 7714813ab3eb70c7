"""The sunlit share of every triangle, sampled from the triangle toward the sun.

The sun's beam is traced forward as a grid of rays (:mod:`.scatter`); the rays a triangle
intercepts, times the cm2 of leaf each stands for, estimate its sunlit area without bias, but
not within bounds: a triangle that the grid's rays would hit ``e < 1`` times if it were fully
lit is hit 0 or 1 times, and the only unbiased reading of one hit is ``1 / e`` of its area
(up to 30 times it on a canopy of 2 cm leaves at 1 ray per cm2). No estimate from those counts
alone can be both unbiased and at most the area: with ``h`` in {0, 1} of mean ``e f``,
``E[T(h)] = f`` for every sunlit fraction ``f`` forces ``T(1) = 1 / e``.

So the sunlit area is sampled from the leaves themselves, as Helios samples each element's
direct light (Bailey 2018) and Caribu gives each triangle its own irradiance (Chelle & Andrieu
1998). Points are drawn on the triangles, each asked whether its path toward the sun is clear
(an occlusion query, wrapped across the plot in a periodic field); the sunlit fraction is the
share of clear points, in [0, 1] by construction and unbiased, and the direct beam a triangle
absorbs is that fraction of what its whole area would intercept, at the beam's exact flux on
its orientation. A triangle that forward rays would hit at least once fully lit gets its own
points, about as many as those rays (:func:`samples_per_triangle`). Smaller ones, which no
number of rays at this density resolves, are taken together with their neighbours of the same
leaf, in mesh order, into patches that would get about one ray (:func:`patches`): a patch's
points are spread over its triangles in proportion to the beam each would intercept, and its
fraction stands for each of them. The leaf's figures stay unbiased and bounded, and a mesh of
millions of triangles costs about as many points as rays, not one per triangle.

Those rays would hit the triangle *fully lit*; most of a dense canopy's leaf area is shaded
(at K = 4 on the bundled block at 4 rays per cm2, the triangles that may send the beam to the
sample rectangle would take 569,000 rays fully lit, against the 64,800 traced), and a point
in the shade tells no more than its neighbours. So where the forward rays have been traced,
their first hits (drawn independently of the points) say where to sample: a patch of about a
ray that one of them hit, or that lies beside one in mesh order (likely a penumbra), keeps its
points; the triangles of the other patches are taken again, with their neighbours of the same
leaf, into patches of about :data:`SHADED_PATCH_RAYS` rays, each sampled with as many points
as a patch of one ray. The patches and their points depend on the rays, never on the points'
outcomes, so each patch's share of clear points is still an unbiased estimate of its sunlit
share, in [0, 1]; a patch wholly in the shade is exact with one point. Only the sunflecks the
rays missed are estimated more coarsely: at K = 4, 160,000 points where 738,000 were drawn
without the rays (the triangles whose beam cannot land in the sample rectangle left out too);
over 16 seeds the canopy's sunlit area is 3.135 m2 where it was 3.138 (standard deviations 62
and 65 cm2), and a lit leaf's varies more (median relative standard deviation 3.6 % against
2.4 %, over the 179 leaves with over 1 cm2 in the sun; 4.8 % without the penumbra kept); the
batches' standard errors carry it.

A point counts only for the light falling on the sample rectangle, as the forward rays do:
its path traced down to the ground (wrapped into the plot in a periodic field) must land in the
rectangle.

References
----------
Bailey, B. N. (2018). A reverse ray-tracing method for modelling the net radiative flux in
leaf-resolving plant canopy simulations. Ecological Modelling 368, 233-245.
https://doi.org/10.1016/j.ecolmodel.2017.11.022
Chelle, M. & Andrieu, B. (1998). The nested radiosity model for the distribution of light
within plant canopies. Ecological Modelling 111, 75-91.
https://doi.org/10.1016/S0304-3800(98)00100-8
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.ids import groups
from maizeviz.light.results.uncertainty import BATCHES
from maizeviz.light.scene.rays import Tracer
from maizeviz.light.trace.beam import Sampler

if TYPE_CHECKING:       # scipy.sparse (0.3 s, and numpy.f2py) is imported when sampled
    from scipy.sparse import csr_array

#: Distance (cm) a sample point is lifted off its triangle toward the sun's side.
LIFT_CM = 1e-3
#: Sample points traced together (bounded memory).
CHUNK_POINTS = 1 << 18
#: Rays a patch of triangles no forward ray hit stands for, sampled as a patch of one ray.
SHADED_PATCH_RAYS = 8.0


@dataclass(frozen=True)
class SunlitShare:
    """The sampled sunlit share of each triangle.

    Attributes
    ----------
    fraction : (F,) float64
        Share of each triangle's area in the direct beam from the sample rectangle, in [0, 1].
    batches : (BATCHES, F) scipy.sparse CSR array
        Each batch's part of ``fraction`` (rows sum to it): the sample points were dealt into
        equal batches at random, so ``BATCHES x row`` are (nearly) independent estimates.
    points : int
        Sample points traced.
    """

    fraction: np.ndarray
    batches: csr_array
    points: int


@dataclass(frozen=True)
class Geometry:
    """What the sampling needs of a scene's triangles (leaves, then stalks), computed once per
    canopy (:func:`geometry`).

    Attributes
    ----------
    area_cm2 : (F,) float64
        One-sided areas [cm2].
    centre : (F, 3) float64
        Centroids [cm].
    radius_cm : (F,) float64
        Farthest corner from the centroid [cm].
    group : (F,) intp
        The leaf (or stalk of a plant) each belongs to; patches never cross it.
    box : (G, 6) float64
        Each group's box of its triangles' centroids, ``xmin, xmax, ymin, ymax, zmin, zmax``,
        widened by its largest radius [cm].
    """

    area_cm2: np.ndarray
    centre: np.ndarray
    radius_cm: np.ndarray
    group: np.ndarray
    box: np.ndarray


_KEPT: dict[int, tuple[weakref.ref, int, Geometry]] = {}


def geometry(canopy: Canopy, n_triangles: int) -> Geometry:
    """The :class:`Geometry` of the scene's ``n_triangles`` triangles (the canopy's leaves,
    then its stalks when traced), kept while the canopy lives."""
    kept = _KEPT.get(id(canopy))
    if kept is not None and kept[0]() is canopy and kept[1] == n_triangles:
        return kept[2]
    tri = scene_triangles(canopy, n_triangles)
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    centre = tri.mean(axis=1)
    radius = np.linalg.norm(tri - centre[:, None, :], axis=2).max(axis=1)
    nl = canopy.n_triangles
    inst = np.zeros(n_triangles, np.int64)
    leaf = np.full(n_triangles, -1, np.int64)               # stalks: -1 of their plant
    inst[:nl], leaf[:nl] = canopy.face_instance, canopy.face_leaf
    if n_triangles > nl and getattr(canopy, "stalk_instance", None) is not None:
        inst[nl:] = np.asarray(canopy.stalk_instance)[:n_triangles - nl]
    _, group = groups(inst, leaf)
    order = np.argsort(group, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(group[order]) != 0])
    c = centre[order]
    r = np.maximum.reduceat(radius[order], starts)[:, None] if len(order) else np.zeros((0, 1))
    box = np.hstack([np.minimum.reduceat(c, starts) - r, np.maximum.reduceat(c, starts) + r]
                    )[:, [0, 3, 1, 4, 2, 5]] if len(order) else np.zeros((0, 6))
    geo = Geometry(area, centre, radius, group, box)
    for key in [k for k, v in _KEPT.items() if v[0]() is None]:
        del _KEPT[key]
    _KEPT[id(canopy)] = (weakref.ref(canopy), n_triangles, geo)
    return geo


def scene_triangles(canopy: Canopy, n_triangles: int, which=None) -> np.ndarray:
    """(n, 3, 3) float64 cm: corners of the scene's triangles ``which`` (default all
    ``n_triangles``: the canopy's leaves, then its stalks)."""
    nl = canopy.n_triangles
    idx = np.arange(n_triangles) if which is None else np.asarray(which, np.int64)
    if not len(idx) or idx.max() < nl:                     # leaves only: one gather
        return canopy.vertices[canopy.faces[idx]]
    out = np.empty((len(idx), 3, 3))
    leaf = idx < nl
    out[leaf] = canopy.vertices[canopy.faces[idx[leaf]]]
    if not leaf.all():
        out[~leaf] = canopy.stalk_vertices[canopy.stalk_faces[idx[~leaf] - nl]]
    return out


def samples_per_triangle(area_cm2: np.ndarray, cos_beam: np.ndarray, ray_area_cm2: float,
                         toward_z: float) -> np.ndarray:
    """(F,) float64: the forward rays that would hit each triangle fully lit: its area across
    the beam over one ray's.

    Parameters
    ----------
    area_cm2 : (F,) float64
        One-sided triangle areas [cm2].
    cos_beam : (F,) float64
        ``|n . s|``, cosine between each triangle's normal and the beam [-].
    ray_area_cm2 : float
        Ground area per forward ray [cm2].
    toward_z : float
        Vertical component of the unit vector toward the sun [-].
    """
    return area_cm2 * cos_beam / (ray_area_cm2 * max(toward_z, 1e-9))


def patches(group: np.ndarray, expected: np.ndarray) -> np.ndarray:
    """(n,) intp: the patch of each triangle, numbered from 0 in the order given (so
    non-decreasing): consecutive triangles of one ``group`` whose ``expected`` rays add up to
    about one; a triangle expecting one or more rays is (nearly always) a patch of its own."""
    n = len(group)
    if not n:
        return np.zeros(0, np.intp)
    cum = np.cumsum(expected)
    new = np.ones(n, dtype=bool)
    new[1:] = group[1:] != group[:-1]
    start = np.maximum.accumulate(np.where(new, np.arange(n), 0))
    base = cum[start] - expected[start]                   # the group's sum before it
    # the ray a triangle's middle falls in, counted along its group: a patch is a run of one
    bucket = np.floor(cum - base - 0.5 * expected)
    new[1:] |= bucket[1:] != bucket[:-1]
    return np.cumsum(new) - 1


def _overlaps(lo_v: np.ndarray, hi_v: np.ndarray, lo: float, hi: float,
              start: float | None, period: float) -> np.ndarray:
    """(n,) bool: whether each interval [``lo_v``, ``hi_v``] meets [``lo``, ``hi``]; with a
    ``period`` (a periodic field starting at ``start``), any of its copies."""
    if start is None:
        return (hi_v >= lo) & (lo_v <= hi)
    a = start + np.mod(lo_v - start, period)
    b = a + (hi_v - lo_v)
    meets = hi_v - lo_v >= period
    for k in (-period, 0.0, period):
        meets |= (b + k >= lo) & (a + k <= hi)
    return meets


def _near_rect(smp: Sampler, geo: Geometry, shift: np.ndarray) -> np.ndarray:
    """(F,) bool: the triangles whose beam may land in the sample rectangle (in a periodic
    field, wrapped across the plot): those of the groups whose box, carried down the beam to
    the ground, meets it."""
    x0, y0, x1, y1 = smp.rect
    bx0, by0, bx1, by1 = smp.bounds
    if smp.periodic and np.allclose((x0, y0, x1, y1), smp.bounds):
        return np.ones(len(geo.group), dtype=bool)         # every beam lands in the plot
    box = geo.box
    near = np.ones(len(box), dtype=bool)
    for axis, (lo, hi, start, period) in enumerate(((x0, x1, bx0, bx1 - bx0),
                                                    (y0, y1, by0, by1 - by0))):
        low = box[:, 2 * axis] - np.maximum(shift[axis] * box[:, 4], shift[axis] * box[:, 5])
        high = box[:, 2 * axis + 1] - np.minimum(shift[axis] * box[:, 4],
                                                 shift[axis] * box[:, 5])
        near &= _overlaps(low, high, lo, hi, start if smp.periodic else None, period)
    return near[geo.group]


def _near_triangles(smp: Sampler, geo: Geometry, shift: np.ndarray) -> np.ndarray:
    """(n,) intp, ascending: the triangles whose beam may land in the sample rectangle. Of
    those of the groups near it (:func:`_near_rect`), each triangle whose points, within
    ``radius`` of its centre in x, y and z, land within ``radius (1 + |shift|)`` of where its
    centre's beam lands, in each axis, which must meet the rectangle (in a periodic field,
    wrapped across the plot)."""
    ids = np.flatnonzero(_near_rect(smp, geo, shift))
    x0, y0, x1, y1 = smp.rect
    bx0, by0, bx1, by1 = smp.bounds
    if not len(ids) or smp.periodic and np.allclose((x0, y0, x1, y1), smp.bounds):
        return ids
    c, r = geo.centre[ids], geo.radius_cm[ids]
    keep = np.ones(len(ids), dtype=bool)
    for axis, (lo, hi, start, period) in enumerate(((x0, x1, bx0, bx1 - bx0),
                                                    (y0, y1, by0, by1 - by0))):
        land = c[:, axis] - shift[axis] * c[:, 2]
        reach = r * (1.0 + abs(shift[axis]))
        keep &= _overlaps(land - reach, land + reach, lo, hi,
                          start if smp.periodic else None, period)
    return ids[keep]


def sunlit_share(smp: Sampler, canopy: Canopy, normals: np.ndarray, toward: np.ndarray,
                 seed: int, hits: np.ndarray | None = None,
                 cos_beam: np.ndarray | None = None) -> SunlitShare:
    """Sample the sunlit share of every triangle (see the module docstring).

    Parameters
    ----------
    smp : Sampler
        The scene, sample rectangle, density, plot and field of the forward trace.
    canopy : Canopy
        The canopy of the scene.
    normals : (F, 3) float64
        Unit normals of the scene's triangles (leaves, then stalks), in its ids.
    toward : (3,) float64
        Unit vector toward the sun, ``z > 0``.
    seed : int
        Seed of the points and of their batches.
    hits : (F,) integers, optional
        The forward rays' first hits on each triangle (drawn independently of the points).
        Given, the patches of about a ray that no ray hit, nor one beside them, are sampled
        :data:`SHADED_PATCH_RAYS` times more sparsely (see the module docstring).
    cos_beam : (F,) float64, optional
        ``|normals . toward|``, where the caller has it.

    Returns
    -------
    SunlitShare
    """
    from scipy.sparse import csr_array

    s = np.asarray(toward, np.float64)
    nf = len(normals)
    geo = geometry(canopy, nf)
    # the triangles whose beam may land in the rectangle (their centre's, within their size)
    shift = s[:2] / s[2]
    tri_ids = _near_triangles(smp, geo, shift)
    cos = np.abs(normals[tri_ids] @ s) if cos_beam is None else cos_beam[tri_ids]
    w = geo.area_cm2[tri_ids] * cos                      # the beam each would intercept
    lit_side = w > 0
    if not lit_side.all():
        tri_ids, cos, w = tri_ids[lit_side], cos[lit_side], w[lit_side]
    expected = samples_per_triangle(geo.area_cm2[tri_ids], cos, smp.ray_area_cm2, float(s[2]))
    group = geo.group[tri_ids]
    patch = patches(group, expected)
    if hits is not None:
        # a patch of about a ray that no ray hit, nor one beside it, is mostly in the shade:
        # those are sampled in patches of about SHADED_PATCH_RAYS rays
        hit = np.bincount(patch, weights=np.asarray(hits)[tri_ids]) > 0
        near_hit = hit.copy()                  # a patch beside a lit one: likely a penumbra
        near_hit[1:] |= hit[:-1]
        near_hit[:-1] |= hit[1:]
        found = near_hit[patch]
        if not found.all():
            expected = np.where(found, expected, expected / SHADED_PATCH_RAYS)
            patch = patches(group, expected)
    n_p = int(patch[-1]) + 1 if len(patch) else 0
    w_patch = np.bincount(patch, weights=w, minlength=n_p)
    first = np.searchsorted(patch, np.arange(n_p))
    cum_w = np.cumsum(w) - w                                    # before each triangle
    points = np.maximum(1, np.ceil(np.minimum(
        np.bincount(patch, weights=expected, minlength=n_p), 1e6))).astype(np.int64)
    owner = np.repeat(np.arange(n_p), points)                   # the patch of each point
    total = len(owner)
    rng = np.random.default_rng([seed, 0x5A17])
    # dealt into equal batches at random, as the forward rays are (scatter_beam): with the
    # batches' sizes fixed, their spread is the points' clear-or-shaded noise alone
    batch = rng.permutation(total) % BATCHES
    lit = np.zeros(total, dtype=bool)
    tracer = Tracer(smp.scene, s, smp.bounds, smp.periodic)
    x0, y0, x1, y1 = smp.rect
    bx0, by0, bx1, by1 = smp.bounds
    rank = np.arange(total) - np.repeat(np.cumsum(points) - points, points)
    for a in range(0, total, CHUNK_POINTS):
        b = min(a + CHUNK_POINTS, total)
        p_of = owner[a:b]
        # stratified along the patch's intercepted beam: which triangle, then where on it
        u = (rank[a:b] + rng.random(b - a)) / points[p_of]
        target = cum_w[first[p_of]] + u * w_patch[p_of]
        k = np.clip(np.searchsorted(cum_w, target, side="right") - 1, first[p_of],
                    np.append(first[1:], len(patch))[p_of] - 1)
        t = tri_ids[k]
        tri = scene_triangles(canopy, nf, t)
        r1, r2 = np.sqrt(rng.random(b - a)), rng.random(b - a)
        pt = ((1 - r1)[:, None] * tri[:, 0] + (r1 * (1 - r2))[:, None] * tri[:, 1]
              + (r1 * r2)[:, None] * tri[:, 2])
        # where the beam through the point lands: it counts for the rectangle's light only
        g = pt[:, :2] - shift[None, :] * pt[:, 2:3]
        if smp.periodic:
            g[:, 0] = bx0 + np.mod(g[:, 0] - bx0, bx1 - bx0)
            g[:, 1] = by0 + np.mod(g[:, 1] - by0, by1 - by0)
        inside = np.flatnonzero((g[:, 0] >= x0) & (g[:, 0] < x1) & (g[:, 1] >= y0)
                                & (g[:, 1] < y1))
        if not len(inside):
            continue
        n = normals[t[inside]]
        org = pt[inside] + LIFT_CM * np.sign(n @ s)[:, None] * n
        length = np.maximum((smp.top - org[:, 2]) / s[2], 0.0)
        lit[a + inside] = ~np.asarray(tracer.occluded(org, length), dtype=bool)
    fraction_p = np.bincount(owner, weights=lit, minlength=n_p) / np.maximum(points, 1)
    fraction = np.zeros(nf)
    fraction[tri_ids] = fraction_p[patch]
    # each batch's share of each patch's fraction, standing for each of its triangles
    keys, cnt = np.unique(batch[lit] * n_p + owner[lit], return_counts=True)
    kb, kp = keys // max(n_p, 1), keys % max(n_p, 1)
    sizes = np.bincount(patch, minlength=n_p)[kp]
    rows = np.repeat(kb, sizes)
    starts = np.repeat(first[kp] - (np.cumsum(sizes) - sizes), sizes)
    cols = tri_ids[starts + np.arange(int(sizes.sum()))]
    vals = np.repeat(cnt / points[kp], sizes)
    share = csr_array((vals, (rows, cols)), shape=(BATCHES, nf))
    share.sum_duplicates()
    return SunlitShare(fraction, share, total)
