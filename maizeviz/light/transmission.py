"""Direct sunlight through a canopy: transmission by height (the paper's Table 3).

Parallel rays on a regular grid of ``density`` rays per cm2 cover the horizontal sample
rectangle on the ground (:class:`~maizeviz.light.hits.SunRays`). Each ray is followed from above
the canopy down toward the ground against the sun direction. Transmission at height h is the
fraction of these rays that are still unobstructed when they pass height h. The same rays serve
every height, so T = 1 above the canopy and T never increases going down; for a periodic canopy
whose period is the sample rectangle this equals the sunfleck fraction of the rectangle at
height h. The rays' first and second hits give the paper's hit classes
(:mod:`maizeviz.light.hits`).

With ``periodic`` a ray that leaves the plot sideways re-enters on the opposite side. Without
it, a warning says when the sun is low enough for rays reaching the rectangle to have crossed
the plot edge, where nothing stops them.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import cached_property
from typing import TypeVar

import numpy as np

from maizeviz.canopy.scene import Canopy
from maizeviz.light.hits import SunRays, first_hits, hit_counts, second_hits
from maizeviz.light.rays import Rect, Tracer, ray_grid
from maizeviz.light.request import LightRequest, check_request
from maizeviz.light.sun import Sun
from maizeviz.mesh.raytrace import RayScene
from maizeviz.progress import ProgressCallback, report

#: Rays traced per chunk: bounds memory and sets the progress step.
CHUNK = 1 << 18

T = TypeVar("T")


@dataclass(frozen=True)
class LightResult:
    """Output of :func:`trace_light`.

    Attributes
    ----------
    sun : Sun
    heights_cm : (H,) float64; transmission : (H,) float64 in [0, 1]
    rays : int; rect : (x0, y0, x1, y1) cm; ray_area_cm2 : horizontal footprint of a ray
    first_z : (N,) float32, height (cm) of each ray's first hit, -inf where none
    first_hits, second_hits : (F,) int64, rays whose first / second hit is each triangle
        (None unless the request asked for hit classes)
    seconds : "build" and "trace" (and "second" for second hits), s
    warnings : what the user should know about this result
    level : mesh level label; density : rays per cm2 asked for
    direction : (3,) unit vector toward the sun in field coordinates
    """

    sun: Sun
    heights_cm: np.ndarray
    transmission: np.ndarray
    rays: int
    rect: Rect
    ray_area_cm2: float
    first_z: np.ndarray
    first_hits: np.ndarray | None
    second_hits: np.ndarray | None
    direction: np.ndarray
    seconds: dict[str, float] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()
    level: str = ""
    density: float = 0.0

    @property
    def rect_area_cm2(self) -> float:
        x0, y0, x1, y1 = self.rect
        return (x1 - x0) * (y1 - y0)

    @property
    def density_per_cm2(self) -> float:
        """Rays actually traced per cm2 of the rectangle (the grid rounds the asked density)."""
        return self.rays / self.rect_area_cm2

    @property
    def sunlit_intercepted_fraction(self) -> float | None:
        """Share of the rectangle's direct sunlight whose first hit is a leaf (None without
        hit classes)."""
        if self.first_hits is None:
            return None
        return float(self.first_hits.sum() * self.ray_area_cm2 / self.rect_area_cm2)

    @cached_property
    def ground_xy(self) -> np.ndarray:
        """Where each ray meets the ground (N, 2) cm, in ray grid order."""
        return ray_grid(self.rect, self.density)[0]

    def crossings(self, height: float) -> np.ndarray:
        """Where each ray crosses the plane at ``height`` (N, 2) cm (ray grid order)."""
        return self.ground_xy + self.direction[:2] * (height / self.direction[2])


def light_scene(canopy: Canopy, with_stalks: bool = False) -> RayScene:
    """The Embree scene of a canopy's leaves (and stalks): build it once, trace many suns."""
    verts, faces = canopy.vertices, canopy.faces
    if with_stalks:
        verts = np.vstack([verts, canopy.stalk_vertices])
        faces = np.vstack([faces, canopy.stalk_faces + len(canopy.vertices)])
    return RayScene(verts, faces)


def _in_chunks(fn: Callable[[int, int], T], n: int, threads: int,
               progress: Callable[[], None]) -> list[T]:
    """``fn(a, b)`` over chunks of :data:`CHUNK` rays on ``threads`` threads, in order;
    ``progress()`` after each chunk (it may raise InterruptedError to stop)."""
    chunks = [(a, min(a + CHUNK, n)) for a in range(0, n, CHUNK)]
    out = []
    with ThreadPoolExecutor(max_workers=threads) as pool:
        futures = [pool.submit(fn, a, b) for a, b in chunks]
        try:
            for f in futures:
                out.append(f.result())
                progress()
        except BaseException:
            for f in futures:
                f.cancel()
            raise
    return out


def trace_light(canopy: Canopy, req: LightRequest, progress: ProgressCallback | None = None,
                with_stalks: bool = False, scene: RayScene | None = None) -> LightResult:
    """Trace the sun through ``canopy``; see the module docstring.

    Parameters
    ----------
    progress : called after each chunk of rays; returning ``False`` cancels with
        :class:`InterruptedError`
    scene : the canopy's scene from :func:`light_scene` (same ``with_stalks``), to trace several
        suns on one scene; built here when not given
    """
    rect, warnings = check_request(canopy, req)
    t0 = time.perf_counter()
    if scene is None:
        scene = light_scene(canopy, with_stalks)
    build_s = time.perf_counter() - t0

    t1 = time.perf_counter()
    s = req.sun.direction(canopy.layout.north_deg)
    top = float(canopy.vertices[:, 2].max()) + 1.0
    if with_stalks and len(canopy.stalk_vertices):
        top = max(top, float(canopy.stalk_vertices[:, 2].max()) + 1.0)
    rays = SunRays(rect, req.density, s, top)
    n = rays.n
    heights = np.asarray(req.heights_cm, dtype=np.float64)
    h32 = heights.astype(np.float32)
    tracer = Tracer(scene, -s, canopy.layout.bounds, req.periodic, min(n, CHUNK))
    first_z = np.empty(n, dtype=np.float32)
    first_prim = np.empty(n, dtype=np.int32) if req.classes else None
    total = -(-n // CHUNK) * (2 if req.classes else 1)
    done = 0

    def tick() -> None:
        nonlocal done
        done += 1
        report(progress, done, total, "light computation")

    def first(a: int, b: int) -> np.ndarray:
        prim, z = first_hits(tracer, rays, a, b, ids=req.classes)
        first_z[a:b] = z
        if first_prim is not None and prim is not None:
            first_prim[a:b] = prim
        # rays whose first hit lies below h have reached h unobstructed
        return np.array([np.count_nonzero(z < h) for h in h32])

    transmission = np.sum(_in_chunks(first, n, req.threads, tick), axis=0) / n
    seconds = {"build": build_s, "trace": time.perf_counter() - t1}
    counts: tuple[np.ndarray, np.ndarray] | tuple[None, None] = (None, None)
    if first_prim is not None:
        t2 = time.perf_counter()
        fp = first_prim
        seconds_prims = _in_chunks(lambda a, b: second_hits(tracer, rays, a, b, fp[a:b],
                                                            first_z[a:b]), n, req.threads, tick)
        counts = hit_counts(fp, seconds_prims, scene.n_triangles)
        seconds["second"] = time.perf_counter() - t2
    return LightResult(req.sun, heights, transmission, n, rect, rays.ray_area_cm2, first_z,
                       counts[0], counts[1], s, seconds, tuple(warnings), canopy.level,
                       req.density)
