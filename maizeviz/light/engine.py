"""One light engine over a canopy: its Embree scenes built once, every sun, sky and day traced
on them.

A scene (:func:`~maizeviz.light.scene.scenes.light_scene`) costs about as much as tracing one
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
from dataclasses import fields, replace

import numpy as np

from maizeviz.canopy.scene import Canopy
from maizeviz.light.results.absorbed import AbsorbedLight, AbsorbedPeriod
from maizeviz.light.results.diffuse import PeriodLight, SkyLight
from maizeviz.light.results.direct import LightResult
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.scene.scenes import light_scene
from maizeviz.light.sources.irradiance import (
    DEFAULT_LINKE_TURBIDITY,
    DEFAULT_PAR_UMOL_PER_J,
    Period,
)
from maizeviz.light.sources.perez import PEREZ_MODELS, perez_split
from maizeviz.light.sources.sky import Sky, make_sky
from maizeviz.light.sources.sun import Sun, sun_at
from maizeviz.light.trace.absorbed import (
    SKY_PASSES,
    absorbed_light,
    absorbed_period,
    check_absorbed,
)
from maizeviz.light.trace.diffuse import trace_period, trace_sky
from maizeviz.light.trace.direct import trace_light
from maizeviz.light.trace.optics import SHORTWAVE_SHARE, Optics, optics_for
from maizeviz.light.trace.scatter import DEFAULT_DEPTH, DEFAULT_THRESHOLD
from maizeviz.mesh.raytrace import RayScene
from maizeviz.progress import ProgressCallback


class LightEngine:
    """Sun, sky and day light through one canopy, on Embree scenes built once.

    Parameters
    ----------
    canopy : Canopy
        From :func:`maizeviz.canopy.scene.build_canopy` (``maizeviz.build_canopy``).
    sampling : Sampling, optional
        Sensor heights (cm), ray density (rays per cm2), sample rectangle (cm), periodic field
        and threads shared by every request; fields given as keywords replace its fields
        (``LightEngine(canopy, periodic=True, density=2.0)``).
    with_stalks : bool
        Stalks intercept light too (their triangles follow the leaves' in per-triangle
        results).
    **fields
        Any field of :class:`~maizeviz.light.scene.request.Sampling`: ``heights_cm``, ``density``,
        ``rect``, ``periodic``, ``threads``.

    Attributes
    ----------
    canopy : Canopy
    sampling : Sampling
    with_stalks : bool
    build_seconds : dict[bool, float]
        Seconds spent building the scene of an open (False) and a periodic (True) field.

    Notes
    -----
    Thread-safe: several threads may trace through one engine (a sweep worker's threads); a
    scene is built by the first thread that needs it.
    """

    def __init__(self, canopy: Canopy, sampling: Sampling | None = None, *,
                 with_stalks: bool = False, **fields_):
        self.canopy = canopy
        self.sampling = self._sampling(sampling or Sampling(), fields_)
        self.with_stalks = bool(with_stalks)
        self.build_seconds: dict[bool, float] = {}
        self._scenes: dict[bool, RayScene] = {}
        self._lock = threading.Lock()
        self._sky: tuple[tuple, SkyLight] | None = None
        self._normals_kept: np.ndarray | None = None

    @staticmethod
    def _sampling(base: Sampling, changes: dict) -> Sampling:
        known = {f.name for f in fields(Sampling)}
        unknown = sorted(set(changes) - known)
        if unknown:
            raise TypeError(f"unknown sampling field(s) {', '.join(unknown)} (known: "
                            f"{', '.join(sorted(known))})")
        if "heights_cm" in changes:
            changes = {**changes, "heights_cm": tuple(float(h) for h in changes["heights_cm"])}
        return replace(base, **changes) if changes else base

    # ------------------------------------------------------------------ scenes
    def scene(self, periodic: bool | None = None) -> RayScene:
        """The Embree scene for an open (``periodic`` False) or periodic field, built on
        first use and kept (``periodic`` None: the engine's sampling says)."""
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
            azimuth: float | None = None, classes: bool = True,
            sampling: Sampling | None = None,
            progress: ProgressCallback | None = None, **fields_) -> LightResult:
        """Direct sunlight: transmission by height and the hit classes of one sun.

        Parameters
        ----------
        sun : Sun, optional
            The sun's angles; else ``zenith`` and ``azimuth`` (deg), or a place and time.
        date, time : str
            "YYYY-MM-DD" and local clock time "HH:MM" (:mod:`maizeviz.light.sources.clock`).
        lat, lon : float
            deg north and east. ``tz``: IANA time zone. ``solar_noon``: the day's true solar
            noon instead of ``time``. ``altitude``: m above sea level.
        zenith, azimuth : float
            deg, zenith from the vertical, azimuth clockwise from north.
        classes : bool
            Also trace second hits and per-triangle counts (the hit classes).
        sampling : Sampling, optional
            Instead of the engine's; keywords (``heights_cm=...``) replace its fields.
        progress : callable, optional
            ``progress(done, total)`` after each chunk of rays; ``False`` cancels.

        Returns
        -------
        LightResult
            ``transmission`` (H,) in [0, 1] at ``heights_cm`` (H,) cm; ``table()`` as a
            DataFrame. ``seconds["build"]`` is the scene's build time when this call built it.

        References
        ----------
        Reda, I. & Andreas, A. (2004). Solar position algorithm for solar radiation
        applications. Solar Energy 76(5), 577-589 (pvlib's ``get_solarposition``).
        """
        if sun is None:
            if zenith is not None:
                sun = Sun(float(zenith), float(azimuth if azimuth is not None else 180.0))
            else:
                if date is None or lat is None or lon is None:
                    raise TypeError("give a Sun, zenith and azimuth, or date, time, lat and "
                                    "lon")
                sun = sun_at(date, time, lat, lon, tz, solar_noon, altitude)
        smp = self._sampling(sampling or self.sampling, fields_)
        scene, build_s = self._scene_and_build(smp.periodic)
        result = trace_light(self.canopy, LightRequest(sun, smp, classes),
                             progress, self.with_stalks, scene)
        result.seconds["build"] = build_s
        return result

    def sky(self, sky: Sky | str = "soc", directions: int = 46, split: str = "auto", *,
            sampling: Sampling | None = None, progress: ProgressCallback | None = None,
            bin_cm: float = 5.0, **fields_) -> SkyLight:
        """Diffuse light under a sky: every sky direction traced like the sun.

        Parameters
        ----------
        sky : Sky or str
            A :class:`~maizeviz.light.sources.sky.Sky`, or its kind: "soc" (standard overcast) or
            "uoc" (uniform overcast), split into ``directions`` directions (``split``: "auto",
            "turtle", "tregenza", "equal").
        sampling, progress, **fields_ : as :meth:`sun` (``progress`` after each direction).
        bin_cm : float
            Bin edge of the transmission maps, cm.

        Returns
        -------
        SkyLight
            ``transmission`` (H,): share of the horizontal diffuse irradiance reaching each
            height; ``table()`` as a DataFrame.

        References
        ----------
        Moon, P. & Spencer, D. E. (1942). Illumination from a non-uniform sky. Illuminating
        Engineering 37, 707-726 (the standard overcast sky).
        """
        sky_obj = sky if isinstance(sky, Sky) else make_sky(sky, directions, split)
        smp = self._sampling(sampling or self.sampling, fields_)
        scene, build_s = self._scene_and_build(smp.periodic)
        light = trace_sky(self.canopy, sky_obj, smp, progress, self.with_stalks, scene, bin_cm)
        light.seconds["build"] = build_s
        self._sky = (_sky_key(sky_obj, smp, bin_cm), light)
        return light

    def day(self, period: Period | None = None, *, date: str | None = None,
            lat: float | None = None, lon: float | None = None, tz: str = "UTC",
            step_min: float = 30.0, start: str | None = None, end: str | None = None,
            altitude: float = 0.0, linke: float = DEFAULT_LINKE_TURBIDITY,
            par_factor: float = DEFAULT_PAR_UMOL_PER_J, sky: Sky | str | None = None,
            sampling: Sampling | None = None, progress: ProgressCallback | None = None,
            bin_cm: float = 5.0, directions: int = 46, **fields_) -> PeriodLight:
        """Light over a day (or any period): the sun traced at every time step, the sky once.

        Parameters
        ----------
        period : Period, optional
            From :func:`~maizeviz.light.sources.irradiance.clear_sky_period` or
            :func:`~maizeviz.light.sources.irradiance.weather_period`; else a clear day from ``date``
            ("YYYY-MM-DD"), ``lat``, ``lon`` (deg), ``tz`` (IANA), ``step_min`` (min),
            ``start``/``end`` (local "HH:MM"), ``altitude`` (m), ``linke`` (Linke turbidity)
            and ``par_factor`` (umol of PAR per J of shortwave).
        sky : Sky or str, optional
            The sky of the diffuse part (default: standard overcast, 46 directions); the sky
            light this engine last traced is reused when its sky, sampling and bins match.
            "perez" (or "perez-driesse") splits each step's diffuse light by Perez's
            anisotropic model (:mod:`maizeviz.light.sources.perez`): its circumsolar part traced with
            the sun, its isotropic part over a uniform sky of ``directions`` directions.
        directions : int
            Directions of a sky given by its kind (default 46, den Dulk's turtle).
        sampling, progress, bin_cm, **fields_ : as :meth:`sky` (``progress`` after each
            direction: sky directions first, then the time steps).

        Returns
        -------
        PeriodLight
            PAR doses in mol/m2 of ground (``par_incident_mol_m2``,
            ``par_transmitted_mol_m2`` (H,), ...); ``table()`` as a DataFrame.

        References
        ----------
        Ineichen, P. & Perez, R. (2002). A new airmass independent formulation for the Linke
        turbidity coefficient. Solar Energy 73(3), 151-157 (the clear sky).
        """
        from maizeviz.light.sources.irradiance import clear_sky_period

        if period is None:
            if date is None or lat is None or lon is None:
                raise TypeError("give a Period, or date, lat and lon")
            period = clear_sky_period(date, lat, lon, tz, step_min, start, end, altitude,
                                      linke, par_factor)
        smp = self._sampling(sampling or self.sampling, fields_)
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
        return light

    def kept_sky(self, sky: Sky, sampling: Sampling | None = None,
                 bin_cm: float = 5.0) -> SkyLight | None:
        """The sky light this engine last traced, if it was traced with this sky, sampling
        (threads aside) and bin edge: what :meth:`day` reuses; else None."""
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
                 **fields_) -> AbsorbedLight:
        """Light absorbed by leaves and ground in one band, with scattering
        (:func:`maizeviz.light.trace.absorbed.absorbed_light`): the sun's direct beam and,
        when ``diffuse_w_m2`` > 0, the diffuse light of a sky.

        Parameters
        ----------
        sun, zenith, azimuth, date, time, lat, lon, tz : the sun, as :meth:`sun`
        band : "par" or "nir"; optics : the band's Optics (default
            :data:`maizeviz.light.trace.optics.DEFAULT_OPTICS`)
        direct_w_m2 : the band's direct irradiance on a horizontal plane above the canopy,
            W/m2 (default: the band's share of 1000 W/m2 of shortwave, 480 in PAR)
        diffuse_w_m2 : the band's diffuse irradiance on a horizontal plane, W/m2, spread over
            ``sky`` (kind or Sky) split into ``directions`` directions
        depth, threshold, seed : scatterings followed, share of the incident power left
            travelling where tracing stops, random seed
        sky_passes : with leaves or soil that scatter, in a periodic field, the diffuse light
            is traced as one beam whose rays each take a sky direction of their own
            (:func:`~maizeviz.light.trace.scatter.scatter_sky`), this many rays per grid cell
            (default 4; 0: every sky direction traced over the whole grid, as black leaves
            are)
        sampling, progress, **fields_ : as :meth:`sun` (``progress`` after each beam)

        Returns
        -------
        AbsorbedLight
            ``balance`` (W/m2 of ground), absorbed W per triangle, ``table("plant", canopy)``,
            ``absorbed_leaves_error`` (the Monte Carlo standard error).

        References
        ----------
        Bailey, B. N. (2018). Ecological Modelling 368, 233-245 (Helios' radiation model).
        """
        from maizeviz.light.scene.request import check_sampling
        from maizeviz.light.trace.direct import sampler

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
        smp_req = self._sampling(sampling or self.sampling, fields_)
        rect, _ = check_sampling(self.canopy, smp_req)
        scene, build_s = self._scene_and_build(smp_req.periodic)
        smp = sampler(self.canopy, scene, rect, smp_req.density, smp_req.heights_cm,
                      smp_req.periodic, self.with_stalks)
        sky_obj = None
        if diffuse_w_m2 > 0:
            sky_obj = sky if isinstance(sky, Sky) else make_sky(sky, directions)
        return absorbed_light(self.canopy, smp, self._normals(), opt, sun, direct,
                              diffuse_w_m2, sky_obj, depth, threshold, seed, smp_req.threads,
                              progress, build_s, sky_passes)

    def photosynthesis(self, sun: Sun | None = None, *, model="c4",
                       temperature_c: float = 25.0, **absorbed):
        """Gross CO2 assimilation of the leaves under one sun (and sky): absorbed PAR
        (:meth:`absorbed`, same keywords) through a leaf model, each triangle's sunlit and
        shaded parts at their own light (:mod:`maizeviz.light.results.assimilation`).

        Parameters
        ----------
        sun, **absorbed : as :meth:`absorbed` (``zenith=``, ``diffuse_w_m2=``, ``optics=``...)
        model : "c4", "wofost" or a leaf model
            (:func:`maizeviz.photosynthesis.split.leaf_model` for other parameters)
        temperature_c : air (leaf) temperature, C

        Returns
        -------
        Assimilation
            ``canopy_gross_umol_m2_s`` (per m2 of ground), ``canopy_gross_kg_co2_ha_h``, their
            standard errors; ``table("plant", canopy)`` as a DataFrame.

        References
        ----------
        Collatz, G. J., Ribas-Carbo, M. & Berry, J. A. (1992). Australian Journal of Plant
        Physiology 19, 519-538. Spitters, C. J. T. (1986). Agricultural and Forest
        Meteorology 38, 231-242.
        """
        from maizeviz.light.results.assimilation import assimilate
        from maizeviz.photosynthesis.split import leaf_model

        leaf = leaf_model(model) if isinstance(model, str) else model
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
                     par_factor: float = DEFAULT_PAR_UMOL_PER_J, photosynthesis=None,
                     temperature_c=25.0, **fields_) -> AbsorbedPeriod:
        """Light absorbed with scattering over a period (a day), in one band: each step's
        sun with the band's share of its direct irradiance, and the diffuse part spread over
        ``sky``, traced once per W/m2 and scaled by each step's diffuse irradiance (the
        transport is linear in the light put in;
        :func:`maizeviz.light.trace.absorbed.absorbed_period`).

        Parameters
        ----------
        period, date, lat, lon, tz, step_min, start, end, altitude, linke, par_factor : the
            period, as :meth:`day`; the period's PAR factor (umol of PAR per J of shortwave)
            also sets the band's share of the shortwave
            (:func:`~maizeviz.light.trace.optics.band_share`: 0.48 for PAR by default), so that
            black leaves absorb exactly the PAR the same day intercepts
        band, optics, depth, threshold, seed, sampling, **fields_ : as :meth:`absorbed`
        sky, directions : the diffuse light's sky (default: standard overcast, 46); "perez"
            (or "perez-driesse") splits each step's diffuse light by Perez's model
            (:mod:`maizeviz.light.sources.perez`): its circumsolar part added to that step's direct
            beam, the rest from a uniform sky
        progress : after the sky and after each step
        photosynthesis : LeafModel, optional
            Also the leaves' gross CO2 assimilation at every step (PAR only,
            :func:`maizeviz.light.results.assimilation.assimilate`), added up over the period
            (``AbsorbedPeriod.assimilation``).
        temperature_c : float or (n,) float64
            Air (leaf) temperature at each step, C (default 25); a period read from a weather
            file with an air temperature column (``Period.temp_air``) gives its own, these
            filling the steps it lacks (NaN).

        Returns
        -------
        AbsorbedPeriod
            ``balance`` in MJ/m2 of ground, J per triangle, ``absorbed_leaves_mol_m2`` (PAR),
            ``table("plant", canopy)``.
        """
        from functools import partial

        from maizeviz.light.sources.irradiance import clear_sky_period

        if period is None:
            if date is None or lat is None or lon is None:
                raise TypeError("give a Period, or date, lat and lon")
            period = clear_sky_period(date, lat, lon, tz, step_min, start, end, altitude,
                                      linke, par_factor)
        opt = optics if optics is not None else optics_for(band)
        one = partial(self.absorbed, band=opt.band, optics=opt, directions=directions,
                      depth=depth, threshold=threshold, seed=seed, sampling=sampling, **fields_)
        return absorbed_period(period, opt, sky, one, progress, self.canopy, photosynthesis,
                               temperature_c)

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


def _sky_key(sky: Sky, s: Sampling, bin_cm: float) -> tuple:
    """What makes a traced sky light reusable: the sky's directions and weights and the
    sampling (threads aside)."""
    return (sky.kind, sky.split, tuple(map(float, sky.zenith_deg)),
            tuple(map(float, sky.azimuth_deg)), tuple(map(float, sky.weights)),
            tuple(float(h) for h in s.heights_cm), float(s.density), s.rect, bool(s.periodic),
            float(bin_cm))
