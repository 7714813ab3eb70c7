"""One light engine over a canopy: its Embree scenes built once, every sun, sky and day traced
on them.

A scene (:func:`~maizeviz.light.scene.embree_scenes.light_scene`) costs about as much as tracing one
sun, and is the same for every direction traced through the canopy; an engine builds it when a
request first needs it (one for an open field, one with the overhanging leaves copied for a
periodic field) and keeps it. The command line, the sweep's workers and the app's core process
all trace through an engine; so does the package's façade (``maizeviz.LightEngine``).

The engine also keeps the last sky light it traced, so that a day traced with the same sky and
sampling reuses it (the sky of a period does not depend on the day).

Example
-------
>>> engine = LightEngine(canopy, periodic=True)                      # doctest: +SKIP
>>> noon = engine.sun(date="2005-08-01", time="12:00", lat=39.9, lon=116.4,
...                   tz="Asia/Shanghai")                                # doctest: +SKIP
>>> noon.table()                                                     # doctest: +SKIP
"""

from __future__ import annotations

import threading
import time
from dataclasses import fields as dataclass_fields
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.light.results.absorbed import AbsorbedLight, AbsorbedPeriod
from maizeviz.light.results.diffuse import PeriodLight, SkyLight
from maizeviz.light.results.direct import LightResult
from maizeviz.light.scene.embree_scenes import light_scene
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.sources.irradiance import (
    DEFAULT_LINKE_TURBIDITY,
    DEFAULT_PAR_UMOL_PER_J,
    Period,
)
from maizeviz.light.sources.perez import PEREZ_MODELS, perez_split
from maizeviz.light.sources.sky import Sky, make_sky
from maizeviz.light.sources.sun import Sun, sun_at
from maizeviz.light.trace.absorption import (
    SKY_PASSES,
    absorbed_light,
    absorbed_period,
    check_absorbed,
)
from maizeviz.light.trace.beam import trace_light
from maizeviz.light.trace.directions import trace_period, trace_sky
from maizeviz.light.trace.optics import SHORTWAVE_SHARE, Optics, optics_for
from maizeviz.light.trace.scatter import DEFAULT_DEPTH, DEFAULT_THRESHOLD
from maizeviz.mesh.raytrace import RayScene
from maizeviz.progress import ProgressCallback

if TYPE_CHECKING:
    from maizeviz.light.results.assimilation import Assimilation
    from maizeviz.photosynthesis.split import LeafModel


class LightEngine:
    """Sun, sky, day and absorbed light through one canopy, on Embree scenes built once.

    A scene costs about as much as tracing one sun and is the same for every direction: the
    engine builds it when a request first needs it (one for an open field, one for a
    periodic field) and keeps it, and keeps the last sky light it traced for the days that
    follow. It only keeps and dispatches: the tracing is :mod:`maizeviz.light.trace`'s.

    Parameters
    ----------
    canopy : Canopy
        From :func:`maizeviz.build_canopy`.
    sampling : Sampling, optional
        Sensor heights [cm], ray density [cm-2], sample rectangle [cm], periodic field and
        threads shared by every request (default: ``Sampling()``).
    with_stalks : bool
        Stalks intercept and scatter light like any organ (the default; their triangles
        follow the leaves' in per-triangle results, their share is reported apart:
        :mod:`maizeviz.light.results.stalks`); False: the paper's leaves-only canopy.
    **fields
        Fields of :class:`~maizeviz.light.scene.request.Sampling` replacing the sampling's:
        ``heights_cm``, ``density``, ``rect``, ``periodic``, ``threads``
        (``LightEngine(canopy, periodic=True, density=2.0)``).

    Attributes
    ----------
    build_seconds : dict of bool to float
        Seconds spent building the scene of an open (False) and a periodic (True) field [s].

    Notes
    -----
    Thread-safe: several threads may trace through one engine (a sweep worker's threads); a
    scene is built by the first thread that needs it.

    References
    ----------
    Wald, I., Woop, S., Benthin, C., Johnson, G. S. & Ernst, M. (2014). Embree: a kernel
    framework for efficient CPU ray tracing. ACM Transactions on Graphics 33(4), 143.
    https://doi.org/10.1145/2601097.2601199
    """

    def __init__(self, canopy: Canopy, sampling: Sampling | None = None, *,
                 with_stalks: bool = True, **fields):
        self.canopy = canopy
        self.sampling = self._sampling(sampling or Sampling(), fields)
        self.with_stalks = bool(with_stalks)
        self.build_seconds: dict[bool, float] = {}
        self._scenes: dict[bool, RayScene] = {}
        self._lock = threading.Lock()
        self._sky: tuple[tuple, SkyLight] | None = None
        self._normals_kept: np.ndarray | None = None

    @staticmethod
    def _sampling(base: Sampling, changes: dict) -> Sampling:
        known = {f.name for f in dataclass_fields(Sampling)}
        unknown = sorted(set(changes) - known)
        if unknown:
            raise TypeError(f"unknown sampling field(s) {', '.join(unknown)} (known: "
                            f"{', '.join(sorted(known))})")
        if "heights_cm" in changes:
            changes = {**changes, "heights_cm": tuple(float(h) for h in changes["heights_cm"])}
        return replace(base, **changes) if changes else base

    # ------------------------------------------------------------------ scenes
    def scene(self, periodic: bool | None = None) -> RayScene:
        """The Embree scene of an open or a periodic field, built on first use and kept.

        Parameters
        ----------
        periodic : bool, optional
            A periodic field's scene (its overhanging leaves copied across the plot); None: the
            engine's sampling says.

        Returns
        -------
        RayScene
            The scene every direction of that field is traced on.
        """
        key = self.sampling.periodic if periodic is None else bool(periodic)
        return self._scene_and_build(key)[0]

    def _scene_and_build(self, periodic: bool) -> tuple[RayScene, float]:
        """The scene, and the seconds spent building it in this call (0 when kept, also for
        a thread that waited while another built it)."""
        with self._lock:
            if periodic in self._scenes:
                return self._scenes[periodic], 0.0
            t0 = time.perf_counter()
            self._scenes[periodic] = light_scene(self.canopy, self.with_stalks, periodic)
            self.build_seconds[periodic] = time.perf_counter() - t0
            return self._scenes[periodic], self.build_seconds[periodic]

    # ------------------------------------------------------------------ light
    def sun(self, sun: Sun | None = None, *, date: str | None = None, time: str | None = None,
            lat: float | None = None, lon: float | None = None, tz: str | None = None,
            solar_noon: bool = False, altitude: float = 0.0, zenith: float | None = None,
            azimuth: float | None = None, classes: bool = True, sunlit: bool = True,
            sampling: Sampling | None = None,
            progress: ProgressCallback | None = None, **fields) -> LightResult:
        """Direct sunlight: transmission by height and the hit classes of one sun.

        Parameters
        ----------
        sun : Sun, optional
            The sun's angles; else ``zenith`` and ``azimuth``, or a place and time.
        date : str, optional
            The local date, "YYYY-MM-DD".
        time : str, optional
            The local clock time "HH:MM[:SS]" (:mod:`maizeviz.light.sources.clock`).
        lat : float, optional
            Latitude [deg north].
        lon : float, optional
            Longitude [deg east].
        tz : str, optional
            IANA time zone of ``time`` ("Asia/Shanghai"); None: UTC or the time's offset.
        solar_noon : bool
            The day's true solar noon instead of ``time``.
        altitude : float
            Height of the place above sea level [m].
        zenith : float, optional
            The sun's angle from the vertical [deg].
        azimuth : float, optional
            The sun's azimuth, clockwise from north [deg] (default 180 with ``zenith``).
        classes : bool
            Also trace second hits and per-triangle counts (the hit classes).
        sunlit : bool
            With the hit classes, also sample each triangle's sunlit area from the triangle
            toward the sun, for the leaf and plant tables (bounded and unbiased; about the
            trace's time again); False: the tables read the rays' count capped at each leaf's
            area (the command line samples only for ``--leaf-light`` or ``--plant-light``).
        sampling : Sampling, optional
            Instead of the engine's.
        progress : callable, optional
            ``progress(done, total)`` after each chunk of rays; returning ``False`` cancels with
            InterruptedError.
        **fields
            Fields of :class:`~maizeviz.light.scene.request.Sampling` replacing the sampling's
            (``heights_cm=(0, 100)``).

        Returns
        -------
        LightResult
            ``transmission`` (H,) in [0, 1] at ``heights_cm`` (H,) [cm]; ``table()`` as a
            DataFrame; ``seconds["build"]`` is the scene's build time when this call built it [s].

        References
        ----------
        Reda, I. & Andreas, A. (2004). Solar position algorithm for solar radiation
        applications. Solar Energy 76(5), 577-589. https://doi.org/10.1016/j.solener.2003.12.003
        """
        if sun is None:
            if zenith is not None:
                sun = Sun(float(zenith), float(azimuth if azimuth is not None else 180.0))
            else:
                if date is None or lat is None or lon is None:
                    raise TypeError("give a Sun, zenith and azimuth, or date, time, lat and "
                                    "lon")
                sun = sun_at(date, time, lat, lon, tz, solar_noon, altitude)
        smp = self._sampling(sampling or self.sampling, fields)
        scene, build_s = self._scene_and_build(smp.periodic)
        result = trace_light(self.canopy, LightRequest(sun, smp, classes),
                             progress, self.with_stalks, scene)
        result.seconds["build"] = build_s
        if sunlit and result.first_hits is not None:
            result = _with_sampled_sunlit(self.canopy, scene, result, self._normals(),
                                          self.with_stalks)
        return result.with_canopy(self.canopy)

    def sky(self, sky: Sky | str = "soc", directions: int = 46, split: str = "auto", *,
            sampling: Sampling | None = None, progress: ProgressCallback | None = None,
            bin_cm: float = 5.0, **fields) -> SkyLight:
        """Diffuse light under a sky: every sky direction traced like the sun.

        Parameters
        ----------
        sky : Sky or str
            A :class:`~maizeviz.light.sources.sky.Sky`, or its kind: "soc" (standard overcast)
            or "uoc" (uniform overcast).
        directions : int
            Directions of a sky given by its kind (46: den Dulk's turtle).
        split : {"auto", "turtle", "tregenza", "equal"}
            How a sky given by its kind is cut into directions.
        sampling : Sampling, optional
            Instead of the engine's.
        progress : callable, optional
            ``progress(done, total)`` after each direction; returning ``False`` cancels with
            InterruptedError.
        bin_cm : float
            Bin edge of the transmission maps [cm].
        **fields
            Fields of :class:`~maizeviz.light.scene.request.Sampling` replacing the sampling's.

        Returns
        -------
        SkyLight
            ``transmission`` (H,): the share of the horizontal diffuse irradiance reaching each
            height; ``table()`` as a DataFrame.

        References
        ----------
        Moon, P. & Spencer, D. E. (1942). Illumination from a non-uniform sky. Illuminating
        Engineering 37, 707-726 (the standard overcast sky; no DOI).
        Chelle, M. & Andrieu, B. (1998). The nested radiosity model for the distribution of
        light within plant canopies. Ecological Modelling 111(1), 75-91 (turtle skies in
        Caribu). https://doi.org/10.1016/S0304-3800(98)00100-8
        """
        sky_obj = sky if isinstance(sky, Sky) else make_sky(sky, directions, split)
        smp = self._sampling(sampling or self.sampling, fields)
        scene, build_s = self._scene_and_build(smp.periodic)
        light = trace_sky(self.canopy, sky_obj, smp, progress, self.with_stalks, scene, bin_cm)
        light.seconds["build"] = build_s
        light = light.with_canopy(self.canopy)
        self._sky = (_sky_key(sky_obj, smp, bin_cm), light)
        return light

    def day(self, period: Period | None = None, *, date: str | None = None,
            lat: float | None = None, lon: float | None = None, tz: str = "UTC",
            step_min: float = 30.0, start: str | None = None, end: str | None = None,
            altitude: float = 0.0, linke: float = DEFAULT_LINKE_TURBIDITY,
            par_factor: float = DEFAULT_PAR_UMOL_PER_J, sky: Sky | str | None = None,
            sampling: Sampling | None = None, progress: ProgressCallback | None = None,
            bin_cm: float = 5.0, directions: int = 46, **fields) -> PeriodLight:
        """Light over a day (or any period): the sun traced at every time step, the sky once.

        Parameters
        ----------
        period : Period, optional
            From :func:`~maizeviz.light.sources.irradiance.clear_sky_period` or
            :func:`~maizeviz.light.sources.irradiance.weather_period`; else a clear day from
            ``date``, ``lat``, ``lon`` and the rest.
        date : str, optional
            The local date, "YYYY-MM-DD".
        lat : float, optional
            Latitude [deg north].
        lon : float, optional
            Longitude [deg east].
        tz : str
            IANA time zone of the day.
        step_min : float
            Time step of a clear day [min].
        start, end : str, optional
            Local clock times "HH:MM" bounding the period (None: the whole day).
        altitude : float
            Height of the place above sea level [m].
        linke : float
            Linke turbidity of the clear sky [-].
        par_factor : float
            PAR photons per joule of shortwave [umol J-1].
        sky : Sky or str, optional
            The sky of the diffuse part (default: standard overcast of ``directions``); the sky
            light this engine last traced is reused when its sky, sampling and bins match.
            "perez" (or "perez-driesse") splits each step's diffuse light by Perez's anisotropic
            model (:mod:`maizeviz.light.sources.perez`): its circumsolar part traced with the
            sun, its isotropic part over a uniform sky.
        sampling : Sampling, optional
            Instead of the engine's.
        progress : callable, optional
            ``progress(done, total)`` after each direction (sky directions first, then the time
            steps); returning ``False`` cancels with InterruptedError.
        bin_cm : float
            Bin edge of the maps [cm].
        directions : int
            Directions of a sky given by its kind (46: den Dulk's turtle).
        **fields
            Fields of :class:`~maizeviz.light.scene.request.Sampling` replacing the sampling's.

        Returns
        -------
        PeriodLight
            PAR doses [mol m-2 of ground] (``par_incident_mol_m2``, ``par_transmitted_mol_m2``
            (H,), ...); ``table()`` as a DataFrame.

        References
        ----------
        Ineichen, P. & Perez, R. (2002). A new airmass independent formulation for the Linke
        turbidity coefficient. Solar Energy 73(3), 151-157.
        https://doi.org/10.1016/S0038-092X(02)00045-2
        """
        from maizeviz.light.sources.irradiance import clear_sky_period

        if period is None:
            if date is None or lat is None or lon is None:
                raise TypeError("give a Period, or date, lat and lon")
            period = clear_sky_period(date, lat, lon, tz, step_min, start, end, altitude,
                                      linke, par_factor)
        smp = self._sampling(sampling or self.sampling, fields)
        model = str(sky).strip().lower() if isinstance(sky, str) else ""
        split = perez_split(period, model) if model in PEREZ_MODELS else None
        sky_obj = sky if isinstance(sky, Sky) else \
            make_sky("uoc" if split is not None else (sky or "soc"), directions)
        diffuse: Sky | SkyLight = self.kept_sky(sky_obj, smp, bin_cm) or sky_obj
        scene, build_s = self._scene_and_build(smp.periodic)
        light = trace_period(self.canopy, period, smp, diffuse, progress, self.with_stalks,
                             scene, bin_cm, split)
        light.seconds["build"] = build_s
        if light.sky is not None:
            self._sky = (_sky_key(sky_obj, smp, bin_cm), light.sky)
        return light.with_canopy(self.canopy)

    def kept_sky(self, sky: Sky, sampling: Sampling | None = None,
                 bin_cm: float = 5.0) -> SkyLight | None:
        """The sky light this engine last traced, if traced with this sky, sampling and bins.

        Parameters
        ----------
        sky : Sky
            The sky asked for.
        sampling : Sampling, optional
            The sampling asked for (threads aside); None: the engine's.
        bin_cm : float
            Bin edge of the maps [cm].

        Returns
        -------
        SkyLight or None
            What :meth:`day` reuses; None when the last sky light was traced otherwise.
        """
        smp = sampling or self.sampling
        if self._sky is not None and self._sky[0] == _sky_key(sky, smp, bin_cm):
            return self._sky[1]
        return None

    # ------------------------------------------------------------------ scattering
    def absorbed(self, sun: Sun | None = None, *, band: str = "par",
                 optics: Optics | None = None, direct_w_m2: float | None = None,
                 diffuse_w_m2: float = 0.0, sky: Sky | str = "soc", directions: int = 46,
                 depth: int = DEFAULT_DEPTH, threshold: float = DEFAULT_THRESHOLD,
                 seed: int = 0, sampling: Sampling | None = None,
                 progress: ProgressCallback | None = None, zenith: float | None = None,
                 azimuth: float | None = None, date: str | None = None,
                 time: str | None = None, lat: float | None = None, lon: float | None = None,
                 tz: str | None = None, sky_passes: int = SKY_PASSES,
                 **fields) -> AbsorbedLight:
        """Light absorbed by leaves and ground in one band, with scattering.

        The sun's direct beam and, when ``diffuse_w_m2`` > 0, the diffuse light of a sky, each
        followed through the canopy (:func:`maizeviz.light.trace.absorption.absorbed_light`).

        Parameters
        ----------
        sun : Sun, optional
            The sun's angles; else ``zenith`` and ``azimuth``, or a place and time as
            :meth:`sun`.
        band : {"par", "nir"}
            The waveband.
        optics : Optics, optional
            The band's leaf and soil optics (default
            :data:`maizeviz.light.trace.optics.DEFAULT_OPTICS`).
        direct_w_m2 : float, optional
            The band's direct irradiance on a horizontal plane above the canopy [W m-2]
            (default: the band's share of 1000 W m-2 of shortwave, 480 in PAR).
        diffuse_w_m2 : float
            The band's diffuse irradiance on a horizontal plane [W m-2], spread over ``sky``.
        sky : Sky or str
            The diffuse light's sky, or its kind.
        directions : int
            Directions of a sky given by its kind.
        depth : int
            Most scatterings followed per ray.
        threshold : float
            Share of the incident power still travelling below which tracing stops [-].
        seed : int
            Seed of the Monte Carlo scattering (the same seed, the same result).
        sampling : Sampling, optional
            Instead of the engine's.
        progress : callable, optional
            ``progress(done, total)`` after each beam; returning ``False`` cancels.
        zenith : float, optional
            The sun's angle from the vertical [deg].
        azimuth : float, optional
            The sun's azimuth, clockwise from north [deg].
        date : str, optional
            The local date, "YYYY-MM-DD".
        time : str, optional
            The local clock time "HH:MM".
        lat : float, optional
            Latitude [deg north].
        lon : float, optional
            Longitude [deg east].
        tz : str, optional
            IANA time zone of ``time``.
        sky_passes : int
            With leaves or soil that scatter, in a periodic field, the diffuse light is traced as
            one beam whose rays each take a sky direction of their own
            (:func:`~maizeviz.light.trace.scatter.scatter_sky`), this many rays per grid cell (0:
            every sky direction traced over the whole grid, as black leaves are).
        **fields
            Fields of :class:`~maizeviz.light.scene.request.Sampling` replacing the sampling's.

        Returns
        -------
        AbsorbedLight
            ``balance`` [W m-2 of ground], the W absorbed per triangle, ``table("plant",
            canopy)``, ``absorbed_leaves_error`` (the Monte Carlo standard error).

        References
        ----------
        Bailey, B. N. (2018). A reverse ray-tracing method for modelling the net radiative flux
        in leaf-resolving plant canopy simulations. Ecological Modelling 368, 233-245.
        https://doi.org/10.1016/j.ecolmodel.2017.11.022
        """
        from maizeviz.light.scene.request import check_sampling
        from maizeviz.light.trace.beam import sampler

        opt = optics if optics is not None else optics_for(band)
        if sun is None:
            if zenith is not None:
                sun = Sun(float(zenith), float(azimuth if azimuth is not None else 180.0))
            elif date is not None and lat is not None and lon is not None:
                sun = sun_at(date, time, lat, lon, tz)
        direct = 1000.0 * SHORTWAVE_SHARE[opt.band] if direct_w_m2 is None else direct_w_m2
        check_absorbed(direct, diffuse_w_m2, depth, threshold)
        if sun is None and (direct > 0 or diffuse_w_m2 == 0):
            raise TypeError("give a Sun, zenith and azimuth, or date, time, lat and lon; or "
                            "direct_w_m2=0 with a diffuse irradiance")
        smp_req = self._sampling(sampling or self.sampling, fields)
        rect, _ = check_sampling(self.canopy, smp_req)
        scene, build_s = self._scene_and_build(smp_req.periodic)
        smp = sampler(self.canopy, scene, rect, smp_req.density, smp_req.heights_cm,
                      smp_req.periodic, self.with_stalks)
        sky_obj = None
        if diffuse_w_m2 > 0:
            sky_obj = sky if isinstance(sky, Sky) else make_sky(sky, directions)
        return absorbed_light(self.canopy, smp, self._normals(), opt, sun, direct,
                              diffuse_w_m2, sky_obj, depth, threshold, seed, smp_req.threads,
                              progress, build_s, sky_passes).with_canopy(self.canopy)

    def photosynthesis(self, sun: Sun | None = None, *, model: LeafModel | str = "c4",
                       temperature_c: float = 25.0, **absorbed: Any) -> Assimilation:
        """Gross CO2 assimilation of the leaves under one sun (and sky).

        Absorbed PAR (:meth:`absorbed`, same keywords) through a leaf model, each triangle's
        sunlit and shaded parts at their own light (:mod:`maizeviz.light.results.assimilation`).

        Parameters
        ----------
        sun : Sun, optional
            The sun, as :meth:`absorbed`.
        model : {"c4", "wofost"} or LeafModel
            The leaf model (:func:`maizeviz.photosynthesis.split.leaf_model` for other
            parameters).
        temperature_c : float
            Air (leaf) temperature [degC].
        **absorbed
            Keywords of :meth:`absorbed` (``zenith=``, ``diffuse_w_m2=``, ``optics=``...).

        Returns
        -------
        Assimilation
            ``canopy_gross_umol_m2_s`` (per m2 of ground), ``canopy_gross_kg_co2_ha_h``, their
            standard errors; ``table("plant")`` as a DataFrame (it knows its canopy).

        References
        ----------
        Collatz, G. J., Ribas-Carbo, M. & Berry, J. A. (1992). Coupled photosynthesis-stomatal
        conductance model for leaves of C4 plants. Australian Journal of Plant Physiology 19,
        519-538. https://doi.org/10.1071/PP9920519
        Spitters, C. J. T., Toussaint, H. A. J. M. & Goudriaan, J. (1986). Separating the diffuse
        and direct component of global radiation and its implications for modeling canopy
        photosynthesis. Part II. Calculation of canopy photosynthesis. Agricultural and Forest
        Meteorology 38, 231-242.
        https://doi.org/10.1016/0168-1923(86)90061-4
        """
        from maizeviz.light.results.assimilation import assimilate
        from maizeviz.photosynthesis.split import as_leaf_model

        leaf = as_leaf_model(model)
        light = self.absorbed(sun, band="par", **absorbed)
        return assimilate(self.canopy, light, leaf, temperature_c)

    def absorbed_day(self, period: Period | None = None, *, band: str = "par",
                     optics: Optics | None = None, sky: Sky | str = "soc",
                     directions: int = 46, depth: int = DEFAULT_DEPTH,
                     threshold: float = DEFAULT_THRESHOLD, seed: int = 0,
                     sampling: Sampling | None = None,
                     progress: ProgressCallback | None = None, date: str | None = None,
                     lat: float | None = None, lon: float | None = None, tz: str = "UTC",
                     step_min: float = 30.0, start: str | None = None,
                     end: str | None = None, altitude: float = 0.0,
                     linke: float = DEFAULT_LINKE_TURBIDITY,
                     par_factor: float = DEFAULT_PAR_UMOL_PER_J,
                     photosynthesis: LeafModel | str | None = None,
                     temperature_c: float | np.ndarray = 25.0, **fields: Any) -> AbsorbedPeriod:
        """Light absorbed with scattering over a period (a day), in one band.

        Each step's sun with the band's share of its direct irradiance, and the diffuse part
        spread over ``sky``, traced once per W m-2 and scaled by each step's diffuse irradiance
        (the transport is linear in the light put in;
        :func:`maizeviz.light.trace.absorption.absorbed_period`).

        Parameters
        ----------
        period : Period, optional
            The period; else a clear day from ``date``, ``lat``, ``lon`` and the rest, as
            :meth:`day`. Its PAR factor also sets the band's share of the shortwave
            (:func:`~maizeviz.light.trace.optics.band_share`: 0.48 for PAR by default), so
            that black leaves absorb exactly the PAR the same day intercepts.
        band : {"par", "nir"}
            The waveband.
        optics : Optics, optional
            The band's leaf and soil optics.
        sky : Sky or str
            The diffuse light's sky (default: standard overcast); "perez" (or "perez-driesse")
            splits each step's diffuse light by Perez's model: its circumsolar part added to that
            step's direct beam, the rest from a uniform sky.
        directions : int
            Directions of a sky given by its kind.
        depth : int
            Most scatterings followed per ray.
        threshold : float
            Share of the incident power still travelling below which tracing stops [-].
        seed : int
            Seed of the Monte Carlo scattering.
        sampling : Sampling, optional
            Instead of the engine's.
        progress : callable, optional
            Called after the sky and after each step; returning ``False`` cancels.
        date : str, optional
            The local date, "YYYY-MM-DD".
        lat : float, optional
            Latitude [deg north].
        lon : float, optional
            Longitude [deg east].
        tz : str
            IANA time zone of the day.
        step_min : float
            Time step of a clear day [min].
        start, end : str, optional
            Local clock times "HH:MM" bounding the period.
        altitude : float
            Height of the place above sea level [m].
        linke : float
            Linke turbidity of the clear sky [-].
        par_factor : float
            PAR photons per joule of shortwave [umol J-1].
        photosynthesis : LeafModel or {"c4", "wofost"}, optional
            Also the leaves' gross CO2 assimilation at every step (PAR only,
            :func:`maizeviz.light.results.assimilation.assimilate`), added up over the period
            (``AbsorbedPeriod.assimilation``).
        temperature_c : float or numpy.ndarray
            Air (leaf) temperature at each step [degC] (one, or (n,)); a period read from a
            weather file with an air temperature column gives its own, these filling the steps it
            lacks (NaN).
        **fields
            Fields of :class:`~maizeviz.light.scene.request.Sampling` replacing the sampling's.

        Returns
        -------
        AbsorbedPeriod
            ``balance`` [MJ m-2 of ground], the J absorbed per triangle,
            ``absorbed_leaves_mol_m2`` (PAR), ``table("plant", canopy)``.

        References
        ----------
        Bailey, B. N. (2018). A reverse ray-tracing method for modelling the net radiative flux
        in leaf-resolving plant canopy simulations. Ecological Modelling 368, 233-245.
        https://doi.org/10.1016/j.ecolmodel.2017.11.022
        """
        from functools import partial

        from maizeviz.light.sources.irradiance import clear_sky_period
        from maizeviz.photosynthesis.split import as_leaf_model

        if period is None:
            if date is None or lat is None or lon is None:
                raise TypeError("give a Period, or date, lat and lon")
            period = clear_sky_period(date, lat, lon, tz, step_min, start, end, altitude,
                                      linke, par_factor)
        opt = optics if optics is not None else optics_for(band)
        one = partial(self.absorbed, band=opt.band, optics=opt, directions=directions,
                      depth=depth, threshold=threshold, seed=seed, sampling=sampling, **fields)
        leaf = None if photosynthesis is None else as_leaf_model(photosynthesis)
        return absorbed_period(period, opt, sky, one, progress, self.canopy, leaf,
                               temperature_c).with_canopy(self.canopy)

    def _normals(self):
        """Unit normals (F, 3) of the scene's leaf triangles, then its stalks' if traced
        (computed once)."""
        import numpy as np

        from maizeviz.mesh.tessellate import triangle_areas_normals

        if self._normals_kept is not None:
            return self._normals_kept
        c = self.canopy
        normals = triangle_areas_normals(c.vertices, c.faces)[1]
        if self.with_stalks:
            normals = np.vstack([normals, triangle_areas_normals(c.stalk_vertices,
                                                                 c.stalk_faces)[1]])
        self._normals_kept = normals
        return normals


#: Seed of the points a sun's sunlit areas are sampled from (the same tables every run).
SUNLIT_SEED = 0


def _with_sampled_sunlit(canopy: Canopy, scene: RayScene, result: LightResult,
                         normals: np.ndarray, with_stalks: bool) -> LightResult:
    """``result`` with the sunlit area of every scene triangle sampled from the triangle
    toward the sun (:func:`~maizeviz.light.trace.sunlit.sunlit_share`, as the absorbed
    light's direct beam): bounded by each triangle's area and unbiased, where the rays'
    count over a small or grazing triangle is unbiased but unbounded (the hit-class tables
    clipped it, which biased their sums low)."""
    from time import perf_counter

    from maizeviz.light.trace.beam import sampler
    from maizeviz.light.trace.sunlit import geometry, sunlit_share

    t0 = perf_counter()
    smp = sampler(canopy, scene, result.rect, result.density, result.heights_cm,
                  result.periodic, with_stalks)
    share = sunlit_share(smp, canopy, normals, np.asarray(result.direction, np.float64),
                         SUNLIT_SEED)
    sunlit = share.fraction * geometry(canopy, len(normals)).area_cm2
    seconds = dict(result.seconds, sunlit=perf_counter() - t0)
    return replace(result, triangle_sunlit_cm2=sunlit, seconds=seconds)


def _sky_key(sky: Sky, s: Sampling, bin_cm: float) -> tuple:
    """What makes a traced sky light reusable: the sky's directions and weights and the
    sampling (threads aside)."""
    return (sky.kind, sky.split, tuple(map(float, sky.zenith_deg)),
            tuple(map(float, sky.azimuth_deg)), tuple(map(float, sky.weights)),
            tuple(float(h) for h in s.heights_cm), float(s.density), s.rect, bool(s.periodic),
            float(bin_cm))
