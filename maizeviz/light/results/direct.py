"""A sun's direct light through a canopy, as traced by
:func:`~maizeviz.light.trace.direct.trace_light`: transmission on the sensor planes, where each
ground ray first met a leaf, and the hit classes per triangle."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from maizeviz.canopy.scene import Canopy
from maizeviz.light.results.per_leaf import LightRow, leaf_light, triangle_light
from maizeviz.light.results.traced import TracedLight
from maizeviz.light.scene.rays import ray_grid
from maizeviz.light.sources.sun import Sun


@dataclass(frozen=True, kw_only=True)
class LightResult(TracedLight):
    """Output of :func:`~maizeviz.light.trace.direct.trace_light` (and the shared fields of
    :class:`~maizeviz.light.results.traced.TracedLight`: heights_cm, rect, rays, level, warnings,
    seconds, periodic).

    Attributes
    ----------
    sun : Sun
    transmission : (H,) float64 in [0, 1], on the sensor planes at ``heights_cm`` (H,) cm
    ray_area_cm2 : horizontal footprint of a ray (and of a sensor)
    first_z : (N,) float32, height (cm) of each ground ray's first hit, -inf where none
    first_hits, second_hits : (F,) int64, rays whose first / second hit is each triangle
        (None unless the request asked for hit classes)
    direction : (3,) unit vector toward the sun in field coordinates
    density : rays per cm2 asked for
    sensor_lit : (H, ceil(N / 8)) uint8, the sensors of each plane whose path to the sun is
        clear, bits packed in ray grid order (:meth:`lit`); None for results made elsewhere
    sensor_offset_cm : (H, 2) float64 cm, where each plane's grid sits relative to the ground
        grid's cell centres (:meth:`sensor_xy`)

    ``seconds`` has "build" and "trace" (and "second" for second hits), s.
    """

    sun: Sun
    transmission: np.ndarray
    ray_area_cm2: float
    first_z: np.ndarray
    first_hits: np.ndarray | None
    second_hits: np.ndarray | None
    direction: np.ndarray
    density: float = 0.0
    sensor_lit: np.ndarray | None = None
    sensor_offset_cm: np.ndarray | None = None

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

    def sensor_xy(self, k: int) -> np.ndarray:
        """Sensor positions (N, 2) cm of the plane of height index ``k``, in ray grid order."""
        off = np.zeros(2) if self.sensor_offset_cm is None else self.sensor_offset_cm[k]
        return self.ground_xy + off

    def lit(self, k: int) -> np.ndarray:
        """(N,) bool: the sensors of the plane of height index ``k`` that see the sun."""
        if self.sensor_lit is None:
            from maizeviz.errors import MaizevizError

            raise MaizevizError("this result carries no sensor planes")
        return np.unpackbits(self.sensor_lit[k], count=self.rays).astype(bool)

    def _height_columns(self) -> dict[str, np.ndarray]:
        return {"transmission": self.transmission}

    def leaf_rows(self, canopy: Canopy) -> list[LightRow]:
        """Per leaf that received rays: sunlit and second-class areas and intercepted light
        (cm2; :func:`~maizeviz.light.results.per_leaf.leaf_light`)."""
        return leaf_light(canopy, self.first_hits, self.second_hits, self.direction,
                          self.ray_area_cm2, self.rect, self.periodic)

    def triangle_light(self, canopy: Canopy) -> np.ndarray:
        """Light class of every leaf triangle (F,) int8: 2 direct, 1 second class only, 0 none,
        -1 not reached by any traced ray
        (:func:`~maizeviz.light.results.per_leaf.triangle_light`)."""
        return triangle_light(canopy, self.first_hits, self.second_hits, self.direction,
                              self.rect, self.periodic)
