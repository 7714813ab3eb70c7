"""Diffuse light under a sky and light over a period, as traced by
:mod:`maizeviz.light.trace.directions`: transmission by height and binned over each sensor plane,
the light each triangle intercepts, and (for a period) PAR doses per time step and summed."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.light.results.maps import TransmissionMap
from maizeviz.light.results.per_leaf import LightRow, leaf_sums
from maizeviz.light.results.traced import MappedLight
from maizeviz.light.sources.irradiance import Period
from maizeviz.light.sources.perez import DiffuseSplit
from maizeviz.light.sources.sky import Sky


@dataclass(frozen=True, eq=False, kw_only=True)
class SkyLight(MappedLight):
    """Diffuse light under a sky.

    From :func:`~maizeviz.light.trace.directions.trace_sky` (``LightEngine.sky``): every
    direction of the sky traced like the sun, weighted by its share of the horizontal
    diffuse irradiance.

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
    maps : numpy.ndarray
        (H, a, b) float64, the binned value of each plane (NaN: no sensor in the bin).
    map_edges : tuple of numpy.ndarray
        The x (a + 1,) and y (b + 1,) bin edges [cm].
    map_rays : numpy.ndarray
        (a, b) int64 sensors per bin (ground grid).
    sky : Sky
        The sky traced.
    transmission : numpy.ndarray
        (H,) float64 in [0, 1]: sum_i w_i T_i(h), the share of the horizontal diffuse
        irradiance reaching each sensor plane.
    per_direction : numpy.ndarray
        (n, H) float64: T_i(h) of each sky direction.
    intercepted_fraction : float
        Share of the rectangle's diffuse light whose first hit is a leaf [-].
    per_direction_intercepted : numpy.ndarray
        (n,) float64: the same per direction (the leaves' share of its beam).
    triangle_share : numpy.ndarray
        (F,) float64: share of the rectangle's diffuse light each scene triangle intercepts
        (leaf triangles first, then stalks).
    density : float
        Rays per cm2 asked for [cm-2].
    """

    sky: Sky
    transmission: np.ndarray
    per_direction: np.ndarray
    intercepted_fraction: float
    per_direction_intercepted: np.ndarray
    triangle_share: np.ndarray
    density: float

    @property
    def triangle_intercepted_cm2(self) -> np.ndarray:
        """Horizontal area whose diffuse light each triangle takes.

        Returns
        -------
        numpy.ndarray
            (F,) float64 [cm2]: each triangle's share times the rectangle's area.
        """
        return self.triangle_share * self.rect_area_cm2

    def transmission_map(self, height: float) -> TransmissionMap:
        """Diffuse transmission binned over one sensor plane.

        Parameters
        ----------
        height : float
            A traced height [cm].

        Returns
        -------
        TransmissionMap
            Its bins, edges [cm] and sensors per bin.
        """
        return self._map_at(height, self.transmission)

    def _height_columns(self) -> dict[str, np.ndarray]:
        return {"diffuse_transmission": self.transmission}

    def leaf_rows(self, canopy: Canopy) -> list[LightRow]:
        """Per leaf: the horizontal area whose diffuse light the leaf intercepts.

        ``diffuse_intercepted_cm2`` [cm2]: its share of the rectangle's sky light times the
        rectangle's area.

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
        return leaf_sums(canopy, {"diffuse_intercepted_cm2": self.triangle_intercepted_cm2},
                         self.rect, self.periodic)


@dataclass(frozen=True, eq=False, kw_only=True)
class PeriodLight(MappedLight):
    """Light over a period (a day), PAR doses in mol per m2 of ground.

    From :func:`~maizeviz.light.trace.directions.trace_period` (``LightEngine.day``): the sun
    traced at every time step, the sky once.

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
    maps : numpy.ndarray
        (H, a, b) float64, the binned value of each plane (NaN: no sensor in the bin).
    map_edges : tuple of numpy.ndarray
        The x (a + 1,) and y (b + 1,) bin edges [cm].
    map_rays : numpy.ndarray
        (a, b) int64 sensors per bin (ground grid).
        Here the maps hold the share of the period's PAR reaching each bin.
    period : Period
        Its times, sun, irradiance and PAR factor.
    sky : SkyLight or None
        The sky light of the diffuse part (None when the sun never rises).
    step_transmission : numpy.ndarray
        (n, H) float64: the direct sun's transmission at each step.
    step_intercepted_fraction : numpy.ndarray
        (n,) float64: the leaves' share of the direct beam at each step.
    triangle_direct_mol, triangle_diffuse_mol : numpy.ndarray
        (F,) float64 PAR intercepted by each scene triangle over the period [mol] (leaf
        triangles first, then stalks).
    diffuse : DiffuseSplit or None
        Each step's diffuse light split by Perez's model (its circumsolar part traced with
        the sun, the rest over the uniform ``sky``); None when the whole diffuse part is
        spread over ``sky``.
    """

    period: Period
    sky: SkyLight | None
    step_transmission: np.ndarray
    step_intercepted_fraction: np.ndarray
    triangle_direct_mol: np.ndarray
    triangle_diffuse_mol: np.ndarray
    diffuse: DiffuseSplit | None = None

    @property
    def n_steps(self) -> int:
        """Time steps with the sun up.

        Returns
        -------
        int
            The period's steps.
        """
        return self.period.n_steps

    @property
    def rect_area_m2(self) -> float:
        """Area of the sample rectangle.

        Returns
        -------
        float
            [m2].
        """
        return self.rect_area_cm2 * 1e-4

    # ---- per step, mol/m2 of ground
    @cached_property
    def step_direct_mol_m2(self) -> np.ndarray:
        """(n,) direct PAR incident at each step."""
        return np.asarray(self.period.step_direct_par_mol_m2, dtype=np.float64)

    @cached_property
    def step_diffuse_mol_m2(self) -> np.ndarray:
        """(n,) diffuse PAR incident at each step."""
        return np.asarray(self.period.step_diffuse_par_mol_m2, dtype=np.float64)

    @cached_property
    def step_circumsolar_mol_m2(self) -> np.ndarray:
        """The part of each step's diffuse PAR traced with the sun.

        Returns
        -------
        numpy.ndarray
            (n,) float64 [mol m-2]: Perez's circumsolar part; zeros without a diffuse split.
        """
        if self.diffuse is None:
            return np.zeros(self.n_steps)
        return self.step_diffuse_mol_m2 * self.diffuse.circumsolar_share

    @cached_property
    def step_sky_mol_m2(self) -> np.ndarray:
        """(n,) the part of each step's diffuse PAR spread over the sky's directions."""
        return self.step_diffuse_mol_m2 - self.step_circumsolar_mol_m2

    @cached_property
    def step_incident_mol_m2(self) -> np.ndarray:
        """(n,) PAR incident at each step (direct + diffuse)."""
        return self.step_direct_mol_m2 + self.step_diffuse_mol_m2

    @cached_property
    def step_diffuse_intercepted_mol_m2(self) -> np.ndarray:
        """(n,) diffuse PAR intercepted by the leaves at each step."""
        fd = self.sky.intercepted_fraction if self.sky is not None else 0.0
        return (self.step_circumsolar_mol_m2 * self.step_intercepted_fraction
                + self.step_sky_mol_m2 * fd)

    @cached_property
    def step_intercepted_mol_m2(self) -> np.ndarray:
        """(n,) PAR intercepted by the leaves at each step."""
        return (self.step_direct_mol_m2 * self.step_intercepted_fraction
                + self.step_diffuse_intercepted_mol_m2)

    @cached_property
    def step_diffuse_transmitted_mol_m2(self) -> np.ndarray:
        """(n, H) diffuse PAR reaching each sensor plane at each step."""
        td = self.sky.transmission if self.sky is not None else np.zeros(len(self.heights_cm))
        return (self.step_circumsolar_mol_m2[:, None] * self.step_transmission
                + self.step_sky_mol_m2[:, None] * td[None, :])

    @cached_property
    def step_transmitted_mol_m2(self) -> np.ndarray:
        """(n, H) PAR reaching each sensor plane at each step."""
        return (self.step_direct_mol_m2[:, None] * self.step_transmission
                + self.step_diffuse_transmitted_mol_m2)

    @cached_property
    def step_fraction_intercepted(self) -> np.ndarray:
        """(n,) share of each step's incident PAR intercepted by the leaves (NaN without light)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.step_incident_mol_m2 > 0,
                            self.step_intercepted_mol_m2 / self.step_incident_mol_m2, np.nan)

    # ---- the period: sums of the steps
    @property
    def par_incident_mol_m2(self) -> float:
        """PAR incident over the period.

        Returns
        -------
        float
            [mol m-2 of ground], the exactly rounded sum of the steps.
        """
        return math.fsum(self.step_incident_mol_m2)

    @property
    def par_direct_mol_m2(self) -> float:
        """Direct PAR incident over the period.

        Returns
        -------
        float
            [mol m-2 of ground].
        """
        return math.fsum(self.step_direct_mol_m2)

    @property
    def par_diffuse_mol_m2(self) -> float:
        """Diffuse PAR incident over the period.

        Returns
        -------
        float
            [mol m-2 of ground].
        """
        return math.fsum(self.step_diffuse_mol_m2)

    @property
    def par_intercepted_mol_m2(self) -> float:
        """PAR intercepted by the leaves over the period.

        Returns
        -------
        float
            [mol m-2 of ground].
        """
        return math.fsum(self.step_intercepted_mol_m2)

    @property
    def par_diffuse_intercepted_mol_m2(self) -> float:
        """Diffuse PAR intercepted by the leaves over the period.

        Returns
        -------
        float
            [mol m-2 of ground].
        """
        return math.fsum(self.step_diffuse_intercepted_mol_m2)

    @property
    def diffuse_transmission_by_height(self) -> np.ndarray:
        """Transmitted over incident diffuse PAR over the period, per height.

        Returns
        -------
        numpy.ndarray
            (H,) float64 [-]: the sky's transmission without a diffuse split; NaN when no
            diffuse light came.
        """
        inc = self.par_diffuse_mol_m2
        if not inc > 0:
            return np.full(len(self.heights_cm), np.nan)
        return np.array([math.fsum(c) for c in self.step_diffuse_transmitted_mol_m2.T]) / inc

    @property
    def par_transmitted_mol_m2(self) -> np.ndarray:
        """PAR reaching each sensor plane over the period.

        Returns
        -------
        numpy.ndarray
            (H,) float64 [mol m-2].
        """
        return np.array([math.fsum(c) for c in self.step_transmitted_mol_m2.T]) \
            if self.n_steps else np.zeros(len(self.heights_cm))

    @property
    def fraction_intercepted(self) -> float | None:
        """Intercepted over incident PAR over the period.

        Returns
        -------
        float or None
            [-]; None when no light came.
        """
        inc = self.par_incident_mol_m2
        return self.par_intercepted_mol_m2 / inc if inc > 0 else None

    @property
    def transmission_by_height(self) -> np.ndarray:
        """Transmitted over incident PAR over the period, per height.

        Returns
        -------
        numpy.ndarray
            (H,) float64 [-]; NaN when no light came.
        """
        inc = self.par_incident_mol_m2
        return self.par_transmitted_mol_m2 / inc if inc > 0 else \
            np.full(len(self.heights_cm), np.nan)

    @property
    def triangle_mol(self) -> np.ndarray:
        """PAR intercepted by each scene triangle over the period.

        Returns
        -------
        numpy.ndarray
            (F,) float64 [mol]: direct plus diffuse.
        """
        return self.triangle_direct_mol + self.triangle_diffuse_mol

    def transmission_map(self, height: float) -> TransmissionMap:
        """The share of the period's PAR reaching each bin of one sensor plane.

        Parameters
        ----------
        height : float
            A traced height [cm].

        Returns
        -------
        TransmissionMap
            Its bins, edges [cm] and sensors per bin.
        """
        return self._map_at(height, self.transmission_by_height)

    def _height_columns(self) -> dict[str, np.ndarray]:
        return {"par_transmitted_mol_m2": self.par_transmitted_mol_m2,
                "transmission": self.transmission_by_height}

    def leaf_rows(self, canopy: Canopy) -> list[LightRow]:
        """Per leaf: PAR intercepted over the period.

        ``par_intercepted_mol`` [mol] with its ``direct_`` and ``diffuse_`` parts, and
        ``par_mol_per_m2_leaf`` [mol m-2 of leaf].

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
        rows = leaf_sums(canopy, {"par_intercepted_mol": self.triangle_mol,
                                  "direct_par_intercepted_mol": self.triangle_direct_mol,
                                  "diffuse_par_intercepted_mol": self.triangle_diffuse_mol},
                         self.rect, self.periodic)
        for r in rows:
            r["par_mol_per_m2_leaf"] = float(r["par_intercepted_mol"]) / \
                (float(r["leaf_area_cm2"]) * 1e-4)
        return rows
