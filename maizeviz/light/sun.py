"""Where the sun is: explicit angles, or place + date + clock time through pvlib.

Angles in degrees: zenith from the vertical, azimuth clockwise from north. Field coordinates
have x = east and y = north unless the layout turns the field (``north_deg``: the clockwise
angle from north to the field's +y axis).
"""

from __future__ import annotations

import datetime as _dt
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
            raise MaizevizError("sun angles must be finite numbers")
        if self.zenith_deg >= 90.0:
            raise MaizevizError(f"the sun is below the horizon (zenith {self.zenith_deg:.2f} deg)"
                                f"{' at ' + self.when if self.when else ''}: no direct light")
        if self.zenith_deg < 0.0:
            raise MaizevizError(f"sun zenith must be between 0 and 90 deg, got {self.zenith_deg}")

    def direction(self, north_deg: float = 0.0) -> np.ndarray:
        """Unit vector (3,) from the ground toward the sun in field coordinates."""
        z = np.radians(self.zenith_deg)
        a = np.radians(self.azimuth_deg - north_deg)
        return np.array([np.sin(z) * np.sin(a), np.sin(z) * np.cos(a), np.cos(z)])


def sun_at(date: str, time: str | None, lat: float, lon: float, tz: str,
           solar_noon: bool = False, altitude: float = 0.0) -> Sun:
    """Sun position at a place and local clock time (or that day's true solar noon).

    Parameters
    ----------
    date : "YYYY-MM-DD"; time : "HH:MM" or "HH:MM:SS" local clock time in ``tz``
    lat, lon : degrees (north, east positive); tz : IANA zone such as "Asia/Shanghai"
    """
    import pandas as pd
    import pvlib

    if not (-90 <= lat <= 90) or not (-180 <= lon <= 360):
        raise MaizevizError(f"latitude must be in [-90, 90] and longitude in [-180, 360], "
                            f"got {lat}, {lon}")
    try:
        day = _dt.date.fromisoformat(date)
    except (TypeError, ValueError):
        raise MaizevizError(f"--date must be YYYY-MM-DD, got '{date}'") from None
    try:
        if solar_noon:
            midnight = pd.DatetimeIndex([pd.Timestamp(day)]).tz_localize(tz)
            transit = pvlib.solarposition.sun_rise_set_transit_spa(midnight, lat, lon)
            when = transit["transit"].iloc[0]
        else:
            if not time:
                raise MaizevizError("give --time HH:MM or --solar-noon with --date")
            clock = _dt.time.fromisoformat(time)
            when = pd.Timestamp(_dt.datetime.combine(day, clock)).tz_localize(tz)
    except MaizevizError:
        raise
    except ValueError as exc:
        raise MaizevizError(f"cannot read the time: {exc}") from None
    except Exception as exc:  # pytz/zoneinfo errors have many types
        raise MaizevizError(f"unknown time zone '{tz}' ({type(exc).__name__})") from None
    pos = pvlib.solarposition.get_solarposition(pd.DatetimeIndex([when]), lat, lon, altitude)
    return Sun(float(pos["apparent_zenith"].iloc[0]), float(pos["azimuth"].iloc[0]),
               when.isoformat())
