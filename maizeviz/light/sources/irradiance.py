"""Sunlight over a day or a period: sun positions, clear-sky or measured irradiance, PAR.

A period (a day, or the hours between two clock times, or the span of a weather file) is cut
into time steps. Each step stands for an interval of ``step_s`` seconds and carries the sun
position and the irradiance at the middle of that interval (the midpoint rule): the energy of a
step is its irradiance times ``step_s``, and the energy of the period is the sum of the energies
of its steps, by construction. Only the steps with the sun above the horizon (apparent zenith
below 90 deg) are kept, since only they can be traced; the period keeps its own bounds. A period
in which the sun never rises (polar night) has zero steps and says so once in its notes.

Irradiance (W/m2 on a horizontal plane unless said otherwise): ``ghi`` global horizontal,
``dni`` direct normal, ``dhi`` diffuse horizontal, ``direct_horizontal`` = dni cos(zenith); for
every step ghi = direct_horizontal + dhi.

- Clear sky, no downloaded data: the Ineichen-Perez model (Ineichen & Perez 2002) as
  implemented by pvlib, with a stated Linke turbidity (default 3, no climatology lookup file)
  and site altitude; air mass by Kasten & Young (1989); sun positions by pvlib's NREL SPA
  (Reda & Andreas 2004).
- Weather file (:func:`read_weather`): measured ``ghi`` and optionally ``dni``/``dhi``. Where
  only ghi is given it is split into direct and diffuse by the Erbs et al. (1982)
  diffuse-fraction correlation (pvlib). See :func:`read_weather` for the format and the rules.

PAR is taken as a fixed fraction of shortwave: ``par_umol_per_j`` umol of PAR photons per J of
shortwave, by default 0.48 (PAR share of global radiation) x 4.57 umol/J (photons per joule of
daylight PAR, McCree 1972) = 2.1936 umol/J.

PAR's diffuse part on a clear-sky day is not the shortwave's: the sky scatters blue more than
the near infrared, and the clear-sky model's diffuse share of shortwave (13-14 % on a clear
summer day) is well below what crop models use for PAR. A clear-sky period splits its PAR as
WOFOST does (Spitters et al. 1986; PCSE's ``astro`` and ``totass7``): the day's atmospheric
transmission ``T`` (its shortwave over the extraterrestrial on the horizontal) gives the day's
diffuse fraction ``FRDIF`` (0.23 above T = 0.75, ``1.33 - 1.46 T`` down to 0.35, ``1 - 2.3 (T -
0.07)^2`` down to 0.07, 1 below), and each step's diffuse PAR is ``FRDIF T I0 sin(beta)`` times
the PAR share (``I0`` the extraterrestrial irradiance, ``beta`` the sun's elevation), at most
the step's PAR; over a whole day the diffuse share of PAR is FRDIF (about 0.26 on a clear
summer day in Beijing, against the shortwave's 0.135). A weather file's PAR is left as measured
(or as its shortwave's split, when it has none), and the near infrared keeps the shortwave's
split.

Angles in degrees: zenith from the vertical, azimuth clockwise from north (as
:class:`maizeviz.light.sources.sun.Sun`).

References
----------
- Ineichen, P. & Perez, R. (2002). A new airmass independent formulation for the Linke
  turbidity coefficient. Solar Energy 73(3), 151-157.
- Erbs, D.G., Klein, S.A. & Duffie, J.A. (1982). Estimation of the diffuse radiation fraction
  for hourly, daily and monthly-average global radiation. Solar Energy 28(4), 293-302.
- Kasten, F. & Young, A.T. (1989). Revised optical air mass tables and approximation formula.
  Applied Optics 28, 4735-4738.
- Reda, I. & Andreas, A. (2004). Solar position algorithm for solar radiation applications.
  Solar Energy 76(5), 577-589.
- McCree, K.J. (1972). Test of current definitions of photosynthetically active radiation
  against leaf photosynthesis data. Agricultural Meteorology 10, 443-453.
- Spitters, C.J.T., Toussaint, H.A.J.M. & Goudriaan, J. (1986). Separating the diffuse and
  direct component of global radiation and its implications for modeling canopy
  photosynthesis. Part I. Components of incoming radiation. Agricultural and Forest
  Meteorology 38, 217-229 (the daily relation of the diffuse fraction to the atmospheric
  transmission, as WOFOST codes it: PCSE 6.0, ``pcse.util.astro``).
"""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.dates import TIME_UNIT
from maizeviz.io.inputs import open_input
from maizeviz.io.weather_csv import (
    BOUNDS,
    WEATHER_OPTIONAL,
    read_weather_csv,
    value_problem,
)
from maizeviz.io.weather_files import (
    PVLIB_FORMATS,
    WeatherFileError,
    WeatherTable,
    detect_format,
    read_pvlib_file,
)
from maizeviz.light.sources.clock import check_altitude as _check_altitude
from maizeviz.light.sources.clock import check_place as _check_place
from maizeviz.light.sources.clock import local_time
from maizeviz.light.sources.clock import zone as _time_zone

if TYPE_CHECKING:
    import pandas as pd

#: Share of shortwave (global) radiation in the PAR band (400-700 nm).
PAR_FRACTION = 0.48
#: Photons per joule of daylight PAR, umol/J (McCree 1972).
PAR_UMOL_PER_J_PAR = 4.57
#: Default conversion from shortwave energy to PAR photons, umol per J of shortwave.
DEFAULT_PAR_UMOL_PER_J = PAR_FRACTION * PAR_UMOL_PER_J_PAR
#: Default Linke turbidity of the clear sky (a clean to average rural atmosphere).
DEFAULT_LINKE_TURBIDITY = 3.0
#: Weather files larger than this are refused (a year of 1-minute rows is about 35 MiB).
MAX_WEATHER_BYTES = 64 * 2 ** 20
#: A step longer than this many times the median step of a weather file is a gap.
GAP_FACTOR = 1.5
#: More time steps than this are refused.
MAX_STEPS = 1_000_000
WEATHER_LABELS = ("center", "start", "end")


# --------------------------------------------------------------------------- small helpers


def _frozen(a, dtype=np.float64) -> np.ndarray:
    a = np.array(a, dtype=dtype)
    a.setflags(write=False)
    return a


def _fmt_duration(seconds: float) -> str:
    if seconds >= 3600 and seconds % 3600 == 0:
        return f"{seconds / 3600:g} h"
    if seconds >= 60:
        return f"{seconds / 60:g} min"
    return f"{seconds:g} s"


def _check_par_factor(par_umol_per_j) -> float:
    if not isinstance(par_umol_per_j, (int, float, np.floating, np.integer)) \
            or not math.isfinite(par_umol_per_j) or not (0 < par_umol_per_j <= 10):
        raise MaizevizError(f"PAR conversion factor must be in (0, 10] umol per J of "
                            f"shortwave, got {par_umol_per_j!r}", quantity="par_factor")
    return float(par_umol_per_j)


def _localize(day: _dt.date, clock: str, tz, what: str):
    """Local clock time ``clock`` on ``day`` in zone ``tz``, a tz-aware Timestamp
    (:func:`maizeviz.light.sources.clock.local_time`)."""
    return local_time(day, clock, tz, what, quantity="period")


def _solar_position(times, lat, lon, altitude):
    """pvlib solar position; returns apparent zenith, true zenith, azimuth as (n,) arrays."""
    import pvlib

    if len(times) == 0:
        empty = np.zeros(0)
        return empty, empty, empty
    pos = pvlib.solarposition.get_solarposition(times, lat, lon, altitude)
    return (pos["apparent_zenith"].to_numpy(float), pos["zenith"].to_numpy(float),
            pos["azimuth"].to_numpy(float))


def _no_sun_note(start, end, lat, lon) -> str:
    return (f"the sun stays below the horizon from {start.isoformat()} to {end.isoformat()} at "
            f"latitude {lat:g}, longitude {lon:g}: no sunlight in this period (zero steps)")


# --------------------------------------------------------------------------- sun track


@dataclass(frozen=True, eq=False)
class SunTrack:
    """Sun positions at the middle of each time step of a period, sun above the horizon only.

    Attributes
    ----------
    times : (n,) pandas DatetimeIndex, time-zone aware: middle of each step
    step_s : (n,) float64, s: length of the interval each step stands for
    zenith_deg : (n,) float64, deg: apparent (refraction-corrected) zenith, < 90
    true_zenith_deg : (n,) float64, deg: geometric zenith (for decomposition models)
    azimuth_deg : (n,) float64, deg, clockwise from north
    start, end : pandas Timestamp, time-zone aware: bounds of the whole period
    latitude, longitude : float, deg (north, east positive); altitude_m : float, m
    tz : str, time zone of ``times``
    notes : tuple of str: things said once about the period (polar night...)
    """

    times: pd.DatetimeIndex
    step_s: np.ndarray
    zenith_deg: np.ndarray
    true_zenith_deg: np.ndarray
    azimuth_deg: np.ndarray
    start: pd.Timestamp
    end: pd.Timestamp
    latitude: float
    longitude: float
    altitude_m: float
    tz: str
    notes: tuple[str, ...] = ()

    def __post_init__(self):
        for name in ("step_s", "zenith_deg", "true_zenith_deg", "azimuth_deg"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))

    @property
    def n_steps(self) -> int:
        """Steps with the sun above the horizon."""
        return len(self.step_s)

    @property
    def period_s(self) -> float:
        """Length of the whole period, s (night included)."""
        return (self.end - self.start).total_seconds()

    @property
    def sun_never_up(self) -> bool:
        """True when the sun stays below the horizon for the whole period."""
        return self.n_steps == 0


def _step_edges(total_s: float, step_s: float) -> np.ndarray:
    """Offsets (s) of the step edges from the period start; the last step may be shorter."""
    full = math.floor(total_s / step_s + 1e-9)
    edges = np.arange(full + 1, dtype=np.float64) * step_s
    if total_s - edges[-1] > 1e-6:
        edges = np.append(edges, total_s)
    edges[-1] = total_s
    return edges


def sun_track(date, lat: float, lon: float, tz: str, step_min: float = 30.0,
              start: str | None = None, end: str | None = None,
              altitude: float = 0.0) -> SunTrack:
    """Sun positions over a day (or part of it) at a fixed time step.

    Parameters
    ----------
    date : "YYYY-MM-DD" or datetime.date: the local day
    lat, lon : float, deg (north, east positive)
    tz : str, IANA time zone such as "Asia/Shanghai"; clock times are local times there
    step_min : float > 0, min: step length; the last step is shorter when the period is not a
        whole number of steps
    start, end : "HH:MM" local clock times, default 00:00 and 24:00 (the whole day);
        daylight-saving changes are honoured (a spring-forward day is 23 h long)
    altitude : float, m above sea level (refraction and air mass)

    Returns
    -------
    SunTrack with the steps whose middle has the sun above the horizon

    Raises
    ------
    MaizevizError
        Bad place, date, zone or clock time, a step of 0 or longer than the period, a period
        that ends before it starts, more than MAX_STEPS steps.
    """
    import pandas as pd

    lat, lon = _check_place(lat, lon)
    altitude = _check_altitude(altitude)
    try:
        day = date if isinstance(date, _dt.date) else _dt.date.fromisoformat(str(date))
    except ValueError:
        raise MaizevizError(f"the date must be YYYY-MM-DD, got '{date}'",
                            quantity="date") from None
    zone = _time_zone(tz)
    if isinstance(step_min, bool) or not isinstance(step_min, (int, float, np.integer,
                                                              np.floating)) \
            or not math.isfinite(step_min) or step_min <= 0:
        raise MaizevizError(f"the time step must be > 0 min, got {step_min!r}", quantity="step")
    t0 = _localize(day, start or "00:00", zone, "start")
    t1 = _localize(day, end or "24:00", zone, "end")
    total = (t1 - t0).total_seconds()
    if total <= 0:
        raise MaizevizError(f"the period must end after it starts, got {start or '00:00'} to "
                            f"{end or '24:00'}", quantity="period")
    step_s = float(step_min) * 60.0
    if step_s > total + 1e-6:
        raise MaizevizError(f"the time step ({_fmt_duration(step_s)}) is longer than the "
                            f"period ({_fmt_duration(total)})", quantity="step")
    if total / step_s > MAX_STEPS:
        raise MaizevizError(f"a time step of {step_min:g} min gives {total / step_s:.0f} steps, "
                            f"more than {MAX_STEPS}", quantity="step")
    edges = _step_edges(total, step_s)
    mids = (edges[:-1] + edges[1:]) / 2.0
    times = t0 + pd.to_timedelta(np.round(mids * 1e6).astype(np.int64), unit="us")
    zen, true_zen, azi = _solar_position(times, lat, lon, altitude)
    up = zen < 90.0
    notes = () if up.any() else (_no_sun_note(t0, t1, lat, lon),)
    return SunTrack(times=times[up], step_s=np.diff(edges)[up], zenith_deg=zen[up],
                    true_zenith_deg=true_zen[up], azimuth_deg=azi[up], start=t0, end=t1,
                    latitude=lat, longitude=lon, altitude_m=altitude, tz=str(zone),
                    notes=notes)


# --------------------------------------------------------------------------- period


@dataclass(frozen=True, eq=False)
class Period:
    """Irradiance at each time step of a period, sun above the horizon only.

    Attributes
    ----------
    times : (n,) pandas DatetimeIndex, time-zone aware: middle of each step
    step_s : (n,) float64, s: length of the interval each step stands for
    zenith_deg : (n,) float64, deg: apparent zenith, < 90
    azimuth_deg : (n,) float64, deg, clockwise from north
    ghi, dni, dhi : (n,) float64, W/m2: global horizontal, direct normal, diffuse horizontal
    direct_horizontal : (n,) float64, W/m2: dni cos(zenith) = ghi - dhi
    start, end : pandas Timestamp: bounds of the whole period (night included)
    source : str: where the irradiance comes from, with the model and its parameters
    parameters : read-only mapping: the same as data (model, linke_turbidity, altitude_m...)
    par_umol_per_j : float, umol of PAR per J of shortwave
    notes : tuple of str: things said once about the period (polar night, dropped rows...)
    par_measured : (n,) float64 umol/m2/s or None: PAR a quantum sensor measured (a weather
        file's ``par`` column), used for PAR instead of ghi x ``par_umol_per_j``; its direct
        and diffuse parts are shared as the shortwave's
    temp_air : (n,) float64 deg C or None: air temperature at each step (NaN where the file
        had none), for models of leaf processes; the light does not use it
    par_diffuse_share : (n,) float64 in [0, 1] or None: the diffuse part of each step's PAR
        when it is not the shortwave's (a clear-sky period: :func:`par_diffuse_shares`);
        None: PAR is split as the shortwave is

    Integration: step i contributes ``ghi[i] * step_s[i]`` J/m2; every total is the exactly
    rounded sum (math.fsum) of its steps.
    """

    times: pd.DatetimeIndex
    step_s: np.ndarray
    zenith_deg: np.ndarray
    azimuth_deg: np.ndarray
    ghi: np.ndarray
    dni: np.ndarray
    dhi: np.ndarray
    direct_horizontal: np.ndarray
    start: pd.Timestamp
    end: pd.Timestamp
    source: str
    parameters: Mapping[str, object] = field(default_factory=dict)
    par_umol_per_j: float = DEFAULT_PAR_UMOL_PER_J
    notes: tuple[str, ...] = ()
    par_measured: np.ndarray | None = None
    temp_air: np.ndarray | None = None
    par_diffuse_share: np.ndarray | None = None

    def __reduce__(self):
        # the read-only parameters mapping does not pickle; a period crosses process
        # boundaries (the app's light process, Dask workers) as its fields, checked again
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        values["parameters"] = dict(self.parameters)
        return (_period_from_fields, (values,))

    def __post_init__(self):
        n = len(self.times)
        for name in ("step_s", "zenith_deg", "azimuth_deg", "ghi", "dni", "dhi",
                     "direct_horizontal"):
            arr = _frozen(getattr(self, name))
            if arr.shape != (n,) or not np.all(np.isfinite(arr)):
                raise MaizevizError(f"period {name} must be {n} finite numbers")
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "parameters", MappingProxyType(dict(self.parameters)))
        object.__setattr__(self, "par_umol_per_j", _check_par_factor(self.par_umol_per_j))
        object.__setattr__(self, "notes", tuple(self.notes))
        for name, finite in (("par_measured", True), ("temp_air", False),
                             ("par_diffuse_share", True)):
            if getattr(self, name) is not None:
                arr = _frozen(getattr(self, name))
                if arr.shape != (n,) or (finite and not np.all(np.isfinite(arr))) or \
                        np.any(np.isinf(arr)):
                    raise MaizevizError(f"period {name} must be {n} finite numbers")
                object.__setattr__(self, name, arr)
        if self.par_measured is not None and np.any(self.par_measured < 0):
            raise MaizevizError("period PAR must be >= 0 umol/m2/s")
        if self.par_diffuse_share is not None and (np.any(self.par_diffuse_share < 0)
                                                   or np.any(self.par_diffuse_share > 1)):
            raise MaizevizError("period par_diffuse_share must be in [0, 1]")
        if np.any(self.step_s <= 0) or np.any(self.zenith_deg >= 90):
            raise MaizevizError("period steps must last > 0 s and have the sun above the horizon")
        if np.any(self.dhi < 0) or np.any(self.direct_horizontal < 0):
            raise MaizevizError("period irradiance must be >= 0 W/m2")
        if not np.allclose(self.direct_horizontal + self.dhi, self.ghi, rtol=1e-9, atol=1e-9):
            raise MaizevizError("period ghi must equal direct_horizontal + dhi at every step")

    # ---- per step
    @property
    def n_steps(self) -> int:
        """Steps with the sun above the horizon."""
        return len(self.step_s)

    @property
    def sun_never_up(self) -> bool:
        """True when the sun stays below the horizon for the whole period."""
        return self.n_steps == 0

    @property
    def step_shortwave_j_m2(self) -> np.ndarray:
        """(n,) float64, J/m2: global shortwave received during each step."""
        return self.ghi * self.step_s

    @property
    def par_source(self) -> str:
        """Where the period's PAR comes from: "measured" (a weather file's ``par`` column,
        :attr:`par_measured`) or "shortwave" (ghi x :attr:`par_umol_per_j`)."""
        return "measured" if self.par_measured is not None else "shortwave"

    @property
    def par_umol_m2_s(self) -> np.ndarray:
        """(n,) float64, umol/m2/s: incident PAR photon flux (PPFD) at each step: measured,
        else ghi x :attr:`par_umol_per_j`."""
        if self.par_measured is not None:
            return self.par_measured
        return self.ghi * self.par_umol_per_j

    @property
    def _direct_share(self) -> np.ndarray:
        """(n,) the direct part of each step's shortwave (a measured PAR is shared so; all
        diffuse where the shortwave is 0)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.ghi > 0, self.direct_horizontal / np.where(
                self.ghi > 0, self.ghi, 1.0), 0.0)

    @property
    def _par_direct_share(self) -> np.ndarray:
        """(n,) the direct part of each step's PAR: the PAR split where the period has one
        (not for a measured PAR), else the shortwave's."""
        if self.par_diffuse_share is not None and self.par_measured is None:
            return 1.0 - self.par_diffuse_share
        return self._direct_share

    def diffuse_ratio(self, band: str) -> np.ndarray:
        """(n,) the band's diffuse share of each step over the shortwave's: 1 but for PAR on a
        period with its own PAR split (:attr:`par_diffuse_share`).

        Parameters
        ----------
        band : {"par", "nir"}
            The waveband.

        Returns
        -------
        numpy.ndarray
            (n,) float64: the band's diffuse irradiance is ``dhi x band share x`` this.
        """
        ones = np.ones(self.n_steps)
        if band != "par" or self.par_diffuse_share is None or self.par_measured is not None:
            return ones
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.dhi > 0, self.par_diffuse_share * self.ghi
                            / np.where(self.dhi > 0, self.dhi, 1.0), ones)

    @property
    def step_par_mol_m2(self) -> np.ndarray:
        """(n,) float64, mol/m2: incident PAR during each step."""
        if self.par_measured is not None:
            return self.par_measured * self.step_s * 1e-6
        return self.ghi * self.step_s * self.par_umol_per_j * 1e-6

    @property
    def step_direct_par_mol_m2(self) -> np.ndarray:
        """(n,) float64, mol/m2: direct (sun) part of :attr:`step_par_mol_m2`."""
        if self.par_measured is not None or self.par_diffuse_share is not None:
            return self.step_par_mol_m2 * self._par_direct_share
        return self.direct_horizontal * self.step_s * self.par_umol_per_j * 1e-6

    @property
    def step_diffuse_par_mol_m2(self) -> np.ndarray:
        """(n,) float64, mol/m2: diffuse (sky) part of :attr:`step_par_mol_m2`."""
        if self.par_measured is not None or self.par_diffuse_share is not None:
            return self.step_par_mol_m2 - self.step_direct_par_mol_m2
        return self.dhi * self.step_s * self.par_umol_per_j * 1e-6

    # ---- period totals: the sums of the steps
    @property
    def shortwave_mj_m2(self) -> float:
        """Global shortwave over the period, MJ/m2."""
        return math.fsum(self.step_shortwave_j_m2) * 1e-6

    @property
    def direct_mj_m2(self) -> float:
        """Direct (sun) shortwave on the horizontal over the period, MJ/m2."""
        return math.fsum(self.direct_horizontal * self.step_s) * 1e-6

    @property
    def diffuse_mj_m2(self) -> float:
        """Diffuse (sky) shortwave on the horizontal over the period, MJ/m2."""
        return math.fsum(self.dhi * self.step_s) * 1e-6

    @property
    def par_mol_m2(self) -> float:
        """Incident PAR over the period, mol/m2."""
        return math.fsum(self.step_par_mol_m2)

    @property
    def direct_par_mol_m2(self) -> float:
        """Direct (sun) part of the incident PAR, mol/m2."""
        return math.fsum(self.step_direct_par_mol_m2)

    @property
    def diffuse_par_mol_m2(self) -> float:
        """Diffuse (sky) part of the incident PAR, mol/m2."""
        return math.fsum(self.step_diffuse_par_mol_m2)

    def daily_totals(self):
        """Totals per local day (a step belongs to the day of its middle).

        Returns
        -------
        pandas DataFrame indexed by date, columns shortwave_mj_m2, direct_mj_m2,
        diffuse_mj_m2, par_mol_m2, steps
        """
        import pandas as pd

        days = pd.Index(self.times.date if self.n_steps else [], name="date")
        frame = pd.DataFrame({"shortwave_mj_m2": self.step_shortwave_j_m2 * 1e-6,
                              "direct_mj_m2": self.direct_horizontal * self.step_s * 1e-6,
                              "diffuse_mj_m2": self.dhi * self.step_s * 1e-6,
                              "par_mol_m2": self.step_par_mol_m2,
                              "steps": np.ones(self.n_steps, dtype=np.int64)}, index=days)
        return frame.groupby(level="date").sum()

    def with_par_factor(self, par_umol_per_j: float) -> Period:
        """The same period with another PAR conversion factor (umol per J of shortwave)."""
        return replace(self, par_umol_per_j=_check_par_factor(par_umol_per_j))

    def suns(self) -> list:
        """One :class:`maizeviz.light.sources.sun.Sun` per step, for tracing the direct light."""
        from maizeviz.light.sources.sun import Sun

        return [Sun(float(z), float(a), t.isoformat())
                for z, a, t in zip(self.zenith_deg, self.azimuth_deg, self.times, strict=True)]


def _period_from_fields(values: dict) -> Period:
    return Period(**values)


# --------------------------------------------------------------------------- clear sky


def clear_sky(track: SunTrack, linke_turbidity: float = DEFAULT_LINKE_TURBIDITY,
              par_umol_per_j: float = DEFAULT_PAR_UMOL_PER_J) -> Period:
    """Clear-sky irradiance at each step of a sun track: pvlib's Ineichen-Perez model.

    Parameters
    ----------
    track : SunTrack (its altitude is the site altitude of the model)
    linke_turbidity : float in [1, 10]: Linke turbidity (1 = clean dry air, 3 = average rural,
        5 and more = hazy or polluted); no climatology lookup file is read
    par_umol_per_j : float, umol of PAR per J of shortwave

    Returns
    -------
    Period whose ``source`` and ``parameters`` name the model and its parameters
    """
    import pandas as pd
    import pvlib

    if isinstance(linke_turbidity, bool) or not isinstance(
            linke_turbidity, (int, float, np.integer, np.floating)) \
            or not math.isfinite(linke_turbidity) or not (1 <= linke_turbidity <= 10):
        raise MaizevizError(f"Linke turbidity must be a number in [1, 10], got "
                            f"{linke_turbidity!r}", quantity="linke_turbidity")
    par = _check_par_factor(par_umol_per_j)
    params = {"model": "ineichen", "linke_turbidity": float(linke_turbidity),
              "altitude_m": track.altitude_m, "airmass_model": "kastenyoung1989",
              "solar_position": "pvlib nrel_numpy (SPA)", "pvlib": pvlib.__version__}
    source = (f"clear sky: Ineichen-Perez model (Ineichen & Perez 2002) in pvlib "
              f"{pvlib.__version__}, Linke turbidity {linke_turbidity:g}, altitude "
              f"{track.altitude_m:g} m, Kasten-Young air mass")
    n = track.n_steps
    if n:
        pos = pd.DataFrame({"apparent_zenith": track.zenith_deg,
                            "zenith": track.true_zenith_deg,
                            "apparent_elevation": 90.0 - track.zenith_deg}, index=track.times)
        site = pvlib.location.Location(track.latitude, track.longitude, tz=track.tz,
                                       altitude=track.altitude_m)
        cs = site.get_clearsky(track.times, model="ineichen", solar_position=pos,
                               linke_turbidity=float(linke_turbidity))
        ghi = cs["ghi"].to_numpy(float)
        dni = cs["dni"].to_numpy(float)
    else:
        ghi = dni = np.zeros(0)
    direct_h = np.minimum(dni * np.cos(np.radians(track.zenith_deg)), ghi)
    params["par_split"] = "spitters1986"
    source += "; PAR's diffuse part by Spitters et al. 1986 (WOFOST)"
    share = np.zeros(0)
    if n:
        transmission = _day_transmission(site, track.times, float(linke_turbidity))
        share = par_diffuse_shares(track.times, track.zenith_deg, ghi, transmission)
    return Period(times=track.times, step_s=track.step_s, zenith_deg=track.zenith_deg,
                  azimuth_deg=track.azimuth_deg, ghi=ghi, dni=dni, dhi=ghi - direct_h,
                  direct_horizontal=direct_h, start=track.start, end=track.end, source=source,
                  parameters=params, par_umol_per_j=par, notes=track.notes,
                  par_diffuse_share=share)


def diffuse_fraction_spitters(transmission):
    """The day's diffuse fraction of global radiation from its atmospheric transmission
    (Spitters et al. 1986, the daily relation as WOFOST codes it: PCSE's ``astro``).

    Parameters
    ----------
    transmission : float or numpy.ndarray
        The day's global radiation over the extraterrestrial on a horizontal plane [-].

    Returns
    -------
    numpy.ndarray
        The diffuse fraction FRDIF [-], in [0.23, 1].
    """
    t = np.asarray(transmission, dtype=np.float64)
    return np.select([t > 0.75, t > 0.35, t > 0.07],
                     [0.23, 1.33 - 1.46 * t, 1.0 - 2.3 * (t - 0.07) ** 2], 1.0)


def _day_transmission(site, times, linke_turbidity: float) -> np.ndarray:
    """(n,) float64: the atmospheric transmission of each step's whole local day (clear-sky
    shortwave over the extraterrestrial on the horizontal, the day sampled every 10 minutes),
    so that a part of a day splits its PAR as the whole day does."""
    import pandas as pd
    import pvlib

    dates = np.asarray(times.date)
    out = np.zeros(len(dates))
    for d in np.unique(dates):
        t = pd.date_range(pd.Timestamp(d, tz=times.tz), periods=144, freq="10min") + \
            pd.Timedelta(minutes=5)
        pos = site.get_solarposition(t)
        up = pos["apparent_zenith"].to_numpy(float) < 90.0
        if not up.any():
            continue
        cs = site.get_clearsky(t[up], model="ineichen", solar_position=pos[up],
                               linke_turbidity=linke_turbidity)
        top = np.asarray(pvlib.irradiance.get_extra_radiation(t[up]), np.float64) * np.cos(
            np.radians(pos["apparent_zenith"].to_numpy(float)[up]))
        out[dates == d] = float(cs["ghi"].to_numpy(float).sum()) / float(top.sum())
    return out


def par_diffuse_shares(times, zenith_deg, ghi, transmission) -> np.ndarray:
    """The diffuse part of each step's PAR by the standard PAR split (Spitters et al. 1986,
    as WOFOST uses it; see the module docstring).

    Parameters
    ----------
    times : (n,) pandas DatetimeIndex, time-zone aware
        Middle of each step.
    zenith_deg : (n,) float64
        The sun's apparent zenith [deg], < 90.
    ghi : (n,) float64
        Global horizontal irradiance [W m-2].
    transmission : (n,) float64
        The atmospheric transmission of each step's day [-].

    Returns
    -------
    numpy.ndarray
        (n,) float64 in [0, 1]: diffuse PAR over PAR at each step (1 where there is no light).
    """
    import pvlib

    ghi = np.asarray(ghi, np.float64)
    if not len(ghi):
        return np.zeros(0)
    t = np.asarray(transmission, np.float64)
    top = np.asarray(pvlib.irradiance.get_extra_radiation(times), np.float64) * np.cos(
        np.radians(np.asarray(zenith_deg, np.float64)))                 # W/m2, horizontal
    diffuse = diffuse_fraction_spitters(t) * t * top                      # W/m2 of shortwave
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(ghi > 0, np.clip(diffuse / np.where(ghi > 0, ghi, 1.0), 0.0, 1.0), 1.0)


def clear_sky_period(date, lat: float, lon: float, tz: str, step_min: float = 30.0,
                     start: str | None = None, end: str | None = None, altitude: float = 0.0,
                     linke_turbidity: float = DEFAULT_LINKE_TURBIDITY,
                     par_umol_per_j: float = DEFAULT_PAR_UMOL_PER_J) -> Period:
    """A clear day (or part of it) at a place: ``clear_sky(sun_track(...))``.

    Parameters
    ----------
    date : str
        The local date, "YYYY-MM-DD".
    lat : float
        Latitude [deg north].
    lon : float
        Longitude [deg east].
    tz : str
        IANA time zone of the day.
    step_min : float
        Time between steps [min].
    start, end : str, optional
        Local clock times "HH:MM" bounding the period (None: the whole day).
    altitude : float
        Height of the place above sea level [m].
    linke_turbidity : float
        Linke turbidity of the clear sky [-].
    par_umol_per_j : float
        PAR photons per joule of shortwave [umol J-1].

    Returns
    -------
    Period
        The steps with the sun up: their times, sun, irradiance and PAR doses.

    References
    ----------
    Ineichen, P. & Perez, R. (2002). A new airmass independent formulation for the Linke
    turbidity coefficient. Solar Energy 73(3), 151-157.
    https://doi.org/10.1016/S0038-092X(02)00045-2
    """
    return clear_sky(sun_track(date, lat, lon, tz, step_min=step_min, start=start, end=end,
                               altitude=altitude),
                     linke_turbidity=linke_turbidity, par_umol_per_j=par_umol_per_j)


# --------------------------------------------------------------------------- weather file


@dataclass(frozen=True, eq=False)
class Weather:
    """A weather file's rows: irradiance, measured PAR and air temperature.

    Attributes
    ----------
    path : str
    times : (n,) pandas DatetimeIndex, time-zone aware: middle of the interval of each row
    step_s : (n,) float64, s: length of the interval each row stands for
    ghi : (n,) float64, W/m2 (a file of PAR alone: estimated from it, see ``estimated``)
    dni, dhi : (n,) float64 W/m2, or None when the file has no such column
    line : (n,) int64: line of each row in the file, for messages
    label : "center", "start" or "end": where the file's times sit in their interval
    start, end : pandas Timestamp: bounds of the period the file covers
    par : (n,) float64 umol/m2/s, measured PAR (a quantum sensor's PPFD), or None
    temp_air : (n,) float64 deg C, air temperature (NaN where the file has none), or None;
        kept for models of leaf processes (photosynthesis), not used by the light
    kind : "csv", "epw", "tmy3" or "psm": the file's format
    place : the file's header's latitude, longitude (deg), altitude (m) and name, where the
        format has them (EPW, TMY3, PSM), else empty
    notes : what the reader decided, one line each
    estimated : names of columns estimated rather than read ("ghi" from PAR alone)
    """

    path: str
    times: pd.DatetimeIndex
    step_s: np.ndarray
    ghi: np.ndarray
    dni: np.ndarray | None
    dhi: np.ndarray | None
    line: np.ndarray
    label: str
    start: pd.Timestamp
    end: pd.Timestamp
    par: np.ndarray | None = None
    temp_air: np.ndarray | None = None
    kind: str = "csv"
    place: Mapping[str, object] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    estimated: tuple[str, ...] = ()

    def __post_init__(self):
        for name in ("step_s", "ghi", "dni", "dhi", "par", "temp_air"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, _frozen(getattr(self, name)))

    @property
    def columns(self) -> tuple[str, ...]:
        """Columns the file gave (irradiance, PAR, air temperature)."""
        return tuple(c for c in WEATHER_OPTIONAL
                     if getattr(self, c) is not None and c not in self.estimated)


def _check_order(utc_us: np.ndarray, lines: list, texts: list, path: Path) -> np.ndarray:
    """Seconds between consecutive rows (times ``utc_us`` in int64 microseconds); refuses
    unsorted, repeated times and gaps."""
    steps = np.diff(utc_us).astype(np.float64) / 1e6
    for k in np.flatnonzero(steps <= 0):
        what = "repeats the time of" if steps[k] == 0 else "is earlier than"
        raise WeatherFileError(f"{path}, line {lines[k + 1]}, column time: '{texts[k + 1]}' "
                               f"{what} line {lines[k]} ('{texts[k]}'); times must increase")
    usual = float(np.median(steps))
    gaps = np.flatnonzero(steps > GAP_FACTOR * usual)
    if len(gaps):
        k = gaps[0]
        raise WeatherFileError(f"{path}, line {lines[k + 1]}, column time: a gap of "
                               f"{_fmt_duration(steps[k])} after line {lines[k]} "
                               f"('{texts[k]}'), more than {GAP_FACTOR:g} x the usual step of "
                               f"{_fmt_duration(usual)}; fill the gap or split the file")
    return steps


def _intervals(utc_us: np.ndarray, label: str) -> np.ndarray:
    """Interval edges (n + 1,) int64 microseconds for rows at times ``utc_us`` (n,) int64
    microseconds sitting at ``label`` of their interval. Integers, not float seconds: a float
    holds a year-0001 time only to about 8 microseconds."""
    steps = np.diff(utc_us)
    if label == "start":
        return np.append(utc_us, utc_us[-1] + steps[-1])
    if label == "end":
        return np.concatenate([[utc_us[0] - steps[0]], utc_us])
    mids = utc_us[:-1] + steps // 2
    return np.concatenate([[utc_us[0] - steps[0] // 2], mids, [utc_us[-1] + steps[-1] // 2]])


def read_weather(path, tz: str | None = None, label: str | None = None,
                 max_bytes: int = MAX_WEATHER_BYTES) -> Weather:
    """Read a weather file: maizeviz's CSV, or an EPW, TMY3 or PSM file through pvlib.

    EnergyPlus EPW, NREL TMY3 and NSRDB PSM3/PSM4 files are read through pvlib
    (:mod:`maizeviz.io.weather_files`), recognised by their first lines.

    maizeviz's CSV: comma-separated, a header line, blank lines and lines starting with '#'
    ignored. Columns (any order and case): ``time`` (ISO 8601 with a UTC offset such as
    2005-08-01T12:00+08:00 or a trailing Z; without an offset only when ``tz`` is given, the
    times are then local clock times in ``tz``), ``ghi`` W/m2, ``dni``, ``dhi`` W/m2,
    ``par`` umol/m2/s (photosynthetic photon flux density measured by a quantum sensor:
    used for PAR instead of the shortwave times the PAR factor; a file of ``par`` without
    ``ghi`` has its shortwave estimated from it, for the direct and diffuse split), and
    ``temp_air`` deg C (kept for leaf process models); ``ghi`` or ``par`` is required, no
    other column.

    EPW, TMY3, PSM: the file's time zone comes from its header (a ``tz`` given is not used,
    said in a note when it differs), its times' place in their interval from the format (see
    :mod:`maizeviz.io.weather_files`), ghi, dni, dhi and the air temperature from its
    columns; a typical year is dated in one year.

    Rules: at least 2 rows; times strictly increasing; a step longer than GAP_FACTOR (1.5) x
    the median step is a gap and refused; irradiance must be numbers in [0,
    MAX_IRRADIANCE_W_M2] W/m2, PAR in [0, MAX_PAR_UMOL_M2_S] umol/m2/s, air temperature in
    AIR_TEMPERATURE_C deg C (no NaN, no empty cell); files over ``max_bytes`` are refused
    before reading. The CSV is parsed, and these bounds are kept, by
    :mod:`maizeviz.io.weather_csv`.

    Each row stands for an interval (the midpoint rule of this module): with ``label``
    "center" (the CSV's default) the row's time is the middle of an interval reaching halfway
    to the neighbouring rows; "start" means the interval begins at the row's time and ends at
    the next row's; "end" means it ends at the row's time (hourly means stamped at the end of
    the hour). None: the format's own (CSV "center").

    Parameters
    ----------
    path : str or Path
        The weather file.
    tz : str, optional
        IANA time zone of CSV times without an offset; None: CSV times must carry their
        offset.
    label : {"center", "start", "end"}, optional
        Where each row's time sits in its interval; None: the format's own (CSV "center").
    max_bytes : int
        Largest file accepted [bytes].

    Returns
    -------
    Weather
        Its times, steps, irradiance columns and, when given, PAR and air temperature.

    Raises
    ------
    WeatherFileError
        One line naming the file, the line, the time and the column at fault.
    """
    path = Path(path)
    if label is not None and str(label).strip().lower() not in WEATHER_LABELS:
        raise MaizevizError(f"unknown weather time label '{label}' (known: "
                            f"{', '.join(WEATHER_LABELS)})")
    zone = _time_zone(tz) if tz is not None else None
    fh, _ = open_input(path, "weather file", WeatherFileError)
    with fh:
        head = fh.read(4096)
    kind = detect_format(path, head)
    if kind != "csv":
        return _from_table(path, read_pvlib_file(path, kind, max_bytes), zone, label)
    key = "center" if label is None else str(label).strip().lower()
    times, values, lines, texts, notes = read_weather_csv(path, zone, max_bytes)
    estimated: tuple[str, ...] = ()
    if "ghi" not in values:
        # PAR alone: its shortwave, for the direct and diffuse split only
        values["ghi"] = values["par"] / DEFAULT_PAR_UMOL_PER_J
        estimated = ("ghi",)
        notes.append(f"{path.name} gives PAR without ghi: the shortwave is taken as PAR / "
                     f"{DEFAULT_PAR_UMOL_PER_J:.4g} umol/J to split it into direct and "
                     "diffuse; PAR is the file's")
    return _assemble(path, times, values, lines, texts, key, "csv", {}, notes, estimated)


def _assemble(path: Path, times: Any, values: dict, lines: Any, texts: list, key: str,
              kind: str, place: dict, notes: list, estimated: tuple) -> Weather:
    """The Weather of rows read (times, columns, lines): order and gaps checked, each row's
    interval from ``key``."""
    utc_us = times.tz_convert("UTC").tz_localize(None).to_numpy(
        f"datetime64[{TIME_UNIT}]").astype(np.int64)
    _check_order(utc_us, list(lines), texts, path)
    edges = _intervals(utc_us, key)
    mids = edges[:-1] + np.diff(edges) // 2
    import pandas as pd

    def stamp(micros):
        return pd.DatetimeIndex(np.asarray(micros).astype(f"datetime64[{TIME_UNIT}]")
                                ).tz_localize("UTC").tz_convert(times.tz)

    bounds = stamp(edges[[0, -1]])
    return Weather(path=str(path), times=stamp(mids), step_s=_frozen(np.diff(edges) / 1e6),
                   ghi=_frozen(values["ghi"]), dni=values.get("dni"), dhi=values.get("dhi"),
                   line=_frozen(lines, np.int64), label=key, start=bounds[0], end=bounds[1],
                   par=values.get("par"), temp_air=values.get("temp_air"), kind=kind,
                   place=dict(place), notes=tuple(notes), estimated=estimated)


def _from_table(path: Path, table: WeatherTable, zone, label: str | None) -> Weather:
    """A Weather of an EPW, TMY3 or PSM file read by pvlib; the time zone is the file's."""
    name = PVLIB_FORMATS[table.kind]
    times = table.times
    notes = list(table.notes)
    if zone is not None and times[:1].tz_convert(zone)[0].utcoffset() != times[0].utcoffset():
        notes.append(f"{path.name}: this {name} file gives its own time zone (UTC"
                     f"{_offset_text(times[0])}), which its times keep; the zone given "
                     f"({tz_name(zone)}) is for CSV files without offsets")
    texts = [t.isoformat() for t in times]
    values = {c: table.values[c] for c in ("ghi", "dni", "dhi")}
    for c, v in values.items():                       # the bounds a CSV's cells are held to
        lo, hi, _ = BOUNDS[c]
        bad = np.flatnonzero(~((v >= lo) & (v <= hi)))
        if len(bad):
            k = int(bad[0])
            raise WeatherFileError(f"{path}, line {table.line[k]} ({texts[k]}), column {c}: "
                                   f"{value_problem(repr(float(v[k])), c)}")
    if np.isfinite(table.values["temp_air"]).any():
        values["temp_air"] = table.values["temp_air"]
    key = table.label if label is None else str(label).strip().lower()
    return _assemble(path, times, values, table.line, texts, key, table.kind, table.meta,
                     notes, ())


def _offset_text(t) -> str:
    off = t.utcoffset().total_seconds()
    return f"{'+' if off >= 0 else '-'}{int(abs(off)) // 3600:02d}:{int(abs(off)) % 3600 // 60:02d}"


def tz_name(zone) -> str:
    """A time zone's name in words (an IANA key, or its UTC offset)."""
    return str(getattr(zone, "key", None) or zone)


def _split_direct_diffuse(weather: Weather, up: np.ndarray, zen: np.ndarray,
                          true_zen: np.ndarray):
    """(direct_horizontal, dhi, decomposition name or None) for the rows with the sun up."""
    import pvlib

    ghi = weather.ghi[up]
    cosz = np.cos(np.radians(zen[up]))
    if weather.dhi is not None:
        dhi = np.minimum(weather.dhi[up], ghi)
        return ghi - dhi, dhi, None
    if weather.dni is not None:
        direct = np.minimum(weather.dni[up] * cosz, ghi)
        return direct, ghi - direct, None
    split = pvlib.irradiance.erbs(ghi, true_zen[up], weather.times[up])
    dhi = np.minimum(np.asarray(split["dhi"], dtype=float), ghi)
    return ghi - dhi, dhi, "erbs"


#: How far [deg] the place traced may be from the one a weather file's header names before a
#: note says so (0.05 deg is about 5 km: the same station, rounded).
PLACE_TOLERANCE_DEG = 0.05


def _place_note(weather: Weather, lat: float, lon: float) -> str:
    """A note when the sun is placed away from the place of the weather file's header
    (its times are that place's, its sun positions are computed at ``lat``, ``lon``)."""
    f_lat, f_lon = weather.place.get("latitude"), weather.place.get("longitude")
    if not isinstance(f_lat, (int, float)) or not isinstance(f_lon, (int, float)):
        return ""
    d_lon = abs((lon - f_lon + 180.0) % 360.0 - 180.0)
    if abs(lat - f_lat) <= PLACE_TOLERANCE_DEG and d_lon <= PLACE_TOLERANCE_DEG:
        return ""
    where = f", {weather.place['name']}" if weather.place.get("name") else ""
    return (f"the sun is placed at latitude {lat:g}, longitude {lon:g}, not where "
            f"{Path(weather.path).name} was measured (latitude {f_lat:g}, longitude "
            f"{f_lon:g}{where}, in its header): its sun positions do not match its "
            f"irradiance; use the file's place unless that is meant")


def weather_period(weather: Weather, lat: float, lon: float, altitude: float = 0.0,
                   par_umol_per_j: float = DEFAULT_PAR_UMOL_PER_J) -> Period:
    """The period of a weather file at a place: sun positions, direct and diffuse parts.

    A measured PAR column is the period's PAR (split into direct and diffuse as the
    shortwave is); the air temperature travels with the steps (:attr:`Period.temp_air`).
    The direct and diffuse parts keep the file's ghi: with ``dhi`` given, direct_horizontal =
    ghi - dhi (dhi above ghi is cut to ghi, said in a note naming the first such row; a
    ``dni`` column is then not used); with only ``dni``, direct_horizontal = dni
    cos(zenith) (cut to ghi) and dhi the rest; with ghi alone, the Erbs et al. (1982)
    diffuse fraction (pvlib; geometric zenith, day of year) gives dhi. ``dni`` is then
    direct_horizontal / cos(zenith). Rows whose middle has the sun below the horizon are
    dropped; their energy (twilight, sensor offsets) is stated in the notes.

    Parameters
    ----------
    weather : Weather
        From :func:`read_weather`.
    lat : float
        Latitude [deg north].
    lon : float
        Longitude [deg east].
    altitude : float
        Height of the place above sea level [m].
    par_umol_per_j : float
        PAR photons per joule of shortwave [umol J-1].

    Returns
    -------
    Period
        The rows with the sun up: their times, sun, irradiance and PAR doses.

    References
    ----------
    Erbs, D. G., Klein, S. A. & Duffie, J. A. (1982). Estimation of the diffuse radiation
    fraction for hourly, daily and monthly-average global radiation. Solar Energy 28(4),
    293-302. https://doi.org/10.1016/0038-092X(82)90302-4
    """
    lat, lon = _check_place(lat, lon)
    altitude = _check_altitude(altitude)
    par = _check_par_factor(par_umol_per_j)
    zen, true_zen, azi = _solar_position(weather.times, lat, lon, altitude)
    up = zen < 90.0
    direct, dhi, decomposition = _split_direct_diffuse(weather, up, zen, true_zen)
    ghi = direct + dhi
    dni = direct / np.cos(np.radians(zen[up]))
    notes = list(weather.notes)
    if weather.dhi is not None:
        over = np.flatnonzero(weather.dhi[up] > weather.ghi[up])
        if len(over):                  # a sensor's offset at low sun, or columns swapped
            first = weather.times[up][int(over[0])]
            unused = " (its dni is not used: ghi - dhi gives the direct part)" \
                if weather.dni is not None else ""
            rows = f"{len(over)} rows" if len(over) > 1 else "1 row"
            notes.append(f"{rows} of {Path(weather.path).name} with the sun up "
                         f"{'have' if len(over) > 1 else 'has'} dhi above ghi (first: "
                         f"{first.isoformat()}): diffuse cut to ghi, no direct light{unused}")
    if not up.any():
        notes.append(_no_sun_note(weather.start, weather.end, lat, lon))
    away = _place_note(weather, lat, lon)
    if away:
        notes.append(away)
    night = ~up
    night_j = math.fsum(weather.ghi[night] * weather.step_s[night])
    if night_j > 0:
        notes.append(f"{int(night.sum())} rows of {Path(weather.path).name} have the sun below "
                     f"the horizon; their {night_j / 1e3:.1f} kJ/m2 of ghi (twilight or sensor "
                     f"offset) is not traced")
    name = Path(weather.path).name
    given = ", ".join(weather.columns)
    fmt = "" if weather.kind == "csv" else f"{PVLIB_FORMATS[weather.kind]} "
    source = f"weather file {fmt}{name} ({given} given"
    source += "; dni and dhi from the Erbs et al. 1982 decomposition in pvlib" \
        if decomposition else ""
    source += "; PAR measured, not from the shortwave)" if weather.par is not None else ")"
    params = {"weather_file": weather.path, "columns": list(weather.columns),
              "decomposition": decomposition, "time_label": weather.label,
              "altitude_m": altitude, "format": weather.kind,
              "par": "measured" if weather.par is not None else "shortwave x factor"}
    return Period(times=weather.times[up], step_s=weather.step_s[up], zenith_deg=zen[up],
                  azimuth_deg=azi[up], ghi=ghi, dni=dni, dhi=dhi, direct_horizontal=direct,
                  start=weather.start, end=weather.end, source=source, parameters=params,
                  par_umol_per_j=par, notes=tuple(notes),
                  par_measured=None if weather.par is None else weather.par[up],
                  temp_air=None if weather.temp_air is None else weather.temp_air[up])
