"""Property-based fuzzing of the weather CSV and sweep TOML readers: arbitrary text or bytes
either read or raise a MaizevizError with a one-line message, within a deadline."""

import os
import shutil
import string
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from maizeviz.errors import MaizevizError
from maizeviz.light.sources.irradiance import read_weather
from maizeviz.resources import example_points

_LONG = int(os.environ.get("MAIZEVIZ_FUZZ_EXAMPLES", "0"))
FUZZ = settings(max_examples=_LONG or 80, deadline=5000, derandomize=not _LONG,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


@pytest.fixture(scope="module")
def folder():
    d = Path(tempfile.mkdtemp(prefix="maizeviz-fuzz-inputs-"))
    shutil.copy(example_points(), d / "block3x3.csv")
    yield d
    shutil.rmtree(d, ignore_errors=True)


def one_line(exc: BaseException) -> None:
    assert isinstance(exc, MaizevizError), f"{type(exc).__name__}: {exc}"
    msg = str(exc)
    assert msg and len(msg.splitlines()) == 1 and len(msg) < 2000, msg


def only_own_errors(fn, *args, **kw):
    try:
        return fn(*args, **kw)
    except Exception as exc:  # noqa: BLE001 - that is what is being tested
        one_line(exc)
        return None


# --------------------------------------------------------------------------------- weather
TIME = st.one_of(
    st.sampled_from(["2005-08-01T06:00+08:00", "2005-08-01 12:30:00+08:00",
                     "2005-08-01T12:00Z", "2005-08-01T12:00", "2005-13-45T99:99+08:00",
                     "yesterday", "", "2005-08-01T12:00+25:00"]),
    st.datetimes().map(lambda t: t.isoformat() + "+08:00"),
    st.text(alphabet=string.printable, max_size=12))
VALUE = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr),
                  st.sampled_from(["", "-1", "0", "850", "1e9", "nan", "n/a", '"5"', "1,5"]),
                  st.integers(-10, 1500).map(str))
COLS = st.sampled_from(["time,ghi", "time,ghi,dni,dhi", "time,ghi,dni", "TIME;GHI",
                        "time,ghi,wind", "ghi", "time,dhi", "", "time,ghi,ghi"])


@st.composite
def weather_text(draw):
    header = draw(COLS)
    n = len(header.replace(";", ",").split(","))
    rows = draw(st.lists(st.tuples(TIME, st.lists(VALUE, min_size=n - 1, max_size=n + 1)),
                         max_size=12))
    lines = [header] + [",".join([t, *vals]) for t, vals in rows]
    return "\n".join(lines) + draw(st.sampled_from(["\n", "", "\r\n"]))


@FUZZ
@given(text=weather_text())
def test_weather_text_fuzz(folder, text):
    path = folder / "weather.csv"
    path.write_text(text, encoding="utf-8")
    weather = only_own_errors(read_weather, path)
    if weather is not None:                               # what is read is usable
        assert len(weather.times) == len(weather.ghi) and (weather.ghi >= 0).all()


@FUZZ
@given(data=st.binary(max_size=600))
def test_weather_bytes_fuzz(folder, data):
    path = folder / "weather.bin"
    path.write_bytes(data)
    only_own_errors(read_weather, path)


# ----------------------------------------------------------------------------------- sweep
KEY = st.sampled_from(["points", "tile", "row_spacing", "plant_spacing", "level", "layout",
                       "preserve_area", "block", "sun", "density", "heights", "periodic",
                       "rect", "cover_resolution", "typo", "levels"])
TOML_VALUE = st.one_of(
    st.sampled_from(['["block3x3.csv"]', '["*.csv"]', '["missing.csv"]', '["3x3"]', '["0x3"]',
                     '[60]', '[-1]', '[1e308]', '["K4", "36"]', '["K99"]', '[]', '"3x3"',
                     '[{zenith = 30, azimuth = 180}]', '[{zenith = 95, azimuth = 0}]',
                     '[{date = "2005-08-01", time = "12:00", lat = 39.9, lon = 116.4}]',
                     '[0, 50, 100]', '[0, nan]', 'true', '1', '[[1]]', '{a = 1}',
                     '[0, 0, 100, 100]', '"x"', '[inf]']),
    st.text(alphabet=string.printable, max_size=10).map(lambda t: '"' + t.replace('"', "") + '"'))


@st.composite
def sweep_text(draw):
    tables = []
    for table in draw(st.lists(st.sampled_from(["canopy", "light", "extra"]), max_size=3,
                               unique=True)):
        items = draw(st.lists(st.tuples(KEY, TOML_VALUE), max_size=6, unique_by=lambda kv: kv[0]))
        tables.append(f"[{table}]\n" + "\n".join(f"{k} = {v}" for k, v in items))
    head = draw(st.sampled_from(["", 'exclude = [{level = "K4"}]\n', "exclude = 3\n"]))
    return head + "\n".join(tables) + "\n"


@FUZZ
@given(text=sweep_text())
def test_sweep_spec_fuzz(folder, text):
    from maizeviz.sweep.spec import load_spec

    path = folder / "sweep.toml"
    path.write_text(text, encoding="utf-8")
    spec = only_own_errors(load_spec, path)
    if spec is not None:
        assert spec.scenarios and all(s.key for s in spec.scenarios)


@FUZZ
@given(data=st.binary(max_size=400))
def test_sweep_spec_bytes_fuzz(folder, data):
    from maizeviz.sweep.spec import load_spec

    path = folder / "bytes.toml"
    path.write_bytes(data)
    only_own_errors(load_spec, path)
