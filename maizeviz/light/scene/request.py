"""What a light computation is asked for, and the checks made before any ray is traced.

:class:`LightRequest` is one sun; :class:`Sampling` is the part every direction shares (heights,
density, rectangle, periodic field, threads), used for skies and periods, where the directions
come from the sky and the sun track.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.errors import MaizevizError, check_range
from maizeviz.light.scene.rays import Rect, check_density, check_rect, ray_count
from maizeviz.light.sources.sun import Sun

#: Highest sensor plane, cm (100 m: far above any crop; float32 tracing stays exact).
MAX_HEIGHT_CM = 10_000.0
#: Most sensor planes in one computation.
MAX_HEIGHTS = 1_000
#: More rays than this are refused (minutes of tracing and GiB of results).
MAX_RAYS = 400_000_000
#: More tracing threads than this are refused (Embree gains nothing past the cores).
MAX_THREADS = 1024
#: Bytes kept per ray for the results (first/second hit ids and heights), plus one bit per
#: ray and sensor plane.
BYTES_PER_RAY = 16



@dataclass(frozen=True)
class Sampling:
    """Where and how densely light is sampled, for any number of directions.

    Parameters
    ----------
    heights_cm : tuple of float
        Heights of the sensor planes [cm], each >= 0.
    density : float
        Rays (and sensors) per cm2 of the sample rectangle [cm-2].
    rect : (x0, y0, x1, y1) tuple of float, optional
        The sample rectangle [cm]; None: the central tile's footprint.
    periodic : bool
        Rays leaving the plot sideways re-enter on the opposite side (an infinite field).
    threads : int
        Tracing threads.
    """

    heights_cm: tuple[float, ...] = (0.0, 50.0, 100.0, 150.0, 200.0, 225.0)
    density: float = 4.0
    rect: Rect | None = None
    periodic: bool = False
    threads: int = 1


@dataclass(frozen=True)
class LightRequest:
    """All inputs of one light computation: one sun, sampled as ``sampling`` says.

    Attributes
    ----------
    sun : Sun
    sampling : Sampling (heights, density, rectangle, periodic field, threads); its fields
        read through the request too (``req.heights_cm``, ``req.density``, ...)
    classes : also trace second hits and per-triangle counts (the paper's hit classes)
    """

    sun: Sun
    sampling: Sampling = Sampling()
    classes: bool = True

    @property
    def heights_cm(self) -> tuple[float, ...]:
        return self.sampling.heights_cm

    @property
    def density(self) -> float:
        return self.sampling.density

    @property
    def rect(self) -> Rect | None:
        return self.sampling.rect

    @property
    def periodic(self) -> bool:
        return self.sampling.periodic

    @property
    def threads(self) -> int:
        return self.sampling.threads


def canopy_top(canopy: Canopy, with_stalks: bool = False) -> float:
    """Height (cm) of the highest triangle of the canopy (and of its stalks)."""
    top = float(canopy.vertices[:, 2].max())
    if with_stalks and len(canopy.stalk_vertices):
        top = max(top, float(canopy.stalk_vertices[:, 2].max()))
    return top


def edge_reach(canopy: Canopy, rect: Rect, zenith_deg: float, toward_sun: np.ndarray,
               top: float) -> float | None:
    """How far (cm) toward the sun rays reaching ``rect`` cross the canopy, when that is beyond
    the plot edge (where nothing stops them); None when they stay inside the plot.

    Parameters
    ----------
    rect : (x0, y0, x1, y1) cm; zenith_deg : deg; toward_sun : (3,) unit vector, field
        coordinates; top : cm, height of the canopy top
    """
    px0, py0, px1, py1 = canopy.layout.bounds
    x0, y0, x1, y1 = rect
    reach = top * math.tan(math.radians(zenith_deg))
    hx, hy = float(toward_sun[0]), float(toward_sun[1])
    hn = math.hypot(hx, hy)
    if hn == 0:
        return None
    sx, sy = reach * hx / hn, reach * hy / hn
    fits = (px0 <= x0 + min(sx, 0) and x1 + max(sx, 0) <= px1 and
            py0 <= y0 + min(sy, 0) and y1 + max(sy, 0) <= py1)
    return None if fits else reach


def check_request(canopy: Canopy, req: LightRequest) -> tuple[Rect, list[str]]:
    """Validate a request against a canopy; returns the sample rectangle (cm) and warnings.

    Raises
    ------
    MaizevizError
        Naming the quantity that is wrong (``exc.quantity``).
    """
    rect, warnings = check_sampling(canopy, req.sampling)
    if not req.periodic:
        reach = edge_reach(canopy, rect, req.sun.zenith_deg,
                           req.sun.direction(canopy.layout.north_deg), canopy_top(canopy))
        if reach is not None:
            warnings.append(
                f"sun zenith {req.sun.zenith_deg:.1f} deg: rays reaching the sample rectangle "
                f"cross the canopy up to {reach:.0f} cm from it toward the sun, beyond the "
                "plot edge where nothing stops them; transmission is overestimated "
                "(trace a periodic field)")
    return rect, warnings


def check_heights(heights_cm) -> None:
    """Refuse sensor heights (cm) that are none, more than :data:`MAX_HEIGHTS`, outside 0 to
    :data:`MAX_HEIGHT_CM` or given twice, naming the first such."""
    if not heights_cm:
        raise MaizevizError("give at least one height", quantity="heights")
    if len(heights_cm) > MAX_HEIGHTS:
        raise MaizevizError(f"{len(heights_cm):,} heights; at most {MAX_HEIGHTS:,} sensor "
                            "planes are traced (one every cm over 10 m)", quantity="heights")
    seen: dict[float, int] = {}
    for k, h in enumerate(heights_cm):
        if not math.isfinite(h) or not 0 <= h <= MAX_HEIGHT_CM:
            raise MaizevizError(f"heights must be from 0 to {MAX_HEIGHT_CM:,.0f} cm, got {h:g}",
                                quantity="heights")
        if h in seen:
            raise MaizevizError(f"height {h + 0.0:g} cm is given twice (heights {seen[h] + 1} and "
                                f"{k + 1})", quantity="heights")
        seen[h] = k


def check_rect_in_plot(rect: Rect, plot: Rect) -> Rect:
    """The sample rectangle (x0, y0, x1, y1) cm checked (:func:`check_rect`) and refused when
    it reaches beyond the ``plot``."""
    px0, py0, px1, py1 = plot
    rect = check_rect(rect)
    x0, y0, x1, y1 = rect
    if x0 < px0 - 1e-6 or y0 < py0 - 1e-6 or x1 > px1 + 1e-6 or y1 > py1 + 1e-6:
        raise MaizevizError(f"the sample rectangle {rect} cm is not inside the plot "
                            f"({px0:.0f}, {py0:.0f}, {px1:.0f}, {py1:.0f}) cm", quantity="rect")
    return rect


def check_sampling(canopy: Canopy, req: Sampling) -> tuple[Rect, list[str]]:
    """Validate the sun-independent part of a request; returns the sample rectangle (cm) and
    warnings (heights above the canopy).

    Raises
    ------
    MaizevizError
        Naming the quantity that is wrong (``exc.quantity``).
    """
    warnings = []
    if canopy.n_triangles == 0:
        raise MaizevizError("the canopy is empty: no leaf triangle to intercept light")
    check_heights(req.heights_cm)
    check_density(req.density)
    check_range(req.threads, "tracing threads", 1, MAX_THREADS, "threads", whole=True)
    rect = check_rect_in_plot(req.rect or canopy.layout.centre_bounds, canopy.layout.bounds)
    x0, y0, x1, y1 = rect
    n = ray_count(rect, req.density)
    if n > MAX_RAYS:
        raise MaizevizError(
            f"a density of {req.density:g} rays/cm2 gives {n:,} rays "
            f"({n * (BYTES_PER_RAY + len(req.heights_cm) / 8) / 2**30:.1f} GiB of results); the "
            f"limit is {MAX_RAYS:,}: lower "
            "the density or the sample rectangle", quantity="density")
    top = float(canopy.vertices[:, 2].max())
    for h in req.heights_cm:
        if h > top:
            warnings.append(f"height {h:g} cm is above the canopy top ({top:.0f} cm): T = 1 there")
            break
    return rect, warnings
