"""Clock times, time zones and places: one rule for every light input that names a time.

A *clock time* is ``HH:MM`` or ``HH:MM:SS``, optionally followed by a UTC offset
(``12:00+08:00``); ``24:00`` is the end of the day. It is read on a given day:

- with an offset and no zone, the offset says where the clock is;
- with a zone (IANA name, "Asia/Shanghai"), the clock is the zone's wall clock; an offset given
  too must be the zone's offset on that day, and a wall-clock time that daylight saving skips
  or repeats is refused rather than guessed;
- with neither, the time is UTC.

The single sun (:func:`maizeviz.light.sources.sun.sun_at`) and the sun track of a period
(:func:`maizeviz.light.sources.irradiance.sun_track`) both read their times here.

References
----------
- IANA time zone database, https://www.iana.org/time-zones (Python's :mod:`zoneinfo`).
- ISO 8601-1:2019, Date and time, representations for information interchange.
"""

from __future__ import annotations

import datetime as _dt
import math
import numbers

from maizeviz.errors import MaizevizError
from maizeviz.io.dates import TIME_UNIT


def zone(tz) -> _dt.tzinfo:
    """The IANA time zone named ``tz``.

    Parameters
    ----------
    tz : str
        IANA name such as "Asia/Shanghai", "Europe/Paris" or "UTC".

    Returns
    -------
    datetime.tzinfo

    Raises
    ------
    MaizevizError
        Unknown name (``quantity`` "tz").
    """
    import zoneinfo

    try:
        return zoneinfo.ZoneInfo(str(tz))
    except (zoneinfo.ZoneInfoNotFoundError, ValueError, TypeError, OSError):
        # OSError: a name that is a folder of the zone database ("Asia") or too long for a
        # file name reaches the file system before zoneinfo can say it is not a zone
        raise MaizevizError(f"unknown time zone '{str(tz)[:40]}' (give an IANA name such as "
                            f"Asia/Shanghai, or UTC)", quantity="tz") from None


def check_place(lat, lon) -> tuple[float, float]:
    """Latitude and longitude as floats, degrees north and east.

    Raises
    ------
    MaizevizError
        Not numbers, or outside [-90, 90] x [-180, 360] (``quantity`` "place").
    """
    try:
        lat, lon = float(lat), float(lon)
    except (TypeError, ValueError):
        raise MaizevizError(f"latitude and longitude must be numbers, got {lat!r}, {lon!r}",
                            quantity="place") from None
    if not (-90 <= lat <= 90) or not (-180 <= lon <= 360):
        raise MaizevizError(f"latitude must be in [-90, 90] and longitude in [-180, 360], "
                            f"got {lat}, {lon}", quantity="place")
    return lat, lon


def check_altitude(altitude) -> float:
    """A site altitude as a float, m above sea level, in [-500, 9000] (the Dead Sea's shore to
    above Everest; pvlib's pressure formula has no real value past 44 km).

    Raises
    ------
    MaizevizError
        Not a finite number in that range (``quantity`` "altitude").
    """
    value = float(altitude) if isinstance(altitude, numbers.Real) and \
        not isinstance(altitude, bool) else math.nan
    if not (math.isfinite(value) and -500 <= value <= 9000):
        raise MaizevizError(f"site altitude must be a number of metres in [-500, 9000], "
                            f"got {altitude!r}", quantity="altitude")
    return value


def parse_clock(clock, what: str = "clock",
                quantity: str = "time") -> tuple[_dt.timedelta, _dt.tzinfo | None]:
    """A clock time (see the module docstring) as the time since midnight and its UTC offset.

    Parameters
    ----------
    clock : str
        ``HH:MM[:SS]`` with an optional UTC offset, or ``24:00``.
    what : str
        Names the time in the message ("start", "end", "clock").
    quantity : str
        The ``quantity`` of the error.

    Returns
    -------
    since_midnight : datetime.timedelta
    offset : datetime.tzinfo or None
        The offset written after the time, None without one.
    """
    text = str(clock).strip()
    if text in ("24:00", "24:00:00"):
        return _dt.timedelta(days=1), None
    try:
        t = _dt.time.fromisoformat(text)
    except ValueError:
        raise MaizevizError(f"the {what} time must be HH:MM (local clock), got '{clock}'",
                            quantity=quantity) from None
    return (_dt.timedelta(hours=t.hour, minutes=t.minute, seconds=t.second,
                          microseconds=t.microsecond), t.tzinfo)


def local_datetime(day: _dt.date, clock, tz=None, what: str = "clock",
                   quantity: str = "time") -> _dt.datetime:
    """The clock time ``clock`` on ``day`` in zone ``tz``, by the module's rule, without pandas.

    Parameters
    ----------
    day : datetime.date
    clock : str, see :func:`parse_clock`
    tz : str or tzinfo or None
        IANA zone of the wall clock; None: the clock's own offset, else UTC.
    what, quantity : name the time and the error's quantity in messages.

    Returns
    -------
    datetime.datetime, timezone-aware.

    Raises
    ------
    MaizevizError
        Bad clock text, unknown zone, an offset that is not the zone's on that day, a wall-clock
        time skipped or repeated by daylight saving.
    OverflowError
        ``24:00`` on 9999-12-31 (the next day is past :class:`datetime.date`'s calendar;
        :func:`local_time` still reads it).
    """
    since, offset = parse_clock(clock, what, quantity)
    naive = _dt.datetime.combine(day, _dt.time()) + since
    where = None if tz is None else (tz if isinstance(tz, _dt.tzinfo) else zone(tz))
    zoned = None
    if where is not None:
        zoned = naive.replace(tzinfo=where)
        # PEP 495: a wall-clock time skipped or repeated by daylight saving is the only kind
        # whose two folds have different offsets
        if zoned.utcoffset() != naive.replace(tzinfo=where, fold=1).utcoffset():
            raise MaizevizError(f"the {what} time {naive:%H:%M} on {naive.date()} does not exist "
                                f"or occurs twice in {where} (a daylight-saving change); pick "
                                "another time", quantity=quantity)
    if offset is None:
        return zoned if zoned is not None else naive.replace(tzinfo=_dt.UTC)
    when = naive.replace(tzinfo=offset)
    if zoned is not None and zoned.utcoffset() != when.utcoffset():
        raise MaizevizError(f"the {what} time {clock} carries UTC offset {when:%z} but the zone "
                            f"{where} is at {zoned:%z} on {day}: give one of them",
                            quantity=quantity)
    return when


def local_time(day: _dt.date, clock, tz=None, what: str = "clock", quantity: str = "time"):
    """:func:`local_datetime` as a pandas Timestamp in microseconds.

    ``24:00`` on 9999-12-31 is read too: it is the next midnight, which pandas' microsecond
    Timestamps reach (:class:`datetime.datetime` does not).

    Returns
    -------
    pandas.Timestamp, timezone-aware, unit "us".
    """
    import pandas as pd

    try:
        return pd.Timestamp(local_datetime(day, clock, tz, what, quantity)).as_unit(TIME_UNIT)
    except OverflowError:      # only 24:00, which carries no offset: the next day's 00:00
        return local_time(day, "00:00", tz, what, quantity) + pd.Timedelta(days=1)
