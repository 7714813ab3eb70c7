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
    """A discretised sky: ``kind`` "soc" or "uoc", ``directions`` (16, 46, 145 or any n for
    an equal-area split), ``split`` "auto" or "equal" (see :func:`maizeviz.light.sources.sky.make_sky`,
    which :meth:`sky` calls)."""

    kind: str = "soc"
    directions: int = 46
    split: str = "auto"

    def sky(self):
        from maizeviz.light.sources.sky import make_sky

        return make_sky(self.kind, self.directions, self.split)


@dataclass(frozen=True)
class DaySpec:
    """A day (or part of it) at a place: clear sky (Ineichen-Perez, ``linke`` turbidity) or a
    weather file (``weather``: its path; it sets the period and its steps).

    Attributes
    ----------
    date : str
        ``YYYY-MM-DD`` (local date at ``tz``).
    lat, lon : float
        Degrees north and east.
    tz : str
        IANA time zone of the clock times (``Asia/Shanghai``, ``UTC``).
    step_min : float
        Minutes between time steps of a clear day.
    start, end : str or None
        Clock times ``HH:MM`` bounding the period (None: the whole day).
    linke : float
        Linke turbidity of the clear sky (dimensionless).
    par_factor : float
        µmol of PAR photons per joule of shortwave.
    weather : str or None
        A weather file instead of a clear sky.
    diffuse : str
        How each step's diffuse light comes from the sky: ``"sky"`` (the sky chosen, one
        shape all day) or ``"perez"`` (Perez's anisotropic split per step: its circumsolar
        part with the sun, the rest from a uniform sky of the sky's directions; see
        :mod:`maizeviz.light.sources.perez`).
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
        """The Period (maizeviz.light.sources.irradiance) the spec describes; refused with a
        MaizevizError naming the quantity (date, tz, step, period, weather...)."""
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
        """At most how many time steps :meth:`period` will have, known without computing it
        (for the cost estimate): the span over the step for a clear sky, the rows a weather
        file of its size can hold (24 bytes a row at the least)."""
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
    """Absorbed light with scattering as a user chooses it: the band, the leaf and soil
    optics, the irradiance and how far scattering is followed (see
    :meth:`maizeviz.light.engine.LightEngine.absorbed`, which :meth:`absorbed` calls).

    Attributes
    ----------
    band : str
        ``"par"`` or ``"nir"``.
    reflectance, transmittance, ground_reflectance : float or None
        Leaf and soil fractions in [0, 1] (None: the band's default,
        :data:`maizeviz.light.trace.optics.DEFAULT_OPTICS`).
    direct_w_m2 : float or None
        The band's direct irradiance on a horizontal plane above the canopy, W/m2 (None: the
        band's share of 1000 W/m2 of shortwave).
    diffuse_w_m2 : float
        The band's diffuse irradiance on a horizontal plane, W/m2, from a standard overcast
        sky of 46 directions (0: the direct beam only).
    depth : int
        Most scatterings followed per ray (0: first hits only; default
        :data:`maizeviz.light.trace.scatter.DEFAULT_DEPTH`, as the command line; Russian roulette
        and the energy threshold end most paths long before).
    seed : int
        Random seed of the Monte Carlo scattering (the same seed gives the same result).
    ranks : tuple of (rank, reflectance, transmittance)
        Leaf optics of the ranks that differ (see :class:`maizeviz.light.trace.optics.Optics`).
    photosynthesis : str
        A leaf model turning the absorbed PAR into gross CO2 assimilation: "c4", "wofost",
        or "" (none; :mod:`maizeviz.photosynthesis`).
    temperature_c : float
        Air (leaf) temperature for the leaf model, C.
    photosynthesis_params : tuple of (name, value)
        The leaf model's parameters that differ from its defaults (``vmax``, ``amax``...).
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

    def leaf_model(self):
        """The leaf model chosen (checked: MaizevizError naming what is wrong), or None."""
        if not self.photosynthesis:
            return None
        from maizeviz.errors import MaizevizError, check_range
        from maizeviz.photosynthesis.split import leaf_model

        if self.band != "par":
            raise MaizevizError("photosynthesis works from absorbed PAR, not "
                                f"{self.band.upper()}", quantity="band")
        check_range(self.temperature_c, "the air temperature (C)", -50, 70, "temperature")
        return leaf_model(self.photosynthesis, **dict(self.photosynthesis_params))

    def assimilation(self, canopy, light):
        """Gross CO2 assimilation of ``light`` (this spec's AbsorbedLight, traced on
        ``canopy``) through the chosen leaf model (an
        :class:`~maizeviz.light.results.assimilation.Assimilation`), or None without one."""
        model = self.leaf_model()
        if model is None:
            return None
        from maizeviz.light.results.assimilation import assimilate

        return assimilate(canopy, light, model, self.temperature_c)

    def optics(self):
        """The :class:`~maizeviz.light.trace.optics.Optics` of the band (checked: MaizevizError
        naming the value out of range)."""
        from dataclasses import replace

        from maizeviz.light.trace.optics import optics_for

        base = optics_for(self.band, self.reflectance, self.transmittance,
                          self.ground_reflectance)
        return replace(base, ranks=tuple(tuple(r) for r in self.ranks)) if self.ranks else base

    def absorbed(self, engine, sun, sampling=None, progress=None):
        """Trace it: ``engine.absorbed`` for ``sun`` (an AbsorbedLight)."""
        return engine.absorbed(sun, band=self.band, optics=self.optics(),
                               direct_w_m2=self.direct_w_m2, diffuse_w_m2=self.diffuse_w_m2,
                               depth=self.depth, seed=self.seed, sampling=sampling,
                               progress=progress)
