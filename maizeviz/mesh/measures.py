"""Leaf measures: area, projected area, deviation from the smooth surface.

The deviation is the largest distance from points of the smooth surface to the mesh. It is
computed for many leaves at once (:func:`max_deviations`) with a vectorised closest point on a
triangle (Ericson, *Real-Time Collision Detection*, 5.1.5: :func:`point_triangle_distance`),
and only where it can matter: each surface point is first measured against the one triangle
that covers its (u, v) parameters, which bounds its distance from above; only the points whose
bound exceeds the largest distance already found are measured against all the triangles of the
nine mesh cells around them. The result is the same as measuring every point against every one
of those triangles.
"""

from __future__ import annotations

import numpy as np

from maizeviz import loops
from maizeviz.leaf.nurbs import count_at_most
from maizeviz.mesh.tessellate import LeafMesh, grid_faces, triangle_areas_normals

#: A triangle whose squared cross product is below this share of |ab|^2 |ac|^2 (its corners
#: collinear to 1e-10 rad, as at a collapsed tip) is measured as its three edges.
_DEGENERATE_SIN2 = 1e-20
#: Pairs (point, triangle) computed in one numpy call: 256 kB per temporary array, so that the
#: forty of them stay in the processor's caches (numpy is four to eight times slower on arrays
#: that do not).
CHUNK_PAIRS = 1 << 15
#: Surface points per leaf measured against all nine cells before the others are bounded.
_TOP_POINTS = 8


def area(mesh: LeafMesh) -> float:
    """One-sided leaf area (cm2): the sum of the triangle areas."""
    a, _ = triangle_areas_normals(mesh.points, mesh.faces)
    return float(a.sum())


def projected_area(mesh: LeafMesh, direction=(0.0, 0.0, 1.0)) -> float:
    """Area projected on the plane normal to ``direction`` (cm2): sum of A |n . d|.

    The default is the horizontal projected area (on the ground, light from the zenith). For a
    single leaf it cannot exceed the leaf area; overlapping parts are counted twice.
    """
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    a, n = triangle_areas_normals(mesh.points, mesh.faces)
    return float((a * np.abs(n @ d)).sum())


def areas(meshes: list[LeafMesh], direction=(0.0, 0.0, 1.0)) -> tuple[np.ndarray, np.ndarray]:
    """Areas and projected areas (cm2) of many meshes with a few numpy calls.

    Each value is the one :func:`area` and :func:`projected_area` give, to rounding in the
    sums (1e-15 relative).

    Returns
    -------
    area : (M,) float64 cm2, projected : (M,) float64 cm2 (on the plane normal to ``direction``)
    """
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    out_a, out_p = np.zeros(len(meshes)), np.zeros(len(meshes))
    if not meshes:
        return out_a, out_p
    counts = np.array([m.n_triangles for m in meshes])
    sizes = np.array([m.points.shape[0] for m in meshes])
    faces = np.concatenate([m.faces for m in meshes]).astype(np.int64)
    faces += np.repeat(np.cumsum(sizes) - sizes, counts)[:, None]
    pts = np.concatenate([m.points for m in meshes]).T                   # (3, V)
    e1 = np.take(pts, faces[:, 1], axis=1) - (v0 := np.take(pts, faces[:, 0], axis=1))
    e2 = np.take(pts, faces[:, 2], axis=1) - v0
    cross = _cross(e1, e2)
    twice = np.sqrt(np.einsum("ij,ij->j", cross, cross))
    # |A n . d| = |cross . d| / 2, as A = |cross| / 2 and n = cross / |cross|
    proj = np.abs(d @ cross)
    starts = np.cumsum(counts) - counts
    some = counts > 0
    out_a[some] = 0.5 * np.add.reduceat(twice, starts[some])
    out_p[some] = 0.5 * np.add.reduceat(proj, starts[some])
    return out_a, out_p


def _cross(e1: np.ndarray, e2: np.ndarray) -> np.ndarray:
    """Cross products of vectors given one row per coordinate: (3, ...) x (3, ...)."""
    return np.stack([e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                     e1[0] * e2[1] - e1[1] * e2[0]])


def grid_areas(vertices: np.ndarray, rel_tol: float = 1e-9) -> np.ndarray:
    """Areas (L,) cm2 of vertex grids (L, a, b, 3) cm triangulated as
    :func:`~maizeviz.mesh.tessellate.mesh_grid` does: :func:`area` of ``mesh_grid(grid)`` for
    each, its zero-area triangles (a grid edge shorter than ``rel_tol`` times the longest, as
    :func:`~maizeviz.mesh.tessellate.degenerate_faces` finds them) left out.

    A few leaves at a time, their arrays in the processor's caches, every intermediate in one
    set of buffers reused from chunk to chunk: fresh temporaries of this size are fresh pages
    of memory each time (above the C library's threshold for mapping memory), and faulting
    them in took three quarters of the time (measured: 3.0 ms against 0.86 ms for 25 leaves of
    61 x 21 vertices, the same areas to the bit). Grids under 2 x 2, or not (L, a, b, 3), are
    refused in one line (:func:`maizeviz.loops.check_grids`), compiled loops or not."""
    vertices = loops.check_grids(vertices)
    nl, a, b = vertices.shape[:3]
    out = np.empty(nl)
    step = max(1, CHUNK_PAIRS // (a * b))              # leaves whose arrays stay in cache
    if loops.available():
        # the same triangles' doubled areas from the compiled loop, summed here as below
        size = min(step, nl) * (a - 1) * (b - 1)
        buf = (np.empty(size), np.empty(size))
        for s in range(0, nl, step):
            twice = loops.grid_twice_areas(vertices[s:s + step], rel_tol, buf)
            assert twice is not None
            total = np.zeros(len(twice[0]))
            for t in twice:
                total += t.sum(axis=1)
            out[s:s + step] = 0.5 * total
        return out
    loops.warn_fallback()                              # once a process, unless turned off
    work = _AreaBuffers(min(step, nl), a, b)
    for s in range(0, nl, step):
        out[s:s + step] = _grid_areas(vertices[s:s + step], rel_tol, work)
    return out


class _AreaBuffers:
    """The arrays :func:`_grid_areas` works in, for up to ``nl`` grids of a x b vertices."""

    def __init__(self, nl: int, a: int, b: int):
        q = (nl, a - 1, b - 1)
        self.v = np.empty((3, nl, a, b))                # x, y, z apart
        self.h = np.empty((3, nl, a, b - 1))            # edges along a row
        self.w = np.empty((3, nl, a - 1, b))            # edges across rows
        self.h2, self.hs = np.empty((nl, a, b - 1)), np.empty((nl, a, b - 1))
        self.w2, self.ws = np.empty((nl, a - 1, b)), np.empty((nl, a - 1, b))
        self.h0, self.w0 = np.empty((nl, a, b - 1), bool), np.empty((nl, a - 1, b), bool)
        self.d, self.c = np.empty((3, *q)), np.empty((3, *q))
        self.t, self.bad = np.empty(q), np.empty(q, bool)

    def take(self, nl: int) -> _AreaBuffers:
        """Views of the first ``nl`` grids' buffers (a last, shorter chunk)."""
        if nl == self.v.shape[1]:
            return self
        part = object.__new__(_AreaBuffers)
        for name, arr in vars(self).items():
            setattr(part, name, arr[:, :nl] if arr.ndim == 4 else arr[:nl])
        return part


def _grid_areas(vertices: np.ndarray, rel_tol: float, work: _AreaBuffers) -> np.ndarray:
    nl = vertices.shape[0]
    ws = work.take(nl)
    v, h, w = ws.v, ws.h, ws.w
    for k in range(3):
        np.copyto(v[k], vertices[..., k])
        np.subtract(v[k][:, :, 1:], v[k][:, :, :-1], out=h[k])
        np.subtract(v[k][:, 1:], v[k][:, :-1], out=w[k])
    for edge, sq, tmp in ((h, ws.h2, ws.hs), (w, ws.w2, ws.ws)):   # squared lengths
        np.multiply(edge[0], edge[0], out=sq)
        sq += np.multiply(edge[1], edge[1], out=tmp)
        sq += np.multiply(edge[2], edge[2], out=tmp)
    longest = np.maximum(ws.h2.reshape(nl, -1).max(axis=1, initial=0.0),
                         ws.w2.reshape(nl, -1).max(axis=1, initial=0.0))
    tol = (rel_tol**2 * np.maximum(longest, 1e-300))[:, None, None]
    h0 = np.less_equal(ws.h2, tol, out=ws.h0)          # (L, a, b-1), (L, a-1, b): zero-length
    w0 = np.less_equal(ws.w2, tol, out=ws.w0)          # edges
    # the two triangles of each quad, (p00, p10, p11) and (p00, p11, p01) as grid_faces has
    # them, share the diagonal d = p11 - p00; their other edges are p10 - p00 (across rows)
    # and p01 - p00 (along the row)
    d, c, t, bad = ws.d, ws.c, ws.t, ws.bad
    for k in range(3):
        np.subtract(v[k][:, 1:, 1:], v[k][:, :-1, :-1], out=d[k])
    total = np.zeros(nl)
    for tri in (0, 1):
        if tri == 0:
            e = [w[k][:, :, :-1] for k in range(3)]
            np.logical_or(h0[:, 1:], w0[:, :, :-1], out=bad)
            terms = ((e[1], d[2], e[2], d[1]), (e[2], d[0], e[0], d[2]),
                     (e[0], d[1], e[1], d[0]))                 # e x d
        else:
            e = [h[k][:, :-1] for k in range(3)]
            np.logical_or(h0[:, :-1], w0[:, :, 1:], out=bad)
            terms = ((d[1], e[2], d[2], e[1]), (d[2], e[0], d[0], e[2]),
                     (d[0], e[1], d[1], e[0]))                 # d x e
        for k, (p, q, r, s) in enumerate(terms):
            np.multiply(p, q, out=c[k])
            c[k] -= np.multiply(r, s, out=t)
        twice = np.multiply(c[0], c[0], out=t)
        twice += np.multiply(c[1], c[1], out=c[1])
        twice += np.multiply(c[2], c[2], out=c[2])
        np.sqrt(twice, out=twice)
        np.copyto(twice, 0.0, where=bad)
        total += twice.reshape(nl, -1).sum(axis=1)
    return 0.5 * total


# ------------------------------------------------------------------ point-to-triangle distance
def point_triangle_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray,
                            c: np.ndarray) -> np.ndarray:
    """Distance (cm) from points to triangles (a, b, c), broadcast over the leading axes.

    The closest point on each triangle is found by its Voronoi region (Ericson, *Real-Time
    Collision Detection*, 2005, 5.1.5); a triangle whose corners are collinear (to 1e-10 rad)
    or coincide is measured as its three edges.

    Parameters
    ----------
    points, a, b, c : (..., 3) float64, cm, broadcastable to one shape (..., 3)

    Returns
    -------
    (...) float64, cm
    """
    p, a, b, c = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (points, a, b, c)))
    shape = p.shape[:-1]
    tri = triangle_terms(*(x.reshape(-1, 3).T for x in (a, b, c)))
    p = p.reshape(-1, 3)
    out = _distances(tuple(np.ascontiguousarray(p[:, k]) for k in range(3)), tri,
                     np.arange(len(p)))
    return out.reshape(shape)


def triangle_terms(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """What the distance needs of each triangle, one row per term: (17, T) float64.

    Rows: a (3), ab = b - a (3), ac = c - a (3), ab.ab, ab.ac, ac.ac, |ab x ac|^2, and the
    reciprocals of ab.ab, ac.ac, |bc|^2 and |ab x ac|^2 (all four 0 for a degenerate triangle,
    which is how :func:`_pair_distances` knows one).

    Parameters
    ----------
    a, b, c : (3, T) float64, cm: the corners, one row per coordinate
    """
    out = np.empty((17, a.shape[1]))
    out[0:3] = a
    ab, ac = out[3:6], out[6:9]
    np.subtract(b, a, out=ab)
    np.subtract(c, a, out=ac)
    e00, e01, e11, n2 = out[9], out[10], out[11], out[12]
    np.einsum("ij,ij->j", ab, ab, out=e00)
    np.einsum("ij,ij->j", ab, ac, out=e01)
    np.einsum("ij,ij->j", ac, ac, out=e11)
    cx = ab[1] * ac[2] - ab[2] * ac[1]
    cy = ab[2] * ac[0] - ab[0] * ac[2]
    cz = ab[0] * ac[1] - ab[1] * ac[0]
    np.add(cx * cx + cy * cy, cz * cz, out=n2)
    ok = n2 > _DEGENERATE_SIN2 * e00 * e11          # and so e00, e11, |bc|^2 > 0 too
    out[13:] = 0.0
    # |bc|^2 from bc itself: e00 - 2 e01 + e11 cancels to 0 on a sliver whose b and c nearly
    # coincide seen from a, and its reciprocal (inf) times a 0 of the blended regions is NaN
    bc = ac - ab
    ebc = np.einsum("ij,ij->j", bc, bc)
    ok &= ebc > 0
    for row, x in zip((13, 14, 15, 16), (e00, e11, ebc, n2)):
        np.divide(1.0, x, out=out[row], where=ok)
    return out


def _pair_distances(p: tuple[np.ndarray, ...], tri: np.ndarray) -> np.ndarray:
    """Distances (N,) cm from points (three (N,) coordinate arrays) to triangles (17, N) of
    :func:`triangle_terms`, pair by pair.

    Ericson's region tests (5.1.5) with his dot products d1 .. d6 and barycentric ratios
    va, vb, vc, written with the triangle's own constants (d3 = d1 - ab.ab, ...; d1 - d3 =
    ab.ab, va + vb + vc = |ab x ac|^2), so that every division is by a constant of the
    triangle and the regions are blended by arithmetic rather than by branches.
    """
    ax, ay, az, bx, by, bz, cx, cy, cz, e00, e01, e11, n2, i00, i11, ibc, inv = tri
    apx, apy, apz = p[0] - ax, p[1] - ay, p[2] - az
    d1 = bx * apx
    d1 += by * apy
    d1 += bz * apz                                      # ab . ap
    d2 = cx * apx
    d2 += cy * apy
    d2 += cz * apz                                      # ac . ap
    d3, d4 = d1 - e00, d2 - e01                         # ab . bp, ac . bp
    d5, d6 = d1 - e01, d2 - e11                         # ab . cp, ac . cp
    vb = e11 * d1
    vb -= e01 * d2                                      # d5 d2 - d1 d6
    vc = e00 * d2
    vc -= e01 * d1                                      # d1 d4 - d3 d2
    va = n2 - vb
    va -= vc                                            # d3 d6 - d5 d4
    s = vb * inv                                        # face region: q = a + s ab + t ac
    t = vc * inv
    d43 = d4 - d3
    d56 = d5 - d6
    m = (va <= 0) & (d43 >= 0) & (d56 >= 0)             # edge BC: q = b + w (c - b)
    w = d43 * ibc
    s += m * (1.0 - w - s)
    t += m * (w - t)
    m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)               # edge AC
    s -= m * s
    t += m * (d2 * i11 - t)
    m = (d6 >= 0) & (d5 <= d6)                          # vertex C
    s -= m * s
    t += m * (1.0 - t)
    m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)               # edge AB
    s += m * (d1 * i00 - s)
    t -= m * t
    m = (d3 >= 0) & (d4 <= d3)                          # vertex B
    s += m * (1.0 - s)
    t -= m * t
    m = (d1 <= 0) & (d2 <= 0)                           # vertex A
    s -= m * s
    t -= m * t
    dx = s * bx
    dx += t * cx
    dx -= apx
    dy = s * by
    dy += t * cy
    dy -= apy
    dz = s * bz
    dz += t * cz
    dz -= apz
    dx *= dx
    dy *= dy
    dz *= dz
    dx += dy
    dx += dz
    dist = np.sqrt(dx, out=dx)
    bad = np.flatnonzero(inv == 0)
    if len(bad):                                         # degenerate: the nearest of its edges
        ap = np.column_stack([apx[bad], apy[bad], apz[bad]])
        ab, ac = tri[3:6, bad].T, tri[6:9, bad].T
        dist[bad] = np.minimum(np.minimum(_segment(ap, ab), _segment(ap, ac)),
                               _segment(ap - ab, ac - ab))
    return dist


def _distances(p: tuple[np.ndarray, ...], tri: np.ndarray, which: np.ndarray) -> np.ndarray:
    """:func:`_pair_distances` of points ``p`` (three (N,) arrays) to the triangles
    ``tri[:, which]`` ((N,) column indices), :data:`CHUNK_PAIRS` at a time."""
    out = np.empty(len(which))
    for s in range(0, len(which), CHUNK_PAIRS):
        sl = slice(s, s + CHUNK_PAIRS)
        out[sl] = _pair_distances(tuple(c[sl] for c in p), np.take(tri, which[sl], axis=1))
    return out


def _segment(p: np.ndarray, e: np.ndarray) -> np.ndarray:
    """Distance (K,) from points p (K, 3) to the segments from the origin to e (K, 3)."""
    ee = np.einsum("ij,ij->i", e, e)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.clip(np.einsum("ij,ij->i", p, e) / ee, 0.0, 1.0)
    f = np.where(ee > 0, f, 0.0)
    return np.linalg.norm(p - f[:, None] * e, axis=1)


# ------------------------------------------------------------------ deviation from the surface
def _cells(params: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Mesh cell (L, R) holding each reference parameter: ``searchsorted(side="right") - 1``
    on each leaf's mesh lines ``params`` (L, a), clipped to 0 .. a - 2."""
    idx = count_at_most(params, ref) - 1
    return np.clip(idx, 0, params.shape[1] - 2)


#: Points measured against their 18 candidate triangles at a time (about 80 MB of work arrays).
EXACT_CHUNK = 1 << 15


def max_deviations(vertices: np.ndarray, u: np.ndarray, v: np.ndarray, ref_points: np.ndarray,
                   ref_u: np.ndarray, ref_v: np.ndarray) -> np.ndarray:
    """Largest distance (cm) from points of each smooth surface to its mesh, for L leaves whose
    meshes share a vertex grid shape and whose surface samples share a shape.

    Each surface point at parameters (u, v) is measured against the two triangles of every
    mesh cell in the 3 x 3 block around the cell that covers (u, v) (clipped at the borders;
    every triangle of the vertex grid counts, zero-area ones too), so the cost is linear in the
    number of points. Measuring from the surface to the mesh (not the other way) is what
    catches a shortened leaf: a collapsed tip leaves surface points far from any triangle.

    The result is that exhaustive maximum, reached with less work: every point is first
    measured against the one triangle covering it in (u, v) (the other of its cell where that
    one has no area), an upper bound of its distance; the eight points of each leaf with the
    largest bounds are measured against all 18 triangles, and then only the points whose bound
    still exceeds the largest distance found (usually under 1%).

    Parameters
    ----------
    vertices : (L, a, b, 3) float64, cm: the mesh vertex grids, a, b >= 2
    u : (L, a), v : (L, b) float64: the surface parameters of the mesh lines, increasing
    ref_points : (L, A, B, 3) float64, cm: each surface sampled on ``ref_u`` x ``ref_v``
    ref_u : (L, A), ref_v : (L, B) float64 in [0, 1]

    Returns
    -------
    (L,) float64, cm
    """
    nl, a, b = vertices.shape[:3]
    na, nb = ref_points.shape[1:3]
    npts = na * nb
    out = np.zeros(nl)
    if nl == 0 or npts == 0:
        return out
    faces = grid_faces(a, b)
    nf = len(faces)
    flat = np.ascontiguousarray(vertices.reshape(nl * a * b, 3).T)      # (3, L a b)
    corner = faces.T[:, None, :] + (np.arange(nl) * (a * b))[None, :, None]  # (3, L, F)
    tri = triangle_terms(*(flat[:, corner[k].reshape(-1)] for k in range(3)))  # (17, L F)
    ci, cj = _cells(u, ref_u), _cells(v, ref_v)                          # (L, A), (L, B)
    li = np.arange(nl)[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        fu = (ref_u - u[li, ci]) / (u[li, ci + 1] - u[li, ci])           # (L, A) in the cell
        fv = (ref_v - v[li, cj]) / (v[li, cj + 1] - v[li, cj])           # (L, B)
    # the triangle covering (u, v): (p00, p10, p11) where fu >= fv, else (p00, p11, p01)
    own = (2 * (ci[:, :, None] * (b - 1) + cj[:, None, :])
           + (fu[:, :, None] < fv[:, None, :])).reshape(nl, npts) + li * nf
    own ^= tri[16, own] == 0                # no area (a collapsed tip): its sibling instead
    pcols = tuple(np.ascontiguousarray(ref_points[..., k]).reshape(-1) for k in range(3))
    bound = _distances(pcols, tri, own.reshape(-1)).reshape(nl, npts)

    step = np.arange(-1, 2)

    def exact(leaves: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Smallest distance over the 18 candidate triangles of the points (leaf, point),
        :data:`EXACT_CHUNK` points at a time: the candidates can be every point of a leaf
        (a flat one, whose bounds all tie), 1.7 million for a leaf of 10,000
        cross-sections, whose 18 distances each at once took 4.5 GB."""
        out = np.empty(len(leaves))
        for s0 in range(0, len(leaves), EXACT_CHUNK):
            leaf, point = leaves[s0:s0 + EXACT_CHUNK], points[s0:s0 + EXACT_CHUNK]
            ii = np.clip(ci[leaf, point // nb][:, None] + step, 0, a - 2)       # (N, 3)
            jj = np.clip(cj[leaf, point % nb][:, None] + step, 0, b - 2)
            cell = (leaf * nf)[:, None, None] + 2 * (ii[:, :, None] * (b - 1) + jj[:, None, :])
            which = (cell[..., None] + np.arange(2)).reshape(-1)               # (N * 18,)
            p = tuple(np.repeat(c[leaf * npts + point], 18) for c in pcols)
            out[s0:s0 + len(leaf)] = np.fmin.reduce(
                _distances(p, tri, which).reshape(len(leaf), 18), axis=1)
        return out

    k = min(_TOP_POINTS, npts)
    top = np.argpartition(bound, npts - k, axis=1)[:, npts - k:]         # (L, k)
    out = exact(np.repeat(np.arange(nl), k), top.reshape(-1)).reshape(nl, k).max(axis=1)
    bound[li, top] = -np.inf                                             # done
    leaf, point = np.nonzero(bound > out[:, None])
    if len(leaf):
        np.maximum.at(out, leaf, exact(leaf, point))
    return out
