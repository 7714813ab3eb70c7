"""The single sun from a date: pvlib's SPA to the last bit, without importing pandas or pvlib."""

from __future__ import annotations

import datetime as dt
import subprocess
import sys

import numpy as np
import pandas as pd
import pvlib
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.errors import MaizevizError
from maizeviz.light.sources import solar_position
from maizeviz.light.sources.clock import local_datetime, local_time, zone
from maizeviz.light.sources.sun import sun_at

ZONES = st.sampled_from([None, "UTC", "Asia/Shanghai", "America/New_York", "Europe/Paris",
                         "Australia/Lord_Howe", "Pacific/Kiritimati", "America/St_Johns"])
CLOCKS = st.tuples(st.integers(0, 23), st.integers(0, 59), st.integers(0, 59),
                   st.sampled_from(["", "+08:00", "-05:00", "+00:00", "+05:45"])).map(
    lambda c: f"{c[0]:02d}:{c[1]:02d}:{c[2]:02d}{c[3]}")
PLACES = st.tuples(st.floats(-66, 66), st.floats(-180, 180), st.floats(0, 4000))
#: pandas 3.0 writes a Timestamp with nanoseconds in a zone whose offset has seconds (a
#: historic local mean time, +08:05:43) with the nanoseconds inside the offset
#: ("...23.437247+08232:05:43"; right from pandas 3.1): there the oracle writes the text
#: from the Timestamp's fields
PANDAS_NS_OFFSET_BUG = pd.Timestamp(1900, 1, 1, 20, 0, 0, 1, nanosecond=232,
                                    tz="Asia/Shanghai").isoformat().endswith("+08232:05:43")


def pvlib_sun(date: str, clock: str | None, lat: float, lon: float, tz: str | None,
              solar_noon: bool, altitude: float) -> tuple[float, float, str]:
    """The oracle: pvlib's public wrappers with pandas, as maizeviz called them before."""
    day = dt.date.fromisoformat(date)
    if solar_noon:
        where = zone(tz) if tz is not None else dt.UTC
        midnight = pd.DatetimeIndex([pd.Timestamp(dt.datetime.combine(day, dt.time(), where))])
        when = pd.Timestamp(pvlib.solarposition.sun_rise_set_transit_spa(
            midnight, lat, lon)["transit"].iloc[0])
    else:
        when = local_time(day, clock, tz)
    pos = pvlib.solarposition.get_solarposition(pd.DatetimeIndex([when]), lat, lon, altitude)
    text = when.isoformat()
    if PANDAS_NS_OFFSET_BUG and when.nanosecond and when.utcoffset().seconds % 60:
        # the same text from the Timestamp's fields: date, time, 9 decimals, the offset
        offset = when.utcoffset()
        sign, rest = ("-", -offset) if offset.days < 0 else ("+", offset)
        hh, mm_ss = divmod(rest.seconds, 3600)
        text = (f"{when:%Y-%m-%dT%H:%M:%S}.{when.microsecond:06d}{when.nanosecond:03d}"
                f"{sign}{hh:02d}:{mm_ss // 60:02d}:{mm_ss % 60:02d}")
    return float(pos["apparent_zenith"].iloc[0]), float(pos["azimuth"].iloc[0]), text


def outcome(call):
    try:
        return call()
    except MaizevizError as e:
        return f"error: {e}"


@settings(max_examples=300, deadline=None)
@given(day=st.dates(dt.date(1800, 1, 1), dt.date(2200, 12, 31)), clock=CLOCKS, tz=ZONES,
       place=PLACES, noon=st.booleans())
def test_the_sun_is_pvlibs_bit_for_bit(day, clock, tz, place, noon):
    lat, lon, altitude = place
    want = outcome(lambda: pvlib_sun(day.isoformat(), clock, lat, lon, tz, noon, altitude))
    if isinstance(want, tuple) and want[0] >= 90:
        with pytest.raises(MaizevizError, match="below the horizon"):
            sun_at(day.isoformat(), clock, lat, lon, tz, noon, altitude)
        return
    got = outcome(lambda: sun_at(day.isoformat(), clock, lat, lon, tz, noon, altitude))
    if isinstance(got, str) or isinstance(want, str):
        assert got == want
    else:
        assert (got.zenith_deg, got.azimuth_deg, got.when) == want


def test_pvlibs_spa_file_alone_computes_what_the_package_does():
    """The file run on its own (no pandas) against the package's module: every output."""
    alone, package = solar_position.spa_file(), pvlib.spa
    assert alone is not package and alone.__file__ == package.__file__
    t = np.linspace(-5e9, 7e9, 4001)
    a = alone.solar_position_numpy(t, 39.9, 116.4, 50.0, 1000.0, 12.0, 67.0, 0.5667, 1,
                                   False, False)
    b = package.solar_position_numpy(t, 39.9, 116.4, 50.0, 1000.0, 12.0, 67.0, 0.5667, 1,
                                     False, False)
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    np.testing.assert_array_equal(
        np.asarray(alone.transit_sunrise_sunset(t[:50] // 86400 * 86400, 39.9, 116.4, 67.0, 1)),
        np.asarray(package.transit_sunrise_sunset(t[:50] // 86400 * 86400, 39.9, 116.4, 67.0,
                                                  1)))


def test_a_sun_from_a_date_imports_neither_pandas_nor_pvlib():
    """pandas and pvlib take 1 to 2 s to import: more than tracing a K = 4 sun (issue 20)."""
    code = ("import sys\n"
            "from maizeviz.light.sources.sun import sun_at\n"
            "s = sun_at('2005-08-01', '12:00', 39.9, 116.4, 'Asia/Shanghai')\n"
            "n = sun_at('2005-08-01', None, 39.9, 116.4, 'Asia/Shanghai', solar_noon=True)\n"
            "print(s.zenith_deg, n.when, sorted(m for m in sys.modules "
            "if m.split('.')[0] in ('pandas', 'pvlib')))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out[-1] == "[]"
    assert float(out[0]) == pytest.approx(22.34, abs=0.01)
    # Beijing (116.4 deg E, clocks at 120 deg E) in August: 14.4 min + 6.3 min equation of time
    assert out[1].startswith("2005-08-01T12:20:4")


@settings(max_examples=400, deadline=None)
@given(day=st.dates(dt.date(1, 1, 1), dt.date(9999, 12, 31)),
       clock=CLOCKS | st.sampled_from(["24:00", "02:30", "01:30", "00:00"]), tz=ZONES)
def test_both_clocks_read_a_time_alike(day, clock, tz):
    """local_datetime (no pandas) and local_time (pandas, for tracks): the same instant, or the
    same refusal, over the whole calendar and zones with daylight saving."""
    want = outcome(lambda: local_time(day, clock, tz))
    try:
        got = outcome(lambda: local_datetime(day, clock, tz))
    except OverflowError:
        assert (day, clock) == (dt.date(9999, 12, 31), "24:00")
        assert want == pd.Timestamp("10000-01-01", tz="UTC").as_unit("us") or tz is not None
        return
    if isinstance(want, str) or isinstance(got, str):
        assert got == want
    else:
        assert pd.Timestamp(got) == want and got.utcoffset() == want.utcoffset()


@pytest.mark.parametrize("day, clock, tz", [("2005-03-27", "02:30", "Europe/Paris"),
                                            ("2005-10-30", "02:30", "Europe/Paris")])
def test_a_wall_clock_time_skipped_or_repeated_is_refused(day, clock, tz):
    with pytest.raises(MaizevizError, match=f"{clock} on {day} does not exist or occurs twice"):
        local_datetime(dt.date.fromisoformat(day), clock, tz)


def test_the_last_midnight_of_the_calendar_is_one_line():
    with pytest.raises(MaizevizError, match="past the last day maizeviz reads"):
        sun_at("9999-12-31", "24:00", 0.0, 0.0, "UTC")


@pytest.mark.parametrize("day", ["0001-01-01", "1500-03-01", "2300-06-01", "3000-06-01",
                                 "9999-12-31"])
def test_solar_noon_over_the_whole_calendar(day, recwarn):
    """pandas' nanoseconds stop at 1677 and 2262: the noon is still that day's, and the sun at
    it is the SPA's at that instant (the sun stands north at noon at 30 deg S)."""
    import warnings

    warnings.simplefilter("error", RuntimeWarning)
    sun = sun_at(day, None, -30.0, 150.0, "Australia/Sydney", solar_noon=True)
    assert sun.when.startswith(f"{day}T1")
    assert min(sun.azimuth_deg, 360 - sun.azimuth_deg) < 1e-3
    ns = solar_position.transit_ns(dt.date.fromisoformat(day), -30.0, 150.0)
    assert (sun.zenith_deg, sun.azimuth_deg) == solar_position.position(ns / 1e9, -30.0, 150.0)


def test_the_altitude_changes_the_refraction_and_is_checked():
    low = sun_at("2005-08-01", "07:00", 39.9, 116.4, "Asia/Shanghai")
    high = sun_at("2005-08-01", "07:00", 39.9, 116.4, "Asia/Shanghai", altitude=3000.0)
    assert 1e-4 < abs(low.zenith_deg - high.zenith_deg) < 0.05        # thinner air bends less
    assert high.zenith_deg == pvlib_sun("2005-08-01", "07:00", 39.9, 116.4, "Asia/Shanghai",
                                        False, 3000.0)[0]
    for bad in (1e9, float("nan"), -600.0, "high", True):
        with pytest.raises(MaizevizError, match="altitude") as err:
            sun_at("2005-08-01", "12:00", 39.9, 116.4, "Asia/Shanghai", altitude=bad)
        assert err.value.quantity == "altitude"
