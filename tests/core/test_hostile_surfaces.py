"""Hostile inputs on the newest surfaces (issue 35, item 7): each case found by the red team
held by a test that failed before its fix. The oracle is the input itself: a file's own
header, line and cells, the options as typed."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from maizeviz.cli import EXIT_FAIL, EXIT_OK, main
from maizeviz.errors import MaizevizError
from maizeviz.light.sources.irradiance import WeatherFileError, read_weather
from maizeviz.resources import example_points

DATA = Path(__file__).resolve().parents[1] / "data" / "weather"
EPW = DATA / "pvgis_tmy_45N_8E_july.epw"
TMY3 = DATA / "tmy3_703165_july.csv"
B = str(example_points())


def _lines(path: Path) -> list[str]:
    return path.read_text(encoding="latin-1").splitlines()


def _write(tmp_path: Path, name: str, lines: list[str], end: str = "\n") -> Path:
    out = tmp_path / name
    out.write_text("\n".join(lines) + end, encoding="latin-1")
    return out


# ------------------------------------------------------------------------------ weather
TURIN = "LOCATION,{city},-,ITA,IWEC,160590,45.000000,8.000000,1,250"


def test_an_epw_city_with_a_quoted_comma_is_read_at_its_own_place(tmp_path):
    """csv reads a quoted city as one field; pvlib split every comma and traced the day at
    52.5 N, 45 E, +08:00 for a file at 45 N, 8 E, +01:00."""
    lines = _lines(EPW)
    lines[0] = TURIN.format(city='"Turin, IT"')
    w = read_weather(_write(tmp_path, "turin.epw", lines))
    assert (w.place["latitude"], w.place["longitude"]) == (45.0, 8.0)
    assert w.place["name"] == "Turin, IT"
    assert w.times[0].isoformat().endswith("+01:00")
    assert np.array_equal(w.ghi, read_weather(EPW).ghi)


def test_an_epw_city_with_a_bare_comma_is_refused_naming_the_field(tmp_path):
    lines = _lines(EPW)
    lines[0] = TURIN.format(city="Turin, IT")
    with pytest.raises(WeatherFileError) as exc:
        read_weather(_write(tmp_path, "turin.epw", lines))
    msg = str(exc.value)
    assert "line 1" in msg and "11 fields" in msg and "city" in msg and "\n" not in msg, msg


@pytest.mark.parametrize("keep", [3, 40, 150])
def test_a_tmy3_cut_inside_its_last_row_is_refused(tmp_path, keep):
    """The cut cell was read as its remaining digits (99 W/m2 direct instead of 41)."""
    lines = _lines(TMY3)
    lines[-1] = lines[-1][:keep]
    bad = _write(tmp_path, "cut.csv", lines, end="")
    with pytest.raises(WeatherFileError) as exc:
        read_weather(bad)
    msg = str(exc.value)
    assert f"line {len(lines)}" in msg and "cut" in msg and "\n" not in msg, msg


def test_an_epw_cut_inside_its_last_row_is_refused(tmp_path):
    lines = _lines(EPW)
    lines[-1] = lines[-1][:30]
    with pytest.raises(WeatherFileError) as exc:
        read_weather(_write(tmp_path, "cut.epw", lines, end=""))
    assert f"line {len(lines)}" in str(exc.value)


def test_a_typical_year_cut_across_a_month_boundary_is_read(tmp_path):
    """Months of a typical year come from different years, forward as well as back: 3 July
    of 1991 followed by 4 July of 2003 was 'a gap of 35065 h'."""
    lines = _lines(TMY3)
    rows = lines[2:]
    first_day = [r for r in rows if r.startswith("07/01/1991")]
    moved = [r.replace("07/01/1991", "06/30/1991") for r in first_day]
    later = [r.replace("07/0", "07/0").replace("/1991,", "/2003,") for r in rows]
    w = read_weather(_write(tmp_path, "typical.csv", lines[:2] + moved + later))
    assert len(w.times) == len(moved) + len(later)
    assert np.all(np.diff(w.times.asi8) > 0) and set(np.unique(w.step_s)) == {3600.0}
    assert any("typical year" in n for n in w.notes)


@pytest.mark.parametrize("field, value", [(4, "nan"), (5, "nan")])
def test_a_nan_header_place_is_named(tmp_path, capsys, field, value):
    lines = _lines(TMY3)
    cells = lines[0].split(",")
    cells[field] = value
    lines[0] = ",".join(cells)
    path = _write(tmp_path, "nan.csv", lines)
    code = main(["light", B, "--triangles", "4", "--density", "0.25", "--weather", str(path)])
    err = capsys.readouterr().err
    name = "latitude" if field == 4 else "longitude"
    assert code == EXIT_FAIL and f"{name} is 'nan'" in err and "needs the place" not in err, err
    # with the place given, the file is used
    code = main(["light", B, "--triangles", "4", "--density", "0.25", "--heights", "0",
                 "--sky-directions", "6", "--weather", str(path), "--lat", "55.3", "--lon",
                 "-160.5", "--json"])
    assert code == EXIT_OK, capsys.readouterr().err


def _cold(tmp_path, line_no: int, value: str) -> Path:
    lines = _lines(EPW)
    cells = lines[line_no - 1].split(",")
    cells[6] = value                                  # EPW field 7: dry bulb, C
    lines[line_no - 1] = ",".join(cells)
    return _write(tmp_path, "cold.epw", lines)


def test_a_files_cold_air_is_blamed_on_the_file_and_its_line(tmp_path, capsys):
    path = _cold(tmp_path, 20, "-80")
    code = main(["light", B, "--triangles", "4", "--density", "0.25", "--heights", "0",
                 "--sky-directions", "6", "--weather", str(path), "--photosynthesis", "c4"])
    err = capsys.readouterr().err
    assert code == EXIT_FAIL, err
    last = [ln for ln in err.splitlines() if ln.startswith("error")][-1]
    assert "line 20" in last and "cold.epw" in last and "--temperature" not in last, last


def test_temperature_given_with_a_files_own_says_which_wins(tmp_path, capsys):
    code = main(["light", B, "--triangles", "4", "--density", "0.25", "--heights", "0",
                 "--sky-directions", "6", "--weather", str(EPW), "--photosynthesis", "c4",
                 "--temperature", "10", "--json"])
    out, err = capsys.readouterr()
    assert code == EXIT_OK, err
    assert "--temperature 10" in err and "air temperature" in err, err


# ------------------------------------------------------------------------------ main job
def _headless(*args, env_extra=None, timeout=300):
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env.update(env_extra or {})
    return subprocess.run([sys.executable, "-m", "maizeviz", *map(str, args)],
                          capture_output=True, text=True, env=env, timeout=timeout)


@pytest.fixture(scope="module")
def small_points(tmp_path_factory):
    """Two plants of the bundled example: a file that is not the example."""
    lines = Path(B).read_text().splitlines()
    head = [ln for ln in lines if not ln[:1].isdigit()]
    rows = [ln for ln in lines if ln[:1].isdigit()]
    plant = [ln for ln in rows if ln.split(",")[0] in ("1", "2")]
    out = tmp_path_factory.mktemp("pts") / "mine.csv"
    out.write_text("\n".join(head + plant) + "\n")
    return out


@pytest.mark.parametrize("form", [("--tile", "1", "{p}"), ("--", "{p}"),
                                  ("{p}", "--tile", "1")])
def test_the_main_job_reports_on_the_file_wherever_it_stands(small_points, form):
    """`maizeviz --tile 1 p.csv` and `maizeviz -- p.csv` reported on the bundled example."""
    args = [a.format(p=small_points) for a in form]
    proc = _headless(*args)
    assert proc.returncode == EXIT_OK, proc.stderr
    assert f"the headless report on {small_points}" in proc.stderr
    tile = "1x1" if "1" in form else "3x3"
    assert f"maizeviz canopy {small_points} --tile {tile} --levels" in proc.stderr
    plants = 2 if tile == "1x1" else 18
    assert f"canopy: {plants} plants" in proc.stdout, proc.stdout


@pytest.mark.parametrize("bad, says", [(("--tile", "4"), "--tile"),
                                       (("--bogus-option",), "--bogus-option"),
                                       (("--size", "big"), "--size")])
def test_the_main_jobs_options_after_the_file_are_checked(small_points, bad, says):
    proc = _headless(small_points, *bad)
    assert proc.returncode == 2 and says in proc.stderr and "LAI" not in proc.stdout
    assert "Traceback" not in proc.stderr


def test_the_main_job_on_a_mesh_reports_it_as_it_is(tmp_path, small_points):
    mesh = tmp_path / "c.ply"
    assert main(["canopy", str(small_points), "--triangles", "4", "--export",
                 str(mesh)]) == EXIT_OK
    proc = _headless(mesh)
    assert proc.returncode == EXIT_OK, proc.stderr
    assert "--levels" not in proc.stderr and "mesh" in proc.stdout
    proc = _headless(mesh, "--tile", "3")
    assert proc.returncode == 2 and "--tile 3: a mesh file" in proc.stderr


def test_a_folder_or_fifo_given_to_the_main_job_is_named_as_such(tmp_path):
    import os

    proc = _headless(tmp_path)
    assert proc.returncode == EXIT_FAIL and "is a folder, not a file" in proc.stderr
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    proc = _headless(fifo)
    assert proc.returncode == EXIT_FAIL and "is a FIFO" in proc.stderr
    assert "no such file" not in proc.stderr


# ------------------------------------------------------------------------------ environment
@pytest.mark.parametrize("name, value", [("MAIZEVIZ_FIELD_POINTS", "abc"),
                                         ("MAIZEVIZ_FIELD_POINTS", "1e3"),
                                         ("MAIZEVIZ_FIELD_POINTS", ""),
                                         ("MAIZEVIZ_FIELD_POINTS", "-5"),
                                         ("MAIZEVIZ_PACKET_WIDTH", "abc"),
                                         ("MAIZEVIZ_PACKET_WIDTH", "7"),
                                         ("MAIZEVIZ_PACKETS", "maybe"),
                                         ("MAIZEVIZ_LOOPS", "2"),
                                         ("MAIZEVIZ_DEBUG", "please")])
def test_a_bad_environment_variable_is_one_line_when_used(tmp_path, name, value):
    """They were int() at import: a traceback."""
    pts = tmp_path / "p.parquet"
    assert main(["convert", B, "--out", str(pts)]) == EXIT_OK
    proc = _headless("light", pts, "--tile", "1x1", "--triangles", "4", "--density", "0.25",
                     "--heights", "0", "--sun-zenith", "30", "--sun-azimuth", "180",
                     env_extra={name: value})
    err = proc.stderr.strip()
    assert proc.returncode == EXIT_FAIL, err
    assert "Traceback" not in err and f"{name}='{value}'" in err, err
    assert err.splitlines()[-1].startswith("error:"), err
    info = _headless("--info", env_extra={name: value})
    assert info.returncode == EXIT_FAIL and name in info.stderr and "Traceback" not in \
        info.stderr


# ------------------------------------------------------------------------------ projects
@pytest.fixture(scope="module")
def traced_project(tmp_path_factory):
    """The bundled block's 2 x 2 tiling at 16 triangles with a sun, a sky and a day."""
    from maizeviz.canopy.build import build_canopy
    from maizeviz.canopy.layout import layout_for
    from maizeviz.leaf.fit import read_leaves
    from maizeviz.light.scene.request import LightRequest, Sampling
    from maizeviz.light.sources.sky import make_sky
    from maizeviz.light.sources.sun import Sun
    from maizeviz.light.trace.beam import trace_light
    from maizeviz.light.trace.directions import trace_sky
    from maizeviz.mesh.levels import parse_level
    from maizeviz.project.study import save_study

    folder = tmp_path_factory.mktemp("project")
    leaves = read_leaves(B).leaves
    layout = layout_for(leaves, (2, 2))
    level = parse_level("16")
    canopy = build_canopy(leaves, layout, level)
    sampling = Sampling((0.0, 100.0), 0.2, None, True, 1)
    sun = trace_light(canopy, LightRequest(Sun(30, 180), sampling))
    sky = trace_sky(canopy, make_sky("soc", 16), sampling)
    path = folder / "ok.maizeviz"
    save_study(path, B, layout, [sun, sky], level=level.label)
    return path, canopy.n_triangles, len(canopy.stalk_faces)


@pytest.mark.parametrize("name, kind", [("triangle_share", 1), ("first_hits", 0)])
@pytest.mark.parametrize("cut", ["one short", "half", "one long"])
def test_a_projects_per_triangle_array_of_another_length_is_refused_at_read(
        tmp_path, traced_project, name, kind, cut):
    """read_study accepted a triangle_share one short, half or one long; table() then said
    the result was 'traced on another canopy'."""
    from dataclasses import replace

    from maizeviz.io.archive import ProjectError, load_project, save_project
    from maizeviz.project.study import read_study

    path, n, stalks = traced_project
    assert len(read_study(path, tmp_path).results) == 2          # the undamaged one reads
    project = load_project(path)
    rec = project.results[kind]
    a = np.asarray(rec.arrays[name])
    changed = {"one short": a[:-1], "half": a[:len(a) // 2],
               "one long": np.append(a, a[-1:])}[cut]
    arrays = {**rec.arrays, name: changed}
    if name == "first_hits":                                    # both hit arrays alike
        arrays["second_hits"] = np.resize(np.asarray(rec.arrays["second_hits"]),
                                          len(changed))
    results = list(project.results)
    results[kind] = replace(rec, arrays=arrays)
    bad = tmp_path / "bad.maizeviz"
    save_project(bad, replace(project, results=tuple(results)))
    with pytest.raises(ProjectError) as exc:
        read_study(bad, tmp_path)
    msg = str(exc.value)
    said = (f"holds {len(changed):,} values, expected {n:,} (one per leaf triangle of its "
            f"canopy) or {n + stalks:,}")
    assert said in msg and "\n" not in msg, msg
    assert "first_hits" in msg if name == "first_hits" else name in msg


# ------------------------------------------------------------------------------ extra columns
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

#: Text a cell may hold: any character but NUL (a zero byte marks a binary file) and the
#: surrogates (no UTF-8 for them).
CELL = st.text(st.characters(exclude_categories=("Cs",), exclude_characters="\x00"),
               max_size=12)


def _points_rows(n: int):
    """n points of one 2 x ceil(n/2) leaf grid: (plant, leaf, row, col, x, y, z)."""
    return [(1, 1, k % 2, k // 2, 0.5 * k, 1.0 + k, 10.0 + k) for k in range(n)]


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture,
                                 HealthCheck.too_slow])
@given(texts=st.lists(st.tuples(CELL, CELL), min_size=4, max_size=8))
def test_extra_columns_survive_convert_both_ways_exactly(tmp_path, texts):
    """Blanks, tabs, newlines, quotes, commas: the CSV reader stripped blanks and tabs, the
    Parquet path wrote a newline as the two characters \\n (convert and back: 384 records
    of 7,650 changed)."""
    import csv

    from maizeviz.io.points import read_points

    src = tmp_path / "p.csv"
    with open(src, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["plant", "leaf", "row", "col", "x", "y", "z", "Note", "operator"])
        for row, (a, b) in zip(_points_rows(len(texts)), texts):
            w.writerow([*row, a, b])
    want = {"Note": [a for a, _ in texts], "operator": [b for _, b in texts]}
    assert read_points(src).extra == want
    pq_path, back = tmp_path / "o.parquet", tmp_path / "back.csv"
    for out, source in ((pq_path, src), (back, pq_path)):
        if out.exists():
            out.unlink()
        assert main(["convert", str(source), "--out", str(out)]) == EXIT_OK
        assert read_points(out).extra == want, out.name


def _parquet(tmp_path, name: str, columns: dict) -> Path:
    import pyarrow as pa
    import pyarrow.parquet as pq

    out = tmp_path / name
    pq.write_table(pa.table(columns), out)
    return out


def _plain_columns(n: int = 8) -> dict:
    rows = _points_rows(n)
    return {name: [r[k] for r in rows] for k, name in
            enumerate(("plant", "leaf", "row", "col", "x", "y", "z"))}


@pytest.mark.parametrize("how", ["x as list", "nested extra with a NaN x", "struct extra"])
def test_a_parquet_column_of_lists_or_structs_is_one_line(tmp_path, capsys, how):
    """It ended in ArrowNotImplementedError (the table cast to text)."""
    cols = _plain_columns()
    if how == "x as list":
        cols["x"] = [[v] for v in cols["x"]]
    elif how == "nested extra with a NaN x":
        cols["x"][3] = math.nan
        cols["tags"] = [[1.0, 2.0]] * len(cols["x"])
    else:
        cols["who"] = [{"name": "a", "n": k} for k in range(len(cols["x"]))]
    path = _parquet(tmp_path, "nested.parquet", cols)
    code = main(["leaf", str(path)])
    err = capsys.readouterr().err
    assert code == EXIT_FAIL and "Traceback" not in err and "internal error" not in err, err
    last = err.strip().splitlines()[-1]
    assert last.startswith("error:") and "not numbers or text" in last, err


@pytest.mark.parametrize("how", ["nan x", "null plant", "text cell", "status column",
                                 "interleaved plants"])
def test_subplots_on_a_parquet_file_needing_the_csv_checks_is_one_line(tmp_path, capsys, how):
    """It ended in NotStreamable (an internal error) where light reads the file."""
    lines = Path(B).read_text().splitlines()
    rows = [ln.split(",") for ln in lines[1:] if ln[:1].isdigit()]
    cols = {name: [float(r[k]) if k >= 4 else int(r[k]) for r in rows] for k, name in
            enumerate(("plant", "leaf", "row", "col", "x", "y", "z"))}
    if how == "nan x":
        cols["x"][5] = math.nan
    elif how == "null plant":
        cols["plant"] = [None if k == 5 else v for k, v in enumerate(cols["plant"])]
    elif how == "text cell":
        cols["y"] = [str(v) for v in cols["y"]]
    elif how == "status column":
        cols["status"] = ["ok"] * len(cols["x"])
    else:
        order = sorted(range(len(cols["x"])), key=lambda k: (k % 2, k))
        cols = {n: [v[k] for k in order] for n, v in cols.items()}
    path = _parquet(tmp_path, "f.parquet", cols)
    code = main(["subplots", str(path), "--parts", "1x1", "--level", "16", "--sun-zenith",
                 "30", "--sun-azimuth", "180", "--workers", "1"])
    err = capsys.readouterr().err
    assert code == EXIT_FAIL and "internal error" not in err, err
    last = err.strip().splitlines()[-1]
    assert last.startswith("error:") and str(path) in last and "'maizeviz light'" in last, err


# ------------------------------------------------------------------------------ the class
ROOT = Path(__file__).resolve().parents[2]


def _variables_read() -> dict[str, list[str]]:
    """Every MAIZEVIZ_* name in the package's and the app's code (comments and docstrings
    too: a name documented is a name someone sets), with the files naming it."""
    import re

    found: dict[str, list[str]] = {}
    for folder in ("maizeviz", "app", "scripts"):
        for path in sorted((ROOT / folder).rglob("*")):
            if path.suffix not in (".py", ".sh", ".c") or ".venv" in path.parts:
                continue
            for name in set(re.findall(r"\bMAIZEVIZ_[A-Z][A-Z0-9_]*", path.read_text(
                    encoding="utf-8", errors="replace"))):
                found.setdefault(name, []).append(str(path.relative_to(ROOT)))
    return found


def test_every_environment_variable_read_has_a_checked_parser():
    """The class behind MAIZEVIZ_FIELD_POINTS=abc's traceback: every variable is in
    maizeviz.environment, read through its readers, and nothing else reads one."""
    import re

    from maizeviz import environment
    from maizeviz.mesh.embree_isa import ISAS

    found = _variables_read()
    assert set(found) <= set(environment.VARIABLES), \
        f"read without a parser in maizeviz/environment.py: {set(found) - set(environment.VARIABLES)}"
    assert set(environment.VARIABLES) <= set(found) - {"MAIZEVIZ_"}
    # nothing reads one around the module: no os.environ / getenv of a MAIZEVIZ_ name
    direct = re.compile(r"(environ\.get|environ\[|getenv)\(?\s*[\"']MAIZEVIZ_")
    for folder in ("maizeviz", "app"):
        for path in (ROOT / folder).rglob("*.py"):
            if path.name == "environment.py":
                continue
            text = path.read_text(encoding="utf-8")
            assert not direct.search(text), f"{path} reads a MAIZEVIZ_ variable itself"
    assert set(environment.VARIABLES["MAIZEVIZ_EMBREE_ISA"].words.values()) == set(ISAS)
    assert set(environment.READERS) == {v.kind for v in environment.VARIABLES.values()}


@settings(max_examples=80, deadline=None)
@given(name=st.sampled_from(sorted(__import__("maizeviz.environment").environment.VARIABLES)),
       value=st.text(st.characters(exclude_categories=("Cs",), exclude_characters="\x00"),
                     max_size=10))
def test_any_value_of_any_variable_is_its_value_or_one_line(name, value):
    import os

    from maizeviz import environment

    var = environment.VARIABLES[name]
    old = os.environ.get(name)
    os.environ[name] = value
    try:
        got = environment.READERS[var.kind](name)
    except environment.EnvironmentVariableError as exc:
        msg = str(exc)
        assert msg.startswith(f"{name}=") and "\n" not in msg and exc.quantity == name
    else:
        if var.kind == "whole":
            assert isinstance(got, int) and got >= var.low
            assert not var.choices or got in var.choices
        elif var.kind == "switch":
            assert isinstance(got, bool)
        else:
            assert got is None or got in var.words.values()
    finally:
        if old is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = old


# ------------------------------------------------------------------------------ smaller
def test_info_lists_the_declared_dependencies_as_declared():
    """--info omitted plyfile and listed pyarrow (required) as optional."""
    import re
    import tomllib

    from maizeviz.info import OPTIONAL, REQUIRED

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]

    def names(reqs):
        out = []
        for r in reqs:
            name, extras = re.match(r"\s*([A-Za-z0-9._-]+)(\[[^\]]*\])?", r).groups()
            out.append(name)
            if extras:                                  # dask[distributed]: distributed too
                out += [e.strip() for e in extras[1:-1].split(",")]
        return out

    required = names(project["dependencies"])
    extras = project["optional-dependencies"]
    optional = [n for n in names(extras["gui"] + extras["sweep"]) if n not in required]
    assert len(set(REQUIRED)) == len(REQUIRED) and set(REQUIRED) == set(required)
    assert len(set(OPTIONAL)) == len(OPTIONAL) and set(OPTIONAL) == set(optional)
    info = _headless("--info")
    assert "plyfile" in info.stdout, info.stdout


def test_subplots_help_says_rect_defaults_to_the_central_tile():
    """It said 'the field'; the code and docs/cli.md take the central tile."""
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
        main(["subplots", "--help"])
    text = " ".join(out.getvalue().split())
    assert "(default: the central tile" in text and "(default: the field)" not in text


def test_a_precision_beyond_reach_says_the_target_in_enough_digits(capsys):
    """--precision 1e-6 stopped at 1,024 rays/cm2 with '0.00% asked for'."""
    code = main(["light", B, "--triangles", "4", "--heights", "0", "--sun-zenith", "30",
                 "--sun-azimuth", "180", "--precision", "1e-6", "--rect", "60,30,70,40"])
    err = capsys.readouterr().err
    assert code == EXIT_OK, err
    assert "above the 0.0001% asked for" in err and "0.00%" not in err, err


def test_the_docs_say_what_meshio_reads_of_a_legacy_vtk(tmp_path):
    """docs/cli.md said meshio reads the plot and period from a legacy .vtk; meshio 5.3.5
    drops its FIELD data (VTK and pyvista read it)."""
    import meshio
    import pyvista

    path = tmp_path / "c.vtk"
    assert main(["canopy", B, "--triangles", "4", "--export", str(path)]) == EXIT_OK
    assert "field_cm" in pyvista.read(path).field_data
    dropped = "field_cm" not in meshio.read(path).field_data
    row = next(ln for ln in (ROOT / "docs" / "cli.md").read_text().splitlines()
               if ln.startswith("| `.vtk` (legacy VTK"))
    assert ("meshio's legacy reader drops FIELD data" in row) == dropped, row


# ------------------------------------------------------------------------------ every reader
@pytest.fixture(scope="module")
def reader_samples(tmp_path_factory, small_points):
    """A small valid file for each reader: (reader, path)."""
    from maizeviz.canopy.layout import layout_for, save_layout
    from maizeviz.io.archive import load_project
    from maizeviz.io.mesh_canopy import read_mesh
    from maizeviz.io.points import read_points
    from maizeviz.leaf.fit import read_leaves
    from maizeviz.project.study import save_study

    folder = tmp_path_factory.mktemp("readers")
    pq_path = folder / "p.parquet"
    assert main(["convert", str(small_points), "--out", str(pq_path)]) == EXIT_OK
    meshes = {}
    for ext in (".ply", ".obj"):
        meshes[ext] = folder / f"c{ext}"
        assert main(["canopy", str(small_points), "--triangles", "4", "--export",
                     str(meshes[ext])]) == EXIT_OK
    leaves = read_leaves(small_points).leaves
    layout = layout_for(leaves, (1, 1))
    lay = folder / "layout.json"
    save_layout(lay, layout)
    project = save_study(folder / "s.maizeviz", small_points, layout, level="16")
    weather = folder / "w.csv"
    weather.write_text("time,ghi,temp_air\n" + "".join(
        f"2005-08-01T{h:02d}:00+08:00,{max(0, 800 - 90 * abs(h - 12))},{20 + h / 2}\n"
        for h in range(24)))
    from maizeviz.canopy.layout import load_layout

    return {"points csv": (read_points, small_points), "points parquet": (read_points, pq_path),
            "ply": (read_mesh, meshes[".ply"]), "obj": (read_mesh, meshes[".obj"]),
            "project": (load_project, project), "layout": (load_layout, lay),
            "weather csv": (read_weather, weather), "epw": (read_weather, EPW),
            "tmy3": (read_weather, TMY3)}


READERS = ["points csv", "points parquet", "ply", "obj", "project", "layout", "weather csv",
           "epw", "tmy3"]


@settings(max_examples=120, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data(), which=st.sampled_from(READERS))
def test_every_reader_reads_a_damaged_file_or_says_one_line(tmp_path, reader_samples, data,
                                                            which):
    """Truncations, flipped bytes, garbage inserted, in each reader's own valid file: a
    result, or one MaizevizError line naming the file; no other exception."""
    reader, path = reader_samples[which]
    raw = bytearray(Path(path).read_bytes())
    for _ in range(data.draw(st.integers(1, 3), label="damages")):
        op = data.draw(st.sampled_from(["cut", "truncate", "flip", "insert"]), label="op")
        at = data.draw(st.integers(0, max(len(raw) - 1, 0)), label="at")
        if op == "cut":
            del raw[at:at + data.draw(st.integers(1, 300), label="n")]
        elif op == "truncate":
            del raw[at:]
        elif op == "flip" and raw:
            raw[at] = data.draw(st.integers(0, 255), label="byte")
        else:
            raw[at:at] = data.draw(st.binary(min_size=1, max_size=16), label="garbage")
    bad = tmp_path / f"damaged{Path(path).suffix}"
    bad.write_bytes(bytes(raw))
    try:
        reader(bad)
    except MaizevizError as exc:
        msg = str(exc)
        assert "\n" not in msg and (str(bad) in msg or bad.name in msg), (which, msg)


def test_a_weather_time_run_into_the_next_is_refused_not_guessed(tmp_path):
    """Found by the reader fuzz above: '2005-08-01T03' run into the next row's time was read
    by pd.Timestamp's fallback as 04:00 (or, beside other offsets, ended in pandas'
    'Tz-aware datetime.datetime cannot be converted' ValueError)."""
    path = tmp_path / "w.csv"
    path.write_text("time,ghi\n2005-08-01T02:00+08:00,0\n"
                    "2005-08-01T032005-08-01T04:00+08:00,10\n2005-08-01T05:00+08:00,20\n")
    with pytest.raises(WeatherFileError, match="line 3, column time: cannot read"):
        read_weather(path)


def test_converting_to_an_mtg_names_the_columns_it_cannot_hold(tmp_path, capsys):
    """An MTG holds fitted leaves: the records' extra columns cannot go in; said, not lost
    without a word."""
    lines = Path(B).read_text().splitlines()
    src = tmp_path / "noted.csv"
    src.write_text("\n".join([lines[0] + ",Note"] + [ln + ",x" for ln in lines[1:] if ln]) + "\n")
    code = main(["convert", str(src), "--out", str(tmp_path / "p.mtg")])
    err = capsys.readouterr().err
    assert code == EXIT_OK, err
    assert "the column(s) Note of" in err and "not in it" in err, err
