"""How far two of Embree's code paths may disagree on a hit's distance.

Embree computes a ray's hit distance in float32 with whichever kernel the CPU and the query
select: single rays (``rtcIntersect1``, embreex) and packets (``rtcIntersect4/8/16``,
:mod:`maizeviz.mesh.packets`) run different SIMD code, and on some instruction sets one fuses
a multiply and an add (FMA) where the other rounds twice, or takes the reciprocal of another
width. Both then find the same triangle, but the distance may differ in its last bits
(measured under AVX2: 32,071 of 60,000 rays, at most 3.8e-6 relative; under SSE2, SSE4.2,
AVX and AVX-512 the two paths agree to the bit on this canopy). :func:`distance_bound` is the
bound both paths keep, derived from the operations of Embree's triangle test; the tests hold
packets and single rays to it under each instruction set (``tests/core/test_packets.py``).

Derivation (Moeller-Trumbore as Embree 4 computes it, ``kernels/geometry/triangle_intersector_
moeller.h``; u = 2^-24, float32's unit roundoff): with ``C = v0 - o`` (one rounding, the same
in both paths), ``Ng = e1 x e2`` and ``t = (Ng . C) / (Ng . D)``,

- each three-term dot product, fused or not, is within 3 u sum|a_i b_i| <= 3 u |a| |b| of its
  exact value (Higham, 2002, eq. 3.5), so ``Ng . C`` contributes 3 u |C| / (|D| cos) to t and
  ``Ng . D`` contributes 3 u t / cos, where cos = |Ng . D| / (|Ng| |D|);
- ``Ng`` itself (computed per query from the vertices in compact scenes) is within about
  3 u |e1| |e2| per component; moving ``Ng`` moves t by ``dNg . (v0 - hit) / (Ng . D)``, at most
  3 u e |e1| |e2| / (|Ng| |D| cos) with e the triangle's longest edge;
- the reciprocal (an estimate refined by one Newton step, Embree's ``rcp``) and the product
  ``T * rcp(den)`` add at most 6 u t and u t.

Each path is within E = u [3 (|C| / |D| + t + e |e1| |e2| / (|Ng| |D|)) / cos + 7 t] of the
exact distance, so the two are within 2 E of each other.

References
----------
Moeller, T. & Trumbore, B. (1997). Fast, minimum storage ray-triangle intersection. Journal of
Graphics Tools 2(1), 21-28. https://doi.org/10.1080/10867651.1997.10487468
Higham, N. J. (2002). Accuracy and Stability of Numerical Algorithms, 2nd ed., SIAM, ch. 3.
"""

from __future__ import annotations

import numpy as np

#: float32's unit roundoff, 2^-24.
U32 = 2.0**-24


def distance_bound(origins: np.ndarray, directions: np.ndarray, t: np.ndarray,
                   triangles: np.ndarray) -> np.ndarray:
    """The most two of Embree's paths (packets, single rays, instruction sets) may differ on
    the distance to the same hit.

    Parameters
    ----------
    origins : (N, 3) float, cm
    directions : (N, 3) float, any length (t is in units of it)
    t : (N,) float, the hit distance one path reported, in units of ``directions``
    triangles : (N, 3, 3) float, cm: the vertices (v0, v1, v2) of each ray's hit triangle, in
        the scene's order

    Returns
    -------
    (N,) float64, in units of ``directions``: 2 E of the module's derivation (inf for a ray
    parallel to its triangle).
    """
    o = np.asarray(origins, np.float64)
    d = np.asarray(directions, np.float64)
    tri = np.asarray(triangles, np.float64)
    t = np.abs(np.asarray(t, np.float64))
    v0, v1, v2 = tri[:, 0], tri[:, 1], tri[:, 2]
    e1, e2 = v1 - v0, v2 - v0
    ng = np.cross(e1, e2)
    n_ng = np.linalg.norm(ng, axis=1)
    n_d = np.linalg.norm(d, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = np.abs(np.einsum("ij,ij->i", ng, d)) / (n_ng * n_d)
        edge = np.max(np.linalg.norm(np.stack([e1, e2, v2 - v1], 1), axis=2), axis=1)
        shape = edge * np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1) / (n_ng * n_d)
        c = np.linalg.norm(v0 - o, axis=1) / n_d
        e = U32 * (3.0 * (c + t + shape) / cos + 7.0 * t)
    return np.where(cos > 0, 2.0 * e, np.inf)
