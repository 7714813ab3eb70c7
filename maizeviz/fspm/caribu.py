"""Caribu's ``CaribuScene``, backed by maizeviz's Embree tracer: an OpenAlea script that calls
Caribu changes one import line.

Caribu (Chelle & Andrieu 1998; ``alinea.caribu``) is the light model OpenAlea's
functional-structural plant models (ADEL, CN-Wheat, ...) call each time step on labelled
triangles. This class takes the same inputs and gives the same outputs, in the same units::

    # from alinea.caribu.CaribuScene import CaribuScene
    from maizeviz.fspm.caribu import CaribuScene

    scene = CaribuScene(scene={"leaf": [[(0, 0, 1), (1, 0, 1), (0, 1, 1)]]},
                        light=[(1.0, (0, 0, -1))], opt={"par": {"leaf": (0.06, 0.07)}},
                        pattern=(-1, -1, 2, 2))
    raw, aggregated = scene.run(direct=False, infinite=True)
    aggregated["par"]["Eabs"]["leaf"]            # absorbed, per m2 of leaf

Inputs (as Caribu's): ``scene`` a ``{label: [triangle, ...]}`` dict (a triangle three
``(x, y, z)`` points) or a Canestra ``.can`` file; ``light`` a list of ``(energy, (vx, vy,
vz))`` sources (energy on a horizontal plane, per m2; the direction light travels) or a
``.light`` file; ``opt`` ``{band: {label: material}}`` or ``{band: material}`` (a material:
``(reflectance,)`` opaque, ``(reflectance, transmittance)`` translucent, or 4 values, lower then
upper side) or a list of ``.opt`` files beside a ``.can`` scene; ``pattern`` ``(xmin, ymin,
xmax, ymax)`` or a ``.8`` file for an infinite canopy; ``scene_unit`` the unit of the
coordinates and the pattern (default metres). Outputs of :meth:`CaribuScene.run`: ``raw``
``{band: {"Eabs"|"Ei"|"area": {label: [value per triangle]}}}`` and ``aggregated`` ``{band:
{...: {label: value}}}`` (areas summed in m2; ``Eabs`` and ``Ei`` area-weighted means, per m2
of organ, in the light's energy unit).

How it computes (the differences from Caribu, see ``docs/fspm.md``):

- Caribu projects the scene on a z-buffer of ``screen_size`` pixels and solves the radiosity
  of the triangles (nested radiosity: exact form factors near each triangle, a turbid medium
  beyond ``d_sphere``). Here each light is a grid of parallel rays traced by Embree, and the
  scattered light is followed by Monte Carlo ray tracing (Russian roulette, Lambertian leaves:
  :mod:`maizeviz.light.trace.scatter`) through the real triangles at every distance. Both
  solve the same transport equation; this one has a sampling error (``density`` rays per cm2
  of ground, default from ``screen_size`` as Caribu's pixel), Caribu a discretisation error
  (pixels, the turbid far field).
- ``direct=True``: first interception only (no scattering), as Caribu's ray casting.
  ``direct=False``: every scattering followed (up to 20, until 1e-4 of the light is left), with
  the soil reflecting (``soil_reflectance``) at the lowest point of the scene (or ``z_soil``).
- ``infinite=True``: the scene repeats over the pattern in x and y (periodic boundaries, exact:
  light leaving one side re-enters on the other), as Caribu's periodic scene does.
- A 4-value material (sides that differ) is traced with the mean of its two sides (said in
  :attr:`CaribuScene.notes`); ``split_face`` (light on each side) is given for
  ``direct=True``; virtual ``sensors`` are not traced (use maizeviz's sensor planes and
  virtual instruments). ``d_sphere``, ``layers`` and ``screen_resolution`` are accepted and
  have no effect beyond what is said here.

References
----------
Chelle, M. & Andrieu, B. (1998). The nested radiosity model for the distribution of light
within plant canopies. Ecological Modelling 111, 75-91.
https://doi.org/10.1016/S0304-3800(98)00100-8
Caribu (``alinea.caribu``), OpenAlea: https://github.com/openalea-incubator/caribu
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from itertools import groupby
from pathlib import Path
from typing import Any

import numpy as np

from maizeviz.errors import MaizevizError

#: Largest number of rays of one light's grid (the default density is lowered to it).
MAX_RAYS_PER_LIGHT = 2_000_000
#: Most scatterings followed with ``direct=False``, and the share of the light still
#: travelling at which tracing stops.
SCATTER_DEPTH = 20
SCATTER_THRESHOLD = 1e-4


class CaribuSceneError(MaizevizError):
    """Caribu's inputs cannot be taken as given (named in the message)."""


Material = tuple[float, ...]
Triangle = Sequence[Sequence[float]]


def _material(band: str, label, po) -> tuple[float, float, bool]:
    """(reflectance, transmittance, sides differ) of a Caribu material."""
    try:
        values = tuple(float(v) for v in po)
    except (TypeError, ValueError):
        raise CaribuSceneError(f"band {band}, label {label}: a material is a tuple of 1, 2 or 4 "
                               f"numbers, got {str(po)[:40]}") from None
    if len(values) not in (1, 2, 4) or not all(math.isfinite(v) for v in values):
        raise CaribuSceneError(f"band {band}, label {label}: a material is 1, 2 or 4 finite "
                               f"numbers, got {values}")
    if len(values) == 1:
        rho, tau, differ = values[0], 0.0, False
    elif len(values) == 2:
        (rho, tau), differ = values, False
    else:
        rho, tau = (values[0] + values[2]) / 2, (values[1] + values[3]) / 2
        differ = values[:2] != values[2:]
    if not (0.0 <= rho <= 1.0 and 0.0 <= tau <= 1.0 and rho + tau <= 1.0 + 1e-12):
        raise CaribuSceneError(f"band {band}, label {label}: reflectance {rho:g} and "
                               f"transmittance {tau:g} must lie in [0, 1] and sum to at most 1")
    return rho, tau, differ


def _opt_files(paths, labels) -> tuple[dict, dict]:
    """Materials of each label and soil reflectance of each band from Caribu's ``.opt`` files
    (one a band, named by the file), species by the labels' optical ids."""
    from maizeviz.io.canestra import decode_label, read_opt

    material: dict[str, dict[Any, Material]] = {}
    soil: dict[str, float] = {}
    for path in paths:
        band = Path(path).name.split(".")[0]
        ro_soil, species = read_opt(path)
        soil[band] = ro_soil
        mats: dict[Any, Material] = {}
        for lab in labels:
            oid, transparent, _, _ = decode_label(lab)
            if oid == 0 and not transparent:
                mats[lab] = (ro_soil,)
                continue
            if oid not in species:
                raise CaribuSceneError(f"{path}: label {lab} has optical id {oid}, the file "
                                       f"defines species 1..{len(species)}")
            stem, r_inf, t_inf, r_sup, t_sup = species[oid]
            if not transparent:
                mats[lab] = (stem,)
            elif (r_inf, t_inf) == (r_sup, t_sup):
                mats[lab] = (r_inf, t_inf)
            else:
                mats[lab] = (r_inf, t_inf, r_sup, t_sup)
        material[band] = mats
    return material, soil


def _area_weighted(pairs) -> float:
    """The area-weighted mean of (value, area) pairs (0 for no area), as Caribu's ``_wsum``."""
    total = sum(a for _, a in pairs)
    return sum(e * a for e, a in pairs if a > 0) / total if total > 0 else 0.0


def _aggregate(values, indices, fun):
    out = {}
    for key, group in groupby(sorted(zip(indices, values), key=lambda x: x[0]),
                              lambda x: x[0]):
        out[key] = fun([v for _, v in group])
    return out


class CaribuScene:
    """A scene of labelled triangles, its lights and optics, as Caribu's ``CaribuScene``.

    Parameters
    ----------
    scene : dict of label to list of triangles, or str / Path of a ``.can`` file
        Each triangle three ``(x, y, z)`` points in ``scene_unit``.
    light : list of (energy, (vx, vy, vz)), or a ``.light`` file
        Energy on a horizontal plane per m2 (any unit: the results are in it); the direction
        light travels (``vz < 0``). Default: ``[(1, (0, 0, -1))]``.
    pattern : (xmin, ymin, xmax, ymax) or ((xmin, ymin), (xmax, ymax)), or a ``.8`` file
        The rectangle an infinite canopy repeats, in ``scene_unit``.
    opt : dict or list of ``.opt`` files
        ``{band: {label: material}}`` or ``{band: material}`` (see the module docstring);
        default: every label ``(0.06, 0.07)`` in one band ``"default_band"``.
    soil_reflectance : dict of band to float
        Default 0.15 in every band (the ``.opt`` files' own with ``.opt`` files).
    soil_mesh : int or None
        Not None (and not -1): report the light reaching the soil (:meth:`getSoilEnergy`);
        needs ``pattern``.
    z_soil : float
        Height of the soil in ``scene_unit`` (default: the scene's lowest point).
    scene_unit : {"mm", "cm", "dm", "m", "dam", "hm", "km"}
    debug, filecache : accepted for compatibility; no temporary files are written.
    density : float, optional
        Rays per cm2 of ground for each light (default: Caribu's pixel, the larger side of the
        area traced over ``screen_size``, at most :data:`MAX_RAYS_PER_LIGHT` rays a light).
    seed : int
        Of the Monte Carlo scattering.
    threads : int
        Threads tracing each light.

    Attributes
    ----------
    notes : list of str
        What was decided about the inputs (one line each).
    seconds : dict of str to float
        Of the last :meth:`run`: "build" (Embree's scene) and "trace" [s].
    balance : dict of band to dict of str to float
        Of the last :meth:`run`, each band's energy over the area traced (energy x m2):
        "incident" (the lights over their ground rectangles), "leaves" (absorbed by the
        triangles), "soil" (absorbed by the soil), "top" (reflected out of the canopy),
        "sides" (escaped sideways, open scenes), "unresolved" (still travelling when tracing
        stopped); the parts add up to the incident within the Monte Carlo error.
    """

    default_material: Material = (0.06, 0.07)
    default_soil_reflectance = 0.15
    default_light = (1, (0, 0, -1))
    default_band = "default_band"
    units = {"mm": 0.001, "cm": 0.01, "dm": 0.1, "m": 1, "dam": 10, "hm": 100, "km": 1000}

    def __init__(self, scene=None, light=None, pattern=None, opt=None, soil_reflectance=None,
                 soil_mesh=None, z_soil=None, scene_unit: str = "m", debug: bool = False,
                 filecache: bool = True, *, density: float | None = None, seed: int = 0,
                 threads: int = 1):
        if scene_unit not in self.units:
            raise CaribuSceneError(f"unknown scene unit {scene_unit!r} (known: "
                                   f"{', '.join(self.units)})")
        self.conv_unit = self.units[scene_unit]
        self.debug = debug
        self.notes: list[str] = []
        self.seconds: dict[str, float] = {}
        self.balance: dict[str, dict[str, float]] = {}
        self.density = density
        self.seed = int(seed)
        self.threads = int(threads)
        self.scene: dict[Any, np.ndarray] | None = None
        if scene is not None:
            self.scene = self._scene(scene)
        self.light: list[tuple[float, tuple[float, float, float]]] = [self.default_light]
        if light is not None:
            self.setLight(light)
        self.pattern = self._pattern(pattern) if pattern is not None else None
        self.material, self.soil_reflectance = self._optics(opt, soil_reflectance, scene)
        self.soil = None
        if soil_mesh is not None and soil_mesh != -1:
            if self.pattern is None:
                raise CaribuSceneError("adding a soil needs the scene's pattern (its domain)")
            self.soil = int(soil_mesh)
        self.z_soil = None if z_soil is None else float(z_soil)
        self.soil_raw: dict = {}
        self.soil_aggregated: dict = {}

    # ------------------------------------------------------------------ inputs
    @staticmethod
    def _scene(scene) -> dict[Any, np.ndarray]:
        if isinstance(scene, (str, Path)):
            from maizeviz.io.canestra import read_can

            return read_can(scene)
        if not isinstance(scene, Mapping) or not scene:
            raise CaribuSceneError("a scene is a non-empty {label: [triangle, ...]} dict or a "
                                   f".can file, got {type(scene).__name__}")
        out = {}
        for label, tris in scene.items():
            try:
                arr = np.asarray(tris, np.float64)
            except (TypeError, ValueError):
                raise CaribuSceneError(f"label {label}: triangles are lists of three (x, y, z) "
                                       "points") from None
            if arr.ndim != 3 or arr.shape[1:] != (3, 3) or len(arr) == 0:
                raise CaribuSceneError(f"label {label}: triangles are lists of three (x, y, z) "
                                       f"points, got an array of shape {arr.shape}")
            if not np.all(np.isfinite(arr)):
                t = int(np.flatnonzero(~np.isfinite(arr).all(axis=(1, 2)))[0])
                raise CaribuSceneError(f"label {label}, triangle {t}: a coordinate is not "
                                       "finite")
            out[label] = arr
        return out

    def setLight(self, light) -> None:
        """Set the light sources: a list of ``(energy, (vx, vy, vz))`` or a ``.light`` file."""
        if isinstance(light, (str, Path)):
            from maizeviz.io.canestra import read_light

            light = read_light(light)
        if not isinstance(light, Sequence) or not light:
            raise CaribuSceneError("lights are a non-empty list of (energy, (vx, vy, vz))")
        out = []
        for k, source in enumerate(light):
            try:
                e, (vx, vy, vz) = source
                e, vx, vy, vz = float(e), float(vx), float(vy), float(vz)
            except (TypeError, ValueError):
                raise CaribuSceneError(f"light {k}: not (energy, (vx, vy, vz)): "
                                       f"{str(source)[:50]}") from None
            if not all(math.isfinite(v) for v in (e, vx, vy, vz)) or e < 0:
                raise CaribuSceneError(f"light {k}: energy {e:g} and direction must be finite, "
                                       "the energy >= 0")
            if vz >= 0:
                raise CaribuSceneError(f"light {k}: the direction ({vx:g}, {vy:g}, {vz:g}) does "
                                       "not come from above (vz must be < 0: the way light "
                                       "travels)")
            out.append((e, (vx, vy, vz)))
        self.light = out

    def _pattern(self, pattern) -> tuple[float, float, float, float]:
        if isinstance(pattern, (str, Path)):
            from maizeviz.io.canestra import read_pattern

            return read_pattern(pattern)
        try:
            flat = [float(v) for v in (sum(pattern, ()) if len(pattern) == 2 else pattern)]
        except (TypeError, ValueError):
            flat = []
        if len(flat) != 4 or not all(math.isfinite(v) for v in flat):
            raise CaribuSceneError(f"a pattern is (xmin, ymin, xmax, ymax), got "
                                   f"{str(pattern)[:50]}")
        x0, y0, x1, y1 = flat
        if x0 == x1 or y0 == y1:
            raise CaribuSceneError(f"the pattern {tuple(flat)} encloses no area")
        return min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1)

    def _optics(self, opt, soil_reflectance, scene_arg):
        labels = list(self.scene) if self.scene is not None else []
        material: dict[Any, dict[Any, Material]]
        if opt is None:
            bands = list(soil_reflectance) if soil_reflectance else [self.default_band]
            soil = dict(soil_reflectance) if soil_reflectance else \
                {self.default_band: self.default_soil_reflectance}
            material = {b: dict.fromkeys(labels, self.default_material) for b in bands}
        elif isinstance(opt, list):
            if not isinstance(scene_arg, (str, Path)):
                raise CaribuSceneError(".opt files go with a .can scene (their species are "
                                       "the labels' optical ids)")
            material, soil = _opt_files(opt, labels)
        elif isinstance(opt, Mapping) and opt:
            first = next(iter(opt.values()))
            if isinstance(first, Mapping):
                material = {b: dict(m) for b, m in opt.items()}
            else:
                material = {b: dict.fromkeys(labels, tuple(m)) for b, m in opt.items()}
            soil = self._soil(soil_reflectance, material)
        else:
            raise CaribuSceneError("opt is {band: {label: material}}, {band: material} or a "
                                   "list of .opt files")
        for band, mats in material.items():
            missing = [lab for lab in labels if lab not in mats]
            if missing:
                raise CaribuSceneError(f"band {band}: no material for label(s) "
                                       f"{', '.join(map(str, missing[:5]))}")
            for lab in labels:
                _material(band, lab, mats[lab])
            r = soil[band]
            if not (isinstance(r, (int, float)) and 0.0 <= float(r) <= 1.0):
                raise CaribuSceneError(f"band {band}: the soil reflectance must be in [0, 1], "
                                       f"got {r!r}")
        return material, soil

    def _soil(self, soil_reflectance, material) -> dict:
        if soil_reflectance is None:
            return dict.fromkeys(material, self.default_soil_reflectance)
        if isinstance(soil_reflectance, Mapping) and set(soil_reflectance) == set(material):
            return dict(soil_reflectance)
        raise CaribuSceneError("soil_reflectance is a {band: reflectance} dict with the bands "
                               f"of opt ({', '.join(map(str, material))})")

    # ------------------------------------------------------------------ Caribu's helpers
    def triangle_areas(self, convert: bool = True) -> np.ndarray:
        """(n,) areas of every triangle, labels in order; in m2 (``convert``) or scene units."""
        tri = self._triangles()[0]
        areas = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]),
                                     axis=1)
        return areas * self.conv_unit ** 2 if convert else areas

    def bbox(self):
        """``(xmin, ymin, zmin), (xmax, ymax, zmax)`` of the scene, in scene units."""
        tri = self._triangles()[0].reshape(-1, 3)
        return tuple(tri.min(axis=0)), tuple(tri.max(axis=0))

    def getIncidentEnergy(self):
        """``(Qi, Qem, Einc)``: the lights' horizontal energy summed, their energy normal to
        each source summed, and the energy over the pattern (None without one), as Caribu's."""
        nrj = [e for e, _ in self.light]
        cos = [abs(d[2]) / math.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2) for _, d in self.light]
        qi = float(sum(nrj))
        qem = float(sum(e / c for e, c in zip(nrj, cos)))
        einc = None
        if self.pattern is not None:
            x0, y0, x1, y1 = self.pattern
            einc = qi * abs((x1 - x0) * (y1 - y0)) * self.conv_unit ** 2
        return qi, qem, einc

    def getSoilEnergy(self):
        """``(Qi, Einc)``: the light reaching the soil per m2, and over the pattern, in the first
        band (after :meth:`run`, with ``soil_mesh``)."""
        if self.soil is None:
            raise CaribuSceneError("a soil should be added (soil_mesh) to report its energy")
        if not self.soil_aggregated:
            raise CaribuSceneError("run the scene before asking for the soil's energy")
        qi = next(iter(self.soil_aggregated.values()))["Ei"]
        x0, y0, x1, y1 = self.pattern                               # type: ignore[misc]
        return qi, qi * abs((x1 - x0) * (y1 - y0)) * self.conv_unit ** 2

    def _triangles(self) -> tuple[np.ndarray, list]:
        if self.scene is None:
            raise CaribuSceneError("the scene is empty: give triangles or a .can file")
        tri = np.concatenate(list(self.scene.values()))
        groups = [lab for lab, arr in self.scene.items() for _ in range(len(arr))]
        return tri, groups

    # ------------------------------------------------------------------ run
    def run(self, direct: bool = True, infinite: bool = False, d_sphere: float = 0.5,
            layers: int = 10, height: float | None = None, screen_size: int = 1536,
            screen_resolution: float | None = None, sensors=None, split_face: bool = False,
            simplify: bool = False):
        """Trace the lights through the scene (see the module docstring for what differs).

        Parameters
        ----------
        direct : first interception only (True) or every scattering (False)
        infinite : the scene repeats over the pattern
        d_sphere, layers, height, screen_resolution : Caribu's radiosity settings; no effect
        screen_size : Caribu's projection screen (pixels): sets the default ray density
        sensors : not traced (CaribuSceneError when given)
        split_face : also ``Ei_sup`` and ``Ei_inf``, the light reaching each side (the side
            the triangle's normal, by its vertex order, points to is ``sup``); direct only
        simplify : with one band, give ``{result: {label: ...}}`` without the band level

        Returns
        -------
        raw : dict
            ``{band: {"Eabs", "Ei", "area" (, "Ei_sup", "Ei_inf"): {label: [per triangle]}}}``;
            areas in m2, energies per m2 of triangle in the lights' unit.
        aggregated : dict
            The same per label: areas summed, energies area-weighted.
        """
        if sensors is not None:
            raise CaribuSceneError("virtual sensors are not traced here: use maizeviz's sensor "
                                   "planes (light --heights) or its virtual instruments")
        if split_face and not direct:
            raise CaribuSceneError("split_face is given for direct light only (direct=True)")
        if infinite and self.pattern is None:
            raise CaribuSceneError("an infinite canopy needs its pattern")
        tri, groups = self._triangles()
        traced = self._trace(tri, groups, direct, infinite, screen_size, split_face)
        results = ["Eabs", "Ei", "area"] + (["Ei_inf", "Ei_sup"] if split_face else [])
        raw: dict = {}
        aggregated: dict = {}
        for band, out in traced.items():
            raw[band], aggregated[band] = {}, {}
            area = out["area"]
            for key in results:
                raw[band][key] = _aggregate(out[key].tolist(), groups, list)
                if key == "area":
                    aggregated[band][key] = _aggregate(area.tolist(), groups, sum)
                else:
                    aggregated[band][key] = _aggregate(
                        list(zip(out[key].tolist(), area.tolist())), groups, _area_weighted)
        if simplify and len(raw) == 1:
            band = next(iter(raw))
            return raw[band], aggregated[band]
        return raw, aggregated

    def _trace(self, tri: np.ndarray, groups: list, direct: bool, infinite: bool,
               screen_size: int, split_face: bool) -> dict[str, dict[str, np.ndarray]]:
        from maizeviz.light.scene.embree_scenes import light_scene
        from maizeviz.light.trace.beam import Sampler
        from maizeviz.light.trace.optics import Optics
        from maizeviz.light.trace.scatter import scatter_beam

        cm = self.conv_unit * 100.0                       # cm per scene unit
        z0 = self.z_soil if self.z_soil is not None else float(tri[:, :, 2].min())
        if float(tri[:, :, 2].min()) < z0 - 1e-9 * max(1.0, abs(z0)):
            raise CaribuSceneError(f"triangles lie below the soil (z_soil = {z0:g}); the "
                                   "light is traced down to the soil")
        verts = (tri.reshape(-1, 3) - np.array([0.0, 0.0, z0])) * cm
        if infinite:
            x0, y0, x1, y1 = (v * cm for v in self.pattern)         # type: ignore[union-attr]
            verts = _into_pattern(verts, (x0, y0, x1, y1))
            plot = (x0, y0, x1, y1)
        faces = np.arange(len(verts)).reshape(-1, 3)
        canopy = _canopy(verts, faces, plot if infinite else None)
        t0 = time.perf_counter()
        scene = light_scene(canopy, periodic=infinite, block=False)
        self.seconds = {"build": time.perf_counter() - t0, "trace": 0.0}
        v = verts.reshape(-1, 3, 3)
        cross = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
        twice = np.linalg.norm(cross, axis=1)
        normals = cross / np.where(twice > 0, twice, 1.0)[:, None]
        area_m2 = 0.5 * twice * 1e-4
        top = float(verts[:, 2].max()) + 1.0
        nf = len(faces)
        out: dict[str, dict[str, np.ndarray]] = {}
        for b, (band, mats) in enumerate(self.material.items()):
            per_label = {lab: _material(band, lab, mats[lab]) for lab in self.scene}  # type: ignore[union-attr]
            if any(d for _, _, d in per_label.values()):
                note = (f"band {band}: materials whose two sides differ are traced with the "
                        "mean of their sides")
                if note not in self.notes:
                    self.notes.append(note)
            rho = np.array([per_label[g][0] for g in groups])
            tau = np.array([per_label[g][1] for g in groups])
            # the soil reflects in an infinite canopy (Caribu's mixed radiosity) or where a soil
            # is added; an isolated scene has none (light passing it is lost)
            soil_reflects = not direct and (infinite or self.soil is not None)
            ground = float(self.soil_reflectance[band]) if soil_reflects else 0.0
            optics = Optics(float(rho.mean()), float(tau.mean()), ground)
            incident = np.zeros(nf)
            sup, inf = np.zeros(nf), np.zeros(nf)
            soil_w = 0.0
            parts = dict.fromkeys(("incident", "leaves", "soil", "top", "sides", "unresolved"),
                                  0.0)
            for k, (energy, d) in enumerate(self.light):
                toward = -np.asarray(d, np.float64) / math.sqrt(sum(c * c for c in d))
                rect = plot if infinite else _shadow_rect(verts, toward)
                bounds = rect if infinite else _union(rect, verts)
                density = self._density(rect, screen_size)
                smp = Sampler(scene, rect, density, np.zeros(0), infinite, bounds, top, nf)
                t0 = time.perf_counter()
                tally, _ = scatter_beam(smp, toward, optics, normals,
                                        0 if direct else SCATTER_DEPTH, SCATTER_THRESHOLD,
                                        self.seed + 7919 * k + 104729 * b, self.threads,
                                        leaf_optics=(rho, tau))
                self.seconds["trace"] += time.perf_counter() - t0
                per_ray = energy * smp.ray_area_cm2 * 1e-4        # energy a ray carries
                got = tally.per_triangle(nf, per_ray)
                incident += got
                if split_face:
                    lit_sup = normals @ toward > 0
                    sup += np.where(lit_sup, got, 0.0)
                    inf += np.where(lit_sup, 0.0, got)
                kept = 1.0 - ground
                soil_w += (tally.ground / kept if kept > 0 else 0.0) * per_ray
                parts["incident"] += energy * (rect[2] - rect[0]) * (rect[3] - rect[1]) * 1e-4
                parts["leaves"] += float((got * (1.0 - rho - tau)).sum())
                for name in ("top", "sides", "unresolved"):
                    parts[name] += float(getattr(tally, name)) * per_ray
                parts["soil"] += float(tally.ground) * per_ray
            self.balance[band] = parts
            with np.errstate(divide="ignore", invalid="ignore"):
                ei = np.where(area_m2 > 0, incident / area_m2, 0.0)
                res = {"Ei": ei, "Eabs": ei * (1.0 - rho - tau), "area": area_m2}
                if split_face:
                    res["Ei_sup"] = np.where(area_m2 > 0, sup / area_m2, 0.0)
                    res["Ei_inf"] = np.where(area_m2 > 0, inf / area_m2, 0.0)
            out[band] = res
            if self.soil is not None:
                x0, y0, x1, y1 = self.pattern                          # type: ignore[misc]
                soil_area = abs((x1 - x0) * (y1 - y0)) * self.conv_unit ** 2
                ei_soil = soil_w / soil_area
                absorbed = ei_soil * (1.0 - float(self.soil_reflectance[band]))
                self.soil_raw[band] = {"Ei": [float(ei_soil)], "Eabs": [float(absorbed)],
                                       "area": [float(soil_area)]}
                self.soil_aggregated[band] = {"Ei": float(ei_soil), "Eabs": float(absorbed),
                                              "area": float(soil_area)}
        return out

    def _density(self, rect, screen_size: int) -> float:
        x0, y0, x1, y1 = rect
        area = (x1 - x0) * (y1 - y0)
        if self.density is not None:
            density = float(self.density)
            if not (math.isfinite(density) and density > 0):
                raise CaribuSceneError(f"the ray density must be > 0 rays per cm2, got "
                                       f"{self.density!r}")
            if density * area > 50 * MAX_RAYS_PER_LIGHT:
                raise CaribuSceneError(f"{density:g} rays per cm2 over {area:,.0f} cm2 is "
                                       f"{density * area:,.0f} rays a light: lower the density")
            return density
        pixel = max(x1 - x0, y1 - y0) / max(int(screen_size), 1)
        return min(1.0 / pixel ** 2, MAX_RAYS_PER_LIGHT / area)


def _into_pattern(verts: np.ndarray, plot) -> np.ndarray:
    """Triangles (3k, 3) cm moved by whole periods so that their centres lie in the pattern,
    as Caribu's periodise does (the light of an infinite canopy does not depend on which copy
    of a triangle is traced)."""
    x0, y0, x1, y1 = plot
    v = verts.reshape(-1, 3, 3).copy()
    centre = v.mean(axis=1)
    for axis, lo, size in ((0, x0, x1 - x0), (1, y0, y1 - y0)):
        shift = np.floor((centre[:, axis] - lo) / size) * size
        v[:, :, axis] -= shift[:, None]
    return v.reshape(-1, 3)


def _shadow_rect(verts: np.ndarray, toward: np.ndarray) -> tuple[float, float, float, float]:
    """The ground rectangle (cm) whose rays toward the light cross every triangle: the
    triangles' shadow on the ground, padded by a hundredth."""
    xy = verts[:, :2] - verts[:, 2:3] * (toward[:2] / toward[2])
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    pad = 0.01 * max(float((hi - lo).max()), 1.0)
    return float(lo[0] - pad), float(lo[1] - pad), float(hi[0] + pad), float(hi[1] + pad)


def _union(rect, verts: np.ndarray) -> tuple[float, float, float, float]:
    lo, hi = verts[:, :2].min(axis=0), verts[:, :2].max(axis=0)
    return (min(rect[0], float(lo[0])) - 1.0, min(rect[1], float(lo[1])) - 1.0,
            max(rect[2], float(hi[0])) + 1.0, max(rect[3], float(hi[1])) + 1.0)


def _canopy(verts: np.ndarray, faces: np.ndarray, plot):
    """A one-plant canopy of the scene's triangles (cm), for the light's scene builder."""
    from maizeviz.canopy.build import Canopy
    from maizeviz.canopy.layout import CanopyLayout, Placement

    if plot is None:
        lo, hi = verts[:, :2].min(axis=0), verts[:, :2].max(axis=0)
        plot = (float(lo[0]) - 1.0, float(lo[1]) - 1.0, float(hi[0]) + 1.0, float(hi[1]) + 1.0)
    x0, y0, x1, y1 = plot
    cells = np.array([plot], np.float64)
    layout = CanopyLayout((Placement(1, (x0 + x1) / 2, (y0 + y1) / 2),), cells, x1 - x0,
                          y1 - y0, 0.0, cells.copy(), (), (x1 - x0) * (y1 - y0), "mesh")
    return Canopy.from_triangles(verts, faces, layout, level="caribu")
