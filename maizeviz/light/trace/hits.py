"""The paper's hit classes: a sun ray's first leaf hit receives direct light, its second hit
second-class light, the rest none.

The rays form a :class:`SunRays` bundle: a regular grid over the sample rectangle on the
ground, each ray started on a plane above the canopy and followed down toward the ground
against the sun direction.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from maizeviz.light.scene.rays import Rect, Tracer, grid_shape, ray_grid

#: Distance (cm) past a first hit where the second-hit ray starts (Embree starts at t = 0).
SECOND_HIT_EPS = 0.01


@dataclass(frozen=True)
class SunRays:
    """Parallel rays toward the ground rectangle.

    Attributes
    ----------
    rect : (x0, y0, x1, y1) cm, the sample rectangle on the ground
    density : rays per cm2 of it
    sun : (3,) unit vector toward the sun, field coordinates
    top : height (cm) of the plane the rays start from, above every triangle
    """

    rect: Rect
    density: float
    sun: np.ndarray
    top: float

    @cached_property
    def shape(self) -> tuple[int, int]:
        return grid_shape(self.rect, self.density)

    @property
    def n(self) -> int:
        return self.shape[0] * self.shape[1]

    @property
    def ray_area_cm2(self) -> float:
        """Horizontal footprint of one ray on the ground (cm2)."""
        x0, y0, x1, y1 = self.rect
        return (x1 - x0) * (y1 - y0) / self.n

    @property
    def reach(self) -> float:
        """Distance (cm) along a ray from the top plane to the ground."""
        return self.top / float(self.sun[2])


def first_hits(tracer: Tracer, rays: SunRays, a: int, b: int,
               ids: bool) -> tuple[np.ndarray | None, np.ndarray]:
    """First hits of rays a..b (grid order: x slow, y fast): triangle ids (b - a,) int32, -1
    where none (None unless ``ids``), and the height (cm) of each hit (b - a,) float32, -inf
    where none. The rays of the rectangle's own lattice cells (:func:`lattice_first_hits`):
    every path that traces ground rays starts them at the same points."""
    i, j = np.divmod(np.arange(a, b), rays.shape[1])
    return lattice_first_hits(tracer, rays, i, j, ids, row=rays.shape[1])


def lattice_first_hits(tracer: Tracer, rays: SunRays, i: np.ndarray, j: np.ndarray,
                       ids: bool, row: int = 0) -> tuple[np.ndarray | None, np.ndarray]:
    """First hits of the rays of the same family landing on lattice cells (i, j) of the ground
    grid extended beyond the rectangle (i across x, j along y; any integers): ids (k,) int32
    (None unless ``ids``) and heights (k,) float32 cm, -inf where none. ``row``: cells per
    row when (i, j) run row by row over a whole box of the lattice (coherent packets), else 0."""
    nx, ny = rays.shape
    x0, y0, x1, y1 = rays.rect
    org = np.empty((len(i), 3))
    org[:, 0] = x0 + (i + 0.5) * ((x1 - x0) / nx) + rays.sun[0] * rays.reach
    org[:, 1] = y0 + (j + 0.5) * ((y1 - y0) / ny) + rays.sun[1] * rays.reach
    org[:, 2] = rays.top
    prim, dist = tracer.trace(org, np.full(len(i), rays.reach, np.float32), ids=ids, row=row)
    return prim, (rays.top - dist * rays.sun[2]).astype(np.float32)


def second_hits(tracer: Tracer, rays: SunRays, a: int, b: int, first_prim: np.ndarray,
                first_z: np.ndarray) -> np.ndarray:
    """Triangle ids of the second hits of rays a..b, given their first hits (ids (b - a,) and
    heights (b - a,) cm): only the rays that have one."""
    sel = np.flatnonzero(first_prim >= 0)
    zf = first_z[sel].astype(np.float64)
    s = rays.sun
    dist_first = (rays.top - zf) / s[2]
    left = rays.reach - dist_first - SECOND_HIT_EPS
    org = np.empty((len(sel), 3))
    org[:, :2] = ray_grid(rays.rect, rays.density, a, b)[0][sel] + left[:, None] * s[:2]
    org[:, 2] = zf - SECOND_HIT_EPS * s[2]
    prim, _ = tracer.trace(org, np.maximum(left, 0.0))
    assert prim is not None
    return prim[prim >= 0]


def hit_counts(first_prim: np.ndarray, second: list[np.ndarray],
               n_faces: int) -> tuple[np.ndarray, np.ndarray]:
    """Rays whose first / second hit is each triangle: two (F,) int64 arrays."""
    first = np.bincount(first_prim[first_prim >= 0], minlength=n_faces).astype(np.int64)
    seconds = np.concatenate(second) if second else np.empty(0, np.int32)
    return first, np.bincount(seconds, minlength=n_faces).astype(np.int64)
