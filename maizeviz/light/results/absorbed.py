"""Light absorbed by the leaves and the ground, with scattering, as traced by
:mod:`maizeviz.light.trace.absorption`: the energy balance (:class:`Balance`), the power or
energy each triangle absorbed, and tables per leaf and per plant.

Units: W and W/m2 of sample ground for one instant (:class:`AbsorbedLight`), J and MJ/m2 over a
period (:class:`AbsorbedPeriod`); PAR also in photons, 4.57 umol per J of PAR
(:data:`maizeviz.light.sources.irradiance.PAR_UMOL_PER_J_PAR`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Self

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.light.results.on_triangles import TriangleResult
from maizeviz.light.results.per_leaf import LightRow, leaf_sums
from maizeviz.light.results.traced import TableBy, table_kind
from maizeviz.light.results.uncertainty import Batches, errors_by

if TYPE_CHECKING:
    import pandas as pd

    from maizeviz.light.results.assimilation import PeriodAssimilation
    from maizeviz.light.sources.irradiance import Period
    from maizeviz.light.trace.optics import Optics  # with the tracing that uses them


#: Share of the incident light left unresolved (still travelling when scattering stopped)
#: above which a result says so.
UNRESOLVED_WARN = 0.01


def unresolved_warning(share: float, depth: int) -> str:
    """The warning for a result that left ``share`` of its light unresolved."""
    return (f"{share:.1%} of the incident light was still travelling after {depth} "
            "scatterings and is not in the absorbed figures: raise the depth")


@dataclass(frozen=True)
class Balance:
    """Where the incident light went, W/m2 of sample ground (or, for a period, MJ/m2 or mol/m2
    as the result says).

    incident = absorbed_leaves + absorbed_stalks + absorbed_ground + reflected_top
    + escaped_sides + unresolved, within Monte Carlo noise (``closure_fraction``, a fraction
    of the incident light). The stalks absorb where they were traced
    (``LightEngine(..., with_stalks=True)``, the default), else 0.
    """

    incident: float
    absorbed_leaves: float
    absorbed_ground: float
    reflected_top: float
    escaped_sides: float = 0.0
    unresolved: float = 0.0
    absorbed_stalks: float = 0.0

    @property
    def closure_fraction(self) -> float:
        """How far the parts miss the incident light, as a fraction of it.

        Returns
        -------
        float
            (sum of the parts) / incident - 1 [-]: 0 up to Monte Carlo noise (0 without
            incident light). Not in the balance's units: a fraction of the incident.
        """
        parts = (self.absorbed_leaves + self.absorbed_stalks + self.absorbed_ground
                 + self.reflected_top + self.escaped_sides + self.unresolved)
        return parts / self.incident - 1.0 if self.incident else 0.0

    @property
    def closure(self) -> float:
        """The same as :attr:`closure_fraction` (its name in maizeviz 0.2), a fraction of the
        incident light [-]."""
        return self.closure_fraction

    def as_dict(self) -> dict[str, float]:
        """The balance as the command line's JSON carries it.

        Returns
        -------
        dict
            The parts in the balance's units, and ``closure_fraction``, a fraction of the
            incident light [-].
        """
        return {"incident": self.incident, "absorbed_leaves": self.absorbed_leaves,
                "absorbed_stalks": self.absorbed_stalks,
                "absorbed_ground": self.absorbed_ground, "reflected_top": self.reflected_top,
                "escaped_sides": self.escaped_sides, "unresolved": self.unresolved,
                "closure_fraction": self.closure_fraction}


def _leaves_error(result: AbsorbedLight | AbsorbedPeriod) -> float | None:
    """The standard error of the leaves' absorbed light in the balance's units: the batches'
    error of the triangles' total, scaled as the balance scales that total."""
    total = result.triangle_total
    if result.batches is None or total <= 0:
        return None if result.batches is None else 0.0
    return float(result.triangle_total_error or 0.0) * result.balance.absorbed_leaves / total


def _fraction_absorbed(self) -> float:
    """Share of the incident light the leaves absorb."""
    b = self.balance
    return b.absorbed_leaves / b.incident if b.incident else 0.0


def _per_plant(frame, sums: tuple[str, ...]):
    """Leaf rows (a DataFrame of :func:`maizeviz.light.results.per_leaf.leaf_sums` rows) summed per
    plant standing in the canopy: its digitized plant, place, leaves, leaf area and ``sums``."""
    return frame.groupby("instance", as_index=False).agg(
        plant=("plant", "first"), x_cm=("x_cm", "first"), y_cm=("y_cm", "first"),
        leaves=("leaf", "size"), leaf_area_cm2=("leaf_area_cm2", "sum"),
        **{name: (name, "sum") for name in sums})


@dataclass(frozen=True)
class AbsorbedLight(TriangleResult):
    """Light absorbed by the leaves (and the ground) in one band, with scattering.

    From :meth:`maizeviz.light.engine.LightEngine.absorbed`.

    Parameters
    ----------
    band : {"par", "nir"}
        The waveband.
    optics : Optics
        The leaf and soil optics traced.
    irradiance_w_m2 : float
        The band's irradiance on a horizontal plane above the canopy (direct plus diffuse as
        traced) [W m-2].
    balance : Balance
        Where the light went [W m-2 of sample ground].
    triangle_absorbed_w : numpy.ndarray
        (F,) float64 power absorbed by each scene triangle (leaves, then stalks) from the
        light falling on the sample rectangle [W].
    triangle_sunlit_cm2 : numpy.ndarray
        (F,) float64 area of each triangle in the direct beam [cm2] (0 for a sky), sampled
        from the triangle (:mod:`maizeviz.light.trace.sunlit`): at most its area.
    rect : (x0, y0, x1, y1) tuple of float
        The sample rectangle [cm].
    rays : int
        Primary rays per direction.
    directions : int
        Beams traced.
    depth : int
        Most scatterings followed per ray.
    threshold : float
        Share of the incident power still travelling where tracing stopped [-].
    seed : int
        Seed of the Monte Carlo scattering.
    events : int
        Scatterings followed.
    periodic : bool
        Rays wrapped across the plot.
    level : str
        Mesh level label of the canopy.
    seconds : dict of str to float
        Time spent [s]: "trace" (primary beams), "scatter", "build".
    triangle_direct_w : numpy.ndarray or None
        (F,) float64 the part of ``triangle_absorbed_w`` the sun's direct beam deposited [W]
        (its sunlit area at the beam's absorbed flux on its orientation: at most what its
        whole area would absorb; the rest came from the sky and scattered light).
    batches : Batches or None
        The per-batch shares of independent batches of rays, the standard errors' source.
    sun_direction : (3,) tuple of float or None
        Unit vector toward the sun traced, field coordinates (None without a sun).
    stands : dict or None
        ``{"n", "sha256"}``, the identity of the stands of the canopy it was traced on.
    canopy : Canopy or None
        The canopy it was traced on (keyword-only; :class:`TriangleResult`): tables per leaf
        and plant use it.

    References
    ----------
    Bailey, B. N. (2018). A reverse ray-tracing method for modelling the net radiative flux
    in leaf-resolving plant canopy simulations. Ecological Modelling 368, 233-245.
    https://doi.org/10.1016/j.ecolmodel.2017.11.022
    """

    band: str
    optics: Optics
    irradiance_w_m2: float
    balance: Balance
    triangle_absorbed_w: np.ndarray
    triangle_sunlit_cm2: np.ndarray
    rect: tuple[float, float, float, float]
    rays: int
    directions: int
    depth: int
    threshold: float
    seed: int
    events: int
    periodic: bool
    level: str = ""
    seconds: dict[str, float] = field(default_factory=dict)
    triangle_direct_w: np.ndarray | None = None
    batches: Batches | None = None
    sun_direction: tuple[float, float, float] | None = None
    stands: dict | None = None

    fraction_absorbed = property(_fraction_absorbed)

    def _triangle_values(self) -> np.ndarray:
        return self.triangle_absorbed_w

    def _triangle_batches(self) -> Any:
        return None if self.batches is None else self.batches.absorbed

    @property
    def absorbed_leaves_error(self) -> float | None:
        """Monte Carlo standard error of ``balance.absorbed_leaves``, from batches of rays.

        Returns
        -------
        float or None
            [W m-2 of ground]; None when the result was not traced in batches.
        """
        return _leaves_error(self)

    @property
    def balance_errors(self) -> dict[str, float] | None:
        """Monte Carlo standard errors of the energy balance's parts, in its units.

        Returns
        -------
        dict of str to float or None
            ``absorbed_leaves``, ``absorbed_ground``, ``reflected_top``, ``escaped_sides``,
            ``unresolved``; None without batches.
        """
        if self.batches is None or self.batches.parts is None:
            return None
        return {"absorbed_leaves": float(self.absorbed_leaves_error or 0.0),
                **(self.batches.balance_errors(1.0) or {})}

    def table(self, by: TableBy | None = None, canopy: Canopy | None = None) -> pd.DataFrame:
        """Absorbed light as a table: the energy balance, or per leaf or per plant.

        Parameters
        ----------
        by : {None, "balance", "leaf", "plant"}
            None (the default) or "balance": the energy balance [W m-2 of ground] as one
            row. "leaf" or "plant": ``absorbed_w`` [W], ``absorbed_w_m2_leaf`` [W m-2 of
            one-sided leaf area], ``sunlit_area_cm2`` and ``shaded_area_cm2`` [cm2] (leaf area
            in and out of the direct beam), and for PAR ``absorbed_umol_s`` [umol s-1]
            (4.57 umol per J of PAR).
        canopy : Canopy, optional
            The canopy the light was traced on (default: the result's own, ``canopy``);
            needed by leaf and plant.

        Returns
        -------
        pandas.DataFrame
            One row, or one per lit leaf or plant.

        Raises
        ------
        MaizevizError
            Another ``by``, or a leaf or plant table without the canopy.
        """
        import pandas as pd

        canopy = self._on(canopy)
        kind = table_kind(by, "balance", canopy)
        if kind == "balance":
            return pd.DataFrame([{"band": self.band, **self.balance.as_dict()}])
        assert canopy is not None
        from maizeviz.light.sources.irradiance import PAR_UMOL_PER_J_PAR

        rows = leaf_sums(canopy, {"absorbed_w": self.triangle_absorbed_w,
                                  "sunlit_area_cm2": self.triangle_sunlit_cm2},
                         self.rect, self.periodic)
        frame = pd.DataFrame(rows)
        if frame.empty:
            return frame
        if kind == "plant":
            frame = _per_plant(frame, ("absorbed_w", "sunlit_area_cm2"))
        if self.batches is not None:
            se = errors_by(canopy, self.batches.absorbed, "absorbed_w", self.rect,
                           self.periodic, kind)
            keys = frame["instance"] if kind == "plant" else zip(frame["instance"], frame["leaf"])
            frame["absorbed_w_se"] = [se.get(k, 0.0) for k in keys]
        frame["shaded_area_cm2"] = frame["leaf_area_cm2"] - frame["sunlit_area_cm2"]
        frame["absorbed_w_m2_leaf"] = frame["absorbed_w"] / (frame["leaf_area_cm2"] * 1e-4)
        if self.band == "par":
            frame["absorbed_umol_s"] = frame["absorbed_w"] * PAR_UMOL_PER_J_PAR
        return frame

    def leaf_rows(self, canopy: Canopy) -> list[LightRow]:
        """Per lit leaf: the power it absorbed.

        ``absorbed_w`` [W], ``absorbed_w_m2_leaf`` [W m-2 of leaf] and
        ``absorbed_sunlit_area_cm2`` [cm2], as the light tables of the command line.

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
        rows = leaf_sums(canopy, {"absorbed_w": self.triangle_absorbed_w,
                                  "absorbed_sunlit_area_cm2": self.triangle_sunlit_cm2},
                         self.rect, self.periodic)
        se = {} if self.batches is None else errors_by(
            canopy, self.batches.absorbed, "absorbed_w", self.rect, self.periodic, "leaf")
        for r in rows:
            r["absorbed_w_m2_leaf"] = float(r["absorbed_w"]) / (float(r["leaf_area_cm2"]) * 1e-4)
            if self.batches is not None:
                r["absorbed_w_se"] = se.get((r["instance"], r["leaf"]), 0.0)
        return rows


@dataclass(frozen=True)
class AbsorbedPeriod(TriangleResult):
    """Light absorbed by the leaves (and the ground) in one band over a period, with scattering.

    From :meth:`maizeviz.light.engine.LightEngine.absorbed_day`: each time step's sun traced
    with its direct irradiance, the diffuse part traced once per unit of diffuse irradiance
    and scaled by each step's (it is linear).

    Parameters
    ----------
    band : {"par", "nir"}
        The waveband.
    optics : Optics
        The leaf and soil optics traced.
    period : Period
        Its steps, sun and irradiance (:mod:`maizeviz.light.sources.irradiance`).
    balance : Balance
        Where the light went over the period [MJ m-2 of sample ground].
    triangle_absorbed_j : numpy.ndarray
        (F,) float64 energy absorbed by each scene triangle over the period [J].
    step_absorbed_leaves_w_m2 : numpy.ndarray
        (n,) float64 what the leaves absorb at each step [W m-2 of ground].
    step_incident_w_m2 : numpy.ndarray
        (n,) float64 the band's irradiance on a horizontal plane at each step [W m-2].
    rect : (x0, y0, x1, y1) tuple of float
        The sample rectangle [cm].
    rays : int
        Primary rays per direction.
    depth : int
        Most scatterings followed per ray.
    seed : int
        Seed of the Monte Carlo scattering.
    periodic : bool
        Rays wrapped across the plot.
    level : str
        Mesh level label of the canopy.
    seconds : dict of str to float
        Time spent [s]: "trace", "scatter", "build".
    batches : Batches or None
        The per-batch shares of independent batches of rays, the standard errors' source.
    assimilation : PeriodAssimilation or None
        The leaves' gross CO2 assimilation over the period, when a leaf model was asked for.
    stands : dict or None
        ``{"n", "sha256"}``, the identity of the stands of the canopy it was traced on.
    canopy : Canopy or None
        The canopy it was traced on (keyword-only; :class:`TriangleResult`): tables per leaf
        and plant use it.

    References
    ----------
    Bailey, B. N. (2018). A reverse ray-tracing method for modelling the net radiative flux
    in leaf-resolving plant canopy simulations. Ecological Modelling 368, 233-245.
    https://doi.org/10.1016/j.ecolmodel.2017.11.022
    """

    band: str
    optics: Optics
    period: Period
    balance: Balance
    triangle_absorbed_j: np.ndarray
    step_absorbed_leaves_w_m2: np.ndarray
    step_incident_w_m2: np.ndarray
    rect: tuple[float, float, float, float]
    rays: int
    depth: int
    seed: int
    periodic: bool
    level: str = ""
    seconds: dict[str, float] = field(default_factory=dict)
    batches: Batches | None = None
    assimilation: PeriodAssimilation | None = None
    stands: dict | None = None

    fraction_absorbed = property(_fraction_absorbed)

    def _triangle_values(self) -> np.ndarray:
        return self.triangle_absorbed_j

    def _triangle_batches(self) -> Any:
        return None if self.batches is None else self.batches.absorbed

    def with_canopy(self, canopy: Canopy | None) -> Self:
        """The same result, and its assimilation, knowing the canopy they were computed on.

        Parameters
        ----------
        canopy : Canopy or None
            The canopy it was traced on.

        Returns
        -------
        AbsorbedPeriod
            A copy holding ``canopy``.
        """
        from dataclasses import replace

        carbon = None if self.assimilation is None else self.assimilation.with_canopy(canopy)
        return replace(self, canopy=canopy, assimilation=carbon)

    @property
    def absorbed_leaves_error(self) -> float | None:
        """Monte Carlo standard error of ``balance.absorbed_leaves``, from batches of rays.

        Returns
        -------
        float or None
            [MJ m-2 of ground]; None when the result was not traced in batches.
        """
        return _leaves_error(self)

    @property
    def balance_errors(self) -> dict[str, float] | None:
        """Monte Carlo standard errors of the period's energy balance's parts, in its units.

        Returns
        -------
        dict of str to float or None
            ``absorbed_leaves``, ``absorbed_ground``, ``reflected_top``, ``escaped_sides``,
            ``unresolved`` [MJ m-2 of ground]; None without batches.
        """
        if self.batches is None or self.batches.parts is None:
            return None
        return {"absorbed_leaves": float(self.absorbed_leaves_error or 0.0),
                **(self.batches.balance_errors(1.0) or {})}

    @property
    def absorbed_leaves_mol_m2(self) -> float | None:
        """PAR the leaves absorbed over the period.

        Returns
        -------
        float or None
            [mol m-2 of ground] (MJ times 4.57 umol per J of PAR); None for NIR.
        """
        from maizeviz.light.sources.irradiance import PAR_UMOL_PER_J_PAR

        return self.balance.absorbed_leaves * PAR_UMOL_PER_J_PAR if self.band == "par" \
            else None                           # MJ x umol/J = mol

    def table(self, by: TableBy | None = None, canopy: Canopy | None = None) -> pd.DataFrame:
        """Absorbed light over the period as a table: the balance, or per leaf or per plant.

        Parameters
        ----------
        by : {None, "balance", "leaf", "plant"}
            None (the default) or "balance": the balance [MJ m-2 of ground] as one row.
            "leaf" or "plant": ``absorbed_mj`` [MJ], ``absorbed_mj_m2_leaf`` [MJ m-2 of leaf],
            and for PAR ``absorbed_mol`` [mol].
        canopy : Canopy, optional
            The canopy the light was traced on (default: the result's own, ``canopy``);
            needed by leaf and plant.

        Returns
        -------
        pandas.DataFrame
            One row, or one per lit leaf or plant.

        Raises
        ------
        MaizevizError
            Another ``by``, or a leaf or plant table without the canopy.
        """
        import pandas as pd

        canopy = self._on(canopy)
        kind = table_kind(by, "balance", canopy)
        if kind == "balance":
            return pd.DataFrame([{"band": self.band, "unit": "MJ/m2",
                                  **self.balance.as_dict()}])
        assert canopy is not None
        from maizeviz.light.sources.irradiance import PAR_UMOL_PER_J_PAR

        rows = leaf_sums(canopy, {"absorbed_mj": self.triangle_absorbed_j * 1e-6}, self.rect,
                         self.periodic)
        frame = pd.DataFrame(rows)
        if frame.empty:
            return frame
        if kind == "plant":
            frame = _per_plant(frame, ("absorbed_mj",))
        if self.batches is not None:
            se = errors_by(canopy, self.batches.absorbed * 1e-6, "absorbed_mj", self.rect,
                           self.periodic, kind)
            keys = frame["instance"] if kind == "plant" else zip(frame["instance"], frame["leaf"])
            frame["absorbed_mj_se"] = [se.get(k, 0.0) for k in keys]
        frame["absorbed_mj_m2_leaf"] = frame["absorbed_mj"] / (frame["leaf_area_cm2"] * 1e-4)
        if self.band == "par":
            frame["absorbed_mol"] = frame["absorbed_mj"] * PAR_UMOL_PER_J_PAR
        return frame

    def leaf_rows(self, canopy: Canopy) -> list[LightRow]:
        """Per lit leaf: the energy it absorbed over the period.

        ``absorbed_mj`` [MJ] and ``absorbed_mj_m2_leaf`` [MJ m-2 of leaf]
        (:func:`maizeviz.light.results.per_leaf.leaf_sums`).

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
        rows = leaf_sums(canopy, {"absorbed_mj": self.triangle_absorbed_j * 1e-6}, self.rect,
                         self.periodic)
        for r in rows:
            r["absorbed_mj_m2_leaf"] = float(r["absorbed_mj"]) / (float(r["leaf_area_cm2"]) * 1e-4)
        return rows
