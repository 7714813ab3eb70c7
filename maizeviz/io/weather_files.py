"""Weather files researchers hold, read through pvlib.iotools: EnergyPlus EPW, NREL TMY3 and
NSRDB PSM3/PSM4 CSV. maizeviz's own CSV is read by
:func:`maizeviz.light.sources.irradiance.read_weather`, which also turns these tables into a
``Weather``.

Each format is recognised by its first lines (an ``.epw`` starts ``LOCATION,``; a TMY3 file's
second line starts ``Date (MM/DD/YYYY)``; a PSM file's first ``Source,`` and its third
``Year,Month,Day,Hour,Minute``), read by pvlib, and given back as a :class:`WeatherTable`:
its times in the file's own time zone (the header's UTC offset: EPW's and TMY3's ``TZ``,
PSM's ``Time Zone``), where they sit in their interval (EPW: its start, as pvlib labels
EnergyPlus's hour-ending rows; TMY3: its end, as the file does; PSM: the middle, the
satellite's instantaneous values), the irradiance columns (W/m2), the air temperature (deg C)
and the line of each row. A typical year (TMY3, most EPW), whose months come from different
years (earlier or later: a file cut from one may go from July 1991 to August 2003), is
dated from the first row's year on, so that its rows follow each other; a note says so.

An EPW's LOCATION line is read with the csv module, as the checks read it: a city quoted
with a comma in it (``"Turin, IT"``) is one field (pvlib alone splits every comma and took
the place and time zone from the wrong fields); a bare comma, which EnergyPlus would split
too, is refused naming the fields. A row with fewer values than the format's columns (a
file cut inside its last row) is refused. A header latitude or longitude that is no finite
number is named in the place's ``problem``.

A file pvlib cannot read, or a value that is missing (EPW's 9999, TMY3's -9900) or not a
number, is refused in one line naming the file and the line. Air temperatures that are
missing or outside -90..70 deg C are kept as NaN, said once in a note (the light does not
use them).
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.inputs import read_input
from maizeviz.numbers import number

#: The formats read here, by name.
PVLIB_FORMATS = {"epw": "EnergyPlus EPW", "tmy3": "NREL TMY3", "psm": "NSRDB PSM3/PSM4"}
#: Air temperatures outside this range (deg C) are taken as missing.
TEMPERATURE_RANGE_C = (-90.0, 70.0)
#: Codes the formats write for a missing value.
MISSING_CODES = {"epw": (9999.0, 99.9, 999.0, 999999.0), "tmy3": (-9900.0, -9999.0),
                 "psm": (-9999.0,)}
#: Where a format's time stamps sit in the interval they stand for.
LABELS = {"epw": "start", "tmy3": "end", "psm": "center"}


class WeatherFileError(MaizevizError):
    """A weather file cannot be used: the message names the file, line, time and column.
    Its ``quantity`` is ``"weather"`` (the file as an input), so the app can mark the field
    that names the file and the command line can name ``--weather``."""

    def __init__(self, message: str = "", quantity: str | None = "weather"):
        super().__init__(message, quantity)


@dataclass(frozen=True)
class WeatherTable:
    """A weather file's rows as read.

    Attributes
    ----------
    kind : "epw", "tmy3" or "psm"
    times : (n,) pandas DatetimeIndex in the file's time zone (a fixed UTC offset)
    values : {"ghi", "dni", "dhi": (n,) float64 W/m2, "temp_air": (n,) float64 deg C, NaN
        where missing}
    line : (n,) int64, the line of each row in the file
    label : "start", "center" or "end": where each time sits in its interval
    meta : the header's place: latitude, longitude (deg), altitude (m), name
    notes : what was decided, one line each
    """

    kind: str
    times: Any
    values: dict[str, np.ndarray]
    line: np.ndarray
    label: str
    meta: dict[str, Any] = field(default_factory=dict)
    notes: tuple[str, ...] = ()


def weather_text(raw: bytes, path: Path) -> tuple[str, list[str]]:
    """A weather file's bytes as text (UTF-8, a byte-order mark dropped; else Latin-1) and
    the notes on it. A file ending in zero bytes (a power cut while it was written leaves its
    new length without its data) is read up to them, said in a note naming how many bytes
    are left; a file of nothing but zeros, or with a zero byte before its tail, is refused."""
    kept = raw.rstrip(b"\x00")
    notes = []
    if len(kept) < len(raw):
        if not kept.strip():
            raise WeatherFileError(f"{path}: not a text file (only zero bytes)")
        notes.append(f"{path.name}: the file ends in {len(raw) - len(kept):,} zero bytes (as a "
                     "power cut leaves a file being written): read up to them, the lines "
                     "before them are kept")
    if b"\x00" in kept:
        line = kept.count(b"\n", 0, kept.index(b"\x00")) + 1
        raise WeatherFileError(f"{path}, line {line}: a zero byte: not a text file (binary "
                               "content)")
    try:
        return kept.decode("utf-8-sig"), notes
    except UnicodeDecodeError:
        return kept.decode("latin-1"), notes          # TMY3 files of SolarAnywhere, old EPW


def detect_format(path: Path, head: bytes) -> str:
    """"epw", "tmy3", "psm" or "csv" (maizeviz's own) from a file's name and first bytes."""
    lines = head.decode("latin-1").lstrip("\ufeff\xef\xbb\xbf").splitlines()[:3]
    first = lines[0] if lines else ""
    second = lines[1] if len(lines) > 1 else ""
    third = lines[2] if len(lines) > 2 else ""
    if path.suffix.lower() == ".epw" or first.upper().startswith("LOCATION,"):
        return "epw"
    if second.startswith("Date (MM/DD/YYYY)"):
        return "tmy3"
    if first.startswith("Source,") and (third.replace(" ", "").startswith(
            "Year,Month,Day,Hour,Minute") or (len(lines) < 3 and "Location ID" in first)):
        return "psm"                                 # (a PSM file cut after its header too)
    return "csv"


def _header_lines(kind: str) -> int:
    return {"epw": 8, "tmy3": 2, "psm": 3}[kind]


def _data_lines(text: str, skip: int) -> np.ndarray:
    """The line number of each data row: the non-blank lines after the header."""
    out = [no for no, ln in enumerate(text.splitlines(), 1) if no > skip and ln.strip(" ,\t")]
    return np.asarray(out, np.int64)


#: Fields of an EPW's first line: LOCATION and nine values.
EPW_LOCATION_FIELDS = 10
#: The line of a format's header that holds its place and time zone (counting from 1).
PLACE_LINE = {"epw": 1, "tmy3": 1, "psm": 2}


def _check_header_numbers(text: str, kind: str, path: Path) -> None:
    """Refuse a header cell (the place, the time zone) that Python's float reads and a data
    file does not mean as a number: an EPW's time zone of ``1_0`` was read as UTC+10, every
    time shifted by 9 hours, no word."""
    lines = text.splitlines()
    no = PLACE_LINE[kind]
    if len(lines) < no:
        return
    for k, cell in enumerate(next(csv.reader([lines[no - 1]]), [])):
        try:
            float(cell)
        except ValueError:
            continue                                    # text: a name, a source
        try:
            number(cell)
        except ValueError:
            raise WeatherFileError(f"{path}, line {no}, field {k + 1} of the header: "
                                   f"'{cell.strip()[:30]}' is not a number") from None


def _text_columns(kind: str, header: list[str]) -> set[int]:
    """Columns of a format that hold text rather than numbers (EPW's data source flags,
    TMY3's date, time and source flags)."""
    if kind == "epw":
        return {5}
    if kind == "tmy3":
        return {k for k, name in enumerate(header) if k < 2 or "source" in name.lower()}
    return set()


def _first_bad_row(text: str, kind: str) -> tuple[int, str] | None:
    """(line, what) of the first data row that is not a row of numbers where the format has
    them, for a file pvlib could not read."""
    skip = _header_lines(kind)
    rows = []
    for no, line in enumerate(text.splitlines(), 1):
        try:
            rows.append(next(csv.reader([line]), []))
        except csv.Error:
            return no, "not readable as CSV"
    header = rows[skip - 1] if kind != "epw" and len(rows) >= skip else []
    width = len([c for c in header if c.strip()]) if header else None
    texts = _text_columns(kind, header)
    for no, cells in enumerate(rows, 1):
        if no <= skip or not any(c.strip() for c in cells):
            continue
        width = width or len(cells)
        if len(cells) < width:
            return no, f"{len(cells)} values, fewer than the {width} columns of the file"
        for k in range(width):
            if k in texts:
                continue
            try:
                number(cells[k])
            except ValueError:
                name = f" ({header[k]})" if k < len(header) and header[k] else ""
                return no, f"column {k + 1}{name} is '{cells[k][:30]}', not a number"
    return None


def _read(kind: str, text: str, coerce: int | None):
    """pvlib's reader of ``kind`` on the file's text: (DataFrame, metadata)."""
    import warnings

    import pvlib.iotools as iot

    warnings.filterwarnings("ignore", module=r"pvlib\.iotools")  # pandas' deprecations there
    buf = io.StringIO(text)
    if kind == "epw":
        return iot.read_epw(buf, coerce_year=coerce)
    if kind == "tmy3":
        return iot.read_tmy3(buf, coerce_year=coerce, map_variables=True)
    return iot.read_nsrdb_psm4(buf, map_variables=True)           # reads PSM3 files too


def _typical_year(times) -> bool:
    """Whether the rows' years change other than at a new year (a typical year's months,
    which come from different years, earlier or later: a file cut across a month boundary
    may go from July 1991 to August 2003)."""
    years, months = np.asarray(times.year), np.asarray(times.month)
    change = np.flatnonzero(np.diff(years) != 0)
    new_year = (months[change] == 12) & (months[change + 1] == 1) & \
        (years[change + 1] == years[change] + 1)
    return bool(len(change) and not np.all(new_year))


def _one_year(times, year: int):
    """A typical year's times dated from ``year`` on: each row in the year of the row before
    it, the next year where its month and day come before the previous row's (pvlib's
    ``coerce_year`` puts the last row in the next year, as for a whole year ending at
    24:00 on 31 December: a cut file's last row went a year ahead)."""
    import pandas as pd

    out, prev = [], None
    for t in times:
        moved = t.replace(year=year)             # 29 February into a common year: refused
        if prev is not None and moved <= prev:
            year += 1
            moved = t.replace(year=year)
        out.append(moved)
        prev = moved
    return pd.DatetimeIndex(out)


def _epw_location(text: str, path: Path) -> tuple[str, str]:
    """(text for pvlib, city) of an EPW: its LOCATION line read with the csv module, as the
    checks read it. pvlib splits the line at every comma, so a quoted city holding one
    (``"Turin, IT"``) shifted the place and the time zone by a field; the line handed to
    pvlib has such commas as blanks, and the city is the csv module's. A bare comma in a
    name gives the line more fields than an EPW's: refused naming them (EnergyPlus splits
    every comma too)."""
    lines = text.lstrip().splitlines()
    place = next(csv.reader([lines[0]]), [])
    if len(place) != EPW_LOCATION_FIELDS:
        extra = ""
        if len(place) > EPW_LOCATION_FIELDS:
            names = ", ".join(f"field {k + 1} '{c.strip()[:20]}'" for k, c in
                              enumerate(place[1:5], 1))
            extra = (f" ({names}): a comma inside the city, state or country? quote the "
                     'name ("Turin, IT") or drop the comma')
        raise WeatherFileError(f"{path}, line 1: the LOCATION line has {len(place)} fields; "
                               f"an EPW's has {EPW_LOCATION_FIELDS} (LOCATION, city, state, "
                               "country, source, WMO, latitude, longitude, time zone, "
                               f"elevation){extra}")
    if any("," in c for c in place):
        lines[0] = ",".join(c.replace(",", " ") for c in place)
        text = "\n".join(lines) + "\n"
    return text, place[1].strip()


def _short_row(text: str, kind: str) -> tuple[int, int, int] | None:
    """(line, values, columns) of the first data row with fewer values than the format's
    rows (the header's columns; an EPW's first row): a row cut short, as a file cut while it
    was written ends. pandas fills the missing cells and reads the cut one as its remaining
    digits."""
    skip = _header_lines(kind)
    width = None
    for no, line in enumerate(text.splitlines(), 1):
        if no < skip or not line.strip(" ,\t"):
            continue
        try:
            cells = next(csv.reader([line]), [])
        except csv.Error:
            return None                          # the read says what is wrong
        if no == skip:
            if kind != "epw":
                width = len([c for c in cells if c.strip()])
            continue
        width = width or len(cells)
        if len(cells) < width:
            return no, len(cells), width
    return None


def read_pvlib_file(path: str | Path, kind: str, max_bytes: int) -> WeatherTable:
    """Read an EPW, TMY3 or PSM file (``kind`` from :func:`detect_format`) through pvlib.

    Raises
    ------
    WeatherFileError
        One line naming the file and the line at fault.
    """
    path = Path(path)
    raw = read_input(path, "weather file", max_bytes, WeatherFileError)
    text, notes = weather_text(raw, path)
    name = PVLIB_FORMATS[kind]
    if not text.strip():
        raise WeatherFileError(f"{path}: the weather file is empty")
    city = None
    if kind == "epw":
        text, city = _epw_location(text, path)
    if len(text.strip().splitlines()) <= _header_lines(kind):
        raise WeatherFileError(f"{path}: the file ends within the {_header_lines(kind)}-line "
                               f"header of an {name} file: no data rows")
    _check_header_numbers(text, kind, path)
    short = _short_row(text, kind)
    if short:
        raise WeatherFileError(f"{path}, line {short[0]}: {short[1]} values, fewer than the "
                               f"{short[2]} columns of the file: a row cut short (a file cut "
                               "while it was written?); complete or delete the row")
    try:
        data, meta = _read(kind, text, None)
        if city is not None:
            meta["city"] = city
        if kind != "psm" and _typical_year(data.index):
            year = int(data.index.year[0])
            data = data.set_axis(_one_year(data.index, year))
            notes.append(f"{path.name}: a typical year (its months come from different "
                         f"years): its rows are dated in {year}")
    except Exception as exc:  # noqa: BLE001 - pvlib and pandas raise many kinds; say where
        bad = _first_bad_row(text, kind)
        where = f"line {bad[0]}: {bad[1]}" if bad else \
            f"not readable as {name} ({type(exc).__name__}: {str(exc)[:120]})"
        raise WeatherFileError(f"{path}, {where}") from None
    lines = _data_lines(text, _header_lines(kind))
    if len(lines) != len(data):
        lines = np.arange(len(data), dtype=np.int64) + _header_lines(kind) + 1
    if len(data) < 2:
        raise WeatherFileError(f"{path}: {len(data)} data row(s); a weather file needs at "
                               "least 2 to know its time step")
    times = data.index
    if times.tz is None:                                          # pragma: no cover
        raise WeatherFileError(f"{path}: pvlib gave no time zone for this {name} file")
    values = {}
    for col in ("ghi", "dni", "dhi"):
        if col not in data:
            raise WeatherFileError(f"{path}: no {col} column in this {name} file")
        v = _floats(data[col], f"{path}, line {{line}} ({{time}}), column {col}", lines, times)
        missing = np.flatnonzero(np.isin(v, MISSING_CODES[kind]) | ~np.isfinite(v))
        if len(missing):
            k = int(missing[0])
            what = f"missing value ({v[k]:g}, {name}'s code for one)" \
                if np.isfinite(v[k]) else f"{v[k]:g} is not a finite number (a missing value?)"
            raise WeatherFileError(f"{path}, line {lines[k]} ({times[k].isoformat()}), column "
                                   f"{col}: {what}; fill the gap or cut the file")
        values[col] = v
    temp = np.array([_float_or_nan(x) for x in data["temp_air"]]) if "temp_air" in data \
        else np.full(len(data), np.nan)
    lo, hi = TEMPERATURE_RANGE_C
    with np.errstate(invalid="ignore"):
        absent = ~((temp >= lo) & (temp <= hi))
    if absent.any():
        k = int(np.flatnonzero(absent)[0])
        notes.append(f"{path.name}: {int(absent.sum()):,} rows without an air temperature "
                     f"(first: line {lines[k]}, {temp[k]:g}); kept as missing")
        temp = np.where(absent, np.nan, temp)
    values["temp_air"] = temp
    return WeatherTable(kind, times, values, lines, LABELS[kind], _place(meta), tuple(notes))


def weather_place(path: str | Path) -> dict[str, Any]:
    """The place an EPW, TMY3 or PSM file's header names, read from its first lines only
    (cheap enough for a file chooser); ``{}`` for maizeviz's CSV (no header place) or a
    file whose header cannot be read (reading the whole file says what is wrong).

    Returns
    -------
    dict
        ``latitude``, ``longitude`` [deg], ``altitude`` [m], ``utc_offset_h`` (the header's
        time zone, hours east of UTC) (None where absent) and ``name``.
    """
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            head = fh.read(64 * 1024)
    except OSError:
        return {}
    kind = detect_format(path, head[:4096])
    if kind == "csv":
        return {}
    text = head.decode("latin-1").lstrip("\ufeff\xef\xbb\xbf")
    lines = text.splitlines()[:_header_lines(kind) + 2]     # the header and two rows
    try:
        text, city = _epw_location("\n".join(lines) + "\n", path) if kind == "epw" \
            else ("\n".join(lines) + "\n", None)
        _data, meta = _read(kind, text, None)
    except Exception:  # noqa: BLE001 - pvlib and pandas raise many kinds; the read says
        return {}
    if city is not None:
        meta["city"] = city
    return _place(meta)


def _place(meta: dict) -> dict[str, Any]:
    """The place of a pvlib reader's metadata."""
    name = str(meta.get("city") or meta.get("Name") or meta.get("City") or "").strip('" ')
    place = {"latitude": _number(meta, "latitude"), "longitude": _number(meta, "longitude"),
             "altitude": _number(meta, "altitude"),
             "name": "" if name.lower() in ("-", "unknown", "none", "nan") else name}
    for key in ("latitude", "longitude"):                # a header's NaN, named for the user
        if place[key] is None and key in meta and str(meta[key]).strip():
            place.setdefault("problem", f"the header's {key} is '{str(meta[key]).strip()}'")
    offset = _number(meta, "TZ") if "TZ" in meta else _number(meta, "Time Zone")
    place["utc_offset_h"] = offset if offset is not None and -14 <= offset <= 14 else None
    return place


def _floats(column, where: str, lines: np.ndarray, times) -> np.ndarray:
    """A column as (n,) float64; the first cell that is no number is refused, ``where``
    formatted with its line and time. pandas leaves a column of text where a cell is not a
    number its parser reads; such cells are read by :func:`maizeviz.numbers.number`, which
    refuses ``8_04`` and full-width digits that ``float`` would take."""
    values = np.asarray(column)
    if values.dtype.kind in "fiu":
        return values.astype(np.float64)
    out = np.empty(len(values), np.float64)
    for k, x in enumerate(values):
        try:
            out[k] = x if isinstance(x, (int, float)) else number(str(x))
        except ValueError:
            raise WeatherFileError(where.format(line=lines[k], time=times[k].isoformat())
                                   + f": '{str(x)[:30]}' is not a number") from None
    return out


def _float_or_nan(x) -> float:
    if isinstance(x, (int, float, np.number)):
        return float(x)
    try:
        return number(str(x))
    except ValueError:
        return math.nan


def _number(meta: dict, key: str) -> float | None:
    try:
        v = float(meta[key])
    except (KeyError, TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None
