"""One clock rule for the single sun and the sun track of a period."""

import datetime as dt

import pytest

from maizeviz.errors import MaizevizError
from maizeviz.light.sources.clock import local_time, parse_clock, zone
from maizeviz.light.sources.irradiance import sun_track
from maizeviz.light.sources.sun import sun_at

DAY = dt.date(2005, 8, 1)


@pytest.mark.parametrize("clock, tz", [("12:00", "Asia/Shanghai"), ("12:00+08:00", None),
                                       ("12:00+08:00", "Asia/Shanghai"), ("04:00", None),
                                       ("04:00", "UTC")])
def test_the_same_instant_however_it_is_written(clock, tz):
    assert local_time(DAY, clock, tz) == local_time(DAY, "04:00+00:00", None)


def test_24_00_is_the_end_of_the_day():
    assert parse_clock("24:00") == (dt.timedelta(days=1), None)
    assert local_time(DAY, "24:00", "UTC") == local_time(dt.date(2005, 8, 2), "00:00", "UTC")


def test_sun_and_track_read_clocks_alike():
    """The sun at a step's middle time equals the sun the track computed there."""
    track = sun_track("2005-08-01", 39.9, 116.4, "Asia/Shanghai", step_min=60,
                      start="11:30", end="12:30")
    sun = sun_at("2005-08-01", "12:00", 39.9, 116.4, "Asia/Shanghai")
    assert sun.zenith_deg == pytest.approx(float(track.zenith_deg[0]), abs=1e-9)
    assert sun.azimuth_deg == pytest.approx(float(track.azimuth_deg[0]), abs=1e-9)


@pytest.mark.parametrize("call", [
    lambda: sun_at("2005-03-27", "02:30", 48.85, 2.35, "Europe/Paris"),
    lambda: sun_track("2005-03-27", 48.85, 2.35, "Europe/Paris", start="02:30"),
])
def test_a_skipped_wall_clock_time_is_refused_by_both(call):
    with pytest.raises(MaizevizError, match="02:30 on 2005-03-27 does not exist"):
        call()


@pytest.mark.parametrize("call", [
    lambda: sun_at("2005-08-01", "12:00+05:00", 39.9, 116.4, "Asia/Shanghai"),
    lambda: sun_track("2005-08-01", 39.9, 116.4, "Asia/Shanghai", start="06:00+05:00"),
])
def test_an_offset_other_than_the_zones_is_refused_by_both(call):
    with pytest.raises(MaizevizError, match=r"carries UTC offset \+0500 but the zone "
                                            "Asia/Shanghai is at \\+0800"):
        call()


@pytest.mark.parametrize("name", ["Asia", "Europe", "x" * 5000, "", "Nowhere/Town"])
def test_a_name_that_is_not_a_zone_is_one_line_naming_tz(name):
    # "Asia" is a folder of the zone database and 5000 characters are too long for a file
    # name: both reached the file system and escaped as OSError before
    with pytest.raises(MaizevizError, match="unknown time zone") as err:
        zone(name)
    assert err.value.quantity == "tz" and "\n" not in str(err.value)
    assert len(str(err.value)) < 200
