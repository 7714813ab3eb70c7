"""Where the sun is: explicit angles, or place + date + clock time by pvlib's SPA.

Angles in degrees: zenith from the vertical, azimuth clockwise from north. Field coordinates
have x = east and y = north unless the layout turns the field (``north_deg``: the clockwise
angle from north to the field's +y axis).
"""

from __future__ import annotations

import datetime as _dt
from dataclasses import dataclass

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.light.sources.clock import (
    check_altitude,
    check_place,
    local_datetime,
    parse_clock,
    zone,
)


@dataclass(frozen=True)
class Sun:
    """The sun's angles and, when computed from a place and time, when.

    Parameters
    ----------
    zenith_deg : float
        Angle of the sun from the vertical [deg], in [0, 90).
    azimuth_deg : float
        Azimuth, clockwise from north [deg].
    when : str
        The local time it was computed for, ISO 8601 with its UTC offset ("" when given as
        angles).

    Raises
    ------
    MaizevizError
        Angles that are not finite, or a sun at or below the horizon (quantity "sun").
    """

    zenith_deg: float
    azimuth_deg: float
    when: str = ""

    def __post_init__(self):
        if not (np.isfinite(self.zenith_deg) and np.isfinite(self.azimuth_deg)):
            raise MaizevizError("sun angles must be finite numbers", quantity="sun")
        if self.zenith_deg >= 90.0:
            raise MaizevizError(f"the sun is below the horizon (zenith {self.zenith_deg:.2f} deg)"
                                f"{' at ' + self.when if self.when else ''}: no direct light",
                                quantity="sun")
        if self.zenith_deg < 0.0:
            raise MaizevizError(f"sun zenith must be between 0 and 90 deg, got {self.zenith_deg}",
                                quantity="sun")

    def direction(self, north_deg: float = 0.0) -> np.ndarray:
        """Unit vector from the ground toward the sun, in field coordinates.

        Parameters
        ----------
        north_deg : float
            Direction of north in the field, clockwise from the field's y axis [deg].

        Returns
        -------
        numpy.ndarray
            (3,) float64 unit vector (x across rows, y along rows, z up).
        """
        z = np.radians(self.zenith_deg)
        a = np.radians(self.azimuth_deg - north_deg)
        return np.array([np.sin(z) * np.sin(a), np.sin(z) * np.cos(a), np.cos(z)])


def sun_at(date: str, time: str | None, lat: float, lon: float, tz: str | None = None,
           solar_noon: bool = False, altitude: float = 0.0) -> Sun:
    """The sun's position at a place and local clock time (or that day's true solar noon).

    Parameters
    ----------
    date : str
        The local date, "YYYY-MM-DD".
    time : str or None
        Local clock time "HH:MM" or "HH:MM:SS" in ``tz``, or with its own offset
        ("12:00+08:00"), read by :func:`maizeviz.light.sources.clock.local_datetime`; None
        with ``solar_noon``.
    lat : float
        Latitude [deg north].
    lon : float
        Longitude [deg east].
    tz : str, optional
        IANA zone such as "Asia/Shanghai" (UTC when neither the time nor ``tz`` says).
    solar_noon : bool
        The day's true solar noon (the sun's transit) instead of ``time``.
    altitude : float
        Height of the place above sea level [m].

    Returns
    -------
    Sun
        ``zenith_deg`` (apparent, refraction-corrected), ``azimuth_deg`` (clockwise from
        north), ``when`` (ISO 8601 with its UTC offset).

    Raises
    ------
    MaizevizError
        A bad date, clock time, zone or place, or the sun below the horizon (``quantity``
        names it).

    References
    ----------
    Reda, I. & Andreas, A. (2004). Solar position algorithm for solar radiation
    applications. Solar Energy 76(5), 577-589. https://doi.org/10.1016/j.solener.2003.12.003
    pvlib's implementation, run as its ``get_solarposition`` and ``sun_rise_set_transit_spa``
    run it but without importing pandas (:mod:`maizeviz.light.sources.solar_position`):
    Holmgren, W. F., Hansen, C. W. & Mikofski, M. A. (2018). pvlib python: a python package
    for modeling solar energy systems. Journal of Open Source Software 3(29), 884.
    https://doi.org/10.21105/joss.00884
    """
    from maizeviz.light.sources import solar_position as spa

    lat, lon = check_place(lat, lon)
    altitude = check_altitude(altitude)
    try:
        day = _dt.date.fromisoformat(str(date))
    except (TypeError, ValueError):
        raise MaizevizError(f"the date must be YYYY-MM-DD, got '{date}'", quantity="date") from None
    if solar_noon:
        where = zone(tz) if tz is not None else _dt.UTC
        ns = spa.transit_ns(day, lat, lon)
        unixtime, when = ns / 1e9, spa.iso_ns(ns, where)
    else:
        if not time:
            raise MaizevizError("give a clock time HH:MM, or ask for the day's solar noon",
                                quantity="time")
        try:
            clock = local_datetime(day, time, tz)
        except OverflowError:              # 24:00 on 9999-12-31
            raise MaizevizError(f"{date} {time} is past the last day maizeviz reads "
                                "(9999-12-31)", quantity="date") from None
        unixtime, when = spa.unix_seconds(clock), clock.isoformat()
    zenith, azimuth = spa.position(unixtime, lat, lon, altitude)
    if zenith >= 90.0 and tz is None and not solar_noon and parse_clock(time)[1] is None:
        # a clock time without a zone nor an offset is UTC: a local noon read so is often night
        raise MaizevizError(f"the sun is below the horizon (zenith {zenith:.2f} deg) at {when}: "
                            "the time was read as UTC, as no time zone was given: give the "
                            "place's zone (--tz Asia/Shanghai, say)", quantity="tz")
    return Sun(zenith, azimuth, when)
