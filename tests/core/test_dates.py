"""Dates across the whole calendar (years 0001-9999): a weather file's times and the date
options read back exactly as written, never wrapped by a nanosecond range (2300 -> 1716)."""

import datetime as dt

import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from maizeviz.io.dates import FIRST_YEAR, LAST_YEAR
from maizeviz.light.sources.irradiance import WeatherFileError, read_weather, sun_track
from maizeviz.light.sources.sun import sun_at

#: Whole minutes, years 1..9999 (a day short of the end: the file's second row and the
#: interval after it must stay inside the calendar).
WHEN = st.datetimes(min_value=dt.datetime(FIRST_YEAR, 1, 2), max_value=dt.datetime(9999, 12, 30)
                    ).map(lambda t: t.replace(second=0, microsecond=0))
OFFSET_MIN = st.integers(-12 * 60, 14 * 60).map(lambda m: m - m % 15)
ZONES = st.sampled_from(["UTC", "Asia/Shanghai", "America/New_York", "Europe/Paris",
                         "Pacific/Kiritimati"])


def _iso(t: dt.datetime, offset_min: int | None) -> str:
    text = f"{t.year:04d}-{t.month:02d}-{t.day:02d}T{t.hour:02d}:{t.minute:02d}"
    if offset_min is None:
        return text
    sign = "+" if offset_min >= 0 else "-"
    return f"{text}{sign}{abs(offset_min) // 60:02d}:{abs(offset_min) % 60:02d}"


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(t0=WHEN, offset=OFFSET_MIN, step=st.integers(1, 180))
def test_weather_times_read_as_written_in_every_year(tmp_path, t0, offset, step):
    t1 = t0 + dt.timedelta(minutes=step)
    path = tmp_path / "w.csv"
    path.write_text(f"time,ghi\n{_iso(t0, offset)},100\n{_iso(t1, offset)},200\n")
    w = read_weather(path, label="start")
    zone = dt.timezone(dt.timedelta(minutes=offset))
    # the data are the oracle: the first interval starts at the first row's time
    assert w.start == pd.Timestamp(t0.replace(tzinfo=zone))
    assert w.end == pd.Timestamp((t1 + dt.timedelta(minutes=step)).replace(tzinfo=zone))
    assert w.start.year == t0.year and w.start.month == t0.month and w.start.day == t0.day
    assert list(w.step_s) == [step * 60.0, step * 60.0]


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(t0=WHEN, tz=ZONES)
def test_weather_local_times_with_a_zone_read_as_written(tmp_path, t0, tz):
    path = tmp_path / "w.csv"
    t1 = t0 + dt.timedelta(hours=1)
    path.write_text(f"time,ghi\n{_iso(t0, None)},100\n{_iso(t1, None)},200\n")
    try:
        w = read_weather(path, tz=tz, label="start")
    except WeatherFileError as exc:          # a clock time skipped or repeated by a DST change
        assert "daylight-saving" in str(exc) and "\n" not in str(exc)
        return
    local = w.start.tz_convert(tz)
    assert (local.year, local.month, local.day, local.hour, local.minute) == \
        (t0.year, t0.month, t0.day, t0.hour, t0.minute)


@pytest.mark.parametrize("year", [1600, 1676, 2263, 2300, 9999, 1])
def test_weather_file_outside_the_nanosecond_range_is_not_wrapped(tmp_path, year):
    path = tmp_path / "w.csv"
    path.write_text(f"time,ghi\n{year:04d}-06-01T12:00+00:00,500\n"
                    f"{year:04d}-06-01T13:00+00:00,500\n")
    w = read_weather(path, label="start")
    assert w.start.year == year and w.end.year == year
    assert str(w.start).startswith(f"{year:04d}-06-01 12:00")


def test_year_zero_is_refused_naming_the_line(tmp_path):
    path = tmp_path / "w.csv"
    path.write_text("time,ghi\n# comment\n0000-06-01T12:00+00:00,500\n0000-06-01T13:00+00:00,5\n")
    with pytest.raises(WeatherFileError) as err:
        read_weather(path)
    msg = str(err.value)
    assert "line 3" in msg and "0000-06-01T12:00+00:00" in msg and "0001" in msg and "\n" not in msg


@settings(max_examples=40, deadline=None)
@given(day=st.dates(min_value=dt.date(FIRST_YEAR, 1, 1), max_value=dt.date(LAST_YEAR, 12, 31)),
       tz=ZONES)
def test_date_options_read_every_year(day, tz):
    text = day.isoformat()
    track = sun_track(text, 40.0, 116.0, tz, step_min=360)
    assert track.start.date() == day and track.start.hour == 0
    assert (track.end - track.start) == pd.Timedelta(days=1) or tz not in ("UTC", "Asia/Shanghai")
    sun = sun_at(text, "12:00", 0.0, 0.0, "UTC")      # the equator at noon: the sun is up
    assert sun.when.startswith(f"{text}T12:00")
