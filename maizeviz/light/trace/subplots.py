"""A field traced in sub-plots: the whole field's answer from parts traced apart.

The sample rectangle's ray lattice (:class:`~maizeviz.light.trace.hits.SunRays`) is cut into
windows of whole cells (:func:`windows`). A window's rays are the whole field's rays of those
cells, to the bit: the same lattice, the same origins (the same top plane, 1 cm above the
whole canopy), the same families of shifted rays answering the sensor planes, or the same
occlusion queries where the whole field asks them (:func:`family_used`). They are traced
through a scene of the plants within reach of the window (:func:`reach`): the window grown by
a halo as wide as any of its rays travels sideways between the top plane and the ground
(:func:`halo_cm`: ``top * tan(zenith)`` for the sun, the widest sky direction for a sky) plus
its plants' own spread. So each ray finds the triangle it finds in the whole field, and the
windows' counts (:class:`WindowCounts`: sensors that see the light on each plane, rays whose
first and second hits are each plant's leaves) add up to the whole field's, per height and per
plant (``tests/core/test_subplots.py``). Two triangles at exactly one distance along a ray (a
shared edge of one leaf) may be told apart differently by a smaller scene: the leaf, the plant
and the height are the same.

Open fields only: a periodic field's rays wrap across the whole plot (its scene is the plot's).
:mod:`maizeviz.sweep.subplots` traces the windows on Dask workers, each building its own plants
from the points file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.light.scene.rays import Rect, Tracer, grid_shape, sensor_offsets
from maizeviz.light.trace.hits import SECOND_HIT_EPS, SunRays, lattice_first_hits
from maizeviz.mesh.raytrace import RayScene

#: Beyond the horizontal travel of the rays, cm: rounding at the window's edge (a cell
#: diagonal is added too).
HALO_MARGIN_CM = 1.0


@dataclass(frozen=True)
class Window:
    """Cells [i0, i1) across x and [j0, j1) along y of a rectangle's ray lattice."""

    i0: int
    i1: int
    j0: int
    j1: int

    @property
    def n(self) -> int:
        return (self.i1 - self.i0) * (self.j1 - self.j0)

    def rect(self, rect: Rect, shape: tuple[int, int]) -> Rect:
        """The window's ground rectangle (cm) in the lattice of ``rect`` of ``shape`` cells."""
        x0, y0, x1, y1 = rect
        dx, dy = (x1 - x0) / shape[0], (y1 - y0) / shape[1]
        return x0 + self.i0 * dx, y0 + self.j0 * dy, x0 + self.i1 * dx, y0 + self.j1 * dy


def windows(shape: tuple[int, int], parts: tuple[int, int]) -> list[Window]:
    """The lattice of ``shape`` (nx, ny) cells cut into ``parts`` (a, b) windows of whole
    cells, a across x and b along y (the first windows one cell larger where they do not
    divide evenly)."""
    nx, ny = shape
    a, b = min(parts[0], nx), min(parts[1], ny)
    xs = np.linspace(0, nx, a + 1).round().astype(int)
    ys = np.linspace(0, ny, b + 1).round().astype(int)
    return [Window(int(xs[i]), int(xs[i + 1]), int(ys[j]), int(ys[j + 1]))
            for i in range(a) for j in range(b)]


def halo_cm(top: float, toward: np.ndarray, rect: Rect, shape: tuple[int, int]) -> float:
    """How far (cm) from its window a ray of the lattice may meet a triangle: the widest
    sideways travel ``top * |s_xy| / s_z`` over the directions ``toward`` ((k, 3) unit vectors
    toward the light), a cell diagonal and :data:`HALO_MARGIN_CM`. A sensor plane's family
    ray starts below the window's own ground cells by at most the same travel."""
    s = np.asarray(toward, dtype=np.float64).reshape(-1, 3)
    travel = float(np.max(top * np.hypot(s[:, 0], s[:, 1]) / s[:, 2])) if len(s) else 0.0
    x0, y0, x1, y1 = rect
    cell = math.hypot((x1 - x0) / shape[0], (y1 - y0) / shape[1])
    return travel + cell + HALO_MARGIN_CM


def reach(window_rect: Rect, halo: float) -> Rect:
    """The ground (cm) a window's rays cross: its rectangle grown by ``halo`` on every side
    (both ways: the ground rays run toward the light, their families' start behind)."""
    x0, y0, x1, y1 = window_rect
    return x0 - halo, y0 - halo, x1 + halo, y1 + halo


def plants_within(canopy: Canopy, area: Rect) -> np.ndarray:
    """Placements (indices) of ``canopy`` with a leaf or stalk triangle over ``area`` (cm):
    each placement's bounding box seen from above against the rectangle."""
    x0, y0, x1, y1 = area
    n = len(canopy.layout.placements)
    lo = np.full((n, 2), np.inf)
    hi = np.full((n, 2), -np.inf)
    corners = canopy.vertices[canopy.faces.reshape(-1)][:, :2]
    inst = np.repeat(canopy.face_instance.astype(np.int64), 3)
    for k in range(2):
        np.minimum.at(lo[:, k], inst, corners[:, k])
        np.maximum.at(hi[:, k], inst, corners[:, k])
    return np.flatnonzero((hi[:, 0] >= x0) & (lo[:, 0] <= x1) & (hi[:, 1] >= y0) &
                          (lo[:, 1] <= y1))


def sub_canopy(canopy: Canopy, placements: np.ndarray) -> tuple[Canopy, np.ndarray]:
    """The canopy of some placements only (their triangles and vertices, in the canopy's
    order), and the whole canopy's placement index of each of its placements."""
    from dataclasses import replace

    keep = np.zeros(len(canopy.layout.placements), bool)
    keep[placements] = True
    faces_kept = keep[canopy.face_instance]
    faces = canopy.faces[faces_kept]
    used = np.zeros(len(canopy.vertices), bool)
    used[faces.reshape(-1)] = True
    renumber = np.cumsum(used) - 1
    index = np.flatnonzero(keep)
    local = np.full(len(keep), -1, np.int64)
    local[index] = np.arange(len(index))
    layout = replace(canopy.layout, placements=tuple(canopy.layout.placements[i] for i in index))
    per = len(canopy.stalk_faces) // max(len(keep), 1) if canopy.stalk_instance is None else 0
    if per:
        stalk_keep = np.repeat(keep, per)
    else:
        stalk_keep = keep[canopy.stalk_instance] if canopy.stalk_instance is not None else \
            np.zeros(len(canopy.stalk_faces), bool)
    sfaces = canopy.stalk_faces[stalk_keep]
    sused = np.zeros(len(canopy.stalk_vertices), bool)
    sused[sfaces.reshape(-1)] = True
    sub = Canopy(canopy.vertices[used], renumber[faces], local[canopy.face_instance[faces_kept]],
                 canopy.face_plant[faces_kept], canopy.face_leaf[faces_kept], layout,
                 canopy.level, canopy.stalk_vertices[sused],
                 (np.cumsum(sused) - 1)[sfaces], canopy.leaves_per_instance[index],
                 None if canopy.stalk_instance is None else
                 local[canopy.stalk_instance[stalk_keep]])
    return sub, index


def family_used(shape: tuple[int, int], rect: Rect, heights: np.ndarray, top: float,
                s: np.ndarray) -> bool:
    """Whether :func:`~maizeviz.light.trace.beam.trace_direction` answers the sensor planes
    of an open field by ray families (else by an occlusion query per sensor): its decision,
    made from the shifted rectangles' union area (coordinate compression) instead of a mask
    of the whole lattice."""
    from maizeviz.light.trace.beam import OCCLUSION_COST

    planes = _planes(heights, top)
    if not planes:
        return False
    nx, ny = shape
    shifts = _shifts(shape, rect, heights, s)
    r = np.vstack([np.zeros((1, 2), np.int64), shifts[planes]])
    lo = (-r).min(axis=0)
    hi = (np.array([nx, ny]) - r).max(axis=0)
    bw, bh = (hi - lo).tolist()
    n = nx * ny
    budget = n * (1 + OCCLUSION_COST * len(planes))
    if bw * bh > 8 * n and bw * bh > budget:
        return False
    boxes = np.column_stack([-r[:, 0], -r[:, 1], nx - r[:, 0], ny - r[:, 1]])
    xs, ys = np.unique(boxes[:, [0, 2]]), np.unique(boxes[:, [1, 3]])
    cells = 0
    for a, b in zip(xs[:-1], xs[1:]):
        for c, d in zip(ys[:-1], ys[1:]):
            if np.any((boxes[:, 0] <= a) & (boxes[:, 2] >= b) & (boxes[:, 1] <= c) &
                      (boxes[:, 3] >= d)):
                cells += (b - a) * (d - c)
    return cells <= budget


def _planes(heights: np.ndarray, top: float) -> list[int]:
    leaf_top = top - 1.0
    return [k for k, h in enumerate(heights) if 0.0 < h <= leaf_top]


def _shifts(shape: tuple[int, int], rect: Rect, heights: np.ndarray, s: np.ndarray) -> np.ndarray:
    """r_k as :func:`~maizeviz.light.trace.beam._lattice_shifts` computes them (every plane)."""
    x0, y0, x1, y1 = rect
    cell = np.array([(x1 - x0) / shape[0], (y1 - y0) / shape[1]])
    t = np.asarray(heights, np.float64)[:, None] * (s[:2] / s[2]) / cell
    return np.round(t).astype(np.int64)


@dataclass
class WindowCounts:
    """What one window's rays found; :meth:`add` sums windows.

    Attributes
    ----------
    rays : ground rays (and sensors per plane) of the window
    lit : (H,) int64, sensors of each plane that see the light
    first, second : (P, L) int64 arrays of rays whose first / second hit is a leaf of rank
        ``l`` of placement ``p`` of the whole canopy (ranks from 0 to L - 1; ``L`` the
        largest rank + 1)
    """

    rays: int
    lit: np.ndarray
    first: np.ndarray
    second: np.ndarray

    def add(self, other: WindowCounts) -> WindowCounts:
        shape = tuple(max(a, b) for a, b in zip(self.first.shape, other.first.shape))
        out = []
        for a, b in ((self.first, other.first), (self.second, other.second)):
            total = np.zeros(shape, np.int64)
            total[:a.shape[0], :a.shape[1]] += a
            total[:b.shape[0], :b.shape[1]] += b
            out.append(total)
        return WindowCounts(self.rays + other.rays, self.lit + other.lit, out[0], out[1])

    @property
    def transmission(self) -> np.ndarray:
        """(H,) the share of each plane's sensors that see the light."""
        return self.lit / self.rays


def trace_window(canopy: Canopy, placement: np.ndarray, n_placements: int, window: Window,
                 rect: Rect, density: float, heights_cm, top: float, toward: np.ndarray,
                 bounds: Rect, scene: RayScene | None = None) -> WindowCounts:
    """Trace the rays of ``window`` of the lattice of ``rect`` (cm) at ``density`` rays per
    cm2 through ``canopy`` (the plants within its reach; ``placement``: the whole canopy's
    index of each of its placements, of ``n_placements``), toward the light ``toward``, from
    the top plane ``top`` (cm: the whole canopy's, 1 cm above its highest triangle).

    Returns the window's :class:`WindowCounts`.
    """
    from maizeviz.light.scene.embree_scenes import light_scene

    s = np.asarray(toward, dtype=np.float64)
    heights = np.asarray(heights_cm, dtype=np.float64)
    h32 = heights.astype(np.float32)
    scene = scene or light_scene(canopy)
    rays = SunRays(rect, density, s, top)
    nx, ny = rays.shape
    down = Tracer(scene, -s, bounds, False)
    row = window.j1 - window.j0
    i = np.repeat(np.arange(window.i0, window.i1), row)       # x slow, y fast: the lattice's
    j = np.tile(np.arange(window.j0, window.j1), window.i1 - window.i0)       # own order
    prim, z = lattice_first_hits(down, rays, i, j, ids=True, row=row)
    assert prim is not None
    leaf_top = top - 1.0
    planes = _planes(heights, top)
    family = family_used((nx, ny), rect, heights, top, s)
    lit = np.zeros(len(heights), np.int64)
    if family:
        # the family rays through the window's sensors: its cells shifted by -r_k, traced
        # once (as the whole field traces its box of them: with ids, the same query)
        shifts = _shifts((nx, ny), rect, heights, s)
        moves = [(0, 0)] + [(-int(shifts[k, 0]), -int(shifts[k, 1])) for k in planes]
        lo_i, lo_j = window.i0 + min(m[0] for m in moves), window.j0 + min(m[1] for m in moves)
        bw = window.i1 + max(m[0] for m in moves) - lo_i
        bh = window.j1 + max(m[1] for m in moves) - lo_j
        mask = np.zeros((bw, bh), bool)
        for dx, dy in moves[1:]:
            mask[window.i0 + dx - lo_i:window.i1 + dx - lo_i,
                 window.j0 + dy - lo_j:window.j1 + dy - lo_j] = True
        cells = np.flatnonzero(mask)
        fi, fj = np.divmod(cells, bh)
        _, fz = lattice_first_hits(down, rays, fi + lo_i, fj + lo_j, ids=True,
                                   row=bh if len(cells) == mask.size else 0)
        index = np.full((bw, bh), -1, np.int64)
        index.flat[cells] = np.arange(len(cells))
    up = Tracer(scene, s, bounds, False)
    offsets = sensor_offsets(heights, s, rect, density)
    x0, y0, x1, y1 = rect
    for k, h in enumerate(heights):
        if h > leaf_top:
            lit[k] = window.n
        elif k not in planes:                                    # the ground's sensors
            lit[k] = np.count_nonzero(z < h32[k])
        elif family:
            dx, dy = -int(shifts[k, 0]), -int(shifts[k, 1])
            ray_of = index[window.i0 + dx - lo_i:window.i1 + dx - lo_i,
                           window.j0 + dy - lo_j:window.j1 + dy - lo_j].ravel()
            lit[k] = np.count_nonzero(fz[ray_of] < h32[k])
        else:
            org = np.empty((len(i), 3))
            org[:, 0] = x0 + (i + 0.5) * ((x1 - x0) / nx) + offsets[k, 0]
            org[:, 1] = y0 + (j + 0.5) * ((y1 - y0) / ny) + offsets[k, 1]
            org[:, 2] = h
            lit[k] = np.count_nonzero(~up.occluded(org, np.full(len(i), (top - h) / s[2]),
                                                   row=row))
    # second hits: the same rays, on past their first hits
    sel = np.flatnonzero(prim >= 0)
    zf = z[sel].astype(np.float64)
    left = rays.reach - (top - zf) / s[2] - SECOND_HIT_EPS
    org = np.empty((len(sel), 3))
    org[:, 0] = x0 + (i[sel] + 0.5) * ((x1 - x0) / nx) + left * s[0]
    org[:, 1] = y0 + (j[sel] + 0.5) * ((y1 - y0) / ny) + left * s[1]
    org[:, 2] = zf - SECOND_HIT_EPS * s[2]
    second, _ = down.trace(org, np.maximum(left, 0.0))
    assert second is not None
    ranks = int(canopy.face_leaf.max(initial=0)) + 1
    first_counts = _per_leaf(canopy, placement, n_placements, ranks, prim[sel])
    second_counts = _per_leaf(canopy, placement, n_placements, ranks, second[second >= 0])
    return WindowCounts(window.n, lit, first_counts, second_counts)


def _per_leaf(canopy: Canopy, placement: np.ndarray, n_placements: int, ranks: int,
              prim: np.ndarray) -> np.ndarray:
    """(P, L) counts of triangles ``prim`` by the whole canopy's placement and leaf rank
    (stalk triangles, numbered after the leaves, are left out)."""
    leaf = prim[prim < canopy.n_triangles]
    inst = placement[canopy.face_instance[leaf].astype(np.int64)]
    rank = canopy.face_leaf[leaf].astype(np.int64)
    counts = np.bincount(inst * ranks + rank, minlength=n_placements * ranks)
    return counts.reshape(n_placements, ranks)


def whole_counts(canopy: Canopy, first_hits: np.ndarray, second_hits: np.ndarray,
                 transmission: np.ndarray, rays: int) -> WindowCounts:
    """The counts of a whole field's trace (a :class:`~maizeviz.light.results.direct.
    LightResult`'s per-triangle hits and transmission), to set beside the windows' sum."""
    n_place = len(canopy.layout.placements)
    ranks = int(canopy.face_leaf.max(initial=0)) + 1
    inst = canopy.face_instance.astype(np.int64)
    rank = canopy.face_leaf.astype(np.int64)
    key = inst * ranks + rank
    f = first_hits[:canopy.n_triangles]
    s = second_hits[:canopy.n_triangles]
    return WindowCounts(
        rays, np.rint(np.asarray(transmission) * rays).astype(np.int64),
        np.bincount(key, f, n_place * ranks).astype(np.int64).reshape(n_place, ranks),
        np.bincount(key, s, n_place * ranks).astype(np.int64).reshape(n_place, ranks))


def default_top(canopy: Canopy) -> float:
    """The top plane (cm) of a canopy's rays: 1 cm above its highest triangle, as
    :func:`~maizeviz.light.trace.beam.sampler` sets it."""
    from maizeviz.light.scene.request import canopy_top

    return canopy_top(canopy) + 1.0


__all__ = ["Window", "WindowCounts", "windows", "halo_cm", "reach", "plants_within",
           "sub_canopy", "family_used", "trace_window", "whole_counts", "default_top",
           "grid_shape"]
