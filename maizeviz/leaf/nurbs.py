"""Global NURBS surface interpolation through leaf point grids (The NURBS Book, A9.4).

Parameters by averaged chord length (or centripetal) over rows and columns, knot vectors by
averaging (eq. 9.8), control points from one collocation solve per direction with every
right-hand side at once. Weights are 1 (the non-rational case the paper uses); evaluation still
divides by the weighted basis, so a surface with other weights evaluates correctly.

Every function works on a batch of leaves of the same grid shape at once (leading axis L):
a canopy's 1,500 leaves are fitted with a few dozen numpy calls, not 1,500 Python loops.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from maizeviz import loops
from maizeviz.errors import LeafError

#: Above this many comparisons, :func:`count_at_most` searches leaf by leaf.
BROADCAST_MOST = 1 << 22


def count_at_most(sorted_rows: np.ndarray, x: np.ndarray) -> np.ndarray:
    """How many values of each row of ``sorted_rows`` (L, K), increasing, are at most each
    ``x`` (L, A): ``searchsorted(side="right")`` row by row, as (L, A) int64.

    A batch of small rows is compared at once, (L, A, K) booleans; past
    :data:`BROADCAST_MOST` of them (a leaf of 10,000 cross-sections sampled at K = 8 made 4.5
    GB of them) each row is searched by itself.
    """
    nbatch, na = x.shape
    if nbatch == 1:
        return np.searchsorted(sorted_rows[0], x[0], side="right")[None].astype(np.int64)
    if nbatch * na * sorted_rows.shape[1] <= BROADCAST_MOST:
        return (x[:, :, None] >= sorted_rows[:, None, :]).sum(axis=2)
    return np.stack([np.searchsorted(k, xi, side="right")
                     for k, xi in zip(sorted_rows, x)]).astype(np.int64)


def basis_values(x: np.ndarray, knots: np.ndarray, degree: int
                 ) -> tuple[np.ndarray, np.ndarray, int]:
    """The non-zero B-spline basis values (The NURBS Book A2.2, vectorised over leaves and
    points): each point has ``degree + 1`` of them, on consecutive control points.

    Parameters
    ----------
    x : (L, A) float64 in [0, 1]
    knots : (L, K) float64, clamped
    degree : int

    Returns
    -------
    values : (L, A, degree + 1) float64, summing to 1 over the last axis
    first : (L, A) int64, the control point of ``values[..., 0]``
    n_control : K - degree - 1

    Raises
    ------
    ValueError
        In one line naming the argument, as the compiled loops' (:func:`maizeviz.loops.
        check_basis`: shapes, a knot count under 2 (degree + 1), knots decreasing).
    """
    x, knots, degree = loops.check_basis(x, knots, degree)
    nbatch, npts = x.shape
    nctrl = knots.shape[1] - degree - 1
    span = count_at_most(knots, x) - 1
    np.maximum(span, degree, out=span)
    np.minimum(span, nctrl - 1, out=span)                         # (L, A); x = 1 -> last span
    li = np.arange(nbatch)[:, None, None]
    # knots t[span - degree + 1] .. t[span + degree], gathered once: (L, A, 2 degree)
    kk = knots[li, span[:, :, None] + np.arange(1 - degree, degree + 1)]
    left = [None] + [x - kk[:, :, degree - j] for j in range(1, degree + 1)]
    right = [None] + [kk[:, :, degree - 1 + j] - x for j in range(1, degree + 1)]
    vals = [np.ones_like(x)]
    for j in range(1, degree + 1):
        saved = 0.0
        new = []
        for r in range(j):
            temp = vals[r] / (right[r + 1] + left[j - r])
            new.append(saved + right[r + 1] * temp)
            saved = left[j - r] * temp
        new.append(saved)
        vals = new
    return np.stack(vals, axis=2), (span - degree).astype(np.int64), nctrl


def basis_matrix(x: np.ndarray, knots: np.ndarray, degree: int) -> np.ndarray:
    """Dense B-spline basis values (:func:`basis_values` spread over every control point).

    Parameters
    ----------
    x : (L, A) float64 in [0, 1]
    knots : (L, K) float64, clamped
    degree : int

    Returns
    -------
    (L, A, K - degree - 1) float64; rows sum to 1.

    Raises
    ------
    ValueError
        In one line naming the argument (:func:`maizeviz.loops.check_basis`), through the
        compiled loops or numpy alike.
    """
    out = loops.basis_matrix(x, knots, degree)       # the same values in one C pass
    if out is not None:
        return out
    vals, first, nctrl = basis_values(x, knots, degree)
    nbatch, npts = first.shape
    out = np.zeros((nbatch, npts, nctrl))
    at = np.arange(nbatch * npts).reshape(nbatch, npts) * nctrl + first
    flat = out.reshape(-1)
    for r in range(degree + 1):
        flat[at + r] = vals[:, :, r]
    return out


#: From this many control points in a direction, the surface is fitted and evaluated through
#: its banded basis (``degree + 1`` values a point) rather than dense matrices, whose memory
#: grows with its square and solve with its cube: a leaf of 10,000 cross-sections took
#: 45 s and 3.9 GB, then 6.7 GiB more to sample at K = 4. Below it the dense path, one numpy
#: call for a batch of leaves, is the faster.
BANDED_FROM = 64


def _contract(values: np.ndarray, first: np.ndarray, data: np.ndarray) -> np.ndarray:
    """Sum over one control-point axis with a banded basis: (L, A, p + 1), (L, A) and data
    (L, N, ...) -> (L, A, ...), ``out[l, a] = sum_r values[l, a, r] data[l, first[l, a] + r]``."""
    li = np.arange(len(first))[:, None]
    shape = values.shape[:2] + (1,) * (data.ndim - 2)
    out = values[:, :, 0].reshape(shape) * data[li, first]
    for r in range(1, values.shape[2]):
        out += values[:, :, r].reshape(shape) * data[li, first + r]
    return out


def _solve_collocation(params: np.ndarray, knots: np.ndarray, degree: int,
                       rhs: np.ndarray) -> np.ndarray:
    """Control points through the data: solve N c = rhs for each leaf, N the (n, n)
    collocation matrix of ``params`` (L, n); rhs (L, n, k). Banded past :data:`BANDED_FROM`
    (LAPACK's banded LU, O(n) memory), else dense."""
    n = params.shape[1]
    if n < BANDED_FROM:
        return np.linalg.solve(basis_matrix(params, knots, degree), rhs)
    from scipy.linalg import solve_banded

    vals, first, _ = basis_values(params, knots, degree)
    out = np.empty_like(rhs)
    rows = np.arange(n)
    for k in range(len(params)):
        band = np.zeros((2 * degree + 1, n))           # upper and lower bandwidth: degree
        for r in range(degree + 1):
            col = first[k] + r
            band[degree + rows - col, col] = vals[k, :, r]
        out[k] = solve_banded((degree, degree), band, rhs[k])
    return out


def data_parameters(points: np.ndarray, method: str = "chord") -> tuple[np.ndarray, np.ndarray]:
    """Averaged parameters of the rows (u) and columns (v) of grids (The NURBS Book 9.2.5).

    Zero-length rows or columns (a collapsed tip) are left out of the average.

    Parameters
    ----------
    points : (L, m, n, 3) or (m, n, 3) float64
    method : "chord" or "centripetal"

    Returns
    -------
    u : (L, m) float64, v : (L, n) float64 (no leading axis for a single grid); each runs
    from 0 to 1 and is NaN for a grid whose points all coincide.
    """
    if method not in ("chord", "centripetal"):
        raise ValueError(f"parameter method must be 'chord' or 'centripetal', not {method!r}")
    single = points.ndim == 3
    pts = points[None] if single else points

    def along(p):  # parameters along axis 1, averaged over axis 2
        d = np.linalg.norm(np.diff(p, axis=1), axis=3)
        if method == "centripetal":
            d = np.sqrt(d)
        total = d.sum(axis=1)                                       # (L, n)
        ok = total > 0
        cum = np.cumsum(d, axis=1) / np.where(ok, total, 1.0)[:, None, :]
        count = ok.sum(axis=1)
        t = (cum * ok[:, None, :]).sum(axis=2) / np.where(count, count, np.nan)[:, None]
        t = np.concatenate([np.zeros((len(p), 1)), t], axis=1)
        t[:, -1] = np.where(count > 0, 1.0, np.nan)
        return t

    u = along(pts)
    v = along(pts.transpose(0, 2, 1, 3))
    return (u[0], v[0]) if single else (u, v)


def averaged_knots(params: np.ndarray, degree: int) -> np.ndarray:
    """Clamped knot vectors by averaging (The NURBS Book eq. 9.8).

    (L, n) -> (L, n + degree + 1), or (n,) -> (n + degree + 1,).
    """
    single = params.ndim == 1
    p = params[None] if single else params
    nb, n = p.shape
    c = np.concatenate([np.zeros((nb, 1)), np.cumsum(p, axis=1)], axis=1)
    j = np.arange(1, n - degree)                        # interior knots j = 1 .. n-1-degree
    inner = (c[:, j + degree] - c[:, j]) / degree
    out = np.concatenate([np.zeros((nb, degree + 1)), inner, np.ones((nb, degree + 1))], axis=1)
    return out[0] if single else out


def refine_parameters(params: np.ndarray, k: int) -> np.ndarray:
    """The data parameters plus ``k`` evenly spaced ones between each consecutive pair.

    (..., n) -> (..., (n - 1)(k + 1) + 1); every data parameter is kept, so every digitized
    point becomes a mesh vertex.
    """
    if k < 0:
        raise ValueError(f"interpolation count must be >= 0, got {k}")
    frac = np.arange(k + 1) / (k + 1)
    inner = params[..., :-1, None] + np.diff(params, axis=-1)[..., None] * frac
    inner = inner.reshape(*params.shape[:-1], -1)
    return np.concatenate([inner, params[..., -1:]], axis=-1)


@dataclass(frozen=True)
class NurbsSurfaces:
    """L tensor-product NURBS surfaces of equal degrees and control grid shape over [0, 1]^2.

    Attributes
    ----------
    degree_u, degree_v : int
    knots_u : (L, nu + degree_u + 1) float64
    knots_v : (L, nv + degree_v + 1) float64
    control : (L, nu, nv, 3) float64, cm
    weights : (L, nu, nv) float64
    params_u : (L, m) float64
        Parameters of the data rows (the digitized cross-sections): 0 at the collar, 1 at the tip.
    params_v : (L, n) float64
        Parameters of the data columns: 0 and 1 at the margins.
    """

    degree_u: int
    degree_v: int
    knots_u: np.ndarray
    knots_v: np.ndarray
    control: np.ndarray
    weights: np.ndarray
    params_u: np.ndarray
    params_v: np.ndarray
    #: (batch, index) of a surface taken from a batch by :meth:`__getitem__`, for :meth:`join`
    _origin: tuple[NurbsSurfaces, int] | None = field(default=None, compare=False, repr=False)

    def __len__(self) -> int:
        return len(self.control)

    def __getitem__(self, i) -> NurbsSurfaces:
        """Surface ``i`` (an int: a batch of one whose arrays are views of this batch's, and
        which :meth:`join` puts back together without a copy), or the surfaces ``i`` picks (a
        slice, indices, a mask: copies)."""
        if isinstance(i, (int, np.integer)):
            k = range(len(self))[i]
            one = slice(k, k + 1)
            origin = (self, k) if self._origin is None else (self._origin[0],
                                                              self._origin[1] + k)
            return NurbsSurfaces(self.degree_u, self.degree_v, self.knots_u[one],
                                 self.knots_v[one], self.control[one], self.weights[one],
                                 self.params_u[one], self.params_v[one], origin)
        i = np.atleast_1d(np.arange(len(self))[i])
        return NurbsSurfaces(self.degree_u, self.degree_v, self.knots_u[i], self.knots_v[i],
                             self.control[i], self.weights[i], self.params_u[i], self.params_v[i])

    @classmethod
    def join(cls, surfaces: list[NurbsSurfaces]) -> NurbsSurfaces:
        """One batch of ``surfaces`` (equal degrees and shapes), in order: the batch they were
        taken from, sliced, where they are consecutive surfaces of one batch (leaves fitted
        together and meshed together), else their arrays concatenated."""
        if len(surfaces) == 1:
            return surfaces[0]
        first = surfaces[0]._origin
        if first is not None and all(
                s._origin is not None and s._origin[0] is first[0]
                and s._origin[1] == first[1] + k for k, s in enumerate(surfaces)):
            batch, start = first
            part = slice(start, start + len(surfaces))
            return cls(batch.degree_u, batch.degree_v, batch.knots_u[part], batch.knots_v[part],
                       batch.control[part], batch.weights[part], batch.params_u[part],
                       batch.params_v[part])
        s0 = surfaces[0]
        knots_u, knots_v, control, weights, params_u, params_v = (
            np.concatenate([getattr(s, f) for s in surfaces])
            for f in ("knots_u", "knots_v", "control", "weights", "params_u", "params_v"))
        return cls(s0.degree_u, s0.degree_v, knots_u, knots_v, control, weights, params_u,
                   params_v)

    def _homogeneous(self) -> np.ndarray:
        w = self.weights[..., None]
        return np.concatenate([self.control * w, w], axis=3)       # (L, nu, nv, 4)

    def evaluate_grid(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Points at every (u[l, a], v[l, b]).

        Parameters
        ----------
        u : (L, A) or (A,) float, v : (L, B) or (B,) float, in [0, 1]

        Returns
        -------
        (L, A, B, 3) float64, cm
        """
        nb = len(self)
        u = np.broadcast_to(np.minimum(np.maximum(u, 0.0), 1.0), (nb, np.shape(u)[-1]))
        v = np.broadcast_to(np.minimum(np.maximum(v, 0.0), 1.0), (nb, np.shape(v)[-1]))
        rational = not np.all(self.weights == 1.0)
        hom = self._homogeneous() if rational else self.control    # (L, nu, nv, c)
        nu, nv, nc = hom.shape[1], hom.shape[2], hom.shape[3]
        na, nbv = u.shape[1], v.shape[1]
        if max(nu, nv) < BANDED_FROM:
            bu = basis_matrix(u, self.knots_u, self.degree_u)           # (L, A, nu)
            bv = basis_matrix(v, self.knots_v, self.degree_v)           # (L, B, nv)
            d = bv[:, None] @ hom                                        # (L, nu, B, c)
            out = (bu @ d.reshape(nb, nu, nbv * nc)).reshape(nb, na, nbv, nc)
        else:                                    # banded: memory of the points, not A x nu
            bv, fv, _ = basis_values(v, self.knots_v, self.degree_v)    # (L, B, q + 1)
            bu, fu, _ = basis_values(u, self.knots_u, self.degree_u)    # (L, A, p + 1)
            d = _contract(bv, fv, hom.transpose(0, 2, 1, 3))            # (L, B, nu, c)
            out = _contract(bu, fu, d.transpose(0, 2, 1, 3))            # (L, A, B, c)
        return out[..., :3] / out[..., 3:] if rational else out

    def evaluate(self, u, v) -> np.ndarray:
        """Points at pairs (u[k], v[k]) on the first surface: (K,), (K,) -> (K, 3) cm."""
        return self._at(u, v)[0]

    def _at(self, u, v, derivative: bool = False):
        u = np.clip(np.asarray(u, dtype=np.float64).ravel(), 0.0, 1.0)
        v = np.clip(np.asarray(v, dtype=np.float64).ravel(), 0.0, 1.0)
        hom = self._homogeneous()[0]                                # (nu, nv, 4)
        ku, kv, pu, pv = self.knots_u[0], self.knots_v[0], self.degree_u, self.degree_v
        if max(hom.shape[:2]) < BANDED_FROM:                     # dense: faster when small
            return self._at_dense(hom, u, v, derivative)
        a = _at_pairs(hom, u, ku, pu, v, kv, pv)
        p = a[:, :3] / a[:, 3:]
        if not derivative:
            return p, None, None
        # the derivative is a spline of one degree less on the control points' differences
        # (The NURBS Book eq. 3.7): banded as the surface itself, whatever its size
        du_net, ku1 = _derivative_net(hom, ku, pu)
        dv_net, kv1 = _derivative_net(hom.transpose(1, 0, 2), kv, pv)
        au = _at_pairs(du_net, u, ku1, pu - 1, v, kv, pv)
        av = _at_pairs(dv_net.transpose(1, 0, 2), u, ku, pu, v, kv1, pv - 1)
        w = a[:, 3:]
        return p, (au[:, :3] - au[:, 3:] * p) / w, (av[:, :3] - av[:, 3:] * p) / w

    def _at_dense(self, hom: np.ndarray, u: np.ndarray, v: np.ndarray, derivative: bool):
        """:meth:`_at` through dense basis matrices (K, nu) and (K, nv): fewer numpy calls
        for the nets of ordinary leaves."""
        bu = basis_matrix(u[None], self.knots_u[:1], self.degree_u)[0]
        bv = basis_matrix(v[None], self.knots_v[:1], self.degree_v)[0]
        a = np.einsum("ki,ijc,kj->kc", bu, hom, bv)
        p = a[:, :3] / a[:, 3:]
        if not derivative:
            return p, None, None
        from scipy.interpolate import BSpline  # ~1 s to import: only for normals

        su = BSpline(self.knots_u[0], hom, self.degree_u).derivative()(u)      # (K, nv, 4)
        sv = BSpline(self.knots_v[0], hom.transpose(1, 0, 2), self.degree_v).derivative()(v)
        au = np.einsum("kjc,kj->kc", su, bv)
        av = np.einsum("kic,ki->kc", sv, bu)
        w = a[:, 3:]
        return p, (au[:, :3] - au[:, 3:] * p) / w, (av[:, :3] - av[:, 3:] * p) / w

    def derivatives(self, u, v) -> tuple[np.ndarray, np.ndarray]:
        """dS/du and dS/dv of the first surface at pairs (K,), (K,) -> two (K, 3), cm."""
        _, du, dv = self._at(u, v, derivative=True)
        return du, dv

    def normals(self, u, v) -> np.ndarray:
        """Unit normals dS/du x dS/dv of the first surface at pairs (K,), (K,) -> (K, 3).

        With the column convention of docs/method.md section 1 (col 0 = right margin seen from above, tip
        ahead) they point out of the upper (adaxial) face. Where the surface is degenerate
        (a collapsed tip) the normal is taken just inside the leaf.
        """
        u = np.clip(np.asarray(u, dtype=np.float64).ravel(), 0.0, 1.0)
        v = np.clip(np.asarray(v, dtype=np.float64).ravel(), 0.0, 1.0)
        du, dv = self.derivatives(u, v)
        n = np.cross(du, dv)
        length = np.linalg.norm(n, axis=1)
        scale = np.linalg.norm(du, axis=1) * np.linalg.norm(dv, axis=1)
        bad = length <= 1e-9 * np.maximum(scale, 1e-300)
        if bad.any():
            uu = np.where(u[bad] > 0.5, u[bad] - 1e-4, u[bad] + 1e-4)
            du2, dv2 = self.derivatives(uu, v[bad])
            n[bad] = np.cross(du2, dv2)
            length[bad] = np.linalg.norm(n[bad], axis=1)
        return n / np.where(length > 0, length, 1.0)[:, None]


def _at_pairs(net: np.ndarray, u: np.ndarray, ku: np.ndarray, pu: int, v: np.ndarray,
              kv: np.ndarray, pv: int) -> np.ndarray:
    """The spline of control net (nu, nv, c) at pairs (u[k], v[k]): (K, c), from each pair's
    (pu + 1) x (pv + 1) control points only."""
    vu, fu, _ = basis_values(u[None], ku[None], pu)
    vv, fv, _ = basis_values(v[None], kv[None], pv)
    out = np.zeros((len(u), net.shape[2]))
    for r in range(pu + 1):
        for t in range(pv + 1):
            out += (vu[0, :, r] * vv[0, :, t])[:, None] * net[fu[0] + r, fv[0] + t]
    return out


def _derivative_net(net: np.ndarray, knots: np.ndarray, degree: int
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The control net (n - 1, ...) and knots of the derivative along the first axis of a
    spline of ``degree`` with control net (n, ...) and ``knots``: degree (P_i+1 - P_i) /
    (t_i+degree+1 - t_i+1), on the knots without their first and last."""
    n = net.shape[0]
    span = knots[degree + 1:degree + n] - knots[1:n]
    scale = np.where(span > 0, degree / np.where(span > 0, span, 1.0), 0.0)
    return (net[1:] - net[:-1]) * scale.reshape((-1,) + (1,) * (net.ndim - 1)), knots[1:-1]


def fit_surfaces(points: np.ndarray, degree_u: int = 3, degree_v: int = 3,
                 method: str = "chord", keys=None) -> NurbsSurfaces:
    """Interpolate a NURBS surface through every point of each grid.

    Parameters
    ----------
    points : (L, m, n, 3) or (m, n, 3) float64, cm
        Leaf grids of one shape; m >= 2, n >= 2.
    degree_u, degree_v : int
        Requested degrees; lowered to m - 1 and n - 1 where there are too few points.
    method : "chord" (default) or "centripetal"
    keys : sequence of (plant, leaf), optional
        Ids of the grids, to name a leaf in an error.

    Raises
    ------
    LeafError
        For the first grid whose rows or columns coincide (singular collocation matrix).
    """
    points = np.asarray(points, dtype=np.float64)
    if points.ndim == 3:
        points = points[None]
    nb, m, n = points.shape[:3]
    keys = list(keys) if keys is not None else [(-1, -1)] * nb
    if m < 2 or n < 2:
        raise LeafError(keys[0][0], keys[0][1], f"grid {m}x{n}: needs at least 2 rows and 2 cols")
    pu = max(1, min(degree_u, m - 1))
    pv = max(1, min(degree_v, n - 1))
    u, v = data_parameters(points, method)
    for name, t in (("row", u), ("col", v)):
        step = np.diff(t, axis=1)
        bad = ~(step > 1e-12).all(axis=1)
        if bad.any():
            leaf = int(np.argmax(bad))
            k = int(np.nanargmin(np.where(np.isnan(step[leaf]), -1, step[leaf])))
            raise LeafError(keys[leaf][0], keys[leaf][1],
                            f"{name}s {k} and {k + 1} coincide; cannot interpolate "
                            f"(merge or remove the repeated {name})")
    ku = averaged_knots(u, pu)
    kv = averaged_knots(v, pv)
    r = _solve_collocation(u, ku, pu, points.reshape(nb, m, n * 3)).reshape(nb, m, n, 3)
    c = _solve_collocation(v, kv, pv, r.transpose(0, 2, 1, 3).reshape(nb, n, m * 3)
                           ).reshape(nb, n, m, 3)
    control = np.ascontiguousarray(c.transpose(0, 2, 1, 3))
    return NurbsSurfaces(pu, pv, ku, kv, control, np.ones((nb, m, n)), u, v)


def fit_surface(points: np.ndarray, degree_u: int = 3, degree_v: int = 3,
                method: str = "chord", plant: int = -1, leaf: int = -1) -> NurbsSurfaces:
    """One leaf: :func:`fit_surfaces` on an (m, n, 3) grid; the result has L = 1."""
    return fit_surfaces(np.asarray(points)[None], degree_u, degree_v, method, [(plant, leaf)])
