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
years, is dated in one year, the first row's (pvlib's ``coerce_year``), so that its rows
follow each other; a note says so.

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
    """Whether the rows' years go back somewhere (a typical year's months)."""
    years = np.asarray(times.year)
    return bool(len(years) > 1 and np.any(np.diff(years) < 0))


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
    if kind == "epw":
        place = next(csv.reader([text.lstrip().splitlines()[0]]), [])
        if len(place) < EPW_LOCATION_FIELDS:
            raise WeatherFileError(f"{path}, line 1: the LOCATION line has {len(place)} "
                                   f"fields; an EPW's has {EPW_LOCATION_FIELDS} (city, state, "
                                   "country, source, WMO, latitude, longitude, time zone, "
                                   "elevation)")
    if len(text.strip().splitlines()) <= _header_lines(kind):
        raise WeatherFileError(f"{path}: the file ends within the {_header_lines(kind)}-line "
                               f"header of an {name} file: no data rows")
    _check_header_numbers(text, kind, path)
    try:
        data, meta = _read(kind, text, None)
        if kind != "psm" and _typical_year(data.index):
            year = int(data.index.year[0])
            data, meta = _read(kind, text, year)
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
        ``latitude``, ``longitude`` [deg], ``altitude`` [m] (None where absent) and ``name``.
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
        _data, meta = _read(kind, "\n".join(lines) + "\n", None)
    except Exception:  # noqa: BLE001 - pvlib and pandas raise many kinds; the read says
        return {}
    return _place(meta)


def _place(meta: dict) -> dict[str, Any]:
    """The place of a pvlib reader's metadata."""
    name = str(meta.get("city") or meta.get("Name") or meta.get("City") or "").strip('" ')
    return {"latitude": _number(meta, "latitude"), "longitude": _number(meta, "longitude"),
            "altitude": _number(meta, "altitude"),
            "name": "" if name.lower() in ("-", "unknown", "none", "nan") else name}


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
