"""Rays through a periodic field: the plot (or one block of it) repeats forever, and a ray is
traced through the copy of the scene under each cell it crosses.

A periodic field is a scene repeated with period (w, h) cm from (x0, y0) cm (a :class:`Wrap`).
A ray crossing cells (i, j) is traced, for each cell, through the scene moved by (i w, j h):
equivalently, the ray moved by (-i w, -j h) through the scene. The scene holds every triangle
that reaches into its cell, the cell's own and copies of its neighbours' overhangs
(:func:`overhang_copies`), so each query sees everything the ray can meet in that cell.

Exact translations. Embree intersects in float32, from ``v0 - org`` (triangle vertex minus ray
origin). Moving a ray by a period only gives the same float32 numbers as moving the scene
when every coordinate involved is a multiple of one power of two, the *quantum* q
(:func:`quantum_cm`: 2^-12 cm = 2.4 um for the bundled 5.4 x 2.7 m plot, coarser for larger
plots), large enough for every multiple of it in the field to be exact in float32: the x, y of
the scene's vertices, of the periods and of the ray origins are rounded to multiples of q
(:func:`snap`, by at most q / 2 = 1.2 um, a hundredth of a leaf's thickness). Then

- a ray is never moved along itself (that would round): every query of a ray starts at its
  own origin moved by whole periods, with ``tfar`` the end of the cell's segment, so a hit
  before the segment is found again at the same distance (it is a real hit too: every
  triangle of the scene stands in the field), and the nearest over the cells is the nearest;
- a long ray is re-anchored every :data:`ANCHOR_CM` of horizontal travel at the grid point
  nearest its line, so that its moved origins stay within float32's exact range.

So a field traced through its plot (the whole tiled canopy, overhangs copied across the plot
edge) and the same field traced through one block of it (:mod:`maizeviz.light.scene.tiling`) make the
same float32 queries up to exact translations, and give the same hits, ray for ray
(``tests/core/test_tiling.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maizeviz.errors import MaizevizError

#: Horizontal travel (cm) after which a ray is re-anchored on the grid (a power of two).
ANCHOR_CM = 1024.0
#: Distance (cm) beyond the cell within which neighbours' triangles are copied into it: more
#: than a re-anchored ray's offset (q / 2) and than rounding at a cell edge.
COPY_MARGIN_CM = 0.01

Rect = tuple[float, float, float, float]


def quantum_cm(plot: Rect) -> float:
    """The grid step q (cm, a power of two) for a field whose plot is ``plot`` (x0, y0, x1, y1)
    cm: every coordinate a periodic query uses (the plot, one period, a re-anchored ray's
    travel) is below 2^24 q, so its multiples of q are exact in float32."""
    x0, y0, x1, y1 = plot
    reach = max(abs(x0), abs(y0), abs(x1), abs(y1)) + max(x1 - x0, y1 - y0) + ANCHOR_CM
    return 2.0 ** (math.ceil(math.log2(reach)) - 23)


def snap(a: np.ndarray, q: float) -> np.ndarray:
    """A float64 copy of points ``a`` (..., 2 or 3) cm with x and y rounded to multiples of q
    (z unchanged); exact arithmetic, q being a power of two."""
    out = np.array(a, dtype=np.float64)
    out[..., :2] = np.round(out[..., :2] / q) * q
    return out


@dataclass(frozen=True)
class Wrap:
    """A periodic field: cell (i, j) is [x0 + i w, x0 + (i + 1) w) x [y0 + j h, ...).

    Attributes
    ----------
    x0, y0 : cm, the corner of cell (0, 0) (the scene's own)
    w, h : cm, the period, multiples of ``q``
    q : cm, the grid step of the field's coordinates (:func:`quantum_cm`)
    """

    x0: float
    y0: float
    w: float
    h: float
    q: float

    @classmethod
    def of(cls, cell: Rect, plot: Rect | None = None) -> Wrap:
        """The field repeating ``cell`` (x0, y0, x1, y1) cm, on the grid of ``plot`` (the
        whole plot the cell belongs to; default the cell)."""
        q = quantum_cm(plot or cell)
        x0, y0, x1, y1 = cell
        w, h = (float(np.round(v / q) * q) for v in (x1 - x0, y1 - y0))
        if w <= 0 or h <= 0:
            raise MaizevizError(f"a periodic cell must have a size, got {cell}")
        return cls(float(x0), float(y0), w, h, q)

    @property
    def period(self) -> np.ndarray:
        return np.array([self.w, self.h])

    @property
    def corner(self) -> np.ndarray:
        return np.array([self.x0, self.y0])


def overhang_copies(verts: np.ndarray, faces: np.ndarray, wrap: Wrap, q: float | None = None
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Copies of the triangles of the 8 neighbouring cells that reach into cell (0, 0) (within
    :data:`COPY_MARGIN_CM`): vertices (3k, 3) cm, faces (k, 3) numbered from 0, the triangle
    each copies (k,) int64 and the cell it comes from (k, 2) int64 (-1, 0 or 1 each).

    ``q``: the vertices' x and y are first rounded to multiples of it (:func:`snap`; the
    copies are then on the grid too). Only the triangles with a corner near the cell's edges
    (where rounding may put it) are looked at: a hectare's 40 million triangles are not all
    gathered as (F, 3, 3) coordinates (72 bytes each) to find the edge's few.
    """
    x0, y0, w, h = wrap.x0, wrap.y0, wrap.w, wrap.h
    m = COPY_MARGIN_CM
    slack = m + (q or 0.0)                 # rounding moves a coordinate by q / 2 at most
    near = ((verts[:, 0] < x0 + slack) | (verts[:, 0] > x0 + w - slack) |
            (verts[:, 1] < y0 + slack) | (verts[:, 1] > y0 + h - slack))
    cand_parts = []
    for s in range(0, len(faces), 1 << 20):
        corner = near.take(faces[s:s + (1 << 20)])          # (k, 3): far faster than
        cand_parts.append(s + np.flatnonzero(corner[:, 0] | corner[:, 1] | corner[:, 2]))
    cand = np.concatenate(cand_parts) if cand_parts else np.empty(0, np.int64)
    tri = verts[faces[cand]]                                # any() over an axis of three
    if q is not None:
        tri = snap(tri, q)
    lo = np.minimum(np.minimum(tri[:, 0], tri[:, 1]), tri[:, 2])   # so are these than
    hi = np.maximum(np.maximum(tri[:, 0], tri[:, 1]), tri[:, 2])   # min / max over it
    out_v, out_src, out_cell = [], [], []
    for i in (-1, 0, 1):
        for j in (-1, 0, 1):
            if i == 0 and j == 0:
                continue
            # the neighbour (i, j)'s triangle sits at +(i w, j h) from the scene's own
            dx, dy = i * w, j * h
            keep = np.flatnonzero((hi[:, 0] + dx > x0 - m) & (lo[:, 0] + dx < x0 + w + m) &
                                  (hi[:, 1] + dy > y0 - m) & (lo[:, 1] + dy < y0 + h + m))
            if len(keep):
                out_v.append((tri[keep] + np.array([dx, dy, 0.0])).reshape(-1, 3))
                out_src.append(cand[keep])
                out_cell.append(np.tile([i, j], (len(keep), 1)))
    if not out_v:
        return (np.empty((0, 3)), np.empty((0, 3), np.int64), np.empty(0, np.int64),
                np.empty((0, 2), np.int64))
    v = np.vstack(out_v)
    return (v, np.arange(len(v)).reshape(-1, 3), np.concatenate(out_src).astype(np.int64),
            np.vstack(out_cell).astype(np.int64))


def _exit_times(org: np.ndarray, dirs: np.ndarray, cell: np.ndarray, wrap: Wrap
                ) -> tuple[np.ndarray, np.ndarray]:
    """Distance along each ray from ``org`` to where it leaves cell ``cell`` (k, 2), and the
    step (k, 2) in -1, 0, 1 to the next cell (both axes at a corner)."""
    t_axis = np.full((len(org), 2), np.inf)
    step = np.zeros((len(org), 2), np.int64)
    for a, (c0, p) in enumerate(((wrap.x0, wrap.w), (wrap.y0, wrap.h))):
        d = dirs[:, a]
        up, down = d > 0, d < 0
        edge = np.where(up, c0 + (cell[:, a] + 1) * p, c0 + cell[:, a] * p)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            t_axis[:, a] = np.where(up | down, (edge - org[:, a]) / d, np.inf)
        step[:, a] = up.astype(np.int64) - down.astype(np.int64)
    t = t_axis.min(axis=1)
    return t, np.where(t_axis <= t[:, None], step, 0)


def trace_wrapped(scene, wrap: Wrap, org: np.ndarray, dirs: np.ndarray, length: np.ndarray,
                  any_hit: bool = False, ids: bool = True, row: int = 0, native: bool = True):
    """Rays through the periodic field ``wrap`` of ``scene`` (see the module docstring).

    Parameters
    ----------
    scene : RayScene holding every triangle that reaches into cell (0, 0)
    org : (N, 3) cm, ray origins anywhere in the field; dirs : (N, 3) or (3,) unit vectors
    length : (N,) cm, how far each ray goes
    any_hit : only whether anything is hit (occlusion queries)
    ids : keep the triangle ids (nearest hits)
    row : rays per row when the rays form a grid laid out row by row (coherent packets)
    native : through the C kernel where the scene has it (:func:`maizeviz.mesh.packets.wrapped`,
        the same steps); False: here, in numpy

    Returns
    -------
    any_hit: blocked (N,) bool. Otherwise scene triangle ids (N,) int32 (-1: none; None unless
    ``ids``), the cell (N, 2) int64 whose copy of the scene holds the hit, and the hit distance
    (N,) float64 cm (inf where none).
    """
    field = getattr(scene, "trace_field", None)
    if field is not None:                        # the scene's own way (a tiled block's)
        got = field(org, np.asarray(dirs).reshape(-1, 3), length, any_hit, row, native)
        return got if any_hit else ((got[0] if ids else None), got[1], got[2])
    return wrap_segments(scene, wrap, org, dirs, length, any_hit, ids, row, native)


def wrap_segments(scene, wrap: Wrap, org: np.ndarray, dirs: np.ndarray, length: np.ndarray,
                  any_hit: bool = False, ids: bool = True, row: int = 0, native: bool = True):
    """:func:`trace_wrapped` through ``scene`` itself, whatever its own way: segment by segment
    over the cells of ``wrap`` (in C where the scene has the packet kernel and ``native``)."""
    kernel = getattr(scene, "_kernel", None) if native else None
    if kernel is not None:                       # the same algorithm, in C
        from maizeviz.mesh.packets import wrapped

        got = wrapped(kernel, scene._handle, org, np.asarray(dirs).reshape(-1, 3), length,
                      (wrap.x0, wrap.y0, wrap.w, wrap.h, wrap.q, ANCHOR_CM), any_hit, row=row)
        if any_hit:
            return got
        return (got[0] if ids else None), got[1], got[2]
    n = len(org)
    q = wrap.q
    o = snap(org, q)
    d = np.asarray(dirs, dtype=np.float64)
    d = np.broadcast_to(d.reshape(-1, 3), (n, 3)) if d.size == 3 else d
    one_dir = np.asarray(dirs).size == 3
    length = np.broadcast_to(np.asarray(length, dtype=np.float64), (n,))
    horiz = np.hypot(d[:, 0], d[:, 1])
    with np.errstate(divide="ignore"):
        anchor_t = np.where(horiz > 0, ANCHOR_CM / horiz, np.inf)   # travel between anchors
    period, corner = wrap.period, wrap.corner
    cell = np.floor((o[:, :2] - corner) / period).astype(np.int64)
    anchor_k = np.zeros(n)                       # which anchor each ray's segment starts from
    best = np.full(n, np.inf)
    prim = np.full(n, -1, np.int32)
    where = np.zeros((n, 2), np.int64)
    blocked = np.zeros(n, dtype=bool)
    todo = np.arange(n)
    for _ in range(1_000_000):
        if not len(todo):
            break
        ot, dt, at = o[todo], d[todo], anchor_t[todo]
        k = anchor_k[todo]
        finite = np.isfinite(at)
        t_anchor = np.where(finite, k * np.where(finite, at, 0.0), 0.0)
        anchor = ot
        moved = k > 0
        if moved.any():                          # re-anchored on the grid nearest the line
            anchor = ot.copy()
            anchor[moved] = snap(ot[moved] + t_anchor[moved, None] * dt[moved], q)
        t_exit, step = _exit_times(ot, dt, cell[todo], wrap)
        t_next = np.where(finite, (k + 1) * np.where(finite, at, 0.0), np.inf)
        end = np.minimum(np.minimum(t_exit, t_next), length[todo])
        qo = anchor.copy()
        qo[:, :2] -= cell[todo] * period        # exact: multiples of q, within 2^24 q
        qd = d[:1] if one_dir else dt
        reach = (end - t_anchor).astype(np.float32)
        r = row if len(todo) == n else 0
        if any_hit:
            hit = scene.occluded(qo, qd, reach, row=r)
            blocked[todo[hit]] = True
            done = hit | (end >= length[todo])
        else:
            p, t = scene.first_hit(qo, qd, reach, row=r)
            found = p >= 0
            dist = t_anchor + t.astype(np.float64)
            better = found & (dist < best[todo])
            sel = todo[better]
            best[sel] = dist[better]
            where[sel] = cell[todo][better]
            prim[sel] = p[better]
            done = (best[todo] <= end) | (end >= length[todo])
        crossed = ~done & (t_exit <= end)
        cell[todo[crossed]] += step[crossed]
        anchor_k[todo[~done & (t_next <= end)]] += 1
        todo = todo[~done]
    if len(todo):  # pragma: no cover - every segment ends at a cell edge, an anchor or the end
        raise MaizevizError(f"periodic tracing left {len(todo)} rays unfinished")
    if any_hit:
        return blocked
    return (prim if ids else None), where, best
