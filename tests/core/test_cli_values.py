"""Every value a user can type is checked by range: one line naming the option, never an
"internal error", and nothing written."""

import pytest

from maizeviz.cli import EXIT_FAIL, main
from maizeviz.resources import example_points

B = str(example_points())
SUN = ["--sun-zenith", "10", "--sun-azimuth", "0"]


@pytest.mark.parametrize("argv, flag", [
    (["synth", "--plants", "1x1", "--seed", "-1"], "--seed"),
    (["synth", "--plants", "1x1", "--sections", "100000000"], "--sections"),
    (["synth", "--plants", "1000x1000"], "--plants"),
    (["synth", "--plants", "1x1", "--points-across", "100000"], "--points-across"),
    (["synth", "--plants", "1x1", "--row-spacing", "nan"], "--row-spacing"),
    (["synth", "--plants", "1x1", "--plant-spacing", "0"], "--plant-spacing"),
    (["light", B, *SUN, "--threads", "1000000000"], "--threads"),
    (["light", B, *SUN, "--heights", "0,inf"], "--heights"),
    (["light", B, *SUN, "--density", "nan"], "--density"),
    (["light", B, "--sun-zenith", "nan", "--sun-azimuth", "0"], "--sun-zenith/--sun-azimuth"),
    (["light", B, "--date", "2005-13-01", "--time", "12:00", "--lat", "39", "--lon", "116"],
     "--date"),
    (["light", B, "--date", "2005-08-01", "--time", "25:00", "--lat", "39", "--lon", "116"],
     "--time"),
    (["light", B, "--date", "2005-08-01", "--time", "12:00:00+05:00", "--tz", "Asia/Shanghai",
      "--lat", "39", "--lon", "116"], "--time"),
    (["light", B, "--date", "2005-08-01", "--time", "12:00", "--tz", "Mars/Olympus",
      "--lat", "39", "--lon", "116"], "--tz"),
    (["light", B, "--date", "2005-08-01", "--time", "12:00", "--lat", "nan", "--lon", "116"],
     "--lat/--lon"),
    (["canopy", B, "--block", "0x3"], "--block"),
    (["canopy", B, "--cover-resolution", "nan"], "--cover-resolution"),
    (["leaf", B, "--interp", "1000"], "--interp"),
    (["fastrak-sim", "--pace", "-1", "--replay", B], "--pace"),
    (["fastrak-sim", "--noise", "inf"], "--noise"),
    (["record", "--port", "/dev/null", "--out", "OUT", "--answer-timeout", "-5"],
     "--answer-timeout"),
    (["record", "--port", "/dev/null", "--out", "OUT", "--baud", "0"], "--baud"),
    (["import-phenomenal", "PHENO", "--plant", "99999999999999999999"], "--plant"),
    (["import-phenomenal", "PHENO", "--at", "nan,nan"], "--at"),
])
def test_a_value_out_of_range_is_one_line_naming_its_option(capsys, tmp_path, argv, flag):
    from maizeviz.resources import example_phenomenal

    out = tmp_path / "out.csv"
    argv = [str(out) if a == "OUT" else str(example_phenomenal()) if a == "PHENO" else a
            for a in argv]
    if argv[0] in ("synth", "import-phenomenal"):
        argv += ["--out", str(out)]
    assert main(argv) == EXIT_FAIL
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith(("error", "internal"))]
    assert len(err) == 1 and err[0].startswith("error: ") and err[0].endswith(f"({flag})"), err
    assert not out.exists()


@pytest.mark.parametrize("option", ["--save-layout", "--export"])
def test_an_output_in_a_missing_folder_is_refused_before_any_work(capsys, tmp_path, option):
    target = tmp_path / "missing" / ("x.json" if option == "--save-layout" else "x.ply")
    argv = ["canopy", B, option, str(target)] + (["--triangles", "4"] if option == "--export"
                                                 else [])
    assert main(argv) == EXIT_FAIL
    out, err = capsys.readouterr()
    assert "does not exist" in err and not out and "note:" not in err
