"""``maizeviz instrument``: the three instruments on the bundled block through the command
line, JSON and tables, files written, bad settings in one line naming the flag."""

from __future__ import annotations

import json

import pytest

from maizeviz.cli import EXIT_FAIL, EXIT_OK, main
from maizeviz.resources import example_points

FAST = ["--triangles", "36"]


def run_json(capsys, *args):
    code = main(["instrument", *args, str(example_points()), *FAST, "--json"])
    out = capsys.readouterr()
    assert code == EXIT_OK, out.err
    return json.loads(out.out), out.err


def test_ceptometer_json_and_csv(capsys, tmp_path):
    csv = tmp_path / "sensors.csv"
    rec, _ = run_json(capsys, "ceptometer", "--sun-zenith", "30", "--sun-azimuth", "180",
                      "--at", "60,40", "--at", "90,50", "--orientation", "along",
                      "--height", "20", "--csv", str(csv))
    assert rec["instrument"] == "ceptometer" and rec["stalks"] is True
    assert len(rec["probes"]) == 2 and rec["probes"][0]["sensors"] == 80
    assert rec["probes"][0]["azimuth_deg"] == 0.0
    assert 0.0 <= rec["tau"] <= 1.0
    assert rec["intercepted"] == pytest.approx(1.0 - rec["tau"])
    lines = csv.read_text().splitlines()
    assert lines[0].startswith("probe,sensor,x_cm") and len(lines) == 161


def test_leaves_only_lets_the_stalks_light_through(capsys):
    args = ("ceptometer", "--sun-zenith", "0", "--sun-azimuth", "180", "--beam-fraction", "1",
            "--orientation", "across", "--spacing", "0.25")
    with_stalks, _ = run_json(capsys, *args)
    leaves, _ = run_json(capsys, *args, "--leaves-only")
    assert leaves["stalks"] is False
    assert leaves["tau"] >= with_stalks["tau"]


def test_analyser_tables_and_json(capsys):
    code = main(["instrument", "analyser", str(example_points()), *FAST, "--rays", "200",
                 "--view-cap", "90", "--heading", "90", "--periodic"])
    out = capsys.readouterr().out
    assert code == EXIT_OK
    assert "ring" in out and "LAI" in out and "62.3-74.1" in out
    rec, _ = run_json(capsys, "analyser", "--rays", "200", "--periodic")
    assert [r["ring"] for r in rec["rings"]] == [1, 2, 3, 4, 5]
    assert rec["lai"] is None or rec["lai"] > 0


def test_hemiphoto_writes_a_png_per_position(capsys, tmp_path):
    png = tmp_path / "hemi.png"
    rec, err = run_json(capsys, "hemiphoto", "--size", "64", "--png", str(png), "--at", "60,40",
                        "--at", "90,50")
    assert len(rec["photos"]) == 2
    for k in (1, 2):
        path = tmp_path / f"hemi_{k}.png"
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert str(path) in err
    assert 0.0 <= rec["photos"][0]["openness"] <= 1.0


@pytest.mark.parametrize("args, words", [
    (["analyser", "--view-cap", "100"], "(--view-cap)"),
    (["ceptometer", "--sun-zenith", "30", "--sun-azimuth", "180", "--orientation", "up"],
     "(--orientation)"),
    (["ceptometer"], "where is the sun"),
    (["ceptometer", "--sun-zenith", "30", "--sun-azimuth", "180", "--date", "2005-08-01",
      "--time", "12:00", "--lat", "40", "--lon", "116"], "not both"),
    (["ceptometer", "--sun-zenith", "30"], "give both"),
    (["ceptometer", "--sun-zenith", "30", "--sun-azimuth", "180", "--beam-fraction", "2"],
     "(--beam-fraction)"),
    (["hemiphoto", "--at", "1"], "(--at)"),
    (["hemiphoto", "--size", "4"], "(--size)"),
    (["analyser", "--levels"], "one canopy"),
])
def test_bad_settings_say_which_flag(capsys, args, words):
    fast = [] if "--levels" in args else FAST
    code = main(["instrument", args[0], str(example_points()), *fast, *args[1:]])
    err = capsys.readouterr().err
    assert code == EXIT_FAIL
    assert words in err and err.count("\n") == 1
