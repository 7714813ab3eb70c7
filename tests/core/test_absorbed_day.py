"""Absorbed light over a period (a day), with scattering: black leaves absorb the PAR the
day intercepts (within the standard error of the sunlit share sampled from each triangle), the balance closes, and the command line reports MJ/m2 and mol/m2."""

import json

import numpy as np
import pytest

import maizeviz as mv
from maizeviz.cli import main as cli_main
from maizeviz.errors import MaizevizError
from maizeviz.light.trace.optics import Optics

DAY = dict(date="2005-08-01", lat=39.9, lon=116.4, tz="Asia/Shanghai", step_min=60)


@pytest.fixture(scope="module")
def engine():
    plants = mv.read_points(mv.example_points())
    canopy = mv.build_canopy(plants, tile=(1, 1), level="16")
    return mv.LightEngine(canopy, density=0.3, heights_cm=(0.0, 100.0), periodic=True)


def intercepts_what_the_day_does(black, day) -> bool:
    """Black leaves' absorbed PAR (the direct beam sampled from each triangle) is the PAR the
    day's rays intercept, within 4 of its standard errors."""
    se = black.absorbed_leaves_error * 4.57                          # MJ -> mol of PAR
    return abs(black.absorbed_leaves_mol_m2 - day.par_intercepted_mol_m2) < 4 * se


def test_black_leaves_absorb_the_par_the_day_intercepts(engine):
    day = engine.day(**DAY)
    black = engine.absorbed_day(optics=Optics(0, 0, 0), **DAY)
    assert intercepts_what_the_day_does(black, day)
    assert black.balance.incident * 4.57 == pytest.approx(day.par_incident_mol_m2, rel=1e-12)
    assert black.balance.reflected_top == 0.0
    assert abs(black.balance.closure) < 4 * black.absorbed_leaves_error / black.balance.incident


def test_the_days_balance_closes_and_tables_add_up(engine):
    got = engine.absorbed_day(**DAY)
    b = got.balance
    assert abs(b.closure) < 0.01 and 0 < b.absorbed_leaves < b.incident
    assert got.absorbed_leaves_mol_m2 == pytest.approx(b.absorbed_leaves * 4.57)
    assert len(got.step_absorbed_leaves_w_m2) == len(got.period.step_s)
    # the steps' absorbed power integrates to the day's absorbed energy
    energy = float((got.step_absorbed_leaves_w_m2 * got.period.step_s).sum()) * 1e-6
    assert energy == pytest.approx(b.absorbed_leaves, rel=1e-9)
    plants = got.table("plant", engine.canopy)
    x0, y0, x1, y1 = got.rect
    area_m2 = (x1 - x0) * (y1 - y0) * 1e-4
    assert plants["absorbed_mj"].sum() == pytest.approx(b.absorbed_leaves * area_m2, rel=1e-6)
    assert got.table("balance")["unit"][0] == "MJ/m2"
    nir = engine.absorbed_day(band="nir", **DAY)
    assert nir.absorbed_leaves_mol_m2 is None and nir.fraction_absorbed < got.fraction_absorbed


def test_a_day_at_altitude_with_its_par_factor_absorbs_what_it_intercepts(engine):
    """absorbed_day takes the period's altitude and PAR factor as day does: black leaves
    absorb the PAR the same day intercepts, PAR and NIR together are the shortwave,
    and the higher site brings more light."""
    high = dict(DAY, altitude=1500.0, par_factor=2.0)
    day = engine.day(**high)
    black = engine.absorbed_day(optics=Optics(0, 0, 0), **high)
    assert dict(black.period.parameters)["altitude_m"] == 1500.0
    assert black.period.par_umol_per_j == 2.0
    np.testing.assert_array_equal(black.period.ghi, day.period.ghi)
    assert intercepts_what_the_day_does(black, day)
    assert black.balance.incident * 4.57 == pytest.approx(day.par_incident_mol_m2, rel=1e-12)
    nir = engine.absorbed_day(band="nir", optics=Optics(0, 0, 0, "nir"), **high)
    shortwave_mj = float(np.sum(day.period.ghi * day.period.step_s)) * 1e-6
    assert black.balance.incident + nir.balance.incident == pytest.approx(shortwave_mj,
                                                                          rel=1e-12)
    assert black.balance.incident / shortwave_mj == pytest.approx(2.0 / 4.57, rel=1e-12)
    low = engine.absorbed_day(optics=Optics(0, 0, 0), **DAY)
    assert np.sum(low.period.ghi) < np.sum(black.period.ghi)      # thinner air at 1500 m


def test_a_par_factor_beyond_the_whole_shortwave_is_refused(engine):
    with pytest.raises(MaizevizError, match="more than the whole shortwave") as info:
        engine.absorbed_day(band="nir", par_factor=5.0, **DAY)
    assert info.value.quantity == "par_factor"


def test_the_cli_reports_a_days_absorbed_par(capsys):
    args = ["light", str(mv.example_points()), "--triangles", "16", "--periodic", "--density",
            "0.3", "--day", "--date", "2005-08-01", "--lat", "39.9", "--lon", "116.4", "--tz",
            "Asia/Shanghai", "--step", "60", "--band", "par", "--json"]
    assert cli_main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["balance"]["units"] == "MJ/m2 of ground"
    a = out["absorbed"]
    assert a["absorbed_leaves_mol_m2"] == pytest.approx(out["balance"]["absorbed_leaves"] * 4.57)
    assert a["absorbed_leaves_mol_m2"] < out["period"]["par_intercepted_mol_m2"]
    assert cli_main(args[:-1] + ["--irradiance", "400"]) != 0
    err = capsys.readouterr().err
    assert "over a period the irradiance is the period's" in err and "Traceback" not in err


def test_a_perez_day_moves_the_circumsolar_light_to_the_sun(engine):
    """Perez: the same incident light, its circumsolar part traced with the sun; black leaves
    absorb what the Perez day intercepts."""
    soc = engine.absorbed_day(optics=Optics(0, 0, 0), **DAY)
    perez = engine.absorbed_day(optics=Optics(0, 0, 0), sky="perez", **DAY)
    day = engine.day(sky="perez", **DAY)
    assert perez.balance.incident == pytest.approx(soc.balance.incident, rel=1e-12)
    assert perez.balance.absorbed_leaves != soc.balance.absorbed_leaves
    assert intercepts_what_the_day_does(perez, day)


@pytest.mark.parametrize("extra, says", [
    (["--seed", "-1"], "the random seed must be a whole number"),
    (["--depth", "-1"], "the scattering depth"),
    (["--optics-table", ""], "optics table"),
])
def test_scattering_options_alone_turn_it_on_and_are_checked(capsys, extra, says):
    args = ["light", str(mv.example_points()), "--triangles", "8", "--density", "0.3",
            "--sun-zenith", "30", "--sun-azimuth", "150", *extra]
    assert cli_main(args) != 0
    err = capsys.readouterr().err
    assert says in err and "internal error" not in err and "Traceback" not in err


def test_depth_alone_asks_for_absorbed_light(capsys):
    args = ["light", str(mv.example_points()), "--triangles", "8", "--density", "0.3",
            "--sun-zenith", "30", "--sun-azimuth", "150", "--depth", "4", "--json"]
    assert cli_main(args) == 0
    assert json.loads(capsys.readouterr().out)["absorbed"]["depth"] == 4


def _weather_with_par(path, par_over_shortwave: float):
    """A day of hourly rows whose PAR column is ``par_over_shortwave`` umol per J of the ghi
    (not the default 2.19) and varies from hour to hour as a sensor's would."""
    rows = ["time,ghi,dhi,par"]
    for hour in range(6, 19):
        ghi = 900.0 * np.sin(np.pi * (hour - 5.5) / 14.0) ** 2
        par = ghi * par_over_shortwave * (1.0 + 0.2 * np.cos(hour))
        rows.append(f"2005-08-01T{hour:02d}:00+08:00,{ghi:.1f},{0.35 * ghi:.1f},{par:.1f}")
    path.write_text("\n".join(rows) + "\n")
    return path


def test_black_leaves_absorb_a_weather_files_measured_par(engine, tmp_path):
    """Over a weather file with a PAR column, the absorbed period takes the measured PAR as
    the intercepted period does: black leaves absorb the PAR the same period intercepts
    (within 4 standard errors), not the shortwave times the PAR share (30 % above here)."""
    from maizeviz.light.sources.irradiance import read_weather, weather_period

    weather = read_weather(_weather_with_par(tmp_path / "w.csv", 2.1936 * 1.3))
    period = weather_period(weather, 39.9, 116.4)
    assert period.par_source == "measured"
    day = engine.day(period)
    black = engine.absorbed_day(period, optics=Optics(0, 0, 0))
    assert black.balance.incident * 4.57 == pytest.approx(day.par_incident_mol_m2, rel=1e-12)
    assert day.par_incident_mol_m2 == pytest.approx(period.par_mol_m2, rel=1e-12)
    assert period.par_mol_m2 > 1.2 * period.shortwave_mj_m2 * period.par_umol_per_j
    assert intercepts_what_the_day_does(black, day)
    # the PAR left out of the shortwave's share: NIR keeps the shortwave's own share
    nir = engine.absorbed_day(period, band="nir", optics=Optics(0, 0, 0, "nir"))
    assert nir.balance.incident == pytest.approx(
        period.shortwave_mj_m2 * (1 - period.par_umol_per_j / 4.57), rel=1e-12)


def test_the_cli_says_which_par_a_period_used(capsys, tmp_path):
    weather = _weather_with_par(tmp_path / "w.csv", 2.1936 * 1.3)
    args = ["light", str(mv.example_points()), "--triangles", "8", "--periodic", "--density",
            "0.2", "--weather", str(weather), "--lat", "39.9", "--lon", "116.4", "--band",
            "par", "--json"]
    assert cli_main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["period"]["par_source"] == "measured"
    assert out["absorbed"]["par_source"] == "measured"
    assert out["absorbed"]["absorbed_leaves_mol_m2"] < out["period"]["par_incident_mol_m2"]
    assert cli_main(args[:-1]) == 0
    assert "PAR measured (the weather file's par column)" in capsys.readouterr().out
