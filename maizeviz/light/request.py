"""What a direct-light computation is asked for, and the checks made before any ray is traced."""

from __future__ import annotations

import math
from dataclasses import dataclass

from maizeviz.canopy.scene import Canopy
from maizeviz.errors import MaizevizError, check_range
from maizeviz.light.rays import ray_count
from maizeviz.light.sun import Sun

#: More rays than this are refused (minutes of tracing and GiB of results).
MAX_RAYS = 400_000_000
#: More tracing threads than this are refused (Embree gains nothing past the cores).
MAX_THREADS = 1024
#: Bytes kept per ray for the results (first/second hit ids and heights).
BYTES_PER_RAY = 16

Rect = tuple[float, float, float, float]


@dataclass(frozen=True)
class LightRequest:
    """All inputs of one light computation.

    Attributes
    ----------
    sun : Sun
    heights_cm : (H,) heights of the sample planes, cm, >= 0
    density : rays per cm2 of the sample rectangle
    rect : (x0, y0, x1, y1) cm, or None for the central tile's footprint
    periodic : rays leaving the plot sideways re-enter on the opposite side (infinite field)
    threads : tracing threads
    classes : also trace second hits and per-triangle counts (the paper's hit classes)
    """

    sun: Sun
    heights_cm: tuple[float, ...] = (0.0, 50.0, 100.0, 150.0, 200.0, 225.0)
    density: float = 4.0
    rect: Rect | None = None
    periodic: bool = False
    threads: int = 1
    classes: bool = True


def check_request(canopy: Canopy, req: LightRequest) -> tuple[Rect, list[str]]:
    """Validate a request against a canopy; returns the sample rectangle (cm) and warnings.

    Raises
    ------
    MaizevizError
        Naming the quantity that is wrong (``exc.quantity``).
    """
    warnings = []
    if canopy.n_triangles == 0:
        raise MaizevizError("the canopy is empty: no leaf triangle to intercept light")
    if not req.heights_cm:
        raise MaizevizError("give at least one height", quantity="heights")
    for h in req.heights_cm:
        if not math.isfinite(h) or h < 0:
            raise MaizevizError(f"heights must be >= 0 cm, got {h}", quantity="heights")
    if not (math.isfinite(req.density) and req.density > 0):
        raise MaizevizError(f"the ray density must be > 0 rays per cm2, got {req.density}",
                            quantity="density")
    check_range(req.threads, "tracing threads", 1, MAX_THREADS, "threads", whole=True)
    px0, py0, px1, py1 = canopy.layout.bounds
    rect: Rect = tuple(float(v) for v in (req.rect or canopy.layout.centre_bounds))  # type: ignore[assignment]
    x0, y0, x1, y1 = rect
    if not all(math.isfinite(v) for v in rect) or x1 <= x0 or y1 <= y0:
        raise MaizevizError(f"the sample rectangle must be x0,y0,x1,y1 with x1 > x0 and y1 > y0, "
                            f"got {rect}", quantity="rect")
    if x0 < px0 - 1e-6 or y0 < py0 - 1e-6 or x1 > px1 + 1e-6 or y1 > py1 + 1e-6:
        raise MaizevizError(f"the sample rectangle {rect} cm is not inside the plot "
                            f"({px0:.0f}, {py0:.0f}, {px1:.0f}, {py1:.0f}) cm", quantity="rect")
    n = ray_count(rect, req.density)
    if n > MAX_RAYS:
        raise MaizevizError(
            f"a density of {req.density:g} rays/cm2 gives {n:,} rays "
            f"({n * BYTES_PER_RAY / 2**30:.1f} GiB of results); the limit is {MAX_RAYS:,}: lower "
            "the density or the sample rectangle", quantity="density")
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
                    "(trace a periodic field)")
    return rect, warnings
