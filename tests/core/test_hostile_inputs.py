"""Hostile values of the issue's list: each a one-line error naming its option or file, never
an "internal error", and nothing written."""

import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from maizeviz.cli import EXIT_FAIL, main
from maizeviz.errors import MaizevizError
from maizeviz.light.sources.irradiance import clear_sky_period, read_weather
from maizeviz.light.sources.sun import sun_at
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


# ------------------------------------------------------------------ what the app passes on

TEXT = st.one_of(st.text(max_size=30), st.sampled_from(
    ["A" * 5000, "Asia/" + "x" * 300, "../../etc/passwd", "UTC\x00", "9999-12-31", "0000-01-01",
     "24:00", "25:61", "12:00+99:00", "nan", "-1"]))
NUMBER = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                   st.integers(-10**30, 10**30))


@settings(max_examples=300, deadline=None)
@given(date=TEXT, clock=TEXT, tz=TEXT, lat=NUMBER, lon=NUMBER, step=NUMBER)
def test_the_apps_day_and_sun_fields_give_only_maizeviz_errors(date, clock, tz, lat, lon, step):
    """Whatever is typed in the light panel's date, time, zone and place fields, the core
    answers with a result or a MaizevizError (the user's), never another exception."""
    for make in (lambda: sun_at(date, clock, lat, lon, tz),
                 lambda: clear_sky_period(date, lat, lon, tz, step, clock or None, None)):
        try:
            make()
        except MaizevizError as exc:
            assert "\n" not in str(exc)


@settings(max_examples=100, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(time=TEXT, ghi=TEXT, tz=st.one_of(st.none(), TEXT))
def test_weather_file_cells_give_only_maizeviz_errors(tmp_path, time, ghi, tz):
    path = tmp_path / "w.csv"
    path.write_text(f"time,ghi\n{time},{ghi}\n2005-08-01T12:00+08:00,5\n", errors="replace")
    try:
        read_weather(path, tz=tz)
    except MaizevizError as exc:
        assert "\n" not in str(exc)
