"""Diffuse light under a sky and light over a period, as traced by
:mod:`maizeviz.light.trace.diffuse`: transmission by height and binned over each sensor plane,
the light each triangle intercepts, and (for a period) PAR doses per time step and summed."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from maizeviz.canopy.scene import Canopy
from maizeviz.light.results.maps import TransmissionMap
from maizeviz.light.results.per_leaf import LightRow, leaf_sums
from maizeviz.light.results.traced import MappedLight
from maizeviz.light.sources.irradiance import Period
from maizeviz.light.sources.perez import DiffuseSplit
from maizeviz.light.sources.sky import Sky


@dataclass(frozen=True, eq=False, kw_only=True)
class SkyLight(MappedLight):
    """Diffuse light under a sky, from :func:`~maizeviz.light.trace.diffuse.trace_sky` (with the shared fields of
    :class:`~maizeviz.light.results.traced.MappedLight`: heights_cm, rect, rays, maps, map_edges,
    map_rays, level, warnings, seconds, periodic).

    Attributes
    ----------
    sky : Sky
    transmission : (H,) float64 in [0, 1]: sum_i w_i T_i(h), the fraction of the horizontal
        diffuse irradiance reaching each sensor plane
    per_direction : (n, H) float64: T_i(h) of each sky direction
    intercepted_fraction : float: share of the rectangle's diffuse light whose first hit is a
        leaf
    per_direction_intercepted : (n,) float64: the same per direction (leaves' share of its beam)
    triangle_share : (F,) float64: share of the rectangle's diffuse light each scene triangle
        intercepts (leaf triangles first, then stalks)
    density : rays per cm2 asked for

    ``maps`` hold the diffuse transmission per bin; ``seconds`` "build", "trace" (wall
    clock), s.
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
        """(F,) float64 cm2: each triangle's share times the rectangle's area (the horizontal
        area whose diffuse light it takes)."""
        return self.triangle_share * self.rect_area_cm2

    def transmission_map(self, height: float) -> TransmissionMap:
        """Diffuse transmission binned over the sensor plane at ``height`` (a traced height)."""
        return self._map_at(height, self.transmission)

    def _height_columns(self) -> dict[str, np.ndarray]:
        return {"diffuse_transmission": self.transmission}

    def leaf_rows(self, canopy: Canopy) -> list[LightRow]:
        """Per leaf: ``diffuse_intercepted_cm2``, the horizontal area whose diffuse light the
        leaf intercepts (its share of the rectangle's sky light times the rectangle's area)."""
        return leaf_sums(canopy, {"diffuse_intercepted_cm2": self.triangle_intercepted_cm2},
                         self.rect, self.periodic)


@dataclass(frozen=True, eq=False, kw_only=True)
class PeriodLight(MappedLight):
    """Light over a period, from :func:`~maizeviz.light.trace.diffuse.trace_period`. PAR doses are mol/m2 of ground. With the
    shared fields of :class:`~maizeviz.light.results.traced.MappedLight` (heights_cm, rect, rays, maps:
    fraction of the period's PAR reaching each bin, map_edges, map_rays, level, warnings,
    seconds "build" and "trace", periodic).

    Attributes
    ----------
    period : Period (times, sun, irradiance, PAR factor)
    sky : SkyLight used for the diffuse part (None when the sun never rises)
    step_transmission : (n, H) float64: direct-sun transmission at each step
    step_intercepted_fraction : (n,) float64: leaves' share of the direct beam at each step
    triangle_direct_mol, triangle_diffuse_mol : (F,) float64 mol: PAR intercepted by each scene
        triangle over the period (leaf triangles first, then stalks)
    diffuse : DiffuseSplit or None: each step's diffuse light split by Perez's model (its
        circumsolar part traced with the sun, the rest over the uniform ``sky``); None when the
        whole diffuse part is spread over ``sky``
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
        return self.period.n_steps

    @property
    def rect_area_m2(self) -> float:
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
        """(n,) the part of each step's diffuse PAR traced with the sun (Perez's circumsolar
        part; zeros without a diffuse split)."""
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
        return math.fsum(self.step_incident_mol_m2)

    @property
    def par_direct_mol_m2(self) -> float:
        return math.fsum(self.step_direct_mol_m2)

    @property
    def par_diffuse_mol_m2(self) -> float:
        return math.fsum(self.step_diffuse_mol_m2)

    @property
    def par_intercepted_mol_m2(self) -> float:
        return math.fsum(self.step_intercepted_mol_m2)

    @property
    def par_diffuse_intercepted_mol_m2(self) -> float:
        """Diffuse PAR intercepted by the leaves over the period, mol/m2 of ground."""
        return math.fsum(self.step_diffuse_intercepted_mol_m2)

    @property
    def diffuse_transmission_by_height(self) -> np.ndarray:
        """(H,) transmitted / incident diffuse PAR over the period (the sky's transmission
        without a diffuse split; NaN when no diffuse light came)."""
        inc = self.par_diffuse_mol_m2
        if not inc > 0:
            return np.full(len(self.heights_cm), np.nan)
        return np.array([math.fsum(c) for c in self.step_diffuse_transmitted_mol_m2.T]) / inc

    @property
    def par_transmitted_mol_m2(self) -> np.ndarray:
        """(H,) PAR reaching each sensor plane over the period."""
        return np.array([math.fsum(c) for c in self.step_transmitted_mol_m2.T]) \
            if self.n_steps else np.zeros(len(self.heights_cm))

    @property
    def fraction_intercepted(self) -> float | None:
        """Intercepted / incident PAR over the period; None when no light came."""
        inc = self.par_incident_mol_m2
        return self.par_intercepted_mol_m2 / inc if inc > 0 else None

    @property
    def transmission_by_height(self) -> np.ndarray:
        """(H,) transmitted / incident PAR over the period (NaN when no light came)."""
        inc = self.par_incident_mol_m2
        return self.par_transmitted_mol_m2 / inc if inc > 0 else \
            np.full(len(self.heights_cm), np.nan)

    @property
    def triangle_mol(self) -> np.ndarray:
        """(F,) float64 mol: PAR intercepted by each scene triangle over the period."""
        return self.triangle_direct_mol + self.triangle_diffuse_mol

    def transmission_map(self, height: float) -> TransmissionMap:
        """Fraction of the period's PAR reaching each bin of the sensor plane at ``height``."""
        return self._map_at(height, self.transmission_by_height)

    def _height_columns(self) -> dict[str, np.ndarray]:
        return {"par_transmitted_mol_m2": self.par_transmitted_mol_m2,
                "transmission": self.transmission_by_height}

    def leaf_rows(self, canopy: Canopy) -> list[LightRow]:
        """Per leaf: PAR intercepted over the period in mol (``par_intercepted_mol``, its
        ``direct_`` and ``diffuse_`` parts) and per m2 of leaf (``par_mol_per_m2_leaf``)."""
        rows = leaf_sums(canopy, {"par_intercepted_mol": self.triangle_mol,
                                  "direct_par_intercepted_mol": self.triangle_direct_mol,
                                  "diffuse_par_intercepted_mol": self.triangle_diffuse_mol},
                         self.rect, self.periodic)
        for r in rows:
            r["par_mol_per_m2_leaf"] = float(r["par_intercepted_mol"]) / \
                (float(r["leaf_area_cm2"]) * 1e-4)
        return rows
