"""Light over a period through real Embree: the period is the sum of its steps, each step is the
sun traced alone, the sky is traced once, polar night, cancellation, and the command line with
every bad input said in one line."""

import json
import math

import numpy as np
import pytest
from test_light_sky import random_leaves

from maizeviz.cli import EXIT_FAIL, EXIT_OK, main
from maizeviz.errors import MaizevizError
from maizeviz.light.scene.embree_scenes import light_scene
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.sources.irradiance import clear_sky_period
from maizeviz.light.sources.sky import make_sky
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.beam import trace_light
from maizeviz.light.trace.directions import trace_period, trace_sky

BEIJING = dict(lat=39.9, lon=116.4, tz="Asia/Shanghai")
HEIGHTS = (0.0, 60.0, 200.0)


@pytest.fixture(scope="module")
def canopy():
    return random_leaves(2.0, 5.0, seed=11, spherical=True, side=100.0)


@pytest.fixture(scope="module")
def scene(canopy):
    return light_scene(canopy, periodic=True)


def sampling(threads=2):
    return Sampling(HEIGHTS, 0.5, (0, 0, 100, 100), True, threads)


def test_the_period_is_the_sum_of_its_steps_and_each_step_is_the_sun_alone(canopy, scene):
    period = clear_sky_period("2005-08-01", step_min=120, **BEIJING)
    sky = make_sky("soc", 16)
    pl = trace_period(canopy, period, sampling(), sky, scene=scene)
    n = period.n_steps
    assert n == 7 and pl.step_transmission.shape == (n, 3)
    # totals are the sums of the steps
    assert pl.par_incident_mol_m2 == math.fsum(pl.step_incident_mol_m2)
    assert pl.par_incident_mol_m2 == pytest.approx(period.par_mol_m2, rel=1e-12)
    assert pl.par_intercepted_mol_m2 == math.fsum(pl.step_intercepted_mol_m2)
    for k in range(3):
        assert pl.par_transmitted_mol_m2[k] == math.fsum(pl.step_transmitted_mol_m2[:, k])
    # each step: the direct part is the sun traced alone, the diffuse part the sky traced once
    for j in (0, 3, 6):
        sun = Sun(period.zenith_deg[j], period.azimuth_deg[j])
        one = trace_light(canopy, LightRequest(sun, Sampling(HEIGHTS, 0.5, (0, 0, 100, 100), True)),
                          scene=scene)
        assert np.array_equal(pl.step_transmission[j], one.transmission)
        assert pl.step_intercepted_fraction[j] == pytest.approx(
            one.sunlit_intercepted_fraction, abs=1e-12)
        expect = (period.step_direct_par_mol_m2[j] * one.transmission
                  + period.step_diffuse_par_mol_m2[j] * pl.sky.transmission)
        assert pl.step_transmitted_mol_m2[j] == pytest.approx(expect, rel=1e-12)
    alone = trace_sky(canopy, sky, sampling(), scene=scene)
    assert np.array_equal(alone.transmission, pl.sky.transmission)
    # light is conserved without stalks: reaching the ground or intercepted by a leaf
    assert pl.par_transmitted_mol_m2[0] + pl.par_intercepted_mol_m2 == pytest.approx(
        pl.par_incident_mol_m2, rel=1e-12)
    area_m2 = 1.0
    assert pl.triangle_mol.sum() == pytest.approx(pl.par_intercepted_mol_m2 * area_m2, rel=1e-12)
    assert pl.transmission_by_height[2] == 1.0 and pl.fraction_intercepted > 0.5


def test_two_halves_of_a_day_add_up_to_the_day_with_the_sky_reused(canopy, scene):
    sky = trace_sky(canopy, make_sky("uoc", 6), sampling(), scene=scene)
    day = trace_period(canopy, clear_sky_period("2005-08-01", step_min=60, **BEIJING),
                       sampling(), sky, scene=scene)
    seen = []
    am = trace_period(canopy, clear_sky_period("2005-08-01", step_min=60, end="12:00",
                                               **BEIJING), sampling(), sky, scene=scene,
                      progress=lambda d, t: seen.append((d, t)))
    pm = trace_period(canopy, clear_sky_period("2005-08-01", step_min=60, start="12:00",
                                               **BEIJING), sampling(), sky, scene=scene)
    assert seen[-1] == (am.n_steps, am.n_steps)          # the sky was not traced again
    assert am.n_steps + pm.n_steps == day.n_steps
    for name in ("par_incident_mol_m2", "par_intercepted_mol_m2"):
        assert getattr(am, name) + getattr(pm, name) == pytest.approx(getattr(day, name),
                                                                     rel=1e-12)
    assert am.triangle_mol + pm.triangle_mol == pytest.approx(day.triangle_mol, rel=1e-9)
    with pytest.raises(MaizevizError, match="other heights"):
        trace_period(canopy, clear_sky_period("2005-08-01", **BEIJING),
                     Sampling((0.0,), 0.5, (0, 0, 100, 100), True, 1), sky, scene=scene)


def test_polar_night_traces_nothing_and_says_so_once(canopy, scene):
    period = clear_sky_period("2005-12-21", lat=80.0, lon=15.0, tz="Europe/Oslo")
    calls = []
    pl = trace_period(canopy, period, sampling(), progress=lambda d, t: calls.append(d),
                      scene=scene)
    assert pl.n_steps == 0 and not calls
    assert pl.par_incident_mol_m2 == pl.par_intercepted_mol_m2 == 0.0
    assert list(pl.par_transmitted_mol_m2) == [0.0, 0.0, 0.0]
    assert pl.fraction_intercepted is None
    assert sum("below the horizon" in w for w in pl.warnings) == 1


def test_a_period_is_cancelled_from_its_progress_callback(canopy, scene):
    period = clear_sky_period("2005-08-01", step_min=60, **BEIJING)
    for threads in (1, 2):
        calls = []
        with pytest.raises(InterruptedError):
            trace_period(canopy, period, sampling(threads), make_sky("soc", 6), scene=scene,
                         progress=lambda d, t, calls=calls: calls.append((d, t)) or d < 4)
        assert calls[-1] == (4, 6 + period.n_steps)


# --------------------------------------------------------------------------- command line


@pytest.fixture(scope="module")
def block(tmp_path_factory):
    path = tmp_path_factory.mktemp("light") / "block.csv"
    assert main(["synth", "--plants", "2x2", "--seed", "5", "--out", str(path)]) == EXIT_OK
    return str(path)


FAST = ["--tile", "3x3", "--block", "2x2", "--triangles", "4", "--density", "0.1",
        "--heights", "0,100,300", "--periodic"]
PLACE = ["--date", "2005-08-01", "--lat", "39.9", "--lon", "116.4", "--tz", "Asia/Shanghai"]
DAY = PLACE + ["--day", "--step", "120", "--sky-directions", "6"]


def test_cli_day_prints_the_period_and_writes_every_file(block, tmp_path, capsys):
    out = tmp_path / "out"
    args = ["light", block, *FAST, *DAY, "--json", "--steps", str(out / "steps.csv"),
            "--plots", str(out / "plots"), "--leaf-light", str(out / "leaf.csv"),
            "--plant-light", str(out / "plant.csv"), "--heatmaps", str(out / "maps"),
            "--verbose"]
    out.mkdir()
    code = main(args)
    cap = capsys.readouterr()
    assert code == EXIT_OK, cap.err
    assert "weights sum to 1.0" in cap.err and "Linke turbidity 3" in cap.err
    data = json.loads(cap.out)
    p = data["period"]
    assert p["steps"] == 7 and p["clear_sky_model"]["linke_turbidity"] == 3.0
    assert 55 < p["par_incident_mol_m2"] < 68                  # clear Beijing day, early August
    assert 0.5 < p["fraction_intercepted"] < 1
    tb = p["transmission_by_height"]
    assert tb["heights_cm"] == [0.0, 100.0, 300.0] and tb["fraction"][2] == 1.0
    # leaves, stalks (on by default) and the ground take the whole of it
    stalks = data["stalks"]["par_intercepted_mol_m2"]
    assert stalks > 0
    assert p["par_intercepted_mol_m2"] + stalks + tb["par_mol_m2"][0] == pytest.approx(
        p["par_incident_mol_m2"], rel=1e-9)
    d = data["diffuse"]
    assert d["directions"] == 6 and math.fsum(d["weights"]) == 1.0
    assert d["transmission"][0] < d["transmission"][1] <= d["transmission"][2] == 1.0
    x0, y0, x1, y1 = data["rect_cm"]
    assert (x1 - x0, y1 - y0) == pytest.approx((120, 60), abs=1)      # the 2 x 2 block's tile
    assert data["sun"] is None and data["rays"] == pytest.approx(720, abs=10)
    steps = (out / "steps.csv").read_text().splitlines()
    assert len(steps) == 8 and steps[0].startswith("time,step_s,zenith_deg,azimuth_deg")
    png = out / "plots" / "day_4_triangles.png"
    assert png.stat().st_size > 20_000
    leaf = (out / "leaf.csv").read_text().splitlines()
    assert "par_intercepted_mol" in leaf[0] and "par_mol_per_m2_leaf" in leaf[0]
    plant = (out / "plant.csv").read_text().splitlines()
    # the 36 plants of the periodic tiling are reported as the 4 of the sample tile
    assert len(plant) == 5
    head = plant[0].split(",")
    total = sum(float(r.split(",")[head.index("par_intercepted_mol")]) for r in plant[1:])
    area_m2 = data["rect_cm"][2] - data["rect_cm"][0]
    area_m2 *= (data["rect_cm"][3] - data["rect_cm"][1]) * 1e-4
    assert total == pytest.approx(p["par_intercepted_mol_m2"] * area_m2, rel=1e-9)
    maps = sorted(x.name for x in (out / "maps").glob("*.png"))
    assert len(maps) == 6 and maps[0].startswith("diffuse_") and maps[-1].startswith("period_")


def test_cli_sky_alone_and_with_a_sun(block, capsys):
    assert main(["light", block, *FAST, "--sky", "uoc", "--sky-directions", "16",
                 "--check"]) == EXIT_OK
    out = capsys.readouterr().out
    assert "diffuse light: uniform overcast sky" in out and "Beer-Lambert" in out
    assert "direct light" not in out
    assert main(["light", block, *FAST, "--sky", "soc", "--sun-zenith", "30",
                 "--sun-azimuth", "180", "--json"]) == EXIT_OK
    data = json.loads(capsys.readouterr().out)
    assert len(data["transmission"]) == 3 and len(data["diffuse"]["transmission"]) == 3


def test_cli_polar_night_is_zero_said_once(block, capsys):
    code = main(["light", block, *FAST, "--date", "2005-12-21", "--lat", "80", "--lon", "15",
                 "--tz", "Europe/Oslo", "--day", "--json"])
    cap = capsys.readouterr()
    assert code == EXIT_OK, cap.err
    assert cap.err.count("stays below the horizon") == 1
    p = json.loads(cap.out)["period"]
    assert p["steps"] == 0 and p["par_incident_mol_m2"] == 0 and p["fraction_intercepted"] is None


WEATHER_OK = "time,ghi\n2005-08-01T11:00+08:00,800\n2005-08-01T12:00+08:00,850\n"


@pytest.mark.parametrize("extra, weather, says", [
    (PLACE + ["--day", "--step", "0"], None, "time step must be > 0 min, got 0.0 (--step)"),
    (PLACE + ["--from", "06:00", "--to", "07:00", "--step", "90"], None,
     "longer than the period"),
    (PLACE + ["--day", "--step", "1500"], None, "longer than the period"),
    (PLACE + ["--from", "12:00", "--to", "06:00"], None, "06:00 (--from/--to)"),
    (["--sky", "soc", "--sky-directions", "0"], None, "at least 1, got 0 (--sky-directions)"),
    (DAY + ["--sky-directions", "-2"], None, "at least 1"),
    (DAY + ["--sun-zenith", "30", "--sun-azimuth", "0"], None, "give no --sun-zenith"),
    (DAY + ["--time", "12:00"], None, "give no --time"),
    (DAY + ["--from", "06:00"], None, "either --day or --from/--to"),
    (["--sun-zenith", "30", "--sun-azimuth", "0", "--step", "30"], None, "--step is for a period"),
    (["--sky-directions", "16", "--sun-zenith", "30", "--sun-azimuth", "0"], None,
     "--sky-directions needs --sky"),
    (PLACE + ["--weather", "W", "--day"], WEATHER_OK, "weather file sets the period"),
    (["--weather", "W"], WEATHER_OK, "needs the place"),
    (PLACE + ["--par-factor", "0", "--day"], None, "PAR conversion factor"),
    (["--lat", "39.9", "--lon", "116.4", "--weather", "W"], "time,ghi,wind\n", "unknown column 'wind'"),
    (["--lat", "39.9", "--lon", "116.4", "--weather", "W"], "time,dni\n", "missing column 'ghi'"),
    (["--lat", "39.9", "--lon", "116.4", "--weather", "W"],
     "time,ghi\n2005-08-01T11:00,800\n2005-08-01T12:00,850\n", "has no time zone"),
    (["--lat", "39.9", "--lon", "116.4", "--weather", "W"],
     WEATHER_OK + "2005-08-01T11:30+08:00,10\n", "times must increase"),
    (["--lat", "39.9", "--lon", "116.4", "--weather", "W"],
     WEATHER_OK + "2005-08-01T13:00+08:00,10\n2005-08-01T17:00+08:00,10\n", "a gap of 4 h"),
    (["--lat", "39.9", "--lon", "116.4", "--weather", "W"],
     WEATHER_OK + "2005-08-01T13:00+08:00,nan\n", "missing value"),
    (["--lat", "39.9", "--lon", "116.4", "--weather", "W"],
     WEATHER_OK + "2005-08-01T13:00+08:00,-5\n", "negative irradiance"),
    (["--lat", "39.9", "--lon", "116.4", "--weather", "missing.csv"], None,
     "no such weather file"),
])
def test_cli_bad_period_input_is_one_line(block, tmp_path, capsys, extra, weather, says):
    if weather is not None:
        w = tmp_path / "weather.csv"
        w.write_text(weather)
        extra = [str(w) if a == "W" else a for a in extra]
    assert main(["light", block, *FAST, *extra]) == EXIT_FAIL
    err = capsys.readouterr().err
    assert says in err, err
    assert "Traceback" not in err
    lines = [x for x in err.splitlines() if x.startswith("error:")]
    assert len(lines) == 1


def test_cli_weather_file_gives_its_period(block, tmp_path, capsys):
    w = tmp_path / "weather.csv"
    w.write_text("time,ghi\n" + "".join(
        f"2005-08-01T{h:02d}:00+08:00,{max(0.0, 900 * math.sin(math.pi * (h - 5.5) / 14)):.1f}\n"
        for h in range(24)))
    code = main(["light", block, *FAST, "--lat", "39.9", "--lon", "116.4", "--weather", str(w),
                 "--json"])
    cap = capsys.readouterr()
    assert code == EXIT_OK, cap.err
    p = json.loads(cap.out)["period"]
    assert p["weather_file"] == str(w) and p["weather"]["decomposition"] == "erbs"
    assert p["steps"] > 10 and p["par_diffuse_mol_m2"] > 0 and p["step_min"] is None
