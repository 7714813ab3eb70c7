"""Direct sunlight through a canopy: transmission by height, first and second hits (Table 3).

Parallel rays on a regular grid of ``density`` rays per cm2 cover the horizontal sample
rectangle on the ground. Each ray is followed from above the canopy down toward the ground
against the sun direction; its first leaf hit receives direct light, its second hit
second-class light (the paper's classes). Transmission at height h is the fraction of these rays
that are still unobstructed when they pass height h. The same rays serve every height, so T = 1
above the canopy and T never increases going down; for a periodic canopy whose period is the
sample rectangle this equals the sunfleck fraction of the rectangle at height h.

With ``periodic`` a ray that leaves the plot sideways re-enters on the opposite side (the plot
repeats forever, as Helios, Caribu and LESS do). Without it, a warning says when the sun is low
enough for rays reaching the rectangle to have crossed the plot edge, where nothing stops them.
"""

from __future__ import annotations

import math
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from maizeviz.canopy.scene import Canopy
from maizeviz.errors import MaizevizError
from maizeviz.light.raytrace import RayScene
from maizeviz.light.sun import Sun
from maizeviz.mesh.tessellate import triangle_areas_normals

#: Rays traced per chunk: bounds memory and sets the progress step.
CHUNK = 1 << 18
#: More rays than this are refused (minutes of tracing and GiB of results).
MAX_RAYS = 400_000_000
#: Bytes kept per ray for the results (first/second hit ids and heights).
BYTES_PER_RAY = 16
#: Distance (cm) past a first hit where the second-hit ray starts (Embree starts at t = 0).
SECOND_HIT_EPS = 0.01


@dataclass(frozen=True)
class LightRequest:
    """All inputs of one light computation.

    Attributes
    ----------
    sun : Sun
    heights_cm : tuple of float, >= 0
    density : float, rays per cm2 of the sample rectangle
    rect : (x0, y0, x1, y1) cm, or None for the central tile's footprint
    periodic : bool
    threads : int
    classes : bool
        Also trace second hits and per-triangle counts (the paper's hit classes).
    """

    sun: Sun
    heights_cm: tuple = (0.0, 50.0, 100.0, 150.0, 200.0, 225.0)
    density: float = 4.0
    rect: tuple | None = None
    periodic: bool = False
    threads: int = 1
    classes: bool = True


@dataclass(frozen=True)
class LightResult:
    """Output of :func:`trace_light`.

    Attributes
    ----------
    heights_cm : (H,) float64; transmission : (H,) float64 in [0, 1]
    rays : int; rect : (x0, y0, x1, y1) cm; ray_area_cm2 : float, horizontal footprint of a ray
    first_z : (N,) float32, height (cm) of each ray's first hit, -inf where none
    first_hits, second_hits : (F,) int64, rays whose first / second hit is each triangle
    seconds : dict, "build" and "trace" (and "second" for second hits)
    warnings : tuple of str
    """

    sun: Sun
    heights_cm: np.ndarray
    transmission: np.ndarray
    rays: int
    rect: tuple
    ray_area_cm2: float
    first_z: np.ndarray
    first_hits: np.ndarray | None
    second_hits: np.ndarray | None
    seconds: dict = field(default_factory=dict)
    warnings: tuple = ()
    level: str = ""
    density: float = 0.0
    direction: np.ndarray | None = None

    @cached_property
    def ground_xy(self) -> np.ndarray:
        """Where each ray meets the ground (N, 2) cm, in ray grid order."""
        return ray_grid(self.rect, self.density)[0]

    def crossings(self, height: float) -> np.ndarray:
        """Where each ray crosses the plane at ``height`` (N, 2) cm (ray grid order)."""
        return self.ground_xy + self.direction[:2] * (height / self.direction[2])


def _grid_shape(rect, density: float) -> tuple[int, int]:
    x0, y0, x1, y1 = rect
    step = 1.0 / math.sqrt(density)
    return max(1, int(round((x1 - x0) / step))), max(1, int(round((y1 - y0) / step)))


def ray_grid(rect, density: float, start: int = 0, stop: int | None = None):
    """Cell-centre points (N, 2) cm of a regular grid over ``rect`` and the cell area (cm2).

    Points run row-major (x slow, y fast) so that neighbouring rays stay together; ``start``
    and ``stop`` select a slice of them without building the rest.
    """
    x0, y0, x1, y1 = rect
    nx, ny = _grid_shape(rect, density)
    i, j = np.divmod(np.arange(start, nx * ny if stop is None else stop), ny)
    pts = np.empty((len(i), 2))
    pts[:, 0] = x0 + (i + 0.5) * ((x1 - x0) / nx)
    pts[:, 1] = y0 + (j + 0.5) * ((y1 - y0) / ny)
    return pts, (x1 - x0) * (y1 - y0) / (nx * ny)


def check_request(canopy: Canopy, req: LightRequest) -> tuple[tuple, list[str]]:
    """Validate a request against a canopy; returns the rectangle and warnings."""
    warnings = []
    if canopy.n_triangles == 0:
        raise MaizevizError("the canopy is empty: no leaf triangle to intercept light")
    if not req.heights_cm:
        raise MaizevizError("give at least one height")
    for h in req.heights_cm:
        if not math.isfinite(h) or h < 0:
            raise MaizevizError(f"heights must be >= 0 cm, got {h}")
    if not (math.isfinite(req.density) and req.density > 0):
        raise MaizevizError(f"--density must be > 0 rays per cm2, got {req.density}")
    if req.threads < 1:
        raise MaizevizError(f"--threads must be >= 1, got {req.threads}")
    px0, py0, px1, py1 = canopy.layout.bounds
    rect = tuple(float(v) for v in (req.rect or canopy.layout.centre_bounds))
    x0, y0, x1, y1 = rect
    if not all(math.isfinite(v) for v in rect) or x1 <= x0 or y1 <= y0:
        raise MaizevizError(f"--rect must be x0,y0,x1,y1 with x1 > x0 and y1 > y0, got {rect}")
    if x0 < px0 - 1e-6 or y0 < py0 - 1e-6 or x1 > px1 + 1e-6 or y1 > py1 + 1e-6:
        raise MaizevizError(f"the sample rectangle {rect} cm is not inside the plot "
                            f"({px0:.0f}, {py0:.0f}, {px1:.0f}, {py1:.0f}) cm")
    n = ray_count(rect, req.density)
    if n > MAX_RAYS:
        raise MaizevizError(
            f"density {req.density:g} rays/cm2 gives {n:,} rays ({n * BYTES_PER_RAY / 2**30:.1f} "
            f"GiB of results); the limit is {MAX_RAYS:,}: lower --density or --rect")
    top = float(canopy.vertices[:, 2].max())
    for h in req.heights_cm:
        if h > top:
            warnings.append(f"height {h:g} cm is above the canopy top ({top:.0f} cm): T = 1 there")
            break
    if not req.periodic:
        reach = top * math.tan(math.radians(req.sun.zenith_deg))
        d = req.sun.direction(canopy.layout.north_deg)
        hx, hy = d[0], d[1]
        hn = math.hypot(hx, hy)
        if hn > 0:
            sx, sy = reach * hx / hn, reach * hy / hn
            fits = (px0 <= x0 + min(sx, 0) and x1 + max(sx, 0) <= px1 and
                    py0 <= y0 + min(sy, 0) and y1 + max(sy, 0) <= py1)
            if not fits:
                warnings.append(
                    f"sun zenith {req.sun.zenith_deg:.1f} deg: rays reaching the sample rectangle "
                    f"cross the canopy up to {reach:.0f} cm from it toward the sun, beyond the "
                    "plot edge where nothing stops them; transmission is overestimated "
                    "(use --periodic)")
    return rect, warnings


def ray_count(rect, density) -> int:
    nx, ny = _grid_shape(rect, density)
    return nx * ny


class _Tracer:
    """Follows rays down through the scene, wrapping them across the plot when periodic."""

    def __init__(self, scene: RayScene, down: np.ndarray, bounds, periodic: bool, size: int):
        self.scene = scene
        self.down = down.astype(np.float64)
        self.bounds = bounds
        self.periodic = periodic
        # one writable float32 direction buffer, sliced per chunk (embreex needs writable input)
        self.dirs = np.tile(down.astype(np.float32), (max(size, 1), 1))

    def _exit(self, org):
        """Distance along ``down`` to where each ray leaves the plot's vertical prism."""
        x0, y0, x1, y1 = self.bounds
        t = np.full(len(org), np.inf)
        for k, lo, hi in ((0, x0, x1), (1, y0, y1)):
            d = self.down[k]
            if abs(d) > 1e-12:
                edge = hi if d > 0 else lo
                t = np.minimum(t, (edge - org[:, k]) / d)
        return np.maximum(t, 0.0)

    def _cross(self, org):
        """Rays that reached a plot edge re-enter through the opposite one."""
        x0, y0, x1, y1 = self.bounds
        for k, lo, hi in ((0, x0, x1), (1, y0, y1)):
            d = self.down[k]
            tol = 1e-7 * (hi - lo)
            if d > 0:
                org[org[:, k] >= hi - tol, k] -= hi - lo
            elif d < 0:
                org[org[:, k] <= lo + tol, k] += hi - lo
        return org

    def _wrap(self, org):
        x0, y0, x1, y1 = self.bounds
        org[:, 0] = x0 + np.mod(org[:, 0] - x0, x1 - x0)
        org[:, 1] = y0 + np.mod(org[:, 1] - y0, y1 - y0)
        return org

    def _query(self, org, length, ids):
        dirs = self.dirs[: len(org)]
        if ids:
            prim, t = self.scene.first_hit(org, dirs, length)
            return prim, t, prim >= 0
        t = self.scene.distance(org, dirs, length)
        return None, t, t < np.asarray(length, np.float32)

    def trace(self, org: np.ndarray, length: np.ndarray, ids: bool = True):
        """First hit of rays from ``org`` (N, 3) along ``down`` within ``length`` (N,) cm.

        Returns triangle ids (N,) int32, -1 where none (None unless ``ids``), hit distances
        (N,) float64 (inf where none).
        """
        n = len(org)
        prim = np.full(n, -1, dtype=np.int32) if ids else None
        dist = np.full(n, np.inf)
        if not self.periodic:
            p, t, hit = self._query(org, length, ids)
            if ids:
                prim[hit] = p[hit]
            dist[hit] = t[hit]
            return prim, dist
        todo = np.arange(n)
        org = self._wrap(org.astype(np.float64))
        done = np.zeros(n)
        remaining = length.astype(np.float64).copy()
        for _ in range(10_000):
            if not len(todo):
                break
            seg = np.minimum(self._exit(org), remaining)
            p, t, hit = self._query(org, seg, ids)
            hit &= t <= seg
            if ids:
                prim[todo[hit]] = p[hit]
            dist[todo[hit]] = done[hit] + t[hit]
            go = ~hit & (remaining - seg > 1e-6)
            todo, org = todo[go], org[go] + seg[go, None] * self.down
            done = done[go] + seg[go]
            remaining = remaining[go] - seg[go]
            org = self._cross(org)
        if len(todo):  # pragma: no cover - a ray advances by at least one plot crossing a step
            raise MaizevizError(f"periodic tracing left {len(todo)} rays unfinished")
        return prim, dist


def trace_light(canopy: Canopy, req: LightRequest, progress=None,
                with_stalks: bool = False) -> LightResult:
    """Trace the sun through ``canopy``; see the module docstring.

    ``progress(done, total)`` is called after each chunk of rays; returning ``False`` cancels
    with :class:`InterruptedError`.
    """
    rect, warnings = check_request(canopy, req)
    t0 = time.perf_counter()
    verts, faces = canopy.vertices, canopy.faces
    if with_stalks:
        verts = np.vstack([verts, canopy.stalk_vertices])
        faces = np.vstack([faces, canopy.stalk_faces + len(canopy.vertices)])
    scene = RayScene(verts, faces)
    build_s = time.perf_counter() - t0

    t1 = time.perf_counter()                             # tracing: ray grid to T(h)
    s = req.sun.direction(canopy.layout.north_deg)
    down = -s
    nx, ny = _grid_shape(rect, req.density)
    n = nx * ny
    ray_area = (rect[2] - rect[0]) * (rect[3] - rect[1]) / n
    heights = np.asarray(req.heights_cm, dtype=np.float64)
    h32 = heights.astype(np.float32)
    top = float(verts[:, 2].max()) + 1.0
    reach = top / s[2]                                   # distance from the top plane to ground
    tracer = _Tracer(scene, down, canopy.layout.bounds, req.periodic, min(n, CHUNK))
    first_z = np.empty(n, dtype=np.float32)
    first_prim = np.empty(n, dtype=np.int32) if req.classes else None
    chunks = [(a, min(a + CHUNK, n)) for a in range(0, n, CHUNK)]
    total = len(chunks) * (2 if req.classes else 1)
    done = 0

    # ray origins on the top plane, built per chunk by slicing (x slow, y fast, as ray_grid)
    dx, dy = (rect[2] - rect[0]) / nx, (rect[3] - rect[1]) / ny
    xs_top = (rect[0] + (np.arange(nx) + 0.5) * dx + s[0] * reach).astype(np.float32)
    ys_top = np.tile((rect[1] + (np.arange(ny) + 0.5) * dy + s[1] * reach).astype(np.float32),
                     min(n, CHUNK) // ny + 2)

    def first(a, b):
        org = np.empty((b - a, 3), dtype=np.float32)
        i0, j0 = divmod(a, ny)
        i1 = (b - 1) // ny + 1
        org[:, 0] = np.repeat(xs_top[i0:i1], ny)[j0:j0 + b - a]
        org[:, 1] = ys_top[j0:j0 + b - a]
        org[:, 2] = top
        prim, dist = tracer.trace(org, np.full(b - a, reach, np.float32), ids=req.classes)
        z = first_z[a:b]
        z[:] = top - dist * s[2]                             # -inf where nothing was hit
        if first_prim is not None:
            first_prim[a:b] = prim
        # rays whose first hit lies below h have reached h unobstructed
        return np.array([np.count_nonzero(z < h) for h in h32])

    def second(a, b):
        sel = np.flatnonzero(first_prim[a:b] >= 0)
        zf = first_z[a:b][sel].astype(np.float64)
        org = np.empty((len(sel), 3))
        dist_first = (top - zf) / s[2]
        org[:, :2] = ray_grid(rect, req.density, a, b)[0][sel] + (reach - dist_first - SECOND_HIT_EPS)[:, None] * s[:2]
        org[:, 2] = zf - SECOND_HIT_EPS * s[2]
        prim, _ = tracer.trace(org, np.maximum(reach - dist_first - SECOND_HIT_EPS, 0.0))
        return prim[prim >= 0]

    def run(fn):
        nonlocal done
        out = []
        with ThreadPoolExecutor(max_workers=req.threads) as pool:
            futures = [pool.submit(fn, a, b) for a, b in chunks]
            try:
                for f in futures:
                    out.append(f.result())
                    done += 1
                    if progress is not None and progress(done, total) is False:
                        raise InterruptedError("light computation cancelled")
            except BaseException:
                for f in futures:
                    f.cancel()
                raise
        return out

    transmission = np.sum(run(first), axis=0) / n
    trace_s = time.perf_counter() - t1
    seconds = {"build": build_s, "trace": trace_s}
    first_hits = second_hits = None
    if req.classes:
        t2 = time.perf_counter()
        seconds_prims = run(second)
        nf = len(faces)
        first_hits = np.bincount(first_prim[first_prim >= 0], minlength=nf).astype(np.int64)
        second_hits = np.bincount(np.concatenate(seconds_prims) if seconds_prims else
                                  np.empty(0, np.int32), minlength=nf).astype(np.int64)
        seconds["second"] = time.perf_counter() - t2
    return LightResult(req.sun, heights, transmission, n, rect, ray_area, first_z, first_hits,
                       second_hits, seconds, tuple(warnings), canopy.level, req.density, s)


def leaf_light(canopy: Canopy, result: LightResult) -> list[dict]:
    """Per leaf of the canopy that received rays: sunlit and second-class areas (cm2).

    ``*_intercepted_cm2`` is the rays' horizontal footprint (ray count x cell area: the share of
    the sample rectangle's sunlight the leaf takes); ``*_area_cm2`` is the leaf surface lit,
    count x footprint x cos(zenith) / |n . s| summed over the leaf's triangles, capped at the
    leaf's area (one ray on a grazing triangle stands for more than the triangle).
    """
    if result.first_hits is None:
        raise MaizevizError("hit classes were not traced")
    nf = canopy.n_triangles
    area, normals = triangle_areas_normals(canopy.vertices, canopy.faces)
    s = result.sun.direction(canopy.layout.north_deg)
    cosz = s[2]
    cos_inc = np.abs(normals @ s)
    beam = result.ray_area_cm2 * cosz
    rows = []
    keys = canopy.face_instance.astype(np.int64) * 10_000 + canopy.face_leaf
    first = result.first_hits[:nf]
    second = result.second_hits[:nf]
    # a grazing triangle can collect a ray "worth" more than its area; cap by leaf below
    lit1 = first * beam / np.maximum(cos_inc, 1e-6)
    lit2 = second * beam / np.maximum(cos_inc, 1e-6)
    touched = np.unique(keys[(first > 0) | (second > 0)])
    order = np.argsort(keys, kind="stable")
    sk = keys[order]
    for key in touched:
        a, b = np.searchsorted(sk, key, "left"), np.searchsorted(sk, key, "right")
        idx = order[a:b]
        inst = int(key // 10_000)
        leaf_area = float(area[idx].sum())
        rows.append({"instance": inst + 1, "plant": int(canopy.face_plant[idx[0]]),
                     "leaf": int(key % 10_000), "x_cm": canopy.layout.placements[inst].x,
                     "y_cm": canopy.layout.placements[inst].y,
                     "leaf_area_cm2": leaf_area,
                     "sunlit_area_cm2": min(float(lit1[idx].sum()), leaf_area),
                     "second_class_area_cm2": min(float(lit2[idx].sum()), leaf_area),
                     "sunlit_intercepted_cm2": float(first[idx].sum() * result.ray_area_cm2),
                     "second_class_intercepted_cm2": float(second[idx].sum() * result.ray_area_cm2)})
    return rows


def plant_light(rows: list[dict]) -> list[dict]:
    """:func:`leaf_light` rows summed per plant standing in the canopy (one row per placement)."""
    sums = ("sunlit_area_cm2", "second_class_area_cm2", "sunlit_intercepted_cm2",
            "second_class_intercepted_cm2")
    per: dict[int, dict] = {}
    for r in rows:
        d = per.setdefault(r["instance"], {
            "instance": r["instance"], "plant": r["plant"], "x_cm": r["x_cm"], "y_cm": r["y_cm"],
            **({"level": r["level"]} if "level" in r else {}), "leaves_lit": 0,
            **{k: 0.0 for k in sums}})
        d["leaves_lit"] += 1
        for k in sums:
            d[k] += r[k]
    return list(per.values())


def beer_lambert(canopy: Canopy, sun: Sun, heights_cm) -> tuple[np.ndarray, float, np.ndarray]:
    """Beer-Lambert check exp(-G L(h) / cos(theta)) with G and L(h) taken from the mesh.

    G = sum A |n . s| / sum A over all leaf triangles; L(h) = leaf area above h (by triangle
    centroid) per ground area of the plot.

    Returns T (H,), G, L (H,).
    """
    area, normals = triangle_areas_normals(canopy.vertices, canopy.faces)
    s = sun.direction(canopy.layout.north_deg)
    g = float((area * np.abs(normals @ s)).sum() / area.sum())
    cz = canopy.vertices[canopy.faces].mean(axis=1)[:, 2]
    order = np.argsort(cz)
    cum_above = area[order][::-1].cumsum()[::-1]
    zs = cz[order]
    h = np.asarray(heights_cm, dtype=np.float64)
    idx = np.searchsorted(zs, h, side="right")
    above = np.where(idx < len(zs), cum_above[np.minimum(idx, len(zs) - 1)], 0.0)
    lai = above / canopy.layout.ground_area_cm2
    return np.exp(-g * lai / s[2]), g, lai
