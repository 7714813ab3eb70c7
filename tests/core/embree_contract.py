"""The contract between two of Embree's paths (packets and single rays, instruction sets,
BVH layouts), as the tests check it: the same triangle for every ray but one passing within
float32 reach of an edge or ending within the distance bound of its tfar (at most 1 in
10,000), distances within :func:`maizeviz.mesh.precision.distance_bound`."""

import numpy as np

from maizeviz.mesh.precision import distance_bound


def near_edge(o, d, tri) -> np.ndarray:
    """Whether each ray (o, d) passes within float32 reach of an edge of its triangle tri
    (N, 3, 3): its smallest barycentric coordinate, in float64, under 1e-4 (float32's
    roundoff, 6e-8, times the worst conditioning of the canopy's triangles)."""
    v0, e1, e2 = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    p = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, p)
    s = o - v0
    u = np.einsum("ij,ij->i", s, p) / det
    v = np.einsum("ij,ij->i", d, np.cross(s, e1)) / det
    return np.minimum(np.minimum(u, v), 1 - u - v) < 1e-4


def assert_same_hits(vertices, faces, o, d, tfar, one, other):
    """The contract between two of Embree's paths: the same triangle for every ray, but for a
    ray passing within float32 reach of an edge or ending within the bound of its tfar (at
    most 1 in 10,000); each distance within :func:`distance_bound` of the other."""
    (p1, t1), (p2, t2) = one, other
    o = np.asarray(o, np.float64)
    d = np.broadcast_to(np.asarray(d, np.float64).reshape(-1, 3), o.shape)
    tri = vertices[faces]
    differ = np.flatnonzero(p1 != p2)
    assert len(differ) <= len(o) // 10_000
    for j in differ:
        hit = [p for p in (p1[j], p2[j]) if p >= 0]
        edge = any(near_edge(o[j:j + 1], d[j:j + 1], tri[[p]])[0] for p in hit)
        t = t1[j] if p1[j] >= 0 else t2[j]
        at_end = tfar is not None and abs(float(np.broadcast_to(tfar, len(o))[j]) - t) <= \
            distance_bound(o[j:j + 1], d[j:j + 1], [t], tri[[hit[0]]])[0]
        assert edge or at_end, f"ray {j}: triangle {p1[j]} or {p2[j]}"
    both = np.flatnonzero((p1 == p2) & (p1 >= 0))
    bound = distance_bound(o[both], d[both], t1[both], tri[p1[both]])
    gap = np.abs(t1[both].astype(np.float64) - t2[both])
    assert np.all(gap <= bound), f"worst gap {np.max(gap / bound):.2f} of the bound"
    miss = p1 < 0
    np.testing.assert_array_equal(t1[miss & (p2 < 0)], t2[miss & (p2 < 0)])   # tfar as given


def assert_same_blocked(vertices, faces, o, d, tfar, one, other, hits):
    """Occlusion by two paths: the same answer for every ray but one whose nearest hit (``hits``:
    ids and distances from one path) lies within the bound of its tfar."""
    differ = np.flatnonzero(one != other)
    if len(differ):
        p, t = hits[0][differ], hits[1][differ]
        o = np.asarray(o, np.float64)[differ]
        d = np.broadcast_to(np.asarray(d, np.float64).reshape(-1, 3), (len(one), 3))[differ]
        assert np.all(p >= 0)
        bound = distance_bound(o, d, t, vertices[faces[p]])
        assert np.all(np.abs(np.broadcast_to(tfar, len(one))[differ] - t) <= bound)
