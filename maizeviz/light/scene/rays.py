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
    (both checked: every grid is sized here).

    Raises
    ------
    MaizevizError
        The density puts less than half a ray step across a side of the rectangle: the grid
        would be one ray there whatever density was asked (``--density 1e-308`` gave a single
        ray for the whole plot, unsaid).
    """
    x0, y0, x1, y1 = check_rect(rect)
    step = 1.0 / math.sqrt(check_density(density))
    nx, ny = int(round((x1 - x0) / step)), int(round((y1 - y0) / step))
    if nx < 1 or ny < 1:
        side = min(x1 - x0, y1 - y0)
        raise MaizevizError(f"a density of {density:g} rays per cm2 (a ray every {step:.3g} cm) "
                            f"puts no ray across the sample rectangle's {side:g} cm side; the "
                            f"lowest density for it is {1.0 / (2.0 * side) ** 2:.3g} rays per "
                            "cm2", quantity="density")
    return nx, ny


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
    periodic (:func:`maizeviz.light.scene.periodic.trace_wrapped`).

    Parameters
    ----------
    scene : the canopy's Embree scene; a scene built for a periodic field carries its
        ``wrap`` (the cell it repeats: the plot, or one block of a tiled canopy) and
        ``resolve`` (scene triangle and cell -> canopy triangle ids)
    direction : (3,) unit vector the rays travel along (down toward the ground for sunlight)
    bounds : (x0, y0, x1, y1) cm, the plot (the cell repeated when the scene has no ``wrap``)
    periodic : wrap rays that leave the plot sideways
    size : largest number of rays traced at once (kept for callers; unused)
    """

    def __init__(self, scene: RayScene, direction: np.ndarray, bounds: Rect, periodic: bool,
                 size: int = 0):
        from maizeviz.light.scene.periodic import Wrap

        self.scene = scene
        self.down = np.asarray(direction, dtype=np.float64)
        self.bounds = bounds
        self.periodic = periodic
        self.wrap = (getattr(scene, "wrap", None) or Wrap.of(bounds)) if periodic else None
        # overhang copies (and the blocks of a tiled field) are reported as canopy triangles
        self.resolve = getattr(scene, "resolve", None)
        self.dirs = self.down.astype(np.float32)[None, :]

    def occluded(self, org: np.ndarray, length: np.ndarray, row: int = 0) -> np.ndarray:
        """Whether anything lies on the rays from ``org`` (N, 3) cm within ``length`` (N,) cm:
        (N,) bool. Embree's occlusion query (any hit, not the nearest), wrapped like
        :meth:`trace` in a periodic field. ``row``: rays per row of a grid laid out row by row
        (coherent packets), else 0."""
        from maizeviz.light.scene.periodic import trace_wrapped

        if self.wrap is None:
            return self.scene.occluded(org, self.dirs, length, row=row)
        return trace_wrapped(self.scene, self.wrap, org, self.down, length, any_hit=True,
                             row=row)

    def trace(self, org: np.ndarray, length: np.ndarray, ids: bool = True,
              row: int = 0) -> tuple[np.ndarray | None, np.ndarray]:
        """First hit of rays from ``org`` (N, 3) cm within ``length`` (N,) cm.

        Returns triangle ids (N,) int32, -1 where none (None unless ``ids``), and hit distances
        (N,) float64 cm (inf where none). ``row`` as :meth:`occluded`.
        """
        from maizeviz.light.scene.periodic import trace_wrapped

        length = np.asarray(length)
        if self.wrap is None:
            if ids:
                prim, t = self.scene.first_hit(org, self.dirs, length, row=row)
                hit = prim >= 0
            else:
                prim, t = None, self.scene.distance(org, self.dirs, length, row=row)
                hit = t < np.asarray(length, np.float32)
            cell = None
            out = np.where(hit, t, np.inf)
        else:         # distances are inf and triangles -1 where nothing is hit
            prim, cell, out = trace_wrapped(self.scene, self.wrap, org, self.down, length,
                                            ids=ids, row=row)
            hit = np.isfinite(out)
        if prim is not None:
            prim = np.where(hit, prim, -1).astype(np.int32, copy=False)
            if self.resolve is not None:
                at = np.flatnonzero(hit)
                if len(at):
                    prim[at] = self.resolve(prim[at], None if cell is None else cell[at])
        return prim, out
