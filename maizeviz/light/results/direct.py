"""A sun's direct light through a canopy, as traced by
:func:`~maizeviz.light.trace.beam.trace_light`: transmission on the sensor planes, where each
ground ray first met a leaf, and the hit classes per triangle."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.light.results.per_leaf import LightRow, leaf_light, triangle_light
from maizeviz.light.results.traced import TracedLight
from maizeviz.light.scene.rays import ray_grid
from maizeviz.light.sources.sun import Sun


@dataclass(frozen=True, kw_only=True)
class LightResult(TracedLight):
    """A sun's direct light through a canopy.

    From :func:`~maizeviz.light.trace.beam.trace_light` (``LightEngine.sun``):
    transmission on the sensor planes, where each ground ray first met a leaf, and the hit
    classes per triangle.

    Parameters
    ----------
    canopy : Canopy or None
        The canopy it was traced on (keyword-only; the engine's results hold it): tables per
        leaf and plant use it.
    heights_cm : numpy.ndarray
        (H,) float64 heights of the sensor planes [cm].
    rect : (x0, y0, x1, y1) tuple of float
        The sample rectangle [cm].
    rays : int
        Rays per direction (and sensors per plane).
    level : str
        Mesh level label of the canopy.
    warnings : tuple of str
        What the user should know about this result.
    seconds : dict of str to float
        Time spent [s]: "build" (the scene, when this call built it), "trace", ...
    periodic : bool
        Rays and sensor paths wrapped across the plot.
    stands : dict or None
        ``{"n", "sha256"}``, the identity of the stands of the canopy it was traced on
        (:func:`maizeviz.canopy.layout.stands_identity`); None where not known.
    sun : Sun
        The sun traced.
    transmission : numpy.ndarray
        (H,) float64 in [0, 1]: the share of each sensor plane's sensors that see the sun.
    ray_area_cm2 : float
        Horizontal footprint of a ray (and of a sensor) [cm2].
    first_z : numpy.ndarray
        (N,) float32 height of each ground ray's first hit [cm], -inf where none.
    first_hits, second_hits : numpy.ndarray or None
        (F,) int64 rays whose first and second hit is each triangle (None unless the request
        asked for hit classes).
    direction : numpy.ndarray
        (3,) unit vector toward the sun in field coordinates.
    density : float
        Rays per cm2 asked for [cm-2].
    sensor_lit : numpy.ndarray or None
        (H, ceil(N / 8)) uint8: the sensors of each plane whose path to the sun is clear,
        bits packed in ray grid order (:meth:`lit`); None for results made elsewhere.
    sensor_offset_cm : numpy.ndarray or None
        (H, 2) float64, where each plane's grid sits relative to the ground grid's cell
        centres [cm] (:meth:`sensor_xy`).
    n_leaf_triangles : int or None
        The canopy's leaf triangles: ids from this one on in ``first_hits`` and
        ``second_hits`` are stalks; None: every triangle is a leaf.
    triangle_sunlit_cm2 : numpy.ndarray or None
        (F,) float64 [cm2]: the sunlit area of each triangle (leaves, then stalks if traced),
        sampled from the triangle toward the sun, in [0, its area] and unbiased
        (``LightEngine.sun`` with hit classes); the leaf tables' ``sunlit_area_cm2``. None:
        the tables read the rays' count, capped at each leaf's area.

    See Also
    --------
    maizeviz.light.engine.LightEngine.sun : What makes it.
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
    n_leaf_triangles: int | None = None
    triangle_sunlit_cm2: np.ndarray | None = None

    @property
    def density_per_cm2(self) -> float:
        """Rays actually traced per cm2 of the rectangle (the grid rounds the asked density)."""
        return self.rays / self.rect_area_cm2

    @property
    def sunlit_intercepted_fraction(self) -> float | None:
        """Share of the rectangle's direct sunlight whose first hit is a leaf.

        Returns
        -------
        float or None
            In [0, 1]; None without hit classes.
        """
        if self.first_hits is None:
            return None
        leaves = self.first_hits[:self.n_leaf_triangles]
        return float(leaves.sum() * self.ray_area_cm2 / self.rect_area_cm2)

    @property
    def stalk_intercepted_fraction(self) -> float | None:
        """Share of the rectangle's direct sunlight whose first hit is a stalk.

        Returns
        -------
        float or None
            In [0, 1] (0 where stalks were not traced); None without hit classes.
        """
        if self.first_hits is None:
            return None
        if self.n_leaf_triangles is None:
            return 0.0
        stalks = self.first_hits[self.n_leaf_triangles:]
        return float(stalks.sum() * self.ray_area_cm2 / self.rect_area_cm2)

    @cached_property
    def ground_xy(self) -> np.ndarray:
        """Where each ray meets the ground (N, 2) cm, in ray grid order."""
        return ray_grid(self.rect, self.density)[0]

    def sensor_xy(self, k: int) -> np.ndarray:
        """Sensor positions of one sensor plane.

        Parameters
        ----------
        k : int
            Index of the plane among ``heights_cm``.

        Returns
        -------
        numpy.ndarray
            (N, 2) float64 [cm], in ray grid order.
        """
        off = np.zeros(2) if self.sensor_offset_cm is None else self.sensor_offset_cm[k]
        return self.ground_xy + off

    def lit(self, k: int) -> np.ndarray:
        """The sensors of one plane that see the sun.

        Parameters
        ----------
        k : int
            Index of the plane among ``heights_cm``.

        Returns
        -------
        numpy.ndarray
            (N,) bool, in ray grid order.

        Raises
        ------
        MaizevizError
            The result carries no sensor planes.
        """
        if self.sensor_lit is None:
            from maizeviz.errors import MaizevizError

            raise MaizevizError("this result carries no sensor planes")
        return np.unpackbits(self.sensor_lit[k], count=self.rays).astype(bool)

    def _height_columns(self) -> dict[str, np.ndarray]:
        return {"transmission": self.transmission}

    def leaf_rows(self, canopy: Canopy) -> list[LightRow]:
        """Per leaf that received rays: sunlit and second-class areas and intercepted light.

        Areas [cm2] of leaf lit and intercepted footprints [cm2]
        (:func:`~maizeviz.light.results.per_leaf.leaf_light`).

        Parameters
        ----------
        canopy : Canopy
            The canopy the light was traced on.

        Returns
        -------
        list of dict
            One row per leaf that received light: ``instance``, ``plant``, ``leaf``, ``x_cm``,
            ``y_cm``, ``leaf_area_cm2`` and the light (copies of a plant in a tile-periodic field
            reported as one); ``table("leaf", canopy)`` as dicts.
        """
        return leaf_light(canopy, self.first_hits, self.second_hits, self.direction,
                          self.ray_area_cm2, self.rect, self.periodic,
                          self.triangle_sunlit_cm2)

    def triangle_light(self, canopy: Canopy) -> np.ndarray:
        """Light class of every leaf triangle, for colouring the canopy.

        Parameters
        ----------
        canopy : Canopy
            The canopy the light was traced on.

        Returns
        -------
        numpy.ndarray
            (F,) int8: 2 direct, 1 second class only, 0 none, -1 not reached by any traced ray
            (:func:`~maizeviz.light.results.per_leaf.triangle_light`).
        """
        return triangle_light(canopy, self.first_hits, self.second_hits, self.direction,
                              self.rect, self.periodic)
