"""A sky and a day as a user chooses them (the app's light panel, a project's stored
settings, a notebook): small frozen records that make the core's :class:`~maizeviz.light.sources.sky.Sky`
and :class:`~maizeviz.light.sources.irradiance.Period` on demand, and compare equal when they would
make the same ones.

Example
-------
>>> spec = DaySpec(date="2005-08-01", lat=39.9, lon=116.4, tz="Asia/Shanghai")
>>> spec.steps_bound()
48
"""

from __future__ import annotations

from dataclasses import dataclass

from maizeviz.light.sources.irradiance import DEFAULT_PAR_UMOL_PER_J
from maizeviz.light.trace.scatter import DEFAULT_DEPTH


@dataclass(frozen=True)
class SkySpec:
    """A discretised sky as a user chooses it (see :func:`maizeviz.light.sources.sky.make_sky`).

    Parameters
    ----------
    kind : {"soc", "uoc"}
        Standard or uniform overcast.
    directions : int
        16, 46, 145, or any count for an equal-area split.
    split : {"auto", "equal"}
        How the hemisphere is cut.
    """

    kind: str = "soc"
    directions: int = 46
    split: str = "auto"

    def sky(self):
        """The sky the spec describes.

        Returns
        -------
        Sky
            From :func:`maizeviz.light.sources.sky.make_sky`.
        """
        from maizeviz.light.sources.sky import make_sky

        return make_sky(self.kind, self.directions, self.split)


@dataclass(frozen=True)
class DaySpec:
    """A day (or part of it) at a place: a clear sky or a weather file.

    The clear sky is Ineichen and Perez's with ``linke`` turbidity; a weather file (its
    path) sets the period and its steps instead.

    Parameters
    ----------
    date : str
        The local date at ``tz``, "YYYY-MM-DD".
    lat : float
        Latitude [deg north].
    lon : float
        Longitude [deg east].
    tz : str
        IANA time zone of the clock times ("Asia/Shanghai", "UTC").
    step_min : float
        Time between the steps of a clear day [min].
    start, end : str or None
        Clock times "HH:MM" bounding the period (None: the whole day).
    linke : float
        Linke turbidity of the clear sky [-].
    par_factor : float
        PAR photons per joule of shortwave [umol J-1].
    weather : str or None
        A weather file instead of a clear sky.
    diffuse : {"sky", "perez"}
        How each step's diffuse light comes from the sky: the sky chosen, one shape all day,
        or Perez's anisotropic split per step (its circumsolar part with the sun, the rest
        from a uniform sky of the sky's directions; :mod:`maizeviz.light.sources.perez`).

    References
    ----------
    Ineichen, P. & Perez, R. (2002). A new airmass independent formulation for the Linke
    turbidity coefficient. Solar Energy 73(3), 151-157.
    https://doi.org/10.1016/S0038-092X(02)00045-2
    """

    date: str = "2005-08-01"
    lat: float = 39.9
    lon: float = 116.4
    tz: str = "Asia/Shanghai"
    step_min: float = 30.0
    start: str | None = None
    end: str | None = None
    linke: float = 3.0
    par_factor: float = DEFAULT_PAR_UMOL_PER_J
    weather: str | None = None
    diffuse: str = "sky"

    def period(self):
        """The period the spec describes.

        Returns
        -------
        Period
            Its time steps, sun and irradiance (:mod:`maizeviz.light.sources.irradiance`).

        Raises
        ------
        MaizevizError
            A bad date, zone, step or weather file, or a period without sun (naming the
            quantity).
        """
        from maizeviz.errors import MaizevizError
        from maizeviz.light.sources import irradiance as irr

        if self.weather:
            weather = irr.read_weather(self.weather, tz=self.tz or None)
            period = irr.weather_period(weather, self.lat, self.lon, 0.0, self.par_factor)
        else:
            period = irr.clear_sky_period(self.date, self.lat, self.lon, self.tz or "UTC",
                                          self.step_min, self.start or None, self.end or None,
                                          0.0, self.linke, self.par_factor)
        if period.n_steps == 0:
            note = period.notes[0] if period.notes else "the sun never rises in this period"
            raise MaizevizError(f"{note}; choose another date or place",
                                quantity="place" if self.weather else "date")
        return period

    def steps_bound(self) -> int:
        """At most how many time steps :meth:`period` will have, known without computing it.

        Returns
        -------
        int
            The span over the step for a clear sky; the rows a weather file of its size can hold
            (24 bytes a row at the least); at least 1.
        """
        import math
        import os

        from maizeviz.errors import MaizevizError
        from maizeviz.light.sources.clock import parse_clock

        if self.weather:
            try:
                return max(os.path.getsize(self.weather) // 24, 1)
            except OSError:
                return 1                                 # refused later, naming the file
        try:
            span = (parse_clock(self.end or "24:00", "end")[0]
                    - parse_clock(self.start or "00:00", "start")[0])
            minutes = max(span.total_seconds() / 60, 1.0)
        except MaizevizError:
            minutes = 24 * 60.0                          # refused when the period is made
        return max(math.ceil(minutes / max(self.step_min, 1.0)), 1)


@dataclass(frozen=True)
class OpticsSpec:
    """Absorbed light with scattering as a user chooses it.

    The band, the leaf and soil optics, the irradiance and how far scattering is followed
    (see :meth:`maizeviz.light.engine.LightEngine.absorbed`, which :meth:`absorbed` calls).

    Parameters
    ----------
    band : {"par", "nir"}
        The waveband.
    reflectance, transmittance : float or None
        Leaf fractions in [0, 1] [-] (None: the band's default,
        :data:`maizeviz.light.trace.optics.DEFAULT_OPTICS`).
    ground_reflectance : float or None
        Soil fraction in [0, 1] [-] (None: the band's default).
    direct_w_m2 : float or None
        The band's direct irradiance on a horizontal plane above the canopy [W m-2] (None:
        the band's share of 1000 W m-2 of shortwave).
    diffuse_w_m2 : float
        The band's diffuse irradiance on a horizontal plane [W m-2], from a standard overcast
        sky of 46 directions (0: the direct beam only).
    depth : int
        Most scatterings followed per ray (0: first hits only; default
        :data:`maizeviz.light.trace.scatter.DEFAULT_DEPTH`).
    seed : int
        Seed of the Monte Carlo scattering (the same seed gives the same result).
    ranks : tuple of (int, float, float)
        ``(rank, reflectance, transmittance)`` of the leaf ranks that differ (see
        :class:`maizeviz.light.trace.optics.Optics`).
    photosynthesis : str
        A leaf model turning the absorbed PAR into gross CO2 assimilation ("c4", "wofost"; ""
        for none: :func:`maizeviz.photosynthesis.split.leaf_model`).
    temperature_c : float
        Air (leaf) temperature for the leaf model [degC].
    photosynthesis_params : tuple of (str, float)
        The leaf model's parameters that differ from its defaults.
    c4_temperature : {"collatz", "clm45"}
        The C4 model's temperature response
        (:data:`maizeviz.photosynthesis.c4.TEMPERATURE_RESPONSES`); a project saved before it
        was a choice reads as "clm45", what it computed.

    References
    ----------
    Bailey, B. N. (2018). A reverse ray-tracing method for modelling the net radiative flux
    in leaf-resolving plant canopy simulations. Ecological Modelling 368, 233-245.
    https://doi.org/10.1016/j.ecolmodel.2017.11.022
    """

    band: str = "par"
    reflectance: float | None = None
    transmittance: float | None = None
    ground_reflectance: float | None = None
    direct_w_m2: float | None = None
    diffuse_w_m2: float = 0.0
    depth: int = DEFAULT_DEPTH
    seed: int = 0
    ranks: tuple = ()
    photosynthesis: str = ""
    temperature_c: float = 25.0
    photosynthesis_params: tuple = ()
    c4_temperature: str = "collatz"

    def leaf_model(self):
        """The leaf model chosen, checked.

        Returns
        -------
        LeafModel or None
            None without one.

        Raises
        ------
        MaizevizError
            A band other than PAR, a temperature out of range or a bad model parameter.
        """
        if not self.photosynthesis:
            return None
        from maizeviz.errors import MaizevizError, check_range
        from maizeviz.photosynthesis.split import leaf_model

        if self.band != "par":
            raise MaizevizError("photosynthesis works from absorbed PAR, not "
                                f"{self.band.upper()}", quantity="band")
        check_range(self.temperature_c, "the air temperature (C)", -50, 70, "temperature")
        params = dict(self.photosynthesis_params)
        if self.photosynthesis == "c4":
            params["temperature_response"] = self.c4_temperature
        return leaf_model(self.photosynthesis, **params)

    def assimilation(self, canopy, light):
        """Gross CO2 assimilation of absorbed light through the chosen leaf model.

        Parameters
        ----------
        canopy : Canopy
            The canopy it was traced on.
        light : AbsorbedLight
            This spec's absorbed light.

        Returns
        -------
        Assimilation or None
            None without a leaf model.
        """
        model = self.leaf_model()
        if model is None:
            return None
        from maizeviz.light.results.assimilation import assimilate

        return assimilate(canopy, light, model, self.temperature_c)

    def optics(self):
        """The optics of the band.

        Returns
        -------
        Optics
            Checked.

        Raises
        ------
        MaizevizError
            A value out of range (naming it).
        """
        from dataclasses import replace

        from maizeviz.light.trace.optics import optics_for

        base = optics_for(self.band, self.reflectance, self.transmittance,
                          self.ground_reflectance)
        return replace(base, ranks=tuple(tuple(r) for r in self.ranks)) if self.ranks else base

    def absorbed(self, engine, sun, sampling=None, progress=None):
        """Trace it: ``engine.absorbed`` for ``sun``.

        Parameters
        ----------
        engine : LightEngine
            The engine of the canopy.
        sun : Sun
            The sun.
        sampling : Sampling, optional
            Instead of the engine's.
        progress : callable, optional
            ``progress(done, total)`` after each beam.

        Returns
        -------
        AbsorbedLight
            As :meth:`maizeviz.light.engine.LightEngine.absorbed` gives it.
        """
        return engine.absorbed(sun, band=self.band, optics=self.optics(),
                               direct_w_m2=self.direct_w_m2, diffuse_w_m2=self.diffuse_w_m2,
                               depth=self.depth, seed=self.seed, sampling=sampling,
                               progress=progress)
