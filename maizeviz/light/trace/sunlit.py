"""The sunlit share of every triangle, sampled from the triangle toward the sun.

The sun's beam is traced forward as a grid of rays (:mod:`.scatter`); the rays a triangle
intercepts, times the cm2 of leaf each stands for, estimate its sunlit area without bias, but
not within bounds: a triangle that the grid's rays would hit ``e < 1`` times if it were fully
lit is hit 0 or 1 times, and the only unbiased reading of one hit is ``1 / e`` of its area
(up to 30 times it on a canopy of 2 cm leaves at 1 ray per cm2). No estimate from those counts
alone can be both unbiased and at most the area: with ``h`` in {0, 1} of mean ``e f``,
``E[T(h)] = f`` for every sunlit fraction ``f`` forces ``T(1) = 1 / e``.

So the sunlit area is sampled from the triangle itself, as Helios samples each element's
direct light (Bailey 2018) and Caribu gives each triangle its own irradiance (Chelle & Andrieu
1998): points drawn uniformly on the triangle, at least one and about as many as forward rays
would hit it fully lit (:func:`samples_per_triangle`), each asked whether its path toward the
sun is clear (an occlusion query, wrapped across the plot in a periodic field). The sunlit
fraction is the share of clear points: in [0, 1] by construction, unbiased, and the direct
beam a triangle absorbs is that fraction of what its whole area would intercept, at the beam's
exact flux on its orientation.

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

from dataclasses import dataclass

import numpy as np
from scipy.sparse import csr_array

from maizeviz.light.results.uncertainty import BATCHES
from maizeviz.light.scene.rays import Tracer
from maizeviz.light.trace.direct import Sampler

#: Distance (cm) a sample point is lifted off its triangle toward the sun's side.
LIFT_CM = 1e-3
#: Sample points traced together (bounded memory).
CHUNK_POINTS = 1 << 18


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


def samples_per_triangle(area_cm2: np.ndarray, cos_beam: np.ndarray, ray_area_cm2: float,
                         toward_z: float) -> np.ndarray:
    """(F,) int64: sample points per triangle, the forward rays that would hit it fully lit
    (its area across the beam over one ray's), rounded up, at least 1.

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
    expected = area_cm2 * cos_beam / (ray_area_cm2 * max(toward_z, 1e-9))
    return np.maximum(1, np.ceil(np.minimum(expected, 1e6))).astype(np.int64)


def sunlit_share(smp: Sampler, triangles: np.ndarray, normals: np.ndarray,
                 toward: np.ndarray, seed: int) -> SunlitShare:
    """Sample the sunlit share of every triangle (see the module docstring).

    Parameters
    ----------
    smp : Sampler
        The scene, sample rectangle, density, plot and field of the forward trace.
    triangles : (F, 3, 3) float64
        Corners of the scene's triangles (leaves, then stalks), in its ids [cm].
    normals : (F, 3) float64
        Their unit normals.
    toward : (3,) float64
        Unit vector toward the sun, ``z > 0``.
    seed : int
        Seed of the points and of their batches.

    Returns
    -------
    SunlitShare
    """
    s = np.asarray(toward, np.float64)
    tri = np.asarray(triangles, np.float64)
    nf = len(tri)
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    cos = np.abs(normals @ s)
    n_t = samples_per_triangle(area, cos, smp.ray_area_cm2, float(s[2]))
    owner = np.repeat(np.arange(nf), n_t)
    rng = np.random.default_rng([seed, 0x5A17])
    # dealt into equal batches at random, as the forward rays are (scatter_beam): with the
    # batches' sizes fixed, their spread is the points' clear-or-shaded noise alone
    batch = rng.permutation(len(owner)) % BATCHES
    lit = np.zeros(len(owner), dtype=bool)
    tracer = Tracer(smp.scene, s, smp.bounds, smp.periodic)
    x0, y0, x1, y1 = smp.rect
    bx0, by0, bx1, by1 = smp.bounds
    for a in range(0, len(owner), CHUNK_POINTS):
        b = min(a + CHUNK_POINTS, len(owner))
        t = owner[a:b]
        # uniform points on each triangle (the square-root map of two uniforms)
        r1, r2 = np.sqrt(rng.random(b - a)), rng.random(b - a)
        p = ((1 - r1)[:, None] * tri[t, 0] + (r1 * (1 - r2))[:, None] * tri[t, 1]
             + (r1 * r2)[:, None] * tri[t, 2])
        # where the beam through the point lands: it counts for the rectangle's light only
        q = p[:, :2] - s[:2] * (p[:, 2] / s[2])[:, None]
        if smp.periodic:
            q[:, 0] = bx0 + np.mod(q[:, 0] - bx0, bx1 - bx0)
            q[:, 1] = by0 + np.mod(q[:, 1] - by0, by1 - by0)
        inside = (q[:, 0] >= x0) & (q[:, 0] < x1) & (q[:, 1] >= y0) & (q[:, 1] < y1)
        idx = np.flatnonzero(inside & (cos[t] > 0))
        if not len(idx):
            continue
        side = np.sign(normals[t[idx]] @ s)[:, None] * normals[t[idx]]
        org = p[idx] + LIFT_CM * side
        length = np.maximum((smp.top - org[:, 2]) / s[2], 0.0)
        lit[a + idx] = ~np.asarray(tracer.occluded(org, length), dtype=bool)
    weight = lit / n_t[owner]
    rows = csr_array((weight[lit], (batch[lit], owner[lit])), shape=(BATCHES, nf))
    rows.sum_duplicates()
    fraction = np.bincount(owner, weights=lit, minlength=nf) / n_t       # clear / drawn
    return SunlitShare(fraction, rows, len(owner))
