"""Direct sunlight through a canopy: transmission on sensor planes by height (the paper's Table 3).

Transmission at height h is measured on the sample rectangle raised to h: the same x, y
rectangle, as a row of light sensors held at that height. The rectangle at h carries a regular
grid of ``density`` sensors per cm2 (:func:`~maizeviz.light.scene.rays.sensor_offsets`), and Embree is
asked whether the path from each sensor toward the sun is blocked (an occlusion query, cheaper
than a nearest-hit query); T(h) is the fraction of sensors whose path is clear.

The paper's hit classes come from parallel rays landing on the ground rectangle
(:class:`~maizeviz.light.trace.hits.SunRays`): each is followed from above the canopy down toward the
ground against the sun direction; its first leaf hit receives direct light, its second hit
second-class light (:mod:`maizeviz.light.trace.hits`). The ground's sensors are these rays' landing
points, so T(0) comes from them without another query.

With ``periodic`` every ray and every sensor path that leaves the plot sideways re-enters on the
opposite side. Without it, a warning says when the sun is low enough for paths reaching the
rectangle to have crossed the plot edge, where nothing stops them.

Why not the rays' own crossings of height h (version 0.1): they lie on the ground rectangle
shifted toward the sun by h tan(zenith), which is the same place only in a periodic canopy whose
period is the rectangle; a single leaf at 100 cm under a 45 deg sun shades the whole rectangle at
50 cm while the shifted crossings report half of it lit, and for a low sun the shifted rectangle
can leave the plot. On sensor planes T need not decrease downward (a shadow can move out of the
rectangle below a height); in a periodic field whose period is the rectangle it does, as in the
continuum, because the grids of all heights are aligned along the sun path.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import TypeVar

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.layout import stands_identity
from maizeviz.light.results.direct import LightResult
from maizeviz.light.scene.embree_scenes import scene_for
from maizeviz.light.scene.rays import Rect, Tracer, ray_grid, sensor_offsets
from maizeviz.light.scene.request import LightRequest, canopy_top, check_request
from maizeviz.light.trace.hits import (
    SunRays,
    first_hits,
    hit_counts,
    lattice_first_hits,
    second_hits,
)
from maizeviz.mesh.raytrace import RayScene
from maizeviz.progress import ProgressCallback, ordered_map, report

#: Rays traced per chunk: bounds memory and sets the progress step (a multiple of 8, so that
#: the sensors' bits of a chunk pack into whole bytes).
CHUNK = 1 << 18

T = TypeVar("T")


def _chunks(n: int) -> list[tuple[int, int]]:
    size = max(8, CHUNK - CHUNK % 8)
    return [(a, min(a + size, n)) for a in range(0, n, size)]


@dataclass(frozen=True)
class Sampler:
    """What every direction traced through one canopy shares: the scene, the sample rectangle
    and its grid, the sensor heights, the periodic field.

    Attributes
    ----------
    scene : RayScene of the canopy (leaves first, then stalks if any)
    rect : (x0, y0, x1, y1) cm; density : rays per cm2 asked for
    heights_cm : (H,) float64 cm; periodic : bool
    bounds : (x0, y0, x1, y1) cm, the plot
    top : cm, height of the plane the ground rays start from (1 cm above every triangle)
    n_leaf_triangles : F_leaf, the canopy's leaf triangles (triangle ids after them are stalks)
    """

    scene: RayScene
    rect: Rect
    density: float
    heights_cm: np.ndarray
    periodic: bool
    bounds: Rect
    top: float
    n_leaf_triangles: int

    @cached_property
    def n(self) -> int:
        return SunRays(self.rect, self.density, np.array([0.0, 0.0, 1.0]), self.top).n

    @property
    def n_triangles(self) -> int:
        """Leaf and stalk triangles: hits are reported in these ids (overhang copies of a
        periodic scene are reported as their originals)."""
        return int(getattr(self.scene, "n_original", self.scene.n_triangles))

    @cached_property
    def ray_area_cm2(self) -> float:
        x0, y0, x1, y1 = self.rect
        return (x1 - x0) * (y1 - y0) / self.n


def sampler(canopy: Canopy, scene: RayScene, rect: Rect, density: float,
            heights_cm: tuple[float, ...] | np.ndarray, periodic: bool,
            with_stalks: bool = False) -> Sampler:
    """A :class:`Sampler` for a checked request (see :func:`check_sampling`)."""
    return Sampler(scene, rect, density, np.asarray(heights_cm, dtype=np.float64), periodic,
                   canopy.layout.bounds, canopy_top(canopy, with_stalks) + 1.0,
                   canopy.n_triangles)


@dataclass(frozen=True)
class DirectionTrace:
    """One direction traced by :func:`trace_direction`.

    Attributes
    ----------
    toward : (3,) unit vector toward the light (sun or sky element)
    transmission : (H,) float64, fraction of each plane's sensors that see the light
    first_z : (N,) float32 cm, height of each ground ray's first hit, -inf where none
    first_prim : (N,) int32, each ground ray's first triangle, -1 where none (None unless ids)
    second_prim : list of int32 arrays, the second triangles hit (None unless second hits)
    sensor_lit : (H, ceil(N / 8)) uint8, packed bits of :attr:`transmission`'s sensors
    sensor_offset_cm : (H, 2) float64 cm
    seconds : "trace" (and "second"), s
    """

    toward: np.ndarray
    transmission: np.ndarray
    first_z: np.ndarray
    first_prim: np.ndarray | None
    second_prim: list[np.ndarray] | None
    sensor_lit: np.ndarray
    sensor_offset_cm: np.ndarray
    seconds: dict[str, float]


#: Cost of an occlusion query from a sensor plane up to the top, relative to a ground ray's
#: nearest-hit query from the top down (measured on the bundled canopy: 0.6 to 0.9).
OCCLUSION_COST = 0.7


@dataclass(frozen=True)
class _Family:
    """The rays of one direction through every sensor of every plane below the canopy top.

    With the grids aligned (:func:`sensor_offsets`), the sensor (a, b) of plane k lies on the ray
    landing on ground lattice cell (a - r_k[0], b - r_k[1]); its path to the light is the part of
    that ray above h_k, so it is lit exactly when the ray's first hit lies below h_k. Tracing
    the union of these shifted grids once answers every plane.
    """

    lo: tuple[int, int]                 # lattice index of the box's first cell
    index: np.ndarray                   # (bw, bh) int32: ray of each box cell, -1 outside
    cells: np.ndarray                   # (k,) int64: flat box cells of the rays, x slow
    shifts: np.ndarray                  # (H, 2) int64: r_k
    size: tuple[int, int]               # nx, ny
    wraps: bool = False                 # the box is the grid, read modulo (_spans_periods)


def _lattice_shifts(smp: Sampler, s: np.ndarray, planes: list[int]) -> np.ndarray:
    """(H, 2) int64: r_k, the ground lattice cells from a sensor of plane k to the ray of its
    family (zero for the planes not in ``planes``); see :func:`sensor_offsets`."""
    from maizeviz.light.scene.rays import grid_shape

    nx, ny = grid_shape(smp.rect, smp.density)
    x0, y0, x1, y1 = smp.rect
    cell = np.array([(x1 - x0) / nx, (y1 - y0) / ny])
    t = smp.heights_cm[:, None] * (s[:2] / s[2]) / cell
    shifts = np.round(t).astype(np.int64)
    shifts[[k for k in range(len(shifts)) if k not in planes]] = 0
    return shifts


#: Answer the planes of a periodic field whose sample rectangle spans whole periods by the
#: ground rays alone (:func:`_spans_periods`); False always traces the family's box
WRAP_FAMILY = True


def _spans_periods(smp: Sampler) -> bool:
    """Whether the sample rectangle spans a whole number of the periodic field's periods in x
    and in y (the paper's case: the central block of a tiled canopy, in its own field).

    Then the family ray through any sensor is a ground ray of the rectangle moved by whole
    periods: the same ray of the field, with the same hits (the field repeats exactly, on its
    grid: :mod:`maizeviz.light.scene.periodic`). The ground rays answer every plane, whatever the
    sun's elevation, and no sensor needs a query of its own.
    """
    wrap = getattr(smp.scene, "period", None)
    if not (WRAP_FAMILY and smp.periodic and wrap is not None):
        return False
    x0, y0, x1, y1 = smp.rect
    spans = np.array([(x1 - x0) / wrap.w, (y1 - y0) / wrap.h])
    whole = np.round(spans)
    return bool(np.all(whole >= 1) and np.all(np.abs(spans - whole) <= 1e-9 * whole))


def _family(smp: Sampler, s: np.ndarray, planes: list[int]) -> _Family | None:
    """The ray family through the planes ``planes`` and the ground, or None when per-plane
    occlusion queries cost less (low suns: the shifted grids hardly overlap)."""
    from maizeviz.light.scene.rays import grid_shape

    nx, ny = grid_shape(smp.rect, smp.density)
    shifts = _lattice_shifts(smp, s, planes)
    r = np.vstack([np.zeros((1, 2), np.int64), shifts[planes]])   # the ground, then planes
    lo = (-r).min(axis=0)
    hi = (np.array([nx, ny]) - r).max(axis=0)
    bw, bh = (hi - lo).tolist()
    n = nx * ny
    budget = n * (1 + OCCLUSION_COST * len(planes))
    if bw * bh > 8 * n and bw * bh > budget:
        return None                                 # too spread out to be worth a box
    mask = np.zeros((bw, bh), dtype=bool)
    for rk in r:             # by shift, not by height index: index 0 need not be the ground
        ox, oy = -rk - lo
        mask[ox:ox + nx, oy:oy + ny] = True
    cells = np.flatnonzero(mask)
    if len(cells) > budget:
        return None
    index = np.full((bw, bh), -1, dtype=np.int32)
    index.flat[cells] = np.arange(len(cells), dtype=np.int32)
    return _Family((int(lo[0]), int(lo[1])), index, cells, shifts, (nx, ny))


def _period_family(smp: Sampler, s: np.ndarray, planes: list[int]) -> _Family:
    """The ray family of a rectangle spanning whole periods (:func:`_spans_periods`): its own
    ground rays, read modulo the grid."""
    from maizeviz.light.scene.rays import grid_shape

    nx, ny = grid_shape(smp.rect, smp.density)
    cells = np.arange(nx * ny, dtype=np.int64)
    return _Family((0, 0), cells.astype(np.int32).reshape(nx, ny), cells,
                   _lattice_shifts(smp, s, planes), (nx, ny), wraps=True)


def _plane_rays(fam: _Family, k: int) -> np.ndarray:
    """(N,) int64: the family ray through each sensor of plane k, in sensor grid order."""
    if fam.wraps:            # sensor (a, b) is on ray (a, b) - r_k, modulo the grid
        return np.roll(fam.index, (int(fam.shifts[k, 0]), int(fam.shifts[k, 1])),
                       axis=(0, 1)).ravel()
    nx, ny = fam.size
    ox, oy = -fam.shifts[k] - np.array(fam.lo)
    return fam.index[ox:ox + nx, oy:oy + ny].ravel()


def trace_direction(smp: Sampler, toward: np.ndarray, ids: bool = False, second: bool = False,
                    threads: int = 1, progress: ProgressCallback | None = None,
                    stop: threading.Event | None = None) -> DirectionTrace:
    """Trace one parallel beam through the canopy: ground rays and every sensor plane.

    Each sensor's path to the light is asked of Embree as an occlusion query, or, where fewer
    rays do it (suns high enough for the shifted grids to overlap), answered by the first hit
    of the ray of the same family through it (:class:`_Family`): the same segment, the same
    periodic wrap, the same answer.

    Parameters
    ----------
    smp : Sampler
    toward : (3,) unit vector toward the light, z > 0 (field coordinates)
    ids : keep each ground ray's first triangle; second : also trace second hits (needs ids)
    threads : threads over chunks of rays (:func:`maizeviz.progress.ordered_map`)
    progress : ``progress(done, total)`` after each chunk of rays; returning ``False`` cancels
        with InterruptedError
    stop : when set, the next chunk raises InterruptedError (cancellation from another thread)
    """
    t0 = time.perf_counter()
    s = np.asarray(toward, dtype=np.float64)
    rays = SunRays(smp.rect, smp.density, s, smp.top)
    n = rays.n
    heights = smp.heights_cm
    leaf_top = smp.top - 1.0
    planes = [k for k, h in enumerate(heights) if 0.0 < h <= leaf_top]
    fam = None if not planes else (_period_family(smp, s, planes) if _spans_periods(smp)
                                   else _family(smp, s, planes))
    chunks = _chunks(n if fam is None else len(fam.cells))
    ground_chunks = _chunks(n)
    total = len(chunks) + (len(ground_chunks) if second else 0)

    def in_chunks(fn: Callable[[int, int], T], parts: list[tuple[int, int]],
                  before: int) -> list[T]:
        def done(k: int) -> None:
            report(progress, before + k, total, "light computation")

        return list(ordered_map(lambda ab: fn(*ab), parts, threads, done, stop))
    keep_ids = ids or second
    p = _Pass(smp, s, rays, planes, sensor_offsets(heights, s, smp.rect, smp.density),
              Tracer(smp.scene, -s, smp.bounds, smp.periodic,
                     max(chunks[0][1], ground_chunks[0][1])),
              np.empty(n, dtype=np.float32),
              np.empty(n, dtype=np.int32) if keep_ids else None,
              np.zeros((len(heights), (n + 7) // 8), dtype=np.uint8), stop)
    if fam is None:
        transmission = _sensor_pass(p, chunks, in_chunks)
    else:
        transmission = _family_pass(p, fam, chunks, in_chunks)
    seconds = {"trace": time.perf_counter() - t0}
    seconds_prims = None
    if second and p.first_prim is not None:
        t2 = time.perf_counter()
        fprim = p.first_prim

        def chunk2(a: int, b: int) -> np.ndarray:
            p.check()
            return second_hits(p.down, rays, a, b, fprim[a:b], p.first_z[a:b])

        seconds_prims = in_chunks(chunk2, ground_chunks, len(chunks))
        seconds["second"] = time.perf_counter() - t2
    return DirectionTrace(s, transmission.astype(np.float64), p.first_z,
                          p.first_prim if keep_ids else None, seconds_prims, p.packed,
                          p.offsets, seconds)


@dataclass
class _Pass:
    """One direction being traced: its rays, the planes a family answers, the downward
    tracer, and the arrays the chunks fill (first hits, packed sensor bits)."""

    smp: Sampler
    s: np.ndarray                      # (3,) toward the light
    rays: SunRays
    planes: list[int]                  # planes between the ground and the leaves' top
    offsets: np.ndarray                # (H, 2) cm, each plane's grid offset
    down: Tracer
    first_z: np.ndarray                # (N,) float32
    first_prim: np.ndarray | None      # (N,) int32 with ids
    packed: np.ndarray                 # (H, ceil(N / 8)) uint8
    stop: threading.Event | None

    @property
    def leaf_top(self) -> float:
        return self.smp.top - 1.0

    def check(self) -> None:
        if self.stop is not None and self.stop.is_set():
            raise InterruptedError("light computation cancelled")


def _sensor_pass(p: _Pass, chunks: list[tuple[int, int]], in_chunks) -> np.ndarray:
    """Ground rays chunk by chunk, each plane's sensors asked by an occlusion query (the
    ground's from the rays' landings); the transmission (H,)."""
    smp, s, rays = p.smp, p.s, p.rays
    heights = smp.heights_cm
    h32 = heights.astype(np.float32)
    leaf_top = p.leaf_top
    keep_ids = p.first_prim is not None
    up = Tracer(smp.scene, s, smp.bounds, smp.periodic, chunks[0][1])

    def chunk(a: int, b: int) -> np.ndarray:
        p.check()
        prim, z = first_hits(p.down, rays, a, b, ids=keep_ids)
        p.first_z[a:b] = z
        if p.first_prim is not None and prim is not None:
            p.first_prim[a:b] = prim
        ground = None
        counts = np.empty(len(heights), dtype=np.int64)
        for k, h in enumerate(heights):
            if h > leaf_top:
                lit = np.ones(b - a, dtype=bool)
            elif h == 0.0:
                lit = z < h32[k]             # the ground's sensors are the rays' landings
            else:
                if ground is None:
                    ground = ray_grid(smp.rect, smp.density, a, b)[0]
                org = np.empty((b - a, 3))
                org[:, :2] = ground + p.offsets[k]
                org[:, 2] = h
                lit = ~up.occluded(org, np.full(b - a, (smp.top - h) / s[2]),
                                   row=rays.shape[1])
            counts[k] = np.count_nonzero(lit)
            p.packed[k, a // 8:(b + 7) // 8] = np.packbits(lit)
        return counts

    return np.sum(in_chunks(chunk, chunks, 0), axis=0) / rays.n


def _family_pass(p: _Pass, family: _Family, chunks: list[tuple[int, int]],
                 in_chunks) -> np.ndarray:
    """The rays of the family through every plane's sensors, chunk by chunk; each sensor lit
    when its family ray's first hit lies below its plane; the transmission (H,)."""
    heights = p.smp.heights_cm
    h32 = heights.astype(np.float32)
    n = p.rays.n
    keep_ids = p.first_prim is not None
    fz = np.empty(len(family.cells), dtype=np.float32)
    fp = np.empty(len(family.cells), dtype=np.int32) if keep_ids else None
    bh = family.index.shape[1]
    whole = len(family.cells) == family.index.size     # the box without holes: a grid

    def fchunk(a: int, b: int) -> None:
        p.check()
        i, j = np.divmod(family.cells[a:b], bh)
        prim, z = lattice_first_hits(p.down, p.rays, i + family.lo[0], j + family.lo[1],
                                     ids=keep_ids, row=bh if whole else 0)
        fz[a:b] = z
        if fp is not None and prim is not None:
            fp[a:b] = prim

    in_chunks(fchunk, chunks, 0)
    g = family.index[-family.lo[0]:-family.lo[0] + family.size[0],
                     -family.lo[1]:-family.lo[1] + family.size[1]].ravel()
    p.first_z[:] = fz[g]
    if p.first_prim is not None and fp is not None:
        p.first_prim[:] = fp[g]
    transmission = np.empty(len(heights))
    for k, h in enumerate(heights):
        if h > p.leaf_top:
            lit = np.ones(n, dtype=bool)
        elif k in p.planes:
            lit = fz[_plane_rays(family, k)] < h32[k]
        else:
            lit = p.first_z < h32[k]
        transmission[k] = np.count_nonzero(lit) / n
        p.packed[k] = np.packbits(lit)
    return transmission


def trace_light(canopy: Canopy, req: LightRequest, progress: ProgressCallback | None = None,
                with_stalks: bool = False, scene: RayScene | None = None) -> LightResult:
    """Trace the sun through ``canopy``; see the module docstring.

    Parameters
    ----------
    progress : called after each chunk of rays; returning ``False`` cancels with
        :class:`InterruptedError`
    scene : the canopy's scene from :func:`~maizeviz.light.scene.embree_scenes.light_scene` (same
        ``with_stalks`` and ``periodic``), to trace several suns on one scene; built here when
        not given
    """
    rect, warnings = check_request(canopy, req)
    t0 = time.perf_counter()
    scene, said = scene_for(canopy, req.periodic, scene, with_stalks)
    warnings += said
    build_s = time.perf_counter() - t0

    s = req.sun.direction(canopy.layout.north_deg)
    smp = sampler(canopy, scene, rect, req.density, req.heights_cm, req.periodic, with_stalks)
    n = smp.n
    tr = trace_direction(smp, s, ids=req.classes, second=req.classes, threads=req.threads,
                         progress=progress)
    seconds = {"build": build_s, **tr.seconds}
    counts: tuple[np.ndarray, np.ndarray] | tuple[None, None] = (None, None)
    if tr.first_prim is not None and tr.second_prim is not None:
        counts = hit_counts(tr.first_prim, tr.second_prim, smp.n_triangles)
    return LightResult(sun=req.sun, heights_cm=smp.heights_cm, transmission=tr.transmission,
                       rays=n, rect=rect, ray_area_cm2=smp.ray_area_cm2, first_z=tr.first_z,
                       first_hits=counts[0], second_hits=counts[1], direction=s,
                       seconds=seconds, warnings=tuple(warnings), level=canopy.level,
                       density=req.density, sensor_lit=tr.sensor_lit,
                       sensor_offset_cm=tr.sensor_offset_cm, periodic=req.periodic,
                       stands=stands_identity(canopy.layout),
                       n_leaf_triangles=canopy.n_triangles)
