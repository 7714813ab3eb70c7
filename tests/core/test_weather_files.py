"""Weather files researchers hold (issue 27): EPW, TMY3 and NSRDB PSM3 through pvlib.iotools,
on real sample files from pvlib's own test data (tests/data/weather, see its README), and a
measured PAR column used as the PAR. The oracle is the file itself, read here with the csv
module: every value, line and time zone the reader gives is the file's."""

from __future__ import annotations

import csv
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

from maizeviz.cli import EXIT_FAIL, EXIT_OK, main
from maizeviz.light.sources.irradiance import (
    DEFAULT_PAR_UMOL_PER_J,
    WeatherFileError,
    read_weather,
    weather_period,
)
from maizeviz.resources import example_points

DATA = Path(__file__).resolve().parents[1] / "data" / "weather"
EPW = DATA / "pvgis_tmy_45N_8E_july.epw"
TMY3 = DATA / "tmy3_703165_july.csv"
PSM3 = DATA / "psm3_401182_july.csv"
B = str(example_points())


def _rows(path: Path, skip: int) -> list[tuple[int, list[str]]]:
    """(line, cells) of the data rows of a file, read with the csv module."""
    with open(path, newline="", encoding="latin-1") as fh:
        return [(no, cells) for no, cells in enumerate(csv.reader(fh), 1) if no > skip]


# the columns of each format, as its documentation numbers them: (ghi, dni, dhi, temp_air)
EPW_COLUMNS = (13, 14, 15, 6)                    # EnergyPlus: fields 14-16 and 7, from 1
TMY3_COLUMNS = (4, 7, 10, 31)                    # TMY3 user's manual, Table 1-1
PSM3_COLUMNS = ("GHI", "DNI", "DHI", "Temperature")


@pytest.mark.parametrize("path, skip, cols, offset, label, place", [
    (EPW, 8, EPW_COLUMNS, "+01:00", "start", (45.0, 8.0)),
    (TMY3, 2, TMY3_COLUMNS, "-09:00", "end", (55.317, -160.517)),
    (PSM3, 3, PSM3_COLUMNS, "-07:00", "center", (40.53, -108.54)),
])
def test_a_real_sample_file_reads_as_it_is_written(path, skip, cols, offset, label, place):
    w = read_weather(path)
    rows = _rows(path, skip)
    if isinstance(cols[0], str):                           # PSM: columns by name
        names = _rows(path, 2)[0][1]
        cols = tuple(names.index(c) for c in cols)
    assert len(w.times) == len(rows) and w.line.tolist() == [no for no, _ in rows]
    for k, name in enumerate(("ghi", "dni", "dhi", "temp_air")):
        file_values = np.array([float(r[cols[k]]) for _, r in rows])
        assert np.array_equal(getattr(w, name), file_values), name
    # the time zone of the header, the times' place in their interval of the format
    assert w.times[0].isoformat().endswith(offset) and w.label == label
    assert w.place["latitude"] == place[0] and w.place["longitude"] == place[1]
    steps = np.unique(w.step_s)
    assert steps.tolist() == ([1800.0] if path == PSM3 else [3600.0])
    # the intervals tile the period: the file's span, a step of overlap at neither end
    assert (w.end - w.start).total_seconds() == pytest.approx(w.step_s.sum())


def test_the_file_labels_its_intervals_as_the_format_says():
    """EPW hour 1 is 00:00-01:00 (pvlib dates it 00:00, its start); TMY3 01:00 is the same
    hour (dated at its end): the middles are 00:30 both."""
    epw, tmy3 = read_weather(EPW), read_weather(TMY3)
    assert epw.times[0].strftime("%H:%M") == tmy3.times[0].strftime("%H:%M") == "00:30"
    psm = read_weather(PSM3)                           # instantaneous at :00 and :30
    assert psm.times[0].strftime("%H:%M:%S") == "00:00:00"


def test_a_whole_typical_year_from_pvlib_is_dated_in_one_year():
    import pvlib

    path = Path(pvlib.__file__).parent / "data" / "703165TY.csv"
    if not path.exists():                                            # pragma: no cover
        pytest.skip("this pvlib has no sample TMY3 file")
    w = read_weather(path)
    assert len(w.times) == 8760 and np.all(np.diff(w.times.asi8) > 0)
    assert any("typical year" in n for n in w.notes)
    period = weather_period(w, 55.317, -160.517)
    daily = period.daily_totals()
    assert len(daily) >= 365
    # Sand Point, Alaska: a dim place; a year's shortwave 2 to 5 GJ/m2
    assert 2000 < daily["shortwave_mj_m2"].sum() < 5000


@pytest.mark.parametrize("path, where, replace, says", [
    (EPW, 12, (13, "9999"), "missing value (9999, EnergyPlus EPW's code for one)"),
    (EPW, 12, (13, "bright"), "not a number"),
    (TMY3, 7, (4, "-9900"), "missing value (-9900, NREL TMY3's code for one)"),
    (PSM3, 10, (6, "sunny"), "not a number"),
])
def test_bad_values_are_one_line_naming_the_line(tmp_path, path, where, replace, says):
    lines = path.read_text(encoding="latin-1").splitlines()
    cells = lines[where - 1].split(",")
    cells[replace[0]] = replace[1]
    lines[where - 1] = ",".join(cells)
    bad = tmp_path / path.name
    bad.write_text("\n".join(lines) + "\n", encoding="latin-1")
    with pytest.raises(WeatherFileError) as exc:
        read_weather(bad)
    message = str(exc.value)
    assert f"line {where}" in message and says in message and "\n" not in message, message


def test_a_file_of_another_zone_keeps_its_own(tmp_path):
    w = read_weather(EPW, tz="Asia/Shanghai")
    assert w.times[0].isoformat().endswith("+01:00")
    assert any("gives its own time zone (UTC+01:00)" in n for n in w.notes)


# ------------------------------------------------------------------------------ PAR, air
def _csv(tmp_path, name, header, rows):
    path = tmp_path / name
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def _day_rows(par=True, ghi=True, temp=True):
    """Half-hourly rows of a clear-ish day at Beijing: ghi, a quantum sensor's PAR (a bit
    more than 2.1936 x ghi, as under a blue sky) and the air temperature."""
    rows = []
    for k in range(48):
        t = f"2005-08-01T{k // 2:02d}:{30 * (k % 2):02d}+08:00"
        sun = max(0.0, math.sin(math.pi * (k / 2 - 5.5) / 13.5))
        g = round(900 * sun, 1)
        cells = [t] + ([str(g)] if ghi else []) + ([str(round(2.3 * g, 1))] if par else []) + \
            ([str(round(20 + 10 * sun, 2))] if temp else [])
        rows.append(",".join(cells))
    return rows


def test_measured_par_is_the_par(tmp_path):
    with_par = read_weather(_csv(tmp_path, "p.csv", "time,ghi,par,temp_air", _day_rows()))
    without = read_weather(_csv(tmp_path, "g.csv", "time,ghi,temp_air", _day_rows(par=False)))
    pp = weather_period(with_par, 39.9, 116.4)
    pg = weather_period(without, 39.9, 116.4)
    # the shortwave is the same; PAR is the file's, not ghi x 2.1936
    assert np.array_equal(pp.ghi, pg.ghi) and np.array_equal(pp.dhi, pg.dhi)
    up = np.isin(with_par.times, pp.times)
    assert pp.par_mol_m2 == pytest.approx(math.fsum(with_par.par[up] * with_par.step_s[up])
                                          * 1e-6, rel=1e-12)
    assert pg.par_mol_m2 == pytest.approx(pg.shortwave_mj_m2 * DEFAULT_PAR_UMOL_PER_J,
                                          rel=1e-12)
    assert pp.par_mol_m2 / pg.par_mol_m2 == pytest.approx(2.3 / DEFAULT_PAR_UMOL_PER_J,
                                                          rel=1e-3)
    # split as the shortwave is; parts add up step by step
    np.testing.assert_allclose(pp.step_direct_par_mol_m2 + pp.step_diffuse_par_mol_m2,
                               pp.step_par_mol_m2, rtol=1e-12)
    lit = pp.step_par_mol_m2 > 0
    np.testing.assert_allclose(pp.step_direct_par_mol_m2[lit] / pp.step_par_mol_m2[lit],
                               pg.step_direct_par_mol_m2[lit] / pg.step_par_mol_m2[lit],
                               rtol=1e-9)
    # the air temperature travels with the weather and the steps, for later models
    assert with_par.temp_air.tolist()[:2] == [20.0, 20.0]
    assert np.array_equal(pp.temp_air, with_par.temp_air[up])
    assert "PAR measured" in pp.source and pp.parameters["par"] == "measured"


def test_par_alone_estimates_the_shortwave_to_split_it(tmp_path):
    w = read_weather(_csv(tmp_path, "q.csv", "time,par", _day_rows(ghi=False, temp=False)))
    assert w.estimated == ("ghi",) and w.columns == ("par",)
    assert np.allclose(w.ghi, w.par / DEFAULT_PAR_UMOL_PER_J)
    assert any("gives PAR without ghi" in n for n in w.notes)
    p = weather_period(w, 39.9, 116.4)
    up = np.isin(w.times, p.times)
    assert p.par_mol_m2 == pytest.approx(math.fsum(w.par[up] * w.step_s[up]) * 1e-6, rel=1e-12)


@pytest.mark.parametrize("header, cell, says", [
    ("time,ghi,par", "5000", "5000 umol/m2/s is more than 4000 umol/m2/s; is the unit umol/m2/s?"),
    ("time,ghi,par", "-3", "negative par -3 umol/m2/s"),
    ("time,ghi,temp_air", "300", "300 deg C is more than 70 deg C; is the unit deg C?"),
    ("time,ghi,temp_air", "", "missing value"),
])
def test_bad_par_and_temperature_cells_name_line_and_column(tmp_path, header, cell, says):
    rows = ["2005-08-01T10:00+08:00,500,1000", f"2005-08-01T11:00+08:00,600,{cell}"]
    if "temp_air" in header:
        rows = ["2005-08-01T10:00+08:00,500,25", f"2005-08-01T11:00+08:00,600,{cell}"]
    with pytest.raises(WeatherFileError) as exc:
        read_weather(_csv(tmp_path, "b.csv", header, rows))
    column = header.split(",")[-1]
    assert f"line 3 (2005-08-01T11:00+08:00), column {column}: {says}" in str(exc.value)


def test_a_period_with_par_and_temperature_survives_a_project(tmp_path):
    """A day's period on a weather file with PAR and air temperature, stored as a project
    stores it (maizeviz.project.records: the period's arrays and metadata) and read back:
    the same arrays, the same PAR."""
    from maizeviz.io.archive import Record
    from maizeviz.project.records import _PERIOD_ARRAYS, _PERIOD_OPTIONAL, _period

    w = read_weather(_csv(tmp_path, "p.csv", "time,ghi,par,temp_air", _day_rows()))
    p = weather_period(w, 39.9, 116.4)
    arrays = {f"period_{k}": np.asarray(getattr(p, k), np.float64)
              for k in (*_PERIOD_ARRAYS, *_PERIOD_OPTIONAL) if getattr(p, k) is not None}
    meta = {"period": {"times": [t.isoformat() for t in p.times], "tz": "UTC+08:00",
                       "start": p.start.isoformat(), "end": p.end.isoformat(),
                       "source": p.source, "parameters": dict(p.parameters),
                       "par_umol_per_j": p.par_umol_per_j, "notes": list(p.notes)}}
    back = _period(Record("light_day", meta, arrays), meta, "test")
    assert np.array_equal(back.par_measured, p.par_measured)
    assert np.array_equal(back.temp_air, p.temp_air)
    assert back.par_mol_m2 == p.par_mol_m2


# ------------------------------------------------------------------------------ CLI
def test_light_on_an_epw_takes_place_and_zone_from_its_header(tmp_path, capsys):
    code = main(["light", B, "--tile", "3x3", "--triangles", "4", "--periodic", "--density",
                 "0.25", "--heights", "0,100", "--sky-directions", "6", "--weather", str(EPW),
                 "--json"])
    out, err = capsys.readouterr()
    assert code == EXIT_OK, err
    rec = json.loads(out)
    assert "latitude 45, longitude 8 (the header of" in err
    period = rec["period"]
    assert period["start"].endswith("+01:00")
    assert "EnergyPlus EPW" in period["source"]
    w = weather_period(read_weather(EPW), 45.0, 8.0)
    assert period["par_incident_mol_m2"] == pytest.approx(w.par_mol_m2, rel=1e-12)


def test_a_csv_without_a_place_is_one_line(tmp_path, capsys):
    path = _csv(tmp_path, "p.csv", "time,ghi", [r.rsplit(",", 2)[0] for r in _day_rows()])
    code = main(["light", B, "--triangles", "4", "--density", "0.25", "--weather", str(path)])
    err = capsys.readouterr().err
    assert code == EXIT_FAIL and "needs the place: give --lat and --lon" in err
    assert os.path.exists(path)


# ------------------------------------------------------------------------------ damaged
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from maizeviz.errors import MaizevizError  # noqa: E402


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data(), path=st.sampled_from([EPW, TMY3, PSM3]))
def test_damaged_weather_files_give_only_weather_errors(tmp_path, data, path):
    """Bytes cut, flipped or inserted anywhere in a real sample: a Weather or one line
    naming the file."""
    raw = bytearray(path.read_bytes())
    for _ in range(data.draw(st.integers(1, 3))):
        op = data.draw(st.sampled_from(["cut", "flip", "insert"]))
        at = data.draw(st.integers(0, len(raw) - 1))
        if op == "cut":
            del raw[at:at + data.draw(st.integers(1, 200))]
        elif op == "flip":
            raw[at] = data.draw(st.integers(0, 255))
        else:
            raw[at:at] = data.draw(st.binary(min_size=1, max_size=12))
    bad = tmp_path / path.name
    bad.write_bytes(bytes(raw))
    try:
        w = read_weather(bad)
    except MaizevizError as exc:
        assert "\n" not in str(exc) and str(bad) in str(exc), str(exc)
    else:
        assert len(w.times) >= 2 and np.all(np.diff(w.times.asi8) > 0)
        assert np.all(np.isfinite(w.ghi)) and np.all(w.ghi >= 0)


def test_the_place_of_a_header_is_read_from_its_first_lines():
    from maizeviz.io.weather_files import weather_place

    for path in (EPW, TMY3, PSM3):
        assert weather_place(path) == read_weather(path).place
    assert weather_place(B) == {}
    assert weather_place(DATA / "no such file.epw") == {}


def test_a_sun_placed_away_from_the_files_place_is_said():
    """The sun positions of a weather period computed far from where the file was measured
    do not match its irradiance: a note says so; at the file's place, none."""
    w = read_weather(EPW)
    assert not any("not where" in n for n in weather_period(w, 45.0, 8.0).notes)
    assert not any("not where" in n for n in weather_period(w, 45.02, 8.03).notes)
    away = [n for n in weather_period(w, 39.9, 116.4).notes if "not where" in n]
    assert len(away) == 1 and "latitude 45, longitude 8" in away[0]
    assert EPW.name in away[0]
