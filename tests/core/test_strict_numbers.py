"""Numbers are read strictly and lists are bounded before work starts (issue 25).

Case 6: ``1_000`` and ``3_4.0`` (Python's literal syntax, which float and int accept) were read
as numbers in points files, ascii PLY, ``--density``, ``--tile``, weather and optics files.
The hangs: ``--levels=8,8,...`` (2,000 repeats), ``--heights=1,1,...`` (20,000 values),
``sweep --connect-timeout 1e308``. The doubtful cases decided here: ``--density 1e-308`` (one
ray for the whole plot, unsaid) and ``--heights 0,,50`` (the empty item dropped) are refused.
"""

import argparse
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.cli import COMMANDS, build_parser, main
from maizeviz.errors import MaizevizError
from maizeviz.io.points import read_points
from maizeviz.numbers import NUMBER_ARG, WHOLE_ARG, number, whole
from maizeviz.resources import example_points

B = str(example_points())
SUN = ["--sun-zenith", "30", "--sun-azimuth", "180"]
PYTHON_ONLY = ["1_000", "3_4.0", "1_0e1_0", "\uff11\uff12", "\u0663", "1__0"]


@pytest.mark.parametrize("text", PYTHON_ONLY)
def test_python_only_forms_are_not_numbers(text):
    float(text.replace("__", "_")) if "__" not in text else None   # Python reads most of them
    with pytest.raises(ValueError):
        number(text)
    with pytest.raises(ValueError):
        whole(text)


@settings(max_examples=300, deadline=None)
@given(st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**20, 10**20)))
def test_every_number_python_writes_reads_back_the_same(x):
    """The oracle is repr: whatever Python prints for a float or an int reads back equal."""
    text = repr(x) if isinstance(x, float) else str(x)
    got = number(text)
    assert got == float(text) or (got != got and x != x)
    if isinstance(x, int):
        assert whole(text) == x


def _number_options():
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name in COMMANDS:
        for action in sub.choices[name]._actions:
            if action.option_strings and action.type is not None:
                yield name, action


def test_every_number_option_reads_strictly():
    """Every option of every command that takes a number reads it here (float and int would
    take 1_000): found in the parser itself, so an option added later is covered too."""
    found = 0
    for name, action in _number_options():
        assert action.type not in (float, int), f"{name} {action.option_strings[0]}"
        if action.type in (NUMBER_ARG, WHOLE_ARG):
            found += 1
            for text in PYTHON_ONLY:
                with pytest.raises(ValueError):
                    action.type(text)
    assert found >= 40


@pytest.mark.parametrize("argv, flag", [
    (["light", B, *SUN, "--density", "1_0"], "--density"),
    (["light", B, *SUN, "--threads", "1_0"], "--threads"),
    (["canopy", B, "--cover-resolution", "0_5"], "--cover-resolution"),
    (["leaf", B, "--interp", "\uff14"], "--interp"),
])
def test_a_number_option_with_underscores_is_a_usage_error(capsys, argv, flag):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    assert f"argument {flag}: invalid" in capsys.readouterr().err


@pytest.mark.parametrize("argv, says", [
    (["light", B, *SUN, "--heights", "0,1_00"], "heights must be numbers"),
    (["light", B, *SUN, "--rect", "0,0,1_0,10"], "sample rectangle must be numbers"),
    (["light", B, *SUN, "--tile", "3_0x3"], "tile must look like 3x3"),
    (["canopy", B, "--tile", "3x3_0"], "tile must look like 3x3"),
    (["canopy", B, "--levels", "3_6"], "is not a mesh level"),
    (["canopy", B, "--levels", "K\u0664"], "is not a mesh level"),
    # the doubtful cases, decided: refused rather than silently changed
    (["light", B, *SUN, "--heights", "0,,50"], "item 2 of 3 is empty"),
    (["light", B, *SUN, "--heights", "0,50,"], "item 3 of 3 is empty"),
    (["light", B, *SUN, "--density", "1e-308"], "puts no ray across the sample rectangle"),
    # duplicates are refused, naming them
    (["light", B, *SUN, "--heights", "0,50,50.0"], "height 50 cm is given twice"),
    (["canopy", B, "--levels", "K4,36,K=4"], "mesh level K=4 is given twice (items 1 and 3)"),
])
def test_list_and_text_options_are_one_line(capsys, argv, says):
    assert main(argv) == 1
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith("error")]
    assert len(lines) == 1 and says in lines[0], err


@pytest.mark.parametrize("argv, says", [
    (["light", B, *SUN, "--heights=" + ",".join(["1"] * 20_000)], "20,000 values"),
    (["canopy", B, "--levels=" + ",".join(["8"] * 2_000)], "2,000 mesh levels"),
    (["light", B, *SUN, "--rect=" + ",".join(["1"] * 100_000)], "100,000 values"),
])
def test_long_lists_are_refused_before_any_work(capsys, argv, says):
    """These hung: each list item was checked against every other, then traced."""
    t0 = time.perf_counter()
    assert main(argv) == 1
    assert time.perf_counter() - t0 < 5
    assert says in capsys.readouterr().err


def test_the_core_bounds_heights_too():
    """The app and sweeps reach the core without the command line's text: the sampling
    itself refuses more than MAX_HEIGHTS planes and repeated heights."""
    from maizeviz.light.scene.request import MAX_HEIGHTS, Sampling, check_sampling
    from tests.core.test_metamorphic import _squares

    canopy = _squares(1)
    with pytest.raises(MaizevizError, match="at most 1,000 sensor planes"):
        check_sampling(canopy, Sampling(tuple(np.arange(MAX_HEIGHTS + 1.0)), 1.0))
    with pytest.raises(MaizevizError, match="height 0 cm is given twice"):
        check_sampling(canopy, Sampling((0.0, 10.0, -0.0), 1.0))


@pytest.mark.parametrize("value", ["1e308", "nan", "-1", "inf", "0"])
def test_sweep_connect_timeout_is_bounded(capsys, value):
    """1e308 waited forever; NaN and -1 ended in Dask's own messages."""
    sweep = Path(B).with_name("sweep-example.toml")
    t0 = time.perf_counter()
    assert main(["sweep", str(sweep), "--out", "unused", "--scheduler",
                 "tcp://127.0.0.1:9", f"--connect-timeout={value}"]) == 2
    assert time.perf_counter() - t0 < 10
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--connect-timeout" in err and "0.1 to 3600 s" in err


# ------------------------------------------------------------------ files


def test_points_file_with_underscores(tmp_path):
    path = tmp_path / "p.csv"
    path.write_text("plant,leaf,row,col,x,y,z\n1,1,0,0,1_000,2,3\n1,1,0,1,1,2,3\n"
                    "1_0,1,0,0,1,2,3\n2,1,0,0,1,2,3\n")
    table = read_points(path)
    assert table.bad_leaves[(1, 1)] == ["row 0, col 0 (line 2): x is not a number ('1_000')"]
    assert any("line 4: plant/leaf id is not an integer ('1_0'" in p for p in table.problems)
    assert [tuple(i) for i in table.ids] == [(1, 1, 0, 1), (2, 1, 0, 0)]


@pytest.mark.parametrize("kind", ["ply", "obj"])
def test_mesh_files_with_underscores(tmp_path, kind):
    from maizeviz.io.mesh_canopy import MeshFileError, read_mesh

    if kind == "ply":
        text = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                "property double z\nelement face 1\nproperty list uchar int vertex_indices\n"
                "property int plant\nproperty int leaf\nend_header\n"
                "0 0 1_0\n1 0 10\n0 1 10\n3 0 1 2 1 1\n")
    else:
        text = "g plant1_leaf1\nv 0 0 1_0\nv 1 0 10\nv 0 1 10\nf 1 2 3\n"
    path = tmp_path / f"m.{kind}"
    path.write_text(text)
    with pytest.raises(MeshFileError, match="line" if kind == "ply" else "x, y and z numbers"):
        read_mesh(path)
    path.write_text(text.replace("1_0", "10"))
    assert read_mesh(path).n_triangles == 1                # the same file, plainly written
    if kind == "obj":
        path.write_text(text.replace("1_0", "10").replace("f 1 2 3", "f 1 2 \uff13"))
        with pytest.raises(MeshFileError, match="is not a face"):
            read_mesh(path)


def test_weather_and_optics_files_with_underscores(tmp_path):
    from maizeviz.light.sources.irradiance import read_weather
    from maizeviz.light.trace.optics import read_optics_table

    weather = tmp_path / "w.csv"
    rows = "\n".join(f"2005-08-01T{h:02d}:00+08:00,{v}" for h, v in
                     ((10, "500"), (11, "6_00"), (12, "700")))
    weather.write_text("time,ghi\n" + rows + "\n")
    with pytest.raises(MaizevizError, match=r"line 3 .*column ghi: '6_00' is not a number"):
        read_weather(weather)
    weather.write_text("time,ghi\n" + rows.replace("6_00", "600") + "\n")
    assert list(read_weather(weather).ghi) == [500.0, 600.0, 700.0]
    optics = tmp_path / "o.csv"
    optics.write_text("rank,reflectance,transmittance\n1,0.1,0.05\n2,0_1,0.05\n")
    with pytest.raises(MaizevizError, match="line 3: rank, reflectance and transmittance"):
        read_optics_table(optics, "par")


# ------------------------------------------------------------------ names too long
LONG = "a" * 300


@pytest.mark.parametrize("argv", [
    ["leaf", B, "--triangles", "8", "--export", "DIR/LONG.ply"],
    ["canopy", B, "--tile", "1x1", "--triangles", "8", "--export", "DIR/LONG.obj"],
    ["canopy", B, "--tile", "1x1", "--triangles", "8", "--save-layout", "DIR/LONG.json"],
    ["light", B, *SUN, "--tile", "1x1", "--triangles", "8", "--leaf-light", "DIR/LONG.csv"],
    ["light", B, *SUN, "--tile", "1x1", "--triangles", "8", "--plant-light", "DIR/LONG.csv"],
    ["light", B, *SUN, "--tile", "1x1", "--triangles", "8", "--heatmaps", "DIR/LONG"],
    ["synth", "--plants", "1x1", "--out", "DIR/LONG.csv"],
    ["leaf", "DIR/LONG.csv"],
    ["canopy", B, "--layout", "DIR/LONG.json"],
])
def test_a_name_too_long_is_one_line_for_every_file(capsys, tmp_path, argv):
    """``--export`` with a 300-character name was an internal error (OSError: File name too
    long) where every other output refused it in one line."""
    argv = [a.replace("DIR", str(tmp_path)).replace("LONG", LONG) for a in argv]
    assert main(argv) == 1
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith(("error", "internal"))]
    assert len(lines) == 1 and lines[0].startswith("error:"), err[-400:]
    assert "too long" in lines[0].lower()
    assert list(tmp_path.iterdir()) == []


def test_weather_rows_with_dhi_above_ghi_are_said(tmp_path):
    """Doubtful case decided: a row whose dhi exceeds its ghi was cut to no direct light and
    its dni ignored without a word; the light is the same, now with a note naming it."""
    from maizeviz.light.sources.irradiance import read_weather, weather_period

    path = tmp_path / "w.csv"
    path.write_text("time,ghi,dni,dhi\n2005-08-01T11:00+08:00,600,500,200\n"
                    "2005-08-01T12:00+08:00,300,700,350\n2005-08-01T13:00+08:00,500,400,100\n")
    period = weather_period(read_weather(path), 39.9, 116.4)
    said = [n for n in period.notes if "dhi above ghi" in n]
    assert len(said) == 1 and said[0].startswith("1 row of w.csv with the sun up has dhi above ghi")
    assert "2005-08-01T12:00:00+08:00" in said[0] and "dni is not used" in said[0]
    assert period.direct_horizontal[1] == 0 and period.dhi[1] == 300
    assert period.direct_horizontal[0] == 400 and period.dhi[0] == 200
