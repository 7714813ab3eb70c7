"""Gross CO2 assimilation of the canopy from the PAR each triangle absorbs.

Each leaf triangle's absorbed PAR (:class:`~maizeviz.light.results.absorbed.AbsorbedLight`) comes in
two parts: what the sun's direct beam deposited on its sunlit area, and the rest (diffuse sky,
scattered light) spread over the whole triangle. A leaf model
(:mod:`maizeviz.photosynthesis`) turns each part's light into assimilation separately
(:func:`~maizeviz.photosynthesis.split.split_assimilation`): the light response is concave, so
a triangle's mean light would overstate it.

In a tile-periodic field sampled on its central tile (the paper's tiled block), the rays over
the tile reach every copy of a plant, and the copies of a triangle together receive what that
triangle receives in the infinite field (:func:`~maizeviz.light.results.per_leaf.tile_representatives`):
their light is added up before the (non-linear) model sees it, and the result stands on the copy
inside the tile. The canopy's assimilation per m2 of ground is then the tile's over its area.

The background light (diffuse sky, scattered light) reaches a triangle as a handful of rays:
fed to a concave response one triangle at a time, that noise alone lowers the answer (by 4 %
on a spherical canopy of 1 cm2 triangles at 1 ray per cm2, by 0.3 % at 8). It varies little
within a leaf at one height, so it is pooled over each leaf's triangles in 5 cm height bands
(``pool_cm``) before the model sees it. A pool must stand for enough rays
(:data:`POOL_RAYS`, its leaf area times the density): the bands of leaves too small for that
are pooled with the small ones of their plant at that height, then of the canopy
(:func:`background_pools`); pooling a leaf on its own, a canopy of 2 cm leaves at 1 ray per
cm2 came out 3 % low, 11 standard errors. The direct beam, which does vary from triangle to
triangle (sunflecks, orientation), is kept per triangle, its sunlit area entering linearly.

Standard errors come from the independent batches of rays the absorbed light was traced in
(:class:`~maizeviz.light.results.uncertainty.Batches`): the model is run on each batch's light alone.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.ids import groups
from maizeviz.light.results.on_triangles import TriangleResult
from maizeviz.photosynthesis.split import (
    LeafModel,
    as_leaf_model,
    model_from_dict,
    split_assimilation,
)
from maizeviz.photosynthesis.units import CO2_G_PER_MOL, KG_HA_H_PER_UMOL_M2_S

if TYPE_CHECKING:
    import pandas as pd

    from maizeviz.canopy.build import Canopy
    from maizeviz.light.results.traced import TableBy
    from maizeviz.light.results.uncertainty import Batches


#: Height band (cm) over which the background light of a leaf's triangles is pooled.
POOL_CM = 5.0
#: Rays (leaf area in cm2 times rays per cm2) a pool of background light stands for at least.
POOL_RAYS = 64.0
#: Halves of the batches of rays (the first of each pair; the other half is the rest) the
#: bias from the density is estimated from: each pair of batches shares a half in one of them.
HALF_SPLITS = ([0, 1, 2, 3], [0, 2, 4, 6], [0, 1, 4, 5], [0, 2, 5, 7])


def background_pools(instance: np.ndarray, leaf: np.ndarray, z_cm: np.ndarray,
                     area_cm2: np.ndarray, density: float, pool_cm: float = POOL_CM,
                     min_rays: float = POOL_RAYS) -> np.ndarray:
    """(F,) intp: the pool each triangle's background light is averaged over.

    A leaf's triangles in one ``pool_cm`` height band make a pool when the rays of that
    band of the leaf are enough (area x density >= ``min_rays``); the triangles of smaller
    ones are pooled with the other small ones of the same plant in that band, and, when those
    are still too few, with all the small ones of the canopy in that band. The choice depends
    on the geometry and the density only (never on the rays traced), and as the density grows
    every leaf becomes its own pool.

    Parameters
    ----------
    instance, leaf : (F,) int
        Plant standing (instance) and leaf of each triangle.
    z_cm : (F,) float64
        Height of each triangle's centre [cm].
    area_cm2 : (F,) float64
        One-sided area of each triangle [cm2].
    density : float
        Primary rays per cm2 of ground.
    pool_cm : float
        Height band [cm]; 0: each triangle its own pool.
    min_rays : float
        Rays a pool's leaf area must stand for (its area in cm2 times ``density``).

    Returns
    -------
    numpy.ndarray
        (F,) intp pool of each triangle, numbered from 0.
    """
    n = len(z_cm)
    if pool_cm <= 0:
        return np.arange(n)
    band = np.floor(np.asarray(z_cm, np.float64) / pool_cm).astype(np.int64)
    inst = np.asarray(instance, np.int64)
    # -1 marks the leaves too small to stand alone at this density, then the plants
    _, own = groups(inst, leaf, band)
    small = (np.bincount(own, weights=area_cm2) * density < min_rays)[own]
    leaf_key = np.where(small, -1, np.asarray(leaf, np.int64))
    _, plant = groups(inst, leaf_key, band)
    thin = small & (np.bincount(plant, weights=area_cm2) * density < min_rays)[plant]
    _, pool = groups(np.where(thin, -1, inst), leaf_key, band)
    return pool


def copy_slots(canopy: Canopy, rect, periodic: bool) -> np.ndarray | None:
    """(F,) int64: for each leaf triangle, the slot it shares with its copies in a
    tile-periodic field (:func:`~maizeviz.light.results.per_leaf.tile_representatives`), numbered
    so that slot ``i`` is a triangle of the copy inside the sample rectangle; None when every
    placement stands for itself."""
    from maizeviz.light.results.per_leaf import tile_representatives

    rep = tile_representatives(canopy.layout, rect, periodic)
    nf = canopy.n_triangles
    inst = canopy.face_instance.astype(np.int64)
    if not nf or not (rep != np.arange(len(rep))).any() or not np.all(np.diff(inst) >= 0):
        return None
    starts = np.searchsorted(inst, np.arange(len(rep)))
    local = np.arange(nf) - starts[inst]
    _, slot = groups(rep[inst], local)
    return slot.astype(np.int64)


def _fold(values: np.ndarray, slot: np.ndarray | None, n_slots: int) -> np.ndarray:
    return values if slot is None else np.bincount(slot, weights=values, minlength=n_slots)


@dataclass(frozen=True)
class Assimilation(TriangleResult):
    """Gross CO2 assimilation of the leaves under one traced light.

    Parameters
    ----------
    model : dict
        The leaf model's name and parameters (``LeafModel.as_dict``).
    temp_c : float
        Leaf (air) temperature [degC].
    triangle_gross_umol_s : numpy.ndarray
        (F,) float64 gross assimilation of each leaf triangle [umol CO2 s-1] (in a
        tile-periodic field on the copy inside the sample rectangle; its other copies 0).
    triangle_batches : numpy.ndarray or None
        (BATCHES, F) float64 the same from each batch of rays alone, or None.
    ground_m2 : float
        Ground the canopy figure is per (the sample rectangle) [m2].
    respiration_umol_m2_leaf : float
        The model's leaf respiration at ``temp_c`` [umol CO2 m-2 of leaf s-1].
    leaf_area_m2 : float
        Leaf the triangles stand for (one copy in a tile-periodic field) [m2].
    rect : (x0, y0, x1, y1) tuple of float
        The sample rectangle [cm].
    periodic : bool
        Rays wrapped across the plot.
    warnings : tuple of str
        What the user should know (leaves partly out of the rays' reach).
    bias_umol_s : float or None
        Estimated bias of the canopy's gross assimilation from the density of the rays
        [umol CO2 s-1] (negative: the figure is low), from the same rays (see
        :func:`assimilate`); None without batches.
    bias_se_umol_s : float or None
        Its spread over the halvings of the batches it was estimated from [umol CO2 s-1].
    canopy : Canopy or None
        The canopy it was computed on (keyword-only; :class:`TriangleResult`): tables per leaf
        and plant use it.

    References
    ----------
    Collatz, G. J., Ribas-Carbo, M. & Berry, J. A. (1992). Coupled photosynthesis-stomatal
    conductance model for leaves of C4 plants. Australian Journal of Plant Physiology 19,
    519-538. https://doi.org/10.1071/PP9920519
    Spitters, C. J. T., Toussaint, H. A. J. M. & Goudriaan, J. (1986). Separating the
    diffuse and direct component of global radiation and its implications for modeling canopy
    photosynthesis. Part II. Calculation of canopy photosynthesis. Agricultural and Forest
    Meteorology 38, 231-242. https://doi.org/10.1016/0168-1923(86)90061-4
    """

    model: dict
    temp_c: float
    triangle_gross_umol_s: np.ndarray
    triangle_batches: np.ndarray | None
    ground_m2: float
    respiration_umol_m2_leaf: float
    leaf_area_m2: float
    rect: tuple[float, float, float, float]
    periodic: bool
    warnings: tuple[str, ...] = ()
    bias_umol_s: float | None = None
    bias_se_umol_s: float | None = None

    def _triangle_values(self) -> np.ndarray:
        return self.triangle_gross_umol_s

    def _triangle_batches(self) -> np.ndarray | None:
        return self.triangle_batches

    @property
    def canopy_gross_umol_m2_s(self) -> float:
        """Canopy gross assimilation, umol CO2 per m2 of ground per s."""
        return self.triangle_total / self.ground_m2

    @property
    def canopy_gross_kg_co2_ha_h(self) -> float:
        """Canopy gross assimilation, kg CO2 per ha of ground per h."""
        return self.canopy_gross_umol_m2_s * KG_HA_H_PER_UMOL_M2_S

    @property
    def canopy_gross_error_umol_m2_s(self) -> float | None:
        """Monte Carlo standard error of :attr:`canopy_gross_umol_m2_s` (None: no batches)."""
        se = self.triangle_total_error
        return None if se is None else se / self.ground_m2

    @property
    def canopy_gross_bias_umol_m2_s(self) -> float | None:
        """Estimated bias of :attr:`canopy_gross_umol_m2_s` from the density of the rays.

        Returns
        -------
        float or None
            [umol CO2 m-2 of ground s-1], negative when the figure is low; None without
            batches.
        """
        return None if self.bias_umol_s is None else self.bias_umol_s / self.ground_m2

    @property
    def canopy_net_umol_m2_s(self) -> float:
        """Gross minus the leaves' respiration, umol CO2 per m2 of ground per s."""
        return self.canopy_gross_umol_m2_s - \
            self.respiration_umol_m2_leaf * self.leaf_area_m2 / self.ground_m2

    def leaf_model(self) -> LeafModel:
        """The leaf model it was computed with.

        Returns
        -------
        LeafModel
            Rebuilt from ``model``.
        """
        return model_from_dict(self.model)

    def as_dict(self) -> dict[str, Any]:
        """The figures the command line's JSON carries (``photosynthesis``).

        Returns
        -------
        dict
            The model, its parameters, the temperature, the canopy's gross assimilation with its
            standard error and its estimated bias from the density (``_bias``, negative: low;
            ``_bias_se``) [umol m-2 s-1, kg CO2 ha-1 h-1], net assimilation, LAI and warnings.
        """
        se = self.canopy_gross_error_umol_m2_s
        bias = self.canopy_gross_bias_umol_m2_s
        bias_se = None if self.bias_se_umol_s is None else self.bias_se_umol_s / self.ground_m2
        return {"model": self.model["model"], "label": self.leaf_model().label,
                "parameters": {k: v for k, v in self.model.items() if k != "model"},
                "temperature_c": self.temp_c,
                "canopy_gross_umol_m2_s": self.canopy_gross_umol_m2_s,
                "canopy_gross_umol_m2_s_se": se,
                "canopy_gross_umol_m2_s_bias": bias,
                "canopy_gross_umol_m2_s_bias_se": bias_se,
                "canopy_gross_kg_co2_ha_h": self.canopy_gross_kg_co2_ha_h,
                "canopy_gross_kg_co2_ha_h_se": None if se is None
                else se * KG_HA_H_PER_UMOL_M2_S,
                "canopy_gross_kg_co2_ha_h_bias": None if bias is None
                else bias * KG_HA_H_PER_UMOL_M2_S,
                "canopy_net_umol_m2_s": self.canopy_net_umol_m2_s,
                "leaf_area_index": self.leaf_area_m2 / self.ground_m2,
                "warnings": list(self.warnings)}

    def table(self, by: TableBy | None = None, canopy: Canopy | None = None) -> pd.DataFrame:
        """Gross assimilation as a table: the canopy's, or per leaf or plant.

        Parameters
        ----------
        by : {None, "canopy", "leaf", "plant"}
            None (the default) or "canopy": the canopy's figures as one row (:meth:`as_dict`'s
            numbers). "leaf" or "plant": ``gross_umol_s`` [umol CO2 s-1], its standard error
            ``gross_umol_s_se``, ``gross_umol_m2_leaf_s`` [umol CO2 m-2 of leaf s-1].
        canopy : Canopy, optional
            The canopy the light was traced on (default: the result's own, ``canopy``);
            needed by leaf and plant.

        Returns
        -------
        pandas.DataFrame
            One row, or one per leaf or plant.
        """
        return _table(self, self.triangle_gross_umol_s, self.triangle_batches, "gross_umol_s",
                      "gross_umol_m2_leaf_s", self.rect, self.periodic, by, self._on(canopy))


@dataclass(frozen=True)
class PeriodAssimilation(TriangleResult):
    """Gross CO2 assimilation of the leaves over a period (a day, a weather file).

    Each time step's light through the leaf model at that step's temperature, times the step.

    Parameters
    ----------
    model : dict
        The leaf model (``LeafModel.as_dict``).
    temperature_c : numpy.ndarray
        (n,) float64 air (leaf) temperature of each step [degC].
    triangle_gross_mol : numpy.ndarray
        (F,) float64 gross assimilation of each leaf triangle over the period [mol CO2]
        (tile-periodic fields: on the copy inside the sample rectangle).
    triangle_batches : numpy.ndarray or None
        (BATCHES, F) float64 the same from each batch of rays alone.
    ground_m2 : float
        Ground (the sample rectangle) [m2].
    step_gross_umol_m2_s : numpy.ndarray
        (n,) float64 the canopy's gross assimilation at each step [umol m-2 of ground s-1].
    rect : (x0, y0, x1, y1) tuple of float
        The sample rectangle [cm].
    periodic : bool
        Rays wrapped across the plot.
    bias_mol : float or None
        Estimated bias of the canopy's gross assimilation over the period from the density of
        the rays [mol CO2] (negative: low), the steps' added up.
    bias_se_mol : float or None
        Its spread over the halvings of the batches, the steps' added up [mol CO2].
    canopy : Canopy or None
        The canopy it was computed on (keyword-only; :class:`TriangleResult`): tables per leaf
        and plant use it.

    References
    ----------
    Collatz, G. J., Ribas-Carbo, M. & Berry, J. A. (1992). Coupled photosynthesis-stomatal
    conductance model for leaves of C4 plants. Australian Journal of Plant Physiology 19,
    519-538. https://doi.org/10.1071/PP9920519
    """

    model: dict
    temperature_c: np.ndarray
    triangle_gross_mol: np.ndarray
    triangle_batches: np.ndarray | None
    ground_m2: float
    step_gross_umol_m2_s: np.ndarray
    rect: tuple[float, float, float, float]
    periodic: bool
    bias_mol: float | None = None
    bias_se_mol: float | None = None

    def _triangle_values(self) -> np.ndarray:
        return self.triangle_gross_mol

    def _triangle_batches(self) -> np.ndarray | None:
        return self.triangle_batches

    @property
    def canopy_gross_mol_m2(self) -> float:
        """Gross CO2 assimilation over the period per m2 of ground.

        Returns
        -------
        float
            [mol CO2 m-2].
        """
        return self.triangle_total / self.ground_m2

    @property
    def canopy_gross_g_m2(self) -> float:
        """Gross CO2 assimilation over the period per m2 of ground.

        Returns
        -------
        float
            [g CO2 m-2].
        """
        return self.canopy_gross_mol_m2 * CO2_G_PER_MOL

    @property
    def canopy_gross_error_mol_m2(self) -> float | None:
        """Monte Carlo standard error of :attr:`canopy_gross_mol_m2`.

        Returns
        -------
        float or None
            [mol CO2 m-2]; None without batches.
        """
        se = self.triangle_total_error
        return None if se is None else se / self.ground_m2

    def as_dict(self) -> dict[str, Any]:
        """The figures the command line's JSON carries.

        Returns
        -------
        dict
            The model, its parameters, the temperatures, the canopy's gross assimilation with its
            standard error [mol m-2, g CO2 m-2] and per step [umol m-2 s-1].
        """
        se = self.canopy_gross_error_mol_m2
        g = self.ground_m2
        return {"model": self.model["model"], "label": model_from_dict(self.model).label,
                "parameters": {k: v for k, v in self.model.items() if k != "model"},
                "temperature_c": [float(t) for t in self.temperature_c],
                "canopy_gross_mol_m2": self.canopy_gross_mol_m2,
                "canopy_gross_mol_m2_se": se,
                "canopy_gross_mol_m2_bias": None if self.bias_mol is None
                else self.bias_mol / g,
                "canopy_gross_mol_m2_bias_se": None if self.bias_se_mol is None
                else self.bias_se_mol / g,
                "canopy_gross_g_co2_m2": self.canopy_gross_g_m2,
                "canopy_gross_g_co2_m2_se": None if se is None else se * CO2_G_PER_MOL,
                "step_gross_umol_m2_s": [float(v) for v in self.step_gross_umol_m2_s]}

    def table(self, by: TableBy | None = None, canopy: Canopy | None = None) -> pd.DataFrame:
        """Gross assimilation over the period as a table: the canopy's, or per leaf or plant.

        Parameters
        ----------
        by : {None, "canopy", "leaf", "plant"}
            None (the default) or "canopy": the canopy's figures as one row (:meth:`as_dict`'s
            numbers). "leaf" or "plant": ``gross_mol`` [mol CO2] over the period,
            ``gross_mol_se``, ``gross_g_co2`` [g], ``gross_mol_m2_leaf`` [mol m-2 of leaf].
        canopy : Canopy, optional
            The canopy the light was traced on (default: the result's own, ``canopy``);
            needed by leaf and plant.

        Returns
        -------
        pandas.DataFrame
            One row, or one per leaf or plant.
        """
        frame = _table(self, self.triangle_gross_mol, self.triangle_batches, "gross_mol",
                       "gross_mol_m2_leaf", self.rect, self.periodic, by, self._on(canopy))
        if by is not None and by != "canopy" and not frame.empty:
            frame["gross_g_co2"] = frame["gross_mol"] * CO2_G_PER_MOL
        return frame


def _table(result, values: np.ndarray, batches: np.ndarray | None, col: str,
           per_leaf_col: str, rect, periodic: bool, by: str | None,
           canopy: Canopy | None) -> pd.DataFrame:
    """The canopy's figures as one row (``by`` None or "canopy"), or per-leaf or per-plant
    sums of per-triangle ``values`` (column ``col``), their standard errors from ``batches``
    (column ``col + "_se"``), and ``per_leaf_col``: per m2 of leaf."""
    import pandas as pd

    from maizeviz.light.results.per_leaf import leaf_sums
    from maizeviz.light.results.traced import table_kind
    from maizeviz.light.results.uncertainty import errors_by

    by = table_kind(by, "canopy", canopy)
    if by == "canopy":
        return pd.DataFrame([{k: v for k, v in result.as_dict().items()
                              if isinstance(v, (str, int, float)) or v is None}])
    assert canopy is not None
    frame = pd.DataFrame(leaf_sums(canopy, {col: values}, rect, periodic))
    if frame.empty:
        return frame
    key = ["instance"] if by == "plant" else ["instance", "leaf"]
    if by == "plant":
        frame = frame.groupby("instance", as_index=False).agg(
            plant=("plant", "first"), x_cm=("x_cm", "first"), y_cm=("y_cm", "first"),
            leaves=("leaf", "size"), leaf_area_cm2=("leaf_area_cm2", "sum"), **{col: (col, "sum")})
    if batches is not None:
        se = errors_by(canopy, batches, col, rect, periodic, by)
        frame[col + "_se"] = [se.get(k, 0.0) for k in frame.set_index(key).index]
    frame[per_leaf_col] = frame[col] / (frame["leaf_area_cm2"] * 1e-4)
    return frame


class AbsorbedPar(Protocol):
    """What :func:`assimilate` reads of absorbed PAR: an
    :class:`~maizeviz.light.results.absorbed.AbsorbedLight` (named by its members, so that the
    absorbed results may name the assimilation they carry without an import circle)."""

    @property
    def band(self) -> str: ...
    @property
    def rect(self) -> tuple[float, float, float, float]: ...
    @property
    def periodic(self) -> bool: ...
    @property
    def rays(self) -> int: ...
    @property
    def triangle_absorbed_w(self) -> np.ndarray: ...
    @property
    def triangle_direct_w(self) -> np.ndarray | None: ...
    @property
    def triangle_sunlit_cm2(self) -> np.ndarray: ...
    @property
    def batches(self) -> Batches | None: ...


def assimilate(canopy: Canopy, light: AbsorbedPar, model: LeafModel | str,
               temp_c: float = 25.0, pool_cm: float = POOL_CM,
               pool_rays: float = POOL_RAYS) -> Assimilation:
    """Gross assimilation of the canopy's leaves under absorbed PAR ``light`` (a sun, a sky,
    or both, traced by :meth:`~maizeviz.light.engine.LightEngine.absorbed`).

    Parameters
    ----------
    canopy : the canopy ``light`` was traced on
    light : AbsorbedLight in the PAR band
    model : a leaf model (:func:`maizeviz.photosynthesis.split.leaf_model`), or its name
        ("c4", "wofost": its default parameters)
    temp_c : leaf temperature, C (the air's: leaves are taken at air temperature)
    pool_cm : height band (cm) over which a leaf's background light is pooled (0: each
        triangle its own)
    pool_rays : rays a pool's leaf area must stand for (area in cm2 times rays per cm2;
        :func:`background_pools`); 0: each leaf's band its own pool, whatever its size

    Returns
    -------
    Assimilation
    """
    from maizeviz.errors import check_range
    from maizeviz.mesh.tessellate import triangle_areas_normals

    model = as_leaf_model(model)
    if light.band != "par":
        raise MaizevizError("photosynthesis needs absorbed PAR, not "
                            f"{light.band.upper()}", quantity="band")
    check_range(temp_c, "the leaf temperature (C)", -50, 70, "temperature")
    nf = canopy.n_triangles
    area = triangle_areas_normals(canopy.vertices, canopy.faces)[0] * 1e-4       # m2
    slot = copy_slots(canopy, light.rect, light.periodic)
    n_slots = int(slot.max()) + 1 if slot is not None else nf
    # the copy inside the rectangle stands for the slot: its area, once
    if slot is not None:
        first = np.full(n_slots, -1, np.int64)
        order = np.arange(nf)[::-1]
        first[slot[order]] = order                     # the lowest triangle index per slot
        x0, y0, x1, y1 = light.rect
        from maizeviz.light.results.per_leaf import tile_representatives

        rep = tile_representatives(canopy.layout, light.rect, light.periodic)
        own = rep[canopy.face_instance.astype(np.int64)] == canopy.face_instance
        first[slot[own]] = np.flatnonzero(own)
        area_s = area[first]
    else:
        first = np.arange(nf)
        area_s = area
    direct_full = light.triangle_direct_w if light.triangle_direct_w is not None else \
        np.zeros_like(light.triangle_absorbed_w)

    # the background light (sky, scattered) of a triangle is a handful of rays: pooled over
    # the triangles of its leaf in the same height band, where it hardly varies, so that the
    # concave response does not turn the rays' noise into a bias (see the module docstring)
    zc = canopy.vertices[canopy.faces[first]][:, :, 2].mean(axis=1)
    x0, y0, x1, y1 = light.rect
    density = light.rays / max((x1 - x0) * (y1 - y0), 1e-300)          # rays per cm2
    pool = background_pools(canopy.face_instance[first], canopy.face_leaf[first], zc,
                            area_s * 1e4, density, pool_cm, pool_rays)
    pool_area = np.bincount(pool, weights=area_s)

    def gross_of(absorbed, direct, sunlit_cm2):
        d = _fold(np.asarray(direct, np.float64)[:nf], slot, n_slots)
        bg = _fold(np.asarray(absorbed, np.float64)[:nf], slot, n_slots) - d
        if pool_cm > 0:
            flux = np.bincount(pool, weights=np.maximum(bg, 0.0)) / np.where(
                pool_area > 0, pool_area, 1.0)
            bg = flux[pool] * area_s
        lit = _fold(np.asarray(sunlit_cm2, np.float64)[:nf], slot, n_slots) * 1e-4
        g = split_assimilation(model, area_s, lit, d, np.maximum(bg, 0.0), temp_c)
        out = np.zeros(nf)
        out[first] = g
        return out

    gross = gross_of(light.triangle_absorbed_w, direct_full, light.triangle_sunlit_cm2)
    batches, bias = None, None
    if light.batches is not None:
        from maizeviz.light.results.uncertainty import BATCHES

        b = light.batches
        rows = []
        for k in range(BATCHES):
            a_k, d_k, s_k = (np.asarray(m[[k], :].todense()).ravel() * BATCHES
                             for m in (b.absorbed, b.direct, b.sunlit_cm2))
            rows.append(gross_of(a_k, d_k, s_k) / BATCHES)
        batches = np.vstack(rows)

        # the same pools at half the rays: the bias of these pools' light through the model
        def half(ks: list[int]) -> float:
            a_h, d_h, s_h = (2.0 * np.asarray(m[ks, :].sum(axis=0)).ravel()
                             for m in (b.absorbed, b.direct, b.sunlit_cm2))
            return float(gross_of(a_h, d_h, s_h).sum())

        total = float(gross.sum())
        bias = np.array([(half(sp) + half([k for k in range(BATCHES) if k not in sp])) / 2
                         - total for sp in HALF_SPLITS])
    x0, y0, x1, y1 = light.rect
    ground = (x1 - x0) * (y1 - y0) * 1e-4
    warnings: list[str] = []
    if slot is None and not _covers_plot(canopy, light.rect, light.periodic):
        warnings.append("the sample rectangle is not the plot nor a tile of a periodic "
                        "field: leaves outside the rays' reach get part of their light, and "
                        "their assimilation is understated")
    return Assimilation(model.as_dict(), float(temp_c), gross, batches, ground,
                        float(model.respiration(temp_c)), float(area_s.sum()),
                        light.rect, light.periodic, tuple(warnings),
                        None if bias is None else float(bias.mean()),
                        None if bias is None else float(bias.std(ddof=1)), canopy=canopy)


def _covers_plot(canopy: Canopy, rect, periodic: bool) -> bool:
    """Whether the rays over ``rect`` reach every leaf fully: a periodic field sampled over
    its whole plot."""
    if not periodic:
        return False
    return bool(np.allclose(np.asarray(rect, float), np.asarray(canopy.layout.bounds, float),
                            atol=1e-6))
