"""Sun over a period, clear-sky and measured irradiance, PAR totals, weather-file refusals."""

import datetime as dt
import math

import numpy as np
import pandas as pd
import pvlib
import pytest

from maizeviz.errors import MaizevizError
from maizeviz.io.weather_csv import MAX_IRRADIANCE_W_M2
from maizeviz.light.sources.irradiance import (
    DEFAULT_PAR_UMOL_PER_J,
    WeatherFileError,
    clear_sky,
    clear_sky_period,
    read_weather,
    sun_track,
    weather_period,
)
from maizeviz.light.sources.sun import sun_at

BEIJING = dict(lat=39.9, lon=116.4, tz="Asia/Shanghai")
DAY = "2005-08-01"
# Beijing, 2005-08-01, Ineichen clear sky, Linke turbidity 3, altitude 0 m (measured here:
# 28.1051 MJ/m2 at 30-min steps, 28.1053 at 10 and 1 min; PAR 61.651 mol/m2 at 2.1936 umol/J)
BEIJING_MJ, BEIJING_MJ_TOL = 28.1, 0.1
BEIJING_PAR, BEIJING_PAR_TOL = 61.65, 0.2


def one_line(err) -> str:
    text = str(err.value)
    assert "\n" not in text and "--" not in text, text
    return text


# --------------------------------------------------------------------------- sun track


def test_a_step_centred_on_noon_has_the_sun_of_sun_at():
    track = sun_track(DAY, **BEIJING, step_min=2, start="11:59", end="12:01")
    assert track.n_steps == 1 and track.step_s[0] == 120.0
    assert track.times[0] == pd.Timestamp("2005-08-01 12:00", tz="Asia/Shanghai")
    sun = sun_at(DAY, "12:00", 39.9, 116.4, "Asia/Shanghai")
    assert track.zenith_deg[0] == pytest.approx(sun.zenith_deg, abs=1e-9)
    assert track.azimuth_deg[0] == pytest.approx(sun.azimuth_deg, abs=1e-9)
    assert track.zenith_deg[0] == pytest.approx(22.35, abs=0.01)   # known noon zenith


def test_day_track_keeps_daylight_steps_and_the_period_bounds():
    track = sun_track(DAY, **BEIJING, step_min=30)
    assert track.start == pd.Timestamp("2005-08-01 00:00", tz="Asia/Shanghai")
    assert track.end == pd.Timestamp("2005-08-02 00:00", tz="Asia/Shanghai")
    assert track.period_s == 86400
    assert np.all(track.zenith_deg < 90) and np.all(track.step_s == 1800)
    assert track.times.tz is not None
    # steps whose middle lies between sunrise and sunset (pvlib SPA) and no other
    midnight = pd.DatetimeIndex([pd.Timestamp(DAY, tz="Asia/Shanghai")])
    rs = pvlib.solarposition.sun_rise_set_transit_spa(midnight, 39.9, 116.4)
    mids = pd.Timestamp(DAY, tz="Asia/Shanghai") + pd.to_timedelta(np.arange(48) * 30 + 15,
                                                                   unit="min")
    daylight = (mids > rs["sunrise"].iloc[0]) & (mids < rs["sunset"].iloc[0])
    assert track.n_steps == int(daylight.sum()) == 29
    assert list(track.times) == list(mids[daylight])


def test_last_step_is_shorter_when_the_period_is_not_a_whole_number_of_steps():
    track = sun_track(DAY, **BEIJING, step_min=30, start="06:00", end="07:10")
    assert list(track.step_s) == [1800.0, 1800.0, 600.0]
    assert [t.strftime("%H:%M") for t in track.times] == ["06:15", "06:45", "07:05"]


def test_daylight_saving_days_are_23_and_25_hours_long():
    assert sun_track("2005-03-27", 48.85, 2.35, "Europe/Paris").period_s == 23 * 3600
    assert sun_track("2005-10-30", 48.85, 2.35, "Europe/Paris").period_s == 25 * 3600


def test_polar_night_has_zero_steps_and_says_so_once():
    track = sun_track("2005-12-15", 80.0, 0.0, "UTC")
    assert track.n_steps == 0 and track.sun_never_up
    assert len(track.notes) == 1 and "below the horizon" in track.notes[0]
    period = clear_sky(track)
    assert period.n_steps == 0 and period.sun_never_up
    assert period.shortwave_mj_m2 == 0.0 and period.par_mol_m2 == 0.0
    assert period.notes == track.notes                     # said once, not repeated
    assert period.start == track.start and period.end == track.end
    assert len(period.daily_totals()) == 0


def test_polar_day_keeps_every_step():
    track = sun_track("2005-06-21", 80.0, 0.0, "UTC", step_min=30)
    assert track.n_steps == 48 and track.notes == ()


@pytest.mark.parametrize("kwargs, message", [
    (dict(step_min=0), "the time step must be > 0 min, got 0"),
    (dict(step_min=-5), "the time step must be > 0 min, got -5"),
    (dict(step_min=float("nan")), "the time step must be > 0 min, got nan"),
    (dict(step_min=90, start="06:00", end="07:00"),
     "the time step (90 min) is longer than the period (1 h)"),
    (dict(start="18:00", end="06:00"), "the period must end after it starts, got 18:00 to 06:00"),
    (dict(start="6h"), "the start time must be HH:MM (local clock), got '6h'"),
    (dict(start="06:00+05:00"),                   # one clock rule: the offset must be the zone's
     "the start time 06:00+05:00 carries UTC offset +0500 but the zone Asia/Shanghai is at "
     "+0800 on 2005-08-01"),
    (dict(step_min=0.001), "a time step of 0.001 min gives 1440000 steps, more than 1000000"),
    (dict(date="2005-02-30"), "the date must be YYYY-MM-DD, got '2005-02-30'"),
    (dict(tz="Mars/Olympus"), "unknown time zone 'Mars/Olympus'"),
    (dict(lat=95), "latitude must be in [-90, 90] and longitude in [-180, 360], got 95.0, 116.4"),
])
def test_bad_periods_are_refused_in_one_line(kwargs, message):
    args = dict(date=DAY, **BEIJING)
    args.update(kwargs)
    with pytest.raises(MaizevizError) as err:
        sun_track(**args)
    assert one_line(err).startswith(message)


def test_a_clock_time_skipped_by_daylight_saving_is_refused():
    with pytest.raises(MaizevizError) as err:
        sun_track("2005-03-27", 48.85, 2.35, "Europe/Paris", start="02:30")
    assert "02:30 on 2005-03-27 does not exist or occurs twice in Europe/Paris" in one_line(err)


# --------------------------------------------------------------------------- clear sky


def test_beijing_clear_day_shortwave_and_par():
    totals = {}
    for step in (30, 10, 1):
        p = clear_sky_period(DAY, **BEIJING, step_min=step, linke_turbidity=3)
        totals[step] = p.shortwave_mj_m2
        assert p.shortwave_mj_m2 == pytest.approx(BEIJING_MJ, abs=BEIJING_MJ_TOL)
        assert p.par_mol_m2 == pytest.approx(BEIJING_PAR, abs=BEIJING_PAR_TOL)
        assert 0.1 < p.diffuse_mj_m2 / p.shortwave_mj_m2 < 0.2      # clear: mostly direct
    # the midpoint rule has converged at 30 min: measured 0.0008 % from 1 min
    assert totals[30] == pytest.approx(totals[1], rel=1e-4)
    assert totals[10] == pytest.approx(totals[1], rel=2e-5)


def test_clear_day_is_a_plausible_share_of_the_extraterrestrial_day():
    # daily extraterrestrial irradiation on the horizontal (Duffie & Beckman eq. 1.10.3)
    n = dt.date(2005, 8, 1).timetuple().tm_yday
    decl = math.radians(23.45 * math.sin(math.radians(360 * (284 + n) / 365)))
    lat = math.radians(39.9)
    ws = math.acos(-math.tan(lat) * math.tan(decl))
    e0 = 1 + 0.033 * math.cos(math.radians(360 * n / 365))
    h0 = 86400 / math.pi * 1367 * e0 * (math.cos(lat) * math.cos(decl) * math.sin(ws)
                                        + ws * math.sin(lat) * math.sin(decl)) / 1e6
    ratio = clear_sky_period(DAY, **BEIJING).shortwave_mj_m2 / h0
    assert 0.65 < ratio < 0.78


def test_period_integral_is_the_sum_of_its_steps():
    day = clear_sky_period(DAY, **BEIJING, step_min=30)
    assert day.par_mol_m2 == math.fsum(day.step_par_mol_m2)
    assert day.shortwave_mj_m2 == math.fsum(day.ghi * day.step_s) * 1e-6
    assert day.direct_par_mol_m2 + day.diffuse_par_mol_m2 == pytest.approx(day.par_mol_m2,
                                                                             rel=1e-13)
    morning = clear_sky_period(DAY, **BEIJING, step_min=30, end="12:00")
    afternoon = clear_sky_period(DAY, **BEIJING, step_min=30, start="12:00")
    assert morning.n_steps + afternoon.n_steps == day.n_steps
    assert morning.par_mol_m2 + afternoon.par_mol_m2 == pytest.approx(day.par_mol_m2,
                                                                       rel=1e-13)
    daily = day.daily_totals()
    assert list(daily.index) == [dt.date(2005, 8, 1)]
    assert daily["par_mol_m2"].iloc[0] == pytest.approx(day.par_mol_m2, rel=1e-13)
    assert daily["steps"].iloc[0] == day.n_steps


def test_clear_sky_components_are_consistent():
    p = clear_sky_period(DAY, **BEIJING, step_min=10)
    cosz = np.cos(np.radians(p.zenith_deg))
    assert p.direct_horizontal == pytest.approx(p.dni * cosz, rel=1e-12, abs=1e-9)
    assert p.direct_horizontal + p.dhi == pytest.approx(p.ghi, rel=1e-12, abs=1e-9)
    assert np.all(p.dhi >= 0) and np.all(p.dni >= 0) and np.all(p.dni < 1100)
    assert p.ghi.max() == pytest.approx(p.ghi[np.argmin(p.zenith_deg)])
    assert p.par_umol_m2_s.max() == pytest.approx(p.ghi.max() * DEFAULT_PAR_UMOL_PER_J)
    assert [round(s.zenith_deg, 9) for s in p.suns()] == list(np.round(p.zenith_deg, 9))


def test_clear_sky_states_its_model_and_parameters():
    p = clear_sky_period(DAY, **BEIJING, linke_turbidity=4.5, altitude=50)
    assert "Ineichen" in p.source and "Linke turbidity 4.5" in p.source
    assert "altitude 50 m" in p.source
    assert p.parameters["model"] == "ineichen"
    assert p.parameters["linke_turbidity"] == 4.5 and p.parameters["altitude_m"] == 50.0
    with pytest.raises(TypeError):
        p.parameters["model"] = "haurwitz"


def test_turbidity_and_altitude_act_in_the_expected_direction():
    base = clear_sky_period(DAY, **BEIJING)
    hazy = clear_sky_period(DAY, **BEIJING, linke_turbidity=6)
    high = clear_sky_period(DAY, **BEIJING, altitude=2000)
    assert hazy.shortwave_mj_m2 < base.shortwave_mj_m2 < high.shortwave_mj_m2
    assert hazy.diffuse_mj_m2 / hazy.shortwave_mj_m2 > base.diffuse_mj_m2 / base.shortwave_mj_m2


def test_par_factor_is_stated_and_overridable():
    assert DEFAULT_PAR_UMOL_PER_J == pytest.approx(0.48 * 4.57)
    p = clear_sky_period(DAY, **BEIJING)
    assert p.par_mol_m2 == pytest.approx(p.shortwave_mj_m2 * 0.48 * 4.57, rel=1e-12)
    q = p.with_par_factor(2.0)
    assert q.par_mol_m2 == pytest.approx(p.shortwave_mj_m2 * 2.0, rel=1e-12)
    assert q.shortwave_mj_m2 == p.shortwave_mj_m2
    for bad in (0, -1, float("nan"), 50):
        with pytest.raises(MaizevizError) as err:
            p.with_par_factor(bad)
        assert one_line(err).startswith("PAR conversion factor must be in (0, 10]")


@pytest.mark.parametrize("bad", [0, 0.5, 12, float("nan"), "3"])
def test_bad_linke_turbidity_is_refused(bad):
    with pytest.raises(MaizevizError) as err:
        clear_sky_period(DAY, **BEIJING, linke_turbidity=bad)
    assert one_line(err).startswith("Linke turbidity must be a number in [1, 10]")


# --------------------------------------------------------------------------- weather file


def clear_day_rows(step_min=30):
    """Full-day ghi/dni/dhi rows at step middles from pvlib directly (night rows zero)."""
    mids = pd.Timestamp(DAY, tz="Asia/Shanghai") + pd.to_timedelta(
        np.arange(0, 1440, step_min) + step_min / 2, unit="min")
    site = pvlib.location.Location(39.9, 116.4, tz="Asia/Shanghai", altitude=0)
    cs = site.get_clearsky(mids, model="ineichen", linke_turbidity=3)
    return mids, cs


def weather_text(mids, cs, columns=("ghi", "dni", "dhi"), fmt=None):
    fmt = fmt or (lambda t: t.isoformat())
    lines = ["time," + ",".join(columns)]
    for t, (_, row) in zip(mids, cs.iterrows(), strict=True):
        lines.append(fmt(t) + "," + ",".join(f"{row[c]:.6f}" for c in columns))
    return "\n".join(lines) + "\n"


def test_weather_file_with_all_columns_reproduces_the_clear_day(write_csv):
    mids, cs = clear_day_rows()
    path = write_csv(weather_text(mids, cs), "beijing.csv")
    w = read_weather(path)
    assert len(w.times) == 48 and np.all(w.step_s == 1800)
    assert w.start == pd.Timestamp(DAY, tz="Asia/Shanghai")
    assert w.end == pd.Timestamp("2005-08-02", tz="Asia/Shanghai")
    p = weather_period(w, 39.9, 116.4)
    clear = clear_sky_period(DAY, **BEIJING)
    assert p.n_steps == clear.n_steps
    assert p.shortwave_mj_m2 == pytest.approx(clear.shortwave_mj_m2, rel=1e-7)
    assert p.diffuse_mj_m2 == pytest.approx(clear.diffuse_mj_m2, rel=1e-6)
    assert p.par_mol_m2 == math.fsum(p.step_par_mol_m2)
    assert "beijing.csv" in p.source and p.parameters["decomposition"] is None


def test_ghi_alone_is_split_by_erbs_and_keeps_its_total(write_csv):
    mids, cs = clear_day_rows()
    full = weather_period(read_weather(write_csv(weather_text(mids, cs), "a.csv")), 39.9, 116.4)
    p = weather_period(read_weather(write_csv(weather_text(mids, cs, ("ghi",)), "b.csv")),
                       39.9, 116.4)
    assert p.shortwave_mj_m2 == pytest.approx(full.shortwave_mj_m2, rel=1e-12)
    assert 0.1 < p.diffuse_mj_m2 / p.shortwave_mj_m2 < 0.35
    assert p.direct_horizontal + p.dhi == pytest.approx(p.ghi, rel=1e-12)
    assert "Erbs" in p.source and p.parameters["decomposition"] == "erbs"
    # the split at noon is pvlib's Erbs for that ghi, geometric zenith and day of year
    k = int(np.argmin(p.zenith_deg))
    pos = pvlib.solarposition.get_solarposition(p.times[k:k + 1], 39.9, 116.4)
    erbs = pvlib.irradiance.erbs(p.ghi[k:k + 1], pos["zenith"].to_numpy(), p.times[k:k + 1])
    assert p.dhi[k] == pytest.approx(float(np.asarray(erbs["dhi"])[0]), rel=1e-12)


def test_dni_alone_gives_the_direct_part(write_csv):
    mids, cs = clear_day_rows()
    p = weather_period(read_weather(write_csv(weather_text(mids, cs, ("ghi", "dni")))),
                       39.9, 116.4)
    full = clear_sky_period(DAY, **BEIJING)
    assert p.direct_mj_m2 == pytest.approx(full.direct_mj_m2, rel=1e-6)


def test_naive_times_with_a_zone_equal_offset_times(write_csv):
    mids, cs = clear_day_rows()
    naive = read_weather(write_csv(weather_text(mids, cs, fmt=lambda t: t.strftime(
        "%Y-%m-%d %H:%M")), "naive.csv"), tz="Asia/Shanghai")
    utc = read_weather(write_csv(weather_text(mids, cs, fmt=lambda t: t.tz_convert(
        "UTC").strftime("%Y-%m-%dT%H:%M:%SZ")), "utc.csv"))
    offset = read_weather(write_csv(weather_text(mids, cs), "offset.csv"))
    assert list(naive.times) == list(offset.times) == list(utc.times)
    assert str(naive.times.tz) == "Asia/Shanghai"


def test_time_label_moves_the_interval(write_csv):
    text = ("# station 54511, hourly means\n\nTIME,GHI\n"
            "2005-08-01T10:00+08:00,500\n2005-08-01T11:00+08:00,600\n"
            "2005-08-01T12:00+08:00,650\n")
    path = write_csv(text)
    centre, start, end = (read_weather(path, label=k) for k in ("center", "start", "end"))
    assert [t.strftime("%H:%M") for t in centre.times] == ["10:00", "11:00", "12:00"]
    assert [t.strftime("%H:%M") for t in start.times] == ["10:30", "11:30", "12:30"]
    assert [t.strftime("%H:%M") for t in end.times] == ["09:30", "10:30", "11:30"]
    assert end.start.strftime("%H:%M") == "09:00" and end.end.strftime("%H:%M") == "12:00"
    p = weather_period(start, 39.9, 116.4)
    assert p.shortwave_mj_m2 == pytest.approx((500 + 600 + 650) * 3600 / 1e6, rel=1e-12)


def test_irregular_steps_up_to_the_gap_rule_are_accepted(write_csv):
    text = ("time,ghi\n2005-08-01T10:00+08:00,500\n2005-08-01T11:00+08:00,600\n"
            "2005-08-01T12:30+08:00,650\n2005-08-01T13:30+08:00,640\n")   # 90 min = 1.5 x 1 h
    w = read_weather(write_csv(text))
    assert list(w.step_s) == [3600.0, 4500.0, 4500.0, 3600.0]
    assert math.fsum(w.step_s) == (w.end - w.start).total_seconds()


def test_night_rows_are_dropped_and_their_energy_stated(write_csv):
    text = ("time,ghi\n2005-08-01T02:00+08:00,3\n2005-08-01T03:00+08:00,2\n"
            "2005-08-01T12:00+08:00,800\n")
    with pytest.raises(WeatherFileError, match="gap"):
        read_weather(write_csv(text))
    # hourly rows 02:00 ... 08:00; the sun rises at 05:10, so the 05:00 row is still night
    text = "time,ghi\n" + "".join(f"2005-08-01T{h:02d}:00+08:00,{3 if h < 6 else 400}\n"
                                  for h in range(2, 9))
    p = weather_period(read_weather(write_csv(text)), 39.9, 116.4)
    assert p.n_steps == 3
    assert len(p.notes) == 1 and "4 rows" in p.notes[0] and "43.2 kJ/m2" in p.notes[0]


def test_weather_in_polar_night_says_so_once(write_csv):
    text = "time,ghi\n" + "".join(f"2005-12-15T{h:02d}:00Z,0\n" for h in range(24))
    p = weather_period(read_weather(write_csv(text)), 80.0, 0.0)
    assert p.n_steps == 0 and len(p.notes) == 1 and "below the horizon" in p.notes[0]


GOOD_HEAD = "time,ghi,dhi\n"
T = ["2005-08-01T10:00+08:00", "2005-08-01T11:00+08:00", "2005-08-01T12:00+08:00",
     "2005-08-01T13:00+08:00"]


def rows(*values):
    return "".join(f"{t},{v}\n" for t, v in zip(T, values, strict=False))


@pytest.mark.parametrize("text, expect", [
    ("", "the weather file is empty"),
    ("# only a comment\n\n", "the weather file is empty (no header, no rows)"),
    ("time,ghi\n", "the weather file has a header but no data rows"),
    ("time,ghi\n2005-08-01T10:00+08:00,500\n", "one data row is not enough to know the time step"),
    ("time,dhi\n" + rows(1, 2), "line 1: missing column 'ghi'"),
    ("ghi,dhi\n1,2\n3,4\n", "line 1: missing column 'time'"),
    ("time,ghi,temp\n" + "".join(f"{t},5,20\n" for t in T),
     "line 1: unknown column 'temp' (known columns: time, ghi, dni, dhi"),
    ("time,ghi,GHI\n" + rows("1,1", "2,2"), "line 1: column 'ghi' appears twice"),
    ("time,ghi,\n" + rows("1,", "2,"), "line 1: column 3 of the header has no name"),
    ("time,ghi\n2005-08-01T10:00,500\n2005-08-01T11:00,600\n",
     "line 2, column time: '2005-08-01T10:00' has no time zone"),
    ("time,ghi\n2005-08-01,500\n2005-08-02,600\n",
     "line 2, column time: '2005-08-01' has no time zone"),
    ("time,ghi\n2005-08-01T10:00+08:00,500\nnoon+08:00,600\n",
     "line 3, column time: 'noon+08:00' has no time zone"),
    ("time,ghi\n2005-08-01T10:00+08:00,500\n2005-08-41T11:00+08:00,600\n",
     "line 3, column time: cannot read '2005-08-41T11:00+08:00' as an ISO 8601 time"),
    ("time,ghi\n" + "".join(f"{t},5\n" for t in [T[0], T[2], T[1]]),
     "line 4, column time: '2005-08-01T11:00+08:00' is earlier than line 3"),
    ("time,ghi\n" + "".join(f"{t},5\n" for t in [T[0], T[1], T[1], T[2]]),
     "line 4, column time: '2005-08-01T11:00+08:00' repeats the time of line 3"),
    ("time,ghi\n" + "".join(f"{t},5\n" for t in [T[0], T[1], T[2], "2005-08-01T14:01+08:00"]),
     "line 5, column time: a gap of 121 min after line 4 ('2005-08-01T12:00+08:00'), "
     "more than 1.5 x the usual step of 1 h"),
    ("time,ghi\n" + rows(500, "nan", 600), "line 3 (2005-08-01T11:00+08:00), column ghi: "
                                           "missing value ('nan')"),
    ("time,ghi\n" + rows(500, "", 600), "line 3 (2005-08-01T11:00+08:00), column ghi: "
                                        "missing value"),
    (GOOD_HEAD + rows("500,20", "600,-3"), "line 3 (2005-08-01T11:00+08:00), column dhi: "
                                           "negative irradiance -3 W/m2"),
    ("time,ghi\n" + rows(500, "abc"), "line 3 (2005-08-01T11:00+08:00), column ghi: "
                                      "'abc' is not a number"),
    ("time,ghi\n" + rows(500, "inf"), "line 3 (2005-08-01T11:00+08:00), column ghi: "
                                      "'inf' is not a finite number"),
    ("time,ghi\n" + rows(500, 360000), "line 3 (2005-08-01T11:00+08:00), column ghi: 360000 "
                                       f"W/m2 is more than {MAX_IRRADIANCE_W_M2:g} W/m2; "
                                       "is the unit W/m2?"),
    (GOOD_HEAD + rows("500,20", "600"), "line 3: 2 values for 3 columns (time, ghi, dhi)"),
])
def test_bad_weather_files_are_refused_in_one_line(write_csv, text, expect):
    path = write_csv(text, "weather.csv")
    with pytest.raises(WeatherFileError) as err:
        read_weather(path)
    message = one_line(err)
    assert message.startswith(f"{path}")
    assert expect in message


def test_missing_binary_and_oversized_weather_files_are_refused(tmp_path, write_csv):
    with pytest.raises(WeatherFileError) as err:
        read_weather(tmp_path / "nowhere.csv")
    assert one_line(err) == f"{tmp_path / 'nowhere.csv'}: no such weather file"
    binary = tmp_path / "w.csv"
    binary.write_bytes(b"time,ghi\n\x00\x01\x02")
    with pytest.raises(WeatherFileError, match="binary content"):
        read_weather(binary)
    big = write_csv("time,ghi\n" + rows(1, 2, 3, 4) * 20)
    with pytest.raises(WeatherFileError) as err:
        read_weather(big, max_bytes=1024)
    assert "more than the 1,024 bytes limit for a weather file" in one_line(err)
    with pytest.raises(WeatherFileError, match="is a folder"):
        read_weather(tmp_path)


def test_weather_zone_label_and_dst_refusals(write_csv):
    with pytest.raises(MaizevizError) as err:
        read_weather(write_csv("time,ghi\n" + rows(1, 2)), tz="Nowhere/City")
    assert one_line(err).startswith("unknown time zone 'Nowhere/City'")
    with pytest.raises(MaizevizError) as err:
        read_weather(write_csv("time,ghi\n" + rows(1, 2)), label="middle")
    assert one_line(err).startswith("unknown weather time label 'middle'")
    skipped = "time,ghi\n2005-03-27 01:30,0\n2005-03-27 02:30,0\n2005-03-27 03:30,0\n"
    path = write_csv(skipped)
    with pytest.raises(WeatherFileError) as err:
        read_weather(path, tz="Europe/Paris")
    assert one_line(err).startswith(f"{path}, line 3, column time: '2005-03-27 02:30' does not "
                                    f"exist or occurs twice in Europe/Paris")
