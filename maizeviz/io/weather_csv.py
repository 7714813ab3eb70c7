"""maizeviz's weather CSV, parsed: a header of known columns, ISO 8601 times with their time
zone, numbers within their units' bounds.

This module reads the text and refuses what is wrong with one line naming the file, the line,
the time and the column; what the rows stand for (intervals, sun positions, a period) is
:func:`maizeviz.light.sources.irradiance.read_weather`'s. EPW, TMY3 and PSM files are read
through pvlib by :mod:`maizeviz.io.weather_files`, beside this one.
"""

from __future__ import annotations

import csv
import io
import math
import re
from pathlib import Path

import numpy as np

from maizeviz.io.dates import FIRST_YEAR, LAST_YEAR, TIME_UNIT, check_year
from maizeviz.io.inputs import read_input
from maizeviz.io.weather_files import WeatherFileError, weather_text
from maizeviz.numbers import NUMBER, first_unplain, number

#: Irradiance above this is refused as a unit mistake (the solar constant is ~1361 W/m2;
#: cloud enhancement rarely passes 1600 W/m2 on a horizontal sensor).
MAX_IRRADIANCE_W_M2 = 2000.0
#: The columns of maizeviz's weather CSV: the one it needs, and those it may have.
WEATHER_REQUIRED = ("time",)
WEATHER_OPTIONAL = ("ghi", "dni", "dhi", "par", "temp_air")
#: Irradiance columns of a weather CSV (W/m2).
WEATHER_IRRADIANCE = ("ghi", "dni", "dhi")
#: PAR above this (umol/m2/s) is refused as a unit mistake (full sun gives about 2,200).
MAX_PAR_UMOL_M2_S = 4000.0
#: Air temperatures outside this range (deg C) are refused in a weather CSV.
AIR_TEMPERATURE_C = (-90.0, 70.0)
# a clock time followed by a UTC offset or Z, at the end of the text
_ZONE_SUFFIX = re.compile(r"\d{2}:\d{2}(?::\d{2}(?:[.,]\d+)?)?\s*(?:Z|[+-]\d{2}(?::?\d{2})?)$",
                          re.IGNORECASE)


def read_weather_csv(path: Path, zone, max_bytes: int) -> tuple:
    """The rows of a weather CSV, checked.

    Parameters
    ----------
    path : Path
        The file.
    zone : tzinfo or None
        Time zone of times written without an offset; None: every time carries its offset.
    max_bytes : int
        Largest file accepted [bytes].

    Returns
    -------
    times : pandas DatetimeIndex, time-zone aware, microseconds
    values : dict of column name -> (n,) float64 in its unit (W/m2, umol/m2/s, deg C)
    lines : list of int, each row's line in the file
    texts : list of str, each row's time as written
    notes : list of str, what was decided (a zero-filled tail read up to)

    Raises
    ------
    WeatherFileError
        One line naming the file, the line, the time and the column at fault.
    """
    text, notes = _read_text(path, max_bytes)
    rows = _rows(text, path)
    first = next(rows, None)
    if first is None:
        raise WeatherFileError(f"{path}: the weather file is empty (no header, no rows)")
    columns = _header(first[0], first[1], path)
    lines, data = [], []
    for line, cells in rows:
        if len(cells) != len(columns):
            raise WeatherFileError(f"{path}, line {line}: {len(cells)} values for "
                                   f"{len(columns)} columns ({', '.join(columns)})")
        lines.append(line)
        data.append(cells)
    if not data:
        raise WeatherFileError(f"{path}: the weather file has a header but no data rows")
    if len(data) < 2:
        raise WeatherFileError(f"{path}: one data row is not enough to know the time step; "
                               f"give at least 2")
    texts = [row[columns["time"]] for row in data]
    times = _parse_times(texts, lines, path, zone)
    values = {c: _parse_values([row[columns[c]] for row in data], lines, texts, c, path)
              for c in WEATHER_OPTIONAL if c in columns}
    return times, values, lines, texts, notes


def _read_text(path: Path, max_bytes: int) -> tuple[str, list[str]]:
    """The text of a weather CSV and the notes on it (a zero-filled tail read up to)."""
    raw = read_input(path, "weather file", max_bytes, WeatherFileError)
    if not raw:
        raise WeatherFileError(f"{path}: the weather file is empty")
    return weather_text(raw, path)


def _rows(text: str, path: Path):
    """(line, fields) of the header and data rows: blank lines and '#' comments skipped."""
    reader = csv.reader(io.StringIO(text))
    try:
        for fields in reader:
            if not any(f.strip() for f in fields) or fields[0].lstrip().startswith("#"):
                continue
            yield reader.line_num, [f.strip() for f in fields]
    except csv.Error as exc:
        raise WeatherFileError(f"{path}, line {reader.line_num}: not readable as CSV "
                               f"({exc})") from None


def _header(line: int, fields: list, path: Path) -> dict:
    names = [f.lower() for f in fields]
    known = WEATHER_REQUIRED + WEATHER_OPTIONAL
    for k, name in enumerate(names):
        if not name:
            raise WeatherFileError(f"{path}, line {line}: column {k + 1} of the header has no "
                                   f"name (known columns: {', '.join(known)})")
        if name not in known:
            raise WeatherFileError(f"{path}, line {line}: unknown column '{fields[k]}' (known "
                                   f"columns: {', '.join(known)}; irradiance in W/m2, par in "
                                   f"umol/m2/s, temp_air in deg C)")
        if names.index(name) != k:
            raise WeatherFileError(f"{path}, line {line}: column '{name}' appears twice")
    if "time" not in names or not ({"ghi", "par"} & set(names)):
        missing = "time" if "time" not in names else "ghi"
        raise WeatherFileError(f"{path}, line {line}: missing column '{missing}' (required: "
                               f"time with a time zone, and ghi in W/m2 or par in umol/m2/s; "
                               f"optional: dni, dhi, temp_air)")
    return {name: k for k, name in enumerate(names)}


def _parse_times(texts: list, lines: list, path: Path, tz):
    """Time texts -> tz-aware DatetimeIndex in microseconds (in ``tz``, or the first row's
    offset); every local date in the years :func:`~maizeviz.io.dates.check_year` allows."""
    import pandas as pd

    zoned = np.array([bool(_ZONE_SUFFIX.search(t)) for t in texts])
    if tz is None and not zoned.all():
        k = int(np.argmin(zoned))
        raise WeatherFileError(f"{path}, line {lines[k]}, column time: '{texts[k]}' has no time "
                               f"zone; write ISO 8601 with an offset (2005-08-01T12:00+08:00) "
                               f"or give the time zone (tz, e.g. Asia/Shanghai)")

    def parse_one(k):
        try:              # ISO 8601 only: pd.Timestamp read '...T032005-08-01T04:00+08:00'
            stamp = pd.to_datetime([texts[k]], format="ISO8601")[0]
        except (ValueError, TypeError, OverflowError):
            raise WeatherFileError(f"{path}, line {lines[k]}, column time: cannot read "
                                   f"'{texts[k]}' as an ISO 8601 time") from None
        check_year(stamp.year, f"{path}, line {lines[k]}, column time", texts[k],
                   WeatherFileError, "weather")
        return stamp.as_unit(TIME_UNIT)

    def parse_all(idx, **kw):
        sub = [texts[k] for k in idx]
        try:
            found = pd.to_datetime(sub, format="ISO8601", **kw)
        except (ValueError, TypeError, OverflowError):
            # pandas refuses a mix it cannot hold in one resolution (nanosecond digits and a
            # year out of the nanosecond range): row by row, naming the first bad one
            stamps = [parse_one(k) for k in idx]
            if kw.get("utc"):                   # offsets of every kind, as one zone
                stamps = [t.tz_convert("UTC") for t in stamps]
            found = pd.DatetimeIndex(stamps)
        return found.as_unit(TIME_UNIT)

    utc = np.empty(len(texts), dtype=f"datetime64[{TIME_UNIT}]")
    with_zone = np.flatnonzero(zoned)
    if len(with_zone):
        utc[with_zone] = parse_all(with_zone, utc=True).tz_localize(None).to_numpy()
    naive = np.flatnonzero(~zoned)
    if len(naive):
        local = parse_all(naive)
        try:
            aware = local.tz_localize(tz, ambiguous="raise", nonexistent="raise")
        except ValueError:  # pandas' NonExistentTimeError / AmbiguousTimeError
            for k, t in zip(naive.tolist(), local, strict=True):
                try:
                    t.tz_localize(tz, ambiguous="raise", nonexistent="raise")
                except ValueError:
                    raise WeatherFileError(
                        f"{path}, line {lines[k]}, column time: '{texts[k]}' does not exist or "
                        f"occurs twice in {tz} (a daylight-saving change); write it with an "
                        f"offset") from None
            raise
        utc[naive] = aware.tz_convert("UTC").tz_localize(None).to_numpy()
    zone = tz if tz is not None else parse_one(0).tz
    times = pd.DatetimeIndex(utc).tz_localize("UTC").tz_convert(zone)
    years = np.asarray(times.year)
    for row in np.flatnonzero((years < FIRST_YEAR) | (years > LAST_YEAR)).tolist():
        check_year(int(years[row]), f"{path}, line {lines[row]}, column time", texts[row],
                   WeatherFileError, "weather")
    return times


#: Bounds of each CSV column's values, with their unit and what a value beyond them suggests.
BOUNDS = {"ghi": (0.0, MAX_IRRADIANCE_W_M2, "W/m2"), "dni": (0.0, MAX_IRRADIANCE_W_M2, "W/m2"),
           "dhi": (0.0, MAX_IRRADIANCE_W_M2, "W/m2"),
           "par": (0.0, MAX_PAR_UMOL_M2_S, "umol/m2/s"),
           "temp_air": (*AIR_TEMPERATURE_C, "deg C")}


def value_problem(text: str, column: str = "ghi") -> str | None:
    """What is wrong with one cell of ``column``, or None."""
    lo, hi, unit = BOUNDS[column]
    if text == "":
        return "missing value"
    try:
        value = number(text)
    except ValueError:
        return f"'{text}' is not a number"
    if math.isnan(value):
        return f"missing value ('{text}')"
    if not math.isfinite(value):
        return f"'{text}' is not a finite number"
    if value < lo:
        what = "irradiance" if unit == "W/m2" else column
        return f"negative {what} {value:g} {unit}" if lo == 0 else \
            f"{value:g} {unit} is below {lo:g} {unit}; is the unit {unit}?"
    if value > hi:
        return f"{value:g} {unit} is more than {hi:g} {unit}; is the unit {unit}?"
    return None


def _parse_values(texts: list, lines: list, times: list, column: str, path: Path) -> np.ndarray:
    """Cells of ``column`` -> (n,) float64 in its unit; refuses the first bad cell in file
    order."""
    lo, hi, _ = BOUNDS[column]
    try:
        values = np.array(texts, dtype=np.float64)
        ok = np.isfinite(values) & (values >= lo) & (values <= hi)
        if first_unplain(texts) is not None:          # numpy reads 1_000 as float does
            ok &= np.array([NUMBER.fullmatch(t) is not None for t in texts], bool)
        bad = np.flatnonzero(~ok)
    except ValueError:                              # an empty or non-numeric cell somewhere
        values, bad = None, np.arange(len(texts))
    for k in bad:
        problem = value_problem(texts[k], column)
        if problem:
            raise WeatherFileError(f"{path}, line {lines[k]} ({times[k]}), column {column}: "
                                   f"{problem}")
    if values is None:                              # forms float() reads and numpy does not
        values = np.array([number(t) for t in texts])
    return values
