"""Issue 25 on the readers that replaced the old ones (EPW/TMY3/PSM through pvlib, Parquet
points, PLY through plyfile, OBJ through numpy) and on the commands that came with them
(``maizeviz convert``, ``maizeviz subplots``): each hostile input a hostile user tried is a
clear one-line error naming the file and the line, or reads as the clean file does with a
note; the oracle is the clean file's own reading."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from maizeviz.light.sources.irradiance import WeatherFileError, read_weather

DATA = Path(__file__).resolve().parents[1] / "data" / "weather"
# (file, header lines, the ghi column: index or name)
WEATHER = {"epw": (DATA / "pvgis_tmy_45N_8E_july.epw", 8, 13),
           "tmy3": (DATA / "tmy3_703165_july.csv", 2, 4),
           "psm": (DATA / "psm3_401182_july.csv", 3, "GHI")}


def _with_cell(tmp_path, kind, value, row=12):
    """The sample file of ``kind`` with its ghi cell of data row ``row`` set to ``value``:
    (path, the line changed)."""
    path, skip, col = WEATHER[kind]
    lines = path.read_text(encoding="latin-1").split("\n")
    if isinstance(col, str):
        col = lines[skip - 1].split(",").index(col)
    cells = lines[skip + row].split(",")
    cells[col] = value
    lines[skip + row] = ",".join(cells)
    out = tmp_path / f"{kind}{path.suffix}"
    out.write_text("\n".join(lines), encoding="utf-8")
    return out, skip + row + 1


@pytest.mark.parametrize("kind", sorted(WEATHER))
@pytest.mark.parametrize("value, says", [
    ("8_04.0", "'8_04.0'"),                          # read as 804 W/m2 before
    ("１２", "'１２'"),                                 # full-width digits, read as 12
    ("-5", "negative irradiance -5 W/m2"),           # a CSV's cell is held to [0, 2000]
    ("2500", "2500 W/m2 is more than 2000 W/m2"),
    ("nan", "not a finite number"),                  # said to be the format's missing code
    ("1e400", "not a finite number"),
])
def test_a_weather_cell_a_csv_refuses_is_refused_in_every_format(tmp_path, kind, value, says):
    path, line = _with_cell(tmp_path, kind, value)
    with pytest.raises(WeatherFileError) as err:
        read_weather(path)
    message = str(err.value)
    assert "\n" not in message and str(path) in message and f"line {line}" in message
    assert says in message
    if says.startswith("'"):
        assert "not a number" in message


@pytest.mark.parametrize("kind", [*sorted(WEATHER), "csv"])
def test_a_weather_file_ending_in_zeros_reads_up_to_them(tmp_path, kind):
    """A power cut leaves a file's new length without its data: zero bytes after intact
    lines. Refused as binary (maizeviz's CSV) or at a line of '1 values' (pvlib's formats)
    before; now read as the file without them, with a note naming how many bytes."""
    if kind == "csv":
        clean = tmp_path / "clean.csv"
        clean.write_text("time,ghi,dhi\n2005-08-01T12:00+08:00,500,100\n"
                         "2005-08-01T13:00+08:00,600,120\n2005-08-01T14:00+08:00,550,110\n")
    else:
        clean = WEATHER[kind][0]
    zeros = tmp_path / f"zeros{clean.suffix}"
    zeros.write_bytes(clean.read_bytes() + b"\0" * 5000)
    a, b = read_weather(clean), read_weather(zeros)
    for name in ("ghi", "dni", "dhi", "temp_air", "step_s", "line"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None and y is None) or np.array_equal(x, y, equal_nan=True), name
    assert list(a.times) == list(b.times)
    assert any("ends in 5,000 zero bytes" in n for n in b.notes), b.notes
    only = tmp_path / f"only{clean.suffix}"
    only.write_bytes(b"\0" * 100)
    with pytest.raises(WeatherFileError, match="only zero bytes"):
        read_weather(only)


@pytest.mark.parametrize("kind", sorted(WEATHER))
def test_a_weather_file_with_a_byte_order_mark_reads_as_without(tmp_path, kind):
    clean = WEATHER[kind][0]
    marked = tmp_path / f"bom{clean.suffix}"
    marked.write_bytes(b"\xef\xbb\xbf" + clean.read_bytes())
    a, b = read_weather(clean), read_weather(marked)
    assert np.array_equal(a.ghi, b.ghi) and list(a.times) == list(b.times)
