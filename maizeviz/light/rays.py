"""Ray sampling: a regular grid of parallel rays over a rectangle, followed through the canopy.

Rays lie on a regular grid of ``density`` rays per cm2 (cell centres, x slow and y fast so
neighbouring rays stay together: Embree is about twice as fast on coherent rays). The
:class:`Tracer` follows rays through an Embree scene, asking either for the first hit
(:meth:`Tracer.trace`) or only whether anything is hit (:meth:`Tracer.occluded`, Embree's
cheaper occlusion query); with a periodic field a ray that leaves the plot sideways re-enters
through the opposite side (the plot repeats forever, as Helios, Caribu and LESS do), segment by
segment, until it has gone its full length.

Sensor planes (:func:`sensor_offsets`): the sample rectangle raised to each height h carries the
same grid, slid by less than half a cell so that the sun path from a sample point at one height
passes through a sample point of every height above it. In a periodic field whose period is the
rectangle the sampled transmission then never increases downward, as in the continuum.
"""

from __future__ import annotations

import math

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.mesh.raytrace import RayScene

Rect = tuple[float, float, float, float]


#: The largest ray density, rays per cm2: a ray every micrometre (a leaf blade is a few
#: hundred thick); larger numbers only overflow the arithmetic of the grid.
MAX_DENSITY = 1e8
#: The largest coordinate of a sample rectangle, cm (100 km).
MAX_COORD_CM = 1e7


def check_density(density: float) -> float:
    """Refuse a ray density (rays per cm2) that is not a number in (0, MAX_DENSITY]."""
    ok = isinstance(density, (int, float)) and not isinstance(density, bool) and \
        0 < density <= MAX_DENSITY
    if not ok:
        raise MaizevizError(f"the ray density must be > 0 and at most {MAX_DENSITY:g} rays per "
                            f"cm2, got {density}", quantity="density")
    return float(density)


def check_rect(rect: Rect) -> Rect:
    """Refuse a sample rectangle (x0, y0, x1, y1) cm that is not four finite numbers of at
    most MAX_COORD_CM with x1 > x0 and y1 > y0; returns it as floats."""
    try:
        vals = tuple(float(v) for v in rect)
    except (TypeError, ValueError):
        vals = ()
    if len(vals) != 4 or not all(abs(v) <= MAX_COORD_CM for v in vals) \
            or vals[2] <= vals[0] or vals[3] <= vals[1]:
        raise MaizevizError(f"the sample rectangle must be x0,y0,x1,y1 with x1 > x0 and y1 > y0, "
                            f"within {MAX_COORD_CM:g} cm, got {rect}", quantity="rect")
    return vals[0], vals[1], vals[2], vals[3]


def grid_shape(rect: Rect, density: float) -> tuple[int, int]:
    """Rays across x and along y of a regular grid of ``density`` rays per cm2 over ``rect``
    (both checked: every grid is sized here)."""
    x0, y0, x1, y1 = check_rect(rect)
    step = 1.0 / math.sqrt(check_density(density))
    return max(1, int(round((x1 - x0) / step))), max(1, int(round((y1 - y0) / step)))


def ray_count(rect: Rect, density: float) -> int:
    """Number of rays of the grid over ``rect`` (cm) at ``density`` rays per cm2."""
    nx, ny = grid_shape(rect, density)
    return nx * ny


def ray_grid(rect: Rect, density: float, start: int = 0,
             stop: int | None = None) -> tuple[np.ndarray, float]:
    """Cell-centre points (N, 2) cm of a regular grid over ``rect`` and the cell area (cm2).

    Points run row-major (x slow, y fast); ``start`` and ``stop`` select a slice of them
    without building the rest.
    """
    x0, y0, x1, y1 = rect
    nx, ny = grid_shape(rect, density)
    i, j = np.divmod(np.arange(start, nx * ny if stop is None else stop), ny)
    pts = np.empty((len(i), 2))
    pts[:, 0] = x0 + (i + 0.5) * ((x1 - x0) / nx)
    pts[:, 1] = y0 + (j + 0.5) * ((y1 - y0) / ny)
    return pts, (x1 - x0) * (y1 - y0) / (nx * ny)


def sensor_offsets(heights_cm: np.ndarray, toward_sun: np.ndarray, rect: Rect,
                   density: float) -> np.ndarray:
    """Offsets (H, 2) cm of the sample grid at each height from the ground grid's cell centres.

    The sun path from a ground cell centre crosses height h at ``h * s_xy / s_z`` from it; the
    grid at h is slid by that distance modulo the cell (to within +- half a cell), so that it
    stays inside the rectangle and every path through a sample point at one height meets a
    sample point of every other height (modulo the rectangle, in a periodic field). A vertical
    sun gives zero offsets.

    Parameters
    ----------
    heights_cm : (H,) float64, cm
    toward_sun : (3,) unit vector toward the sun (z > 0)
    rect : (x0, y0, x1, y1) cm; density : rays per cm2
    """
    x0, y0, x1, y1 = rect
    nx, ny = grid_shape(rect, density)
    cell = np.array([(x1 - x0) / nx, (y1 - y0) / ny])
    h = np.asarray(heights_cm, dtype=np.float64)
    shift = h[:, None] * (np.asarray(toward_sun[:2], dtype=np.float64) / float(toward_sun[2]))
    t = shift / cell
    return (t - np.round(t)) * cell


class Tracer:
    """Follows rays along one direction through a scene, wrapping them across the plot when
    periodic.

    Parameters
    ----------
    scene : the canopy's Embree scene
    direction : (3,) unit vector the rays travel along (down toward the ground for sunlight)
    bounds : (x0, y0, x1, y1) cm, the plot
    periodic : wrap rays that leave the plot sideways
    size : largest number of rays traced at once (sizes the direction buffer)
    """

    def __init__(self, scene: RayScene, direction: np.ndarray, bounds: Rect, periodic: bool,
                 size: int):
        self.scene = scene
        self.down = np.asarray(direction, dtype=np.float64)
        self.bounds = bounds
        self.periodic = periodic
        # overhang copies of a periodic scene are reported as the triangles they copy
        self.source = getattr(scene, "source", None)
        # one writable float32 direction buffer, sliced per chunk (embreex needs writable input)
        self.dirs = np.tile(self.down.astype(np.float32), (max(size, 1), 1))

    def _exit(self, org: np.ndarray) -> np.ndarray:
        """Distance along the direction to where each ray leaves the plot's vertical prism."""
        x0, y0, x1, y1 = self.bounds
        t = np.full(len(org), np.inf)
        for k, lo, hi in ((0, x0, x1), (1, y0, y1)):
            d = self.down[k]
            if abs(d) > 1e-12:
                edge = hi if d > 0 else lo
                t = np.minimum(t, (edge - org[:, k]) / d)
        return np.maximum(t, 0.0)

    def _cross(self, org: np.ndarray) -> np.ndarray:
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

    def _wrap(self, org: np.ndarray) -> np.ndarray:
        x0, y0, x1, y1 = self.bounds
        org[:, 0] = x0 + np.mod(org[:, 0] - x0, x1 - x0)
        org[:, 1] = y0 + np.mod(org[:, 1] - y0, y1 - y0)
        return org

    def _query(self, org: np.ndarray, length: np.ndarray,
               ids: bool) -> tuple[np.ndarray | None, np.ndarray, np.ndarray]:
        dirs = self.dirs[: len(org)]
        if ids:
            prim, t = self.scene.first_hit(org, dirs, length)
            return prim, t, prim >= 0
        t = self.scene.distance(org, dirs, length)
        return None, t, t < np.asarray(length, np.float32)

    def occluded(self, org: np.ndarray, length: np.ndarray) -> np.ndarray:
        """Whether anything lies on the rays from ``org`` (N, 3) cm within ``length`` (N,) cm:
        (N,) bool. Embree's occlusion query (any hit, not the nearest), wrapped like
        :meth:`trace` in a periodic field."""
        n = len(org)
        if not self.periodic:
            return self.scene.occluded(org, self.dirs[:n], length)
        blocked = np.zeros(n, dtype=bool)
        todo = np.arange(n)
        org = self._wrap(np.asarray(org, dtype=np.float64).copy())
        remaining = np.asarray(length, dtype=np.float64).copy()
        for _ in range(10_000):
            if not len(todo):
                break
            seg = np.minimum(self._exit(org), remaining)
            hit = self.scene.occluded(org, self.dirs[: len(org)], seg)
            blocked[todo[hit]] = True
            go = ~hit & (remaining - seg > 1e-6)
            todo, org = todo[go], org[go] + seg[go, None] * self.down
            remaining = remaining[go] - seg[go]
            org = self._cross(org)
        if len(todo):  # pragma: no cover - a ray advances by at least one plot crossing a step
            raise MaizevizError(f"periodic tracing left {len(todo)} rays unfinished")
        return blocked

    def trace(self, org: np.ndarray, length: np.ndarray,
              ids: bool = True) -> tuple[np.ndarray | None, np.ndarray]:
        """First hit of rays from ``org`` (N, 3) cm within ``length`` (N,) cm.

        Returns triangle ids (N,) int32, -1 where none (None unless ``ids``), and hit distances
        (N,) float64 cm (inf where none).
        """
        prim, dist = self._trace(org, length, ids)
        if prim is not None and self.source is not None:
            hit = prim >= 0
            prim[hit] = self.source[prim[hit]]
        return prim, dist

    def _trace(self, org: np.ndarray, length: np.ndarray,
               ids: bool) -> tuple[np.ndarray | None, np.ndarray]:
        n = len(org)
        prim = np.full(n, -1, dtype=np.int32) if ids else None
        dist = np.full(n, np.inf)
        if not self.periodic:
            p, t, hit = self._query(org, length, ids)
            if prim is not None and p is not None:
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
            if prim is not None and p is not None:
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
