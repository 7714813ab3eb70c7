"""Hostile values of the issue's list: each a one-line error naming its option or file, never
an "internal error", and nothing written."""

import os

import pytest

from maizeviz.cli import EXIT_FAIL, main
from maizeviz.resources import example_points

B = str(example_points())
SUN = ["--sun-zenith", "10", "--sun-azimuth", "0"]


def _one_error(capsys) -> str:
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith(("error", "internal"))]
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    return lines[0]


@pytest.mark.parametrize("argv, flag", [
    (["light", B, *SUN, "--density", "1e308"], "--density"),
    (["light", B, *SUN, "--rect=nan,0,10,10"], "--rect"),
    (["light", B, *SUN, "--rect=0,0,1e308,10"], "--rect"),
    (["light", B, "--date", "2005-08-01", "--time", "12:00", "--lat", "40", "--lon", "116",
      "--tz", "A" * 5000], "--tz"),
    (["light", B, "--date", "2005-08-01", "--day", "--lat", "40", "--lon", "116",
      "--tz", "Asia/" + "x" * 5000], "--tz"),
])
def test_hostile_values_are_one_line_naming_the_option(capsys, tmp_path, argv, flag):
    out = tmp_path / "leaf.csv"
    assert main([*argv, "--leaf-light", str(out)]) == EXIT_FAIL
    assert _one_error(capsys).endswith(f"({flag})")
    assert not out.exists()


def test_a_50000_deep_sweep_file_is_one_line(capsys, tmp_path):
    spec = tmp_path / "deep.toml"
    spec.write_text("a = " + "[" * 50_000 + "]" * 50_000 + "\n")
    assert main(["sweep", str(spec), "--dry-run"]) == EXIT_FAIL
    line = _one_error(capsys)
    assert str(spec) in line and "nested too deeply" in line


@pytest.mark.parametrize("role", ["input", "output"])
def test_a_symlink_loop_is_one_line(capsys, tmp_path, role):
    loop = tmp_path / "loop.csv"
    os.symlink(loop, loop)
    argv = ["leaf", str(loop)] if role == "input" else \
        ["canopy", B, "--save-layout", str(loop)]
    assert main(argv) == EXIT_FAIL
    assert "loop.csv" in _one_error(capsys)
    assert os.readlink(loop) == str(loop)
