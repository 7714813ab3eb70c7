"""Where the sun is: explicit angles, or place + date + clock time through pvlib.

Angles in degrees: zenith from the vertical, azimuth clockwise from north. Field coordinates
have x = east and y = north unless the layout turns the field (``north_deg``: the clockwise
angle from north to the field's +y axis).
"""

from __future__ import annotations

import datetime as _dt
import zoneinfo
from dataclasses import dataclass

import numpy as np

from maizeviz.errors import MaizevizError


@dataclass(frozen=True)
class Sun:
    """Sun angles (degrees) and, when computed from a place, when and where."""

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
        """Unit vector (3,) from the ground toward the sun in field coordinates."""
        z = np.radians(self.zenith_deg)
        a = np.radians(self.azimuth_deg - north_deg)
        return np.array([np.sin(z) * np.sin(a), np.sin(z) * np.cos(a), np.cos(z)])


def _zone(tz: str) -> _dt.tzinfo:
    try:
        return zoneinfo.ZoneInfo(tz)
    except (zoneinfo.ZoneInfoNotFoundError, ValueError, TypeError, OSError):  # OSError: a name
        # too long for a file name (ZoneInfo looks it up as a path)
        raise MaizevizError(f"unknown time zone '{tz}': use an IANA name such as "
                            "Asia/Shanghai or Europe/Paris", quantity="tz") from None


def local_time(day: _dt.date, clock: str, tz: str | None) -> _dt.datetime:
    """A timezone-aware time from a date, a clock time ``HH:MM[:SS][+HH:MM]`` and a zone.

    A clock time with its own UTC offset needs no zone; with a zone too, both must agree.
    Without either, the time is UTC.
    """
    try:
        t = _dt.time.fromisoformat(str(clock).strip())
    except ValueError:
        raise MaizevizError(f"the clock time must be HH:MM or HH:MM:SS, got '{clock}'",
                            quantity="time") from None
    when = _dt.datetime.combine(day, t)
    if when.tzinfo is not None:
        if tz is not None:
            zoned = when.replace(tzinfo=None).replace(tzinfo=_zone(tz))
            if zoned.utcoffset() != when.utcoffset():
                raise MaizevizError(
                    f"the time {clock} carries UTC offset {when.strftime('%z')} but the zone "
                    f"{tz} is at {zoned.strftime('%z')} on {day}: give one of them",
                    quantity="time")
        return when
    return when.replace(tzinfo=_zone(tz) if tz is not None else _dt.timezone.utc)


def sun_at(date: str, time: str | None, lat: float, lon: float, tz: str | None = None,
           solar_noon: bool = False, altitude: float = 0.0) -> Sun:
    """Sun position at a place and local clock time (or that day's true solar noon).

    Parameters
    ----------
    date : "YYYY-MM-DD"; time : "HH:MM" or "HH:MM:SS" local clock time in ``tz`` (or with
        its own offset, "12:00+08:00")
    lat, lon : degrees (north, east positive); tz : IANA zone such as "Asia/Shanghai" (UTC
        when neither the time nor ``tz`` says)
    """
    import pandas as pd
    import pvlib

    if not (-90 <= lat <= 90) or not (-180 <= lon <= 360):
        raise MaizevizError(f"latitude must be in [-90, 90] and longitude in [-180, 360], "
                            f"got {lat}, {lon}", quantity="place")
    try:
        day = _dt.date.fromisoformat(str(date))
    except (TypeError, ValueError):
        raise MaizevizError(f"the date must be YYYY-MM-DD, got '{date}'", quantity="date") from None
    if solar_noon:
        zone = _zone(tz) if tz is not None else _dt.timezone.utc
        midnight = pd.DatetimeIndex([pd.Timestamp(_dt.datetime.combine(day, _dt.time(), zone))])
        transit = pvlib.solarposition.sun_rise_set_transit_spa(midnight, lat, lon)
        when = pd.Timestamp(transit["transit"].iloc[0])
    else:
        if not time:
            raise MaizevizError("give a clock time HH:MM, or ask for the day's solar noon",
                                quantity="time")
        when = pd.Timestamp(local_time(day, time, tz))
    pos = pvlib.solarposition.get_solarposition(pd.DatetimeIndex([when]), lat, lon, altitude)
    return Sun(float(pos["apparent_zenith"].iloc[0]), float(pos["azimuth"].iloc[0]),
               when.isoformat())
