"""An anisotropic diffuse sky for a period (Perez's model through pvlib), through real Embree:
the three parts add to the diffuse irradiance at every step, an overcast step comes close to
the uniform sky, a clear step puts more diffuse light on sunlit leaves than the uniform sky,
the day's intercepted diffuse PAR is the weighted sum of what each traced direction
intercepts, nothing more is traced than for an overcast sky, and the command line says what
is wrong in one line."""

import json
import math

import numpy as np
import pandas as pd
import pvlib
import pytest
from test_light_period import BEIJING, DAY, FAST, block  # noqa: F401  (a fixture)
from test_light_sky import random_leaves

from maizeviz.cli import EXIT_FAIL, EXIT_OK, main
from maizeviz.errors import MaizevizError
from maizeviz.light.engine import LightEngine
from maizeviz.light.scene.embree_scenes import light_scene
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.sources.irradiance import Period, clear_sky_period
from maizeviz.light.sources.perez import PEREZ_MODELS, perez_split
from maizeviz.light.sources.sky import make_sky
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.beam import trace_light
from maizeviz.light.trace.directions import trace_period, trace_sky
from maizeviz.mesh.tessellate import triangle_areas_normals
from maizeviz.project.records import day_from_record, day_record

HEIGHTS = (0.0, 60.0, 200.0)


@pytest.fixture(scope="module")
def canopy():
    return random_leaves(2.0, 5.0, seed=11, spherical=True, side=100.0)


@pytest.fixture(scope="module")
def scene(canopy):
    return light_scene(canopy, periodic=True)


def sampling(threads=2):
    return Sampling(HEIGHTS, 0.5, (0, 0, 100, 100), True, threads)


def steps(rows, when="2005-08-01T12:00+08:00", step_s=1800.0):
    """A period of one step per (zenith deg, azimuth deg, dni W/m2, dhi W/m2), step_s apart."""
    t0 = pd.Timestamp(when)
    times = pd.DatetimeIndex([t0 + pd.Timedelta(seconds=step_s * k) for k in range(len(rows))])
    z, a, dni, dhi = (np.array(c, dtype=np.float64) for c in zip(*rows))
    direct = dni * np.cos(np.radians(z))
    half = pd.Timedelta(seconds=step_s / 2)
    return Period(times=times, step_s=np.full(len(rows), step_s), zenith_deg=z, azimuth_deg=a,
                  ghi=direct + dhi, dni=dni, dhi=dhi, direct_horizontal=direct,
                  start=times[0] - half, end=times[-1] + half, source="test")


# --------------------------------------------------------------------------- the split


# every kind of step: clear, hazy, overcast, dark, no diffuse light, a sun below 5 deg of
# elevation, and a near-zenith sun under a thin clear sky (the 1990 coefficients give F1 > 1)
ROWS = [(22.0, 170.0, 900.0, 100.0), (45.0, 120.0, 600.0, 200.0), (40.0, 150.0, 0.0, 150.0),
        (60.0, 250.0, 0.0, 20.0), (30.0, 200.0, 800.0, 0.0), (87.0, 70.0, 200.0, 15.0),
        (89.5, 290.0, 30.0, 3.0), (3.0, 0.0, 34.0, 13.7), (70.0, 100.0, 50.0, 120.0)]


@pytest.mark.parametrize("model", list(PEREZ_MODELS))
def test_the_three_parts_add_to_the_diffuse_irradiance_at_every_step(model):
    for period in (steps(ROWS), clear_sky_period("2005-08-01", step_min=10, **BEIJING)):
        split = perez_split(period, model)
        dhi = period.dhi
        iso, circ, hor = split.isotropic_w_m2, split.circumsolar_w_m2, split.horizon_w_m2
        assert split.n_steps == period.n_steps
        assert np.all(iso >= 0) and np.all(circ >= 0) and np.all(hor == 0)
        assert iso + circ + hor == pytest.approx(dhi, rel=1e-12, abs=1e-12)
        assert np.all((split.circumsolar_share >= 0) & (split.circumsolar_share <= 1))
        # pvlib's own parts on the horizontal wherever they already add to dhi
        fn = pvlib.irradiance.perez if model == "perez" else pvlib.irradiance.perez_driesse
        ref = fn(0.0, 180.0, dhi, period.dni,
                 pvlib.irradiance.get_extra_radiation(period.times).to_numpy(),
                 period.zenith_deg, period.azimuth_deg,
                 pvlib.atmosphere.get_relative_airmass(period.zenith_deg), return_components=True)
        ok = (period.zenith_deg <= 85.0) & (dhi > 0) & (split.f1 <= 1.0)
        assert ok.sum() >= 3
        assert iso[ok] == pytest.approx(np.asarray(ref["poa_isotropic"])[ok], rel=1e-9)
        assert circ[ok] == pytest.approx(np.asarray(ref["poa_circumsolar"])[ok], rel=1e-9)
        # the sun below 5 deg: pvlib's parts add to less than dhi; the isotropic part takes
        # the rest, the circumsolar part stays pvlib's
        low = (period.zenith_deg > 85.0) & (dhi > 0)
        assert low.any()
        assert np.all(np.asarray(ref["poa_isotropic"])[low] + np.asarray(
            ref["poa_circumsolar"])[low] < dhi[low])
        assert circ[low] == pytest.approx(np.asarray(ref["poa_circumsolar"])[low], rel=1e-9)
        # the horizon band: F2 dhi on a vertical plane, nothing on the horizontal
        assert split.horizon_vertical_w_m2 == pytest.approx(split.f2 * dhi, rel=1e-12)
    one = perez_split(steps(ROWS), model)
    assert one.clearness[2] == pytest.approx(1.0) and one.clearness[0] > 6.2   # overcast, clear
    assert one.circumsolar_share[2] < 0.05 < 0.4 < one.circumsolar_share[0]
    assert one.circumsolar_w_m2[4] == one.isotropic_w_m2[4] == 0.0          # no diffuse light
    if model == "perez":                            # F1 above 1: everything circumsolar
        assert one.f1[7] > 1.0
        assert one.circumsolar_w_m2[7] == 13.7 and one.isotropic_w_m2[7] == 0.0


def test_an_unknown_model_and_a_split_of_another_period_are_refused(canopy, scene):
    with pytest.raises(MaizevizError, match="unknown diffuse model 'hay'"):
        perez_split(steps(ROWS), "hay")
    period = steps(ROWS[:3])
    with pytest.raises(MaizevizError, match="not this period's"):
        trace_period(canopy, period, sampling(), make_sky("uoc", 6), scene=scene,
                     diffuse=perez_split(steps(ROWS[:2])))
    with pytest.raises(MaizevizError, match="not a soc sky"):
        trace_period(canopy, period, sampling(), make_sky("soc", 6), scene=scene,
                     diffuse=perez_split(period))


# --------------------------------------------------------------------------- traced


def _pair(canopy, scene, period, n=16):
    """The period traced under Perez's sky and under the uniform sky of the same directions
    (one traced sky for both)."""
    sky = trace_sky(canopy, make_sky("uoc", n), sampling(), scene=scene)
    perez = trace_period(canopy, period, sampling(), sky, scene=scene,
                         diffuse=perez_split(period))
    uniform = trace_period(canopy, period, sampling(), sky, scene=scene)
    return perez, uniform


def test_an_overcast_step_comes_close_to_the_uniform_sky(canopy, scene):
    period = steps([(40.0, 150.0, 0.0, 150.0)])            # overcast: no direct beam
    perez, uniform = _pair(canopy, scene, period)
    share = float(perez.diffuse.circumsolar_share[0])
    assert share < 0.05
    a, b = perez.par_diffuse_intercepted_mol_m2, uniform.par_diffuse_intercepted_mol_m2
    # only the circumsolar part moves, and its interception differs by at most itself
    assert abs(a - b) <= share * perez.par_diffuse_mol_m2
    assert abs(a / b - 1) < 0.01
    assert np.abs(perez.diffuse_transmission_by_height - uniform.sky.transmission).max() < 0.01
    assert uniform.diffuse_transmission_by_height == pytest.approx(uniform.sky.transmission,
                                                                   rel=1e-12)


def test_a_clear_step_puts_more_diffuse_light_on_sunlit_leaves_than_the_uniform_sky(canopy,
                                                                                   scene):
    period = steps([(30.0, 180.0, 850.0, 100.0)])
    perez, uniform = _pair(canopy, scene, period)
    share = float(perez.diffuse.circumsolar_share[0])
    assert share > 0.4
    # a triangle's direct PAR over what it would get in full sun: its lit fraction
    area, normal = triangle_areas_normals(canopy.vertices, canopy.faces)
    s = Sun(30.0, 180.0).direction(0.0)
    full = period.step_direct_par_mol_m2[0] / s[2] * np.abs(normal @ s) * area * 1e-4
    lit = perez.triangle_direct_mol / full
    assert np.array_equal(perez.triangle_direct_mol, uniform.triangle_direct_mol)
    sunlit, shaded = lit > 0.9, lit == 0
    assert sunlit.sum() > 100 and shaded.sum() > 100
    on = perez.triangle_diffuse_mol[sunlit].sum() / uniform.triangle_diffuse_mol[sunlit].sum()
    assert on > 1.08                                         # measured 1.116
    # shaded leaves get none of the circumsolar part: exactly the isotropic share
    assert perez.triangle_diffuse_mol[shaded].sum() == pytest.approx(
        (1 - share) * uniform.triangle_diffuse_mol[shaded].sum(), rel=1e-12)
    # what the sun misses, its circumsolar part misses too: more diffuse light reaches the
    # ground in this canopy (T_sun at 30 deg is above the uniform sky's T)
    assert perez.step_transmission[0, 0] > uniform.sky.transmission[0]
    assert perez.diffuse_transmission_by_height[0] > uniform.diffuse_transmission_by_height[0]


def test_the_days_diffuse_interception_is_the_weighted_sum_of_its_directions(canopy, scene):
    period = clear_sky_period("2005-08-01", step_min=120, **BEIJING)
    split = perez_split(period)
    calls = []
    engine = LightEngine(canopy, sampling())
    pl = engine.day(period, sky="perez", directions=6,
                    progress=lambda d, t: calls.append(t) or True)
    assert pl.diffuse is not None and pl.sky is not None and pl.sky.sky.kind == "uoc"
    # no more tracing than an overcast sky: the sky's 6 directions and the 7 suns
    assert calls[-1] == 6 + period.n_steps == len(calls)
    # independently: the uniform sky traced alone and each sun traced alone
    sky = trace_sky(canopy, make_sky("uoc", 6), sampling(), scene=scene)
    f_sky = sky.sky.weights @ sky.per_direction_intercepted
    S = period.step_diffuse_par_mol_m2
    C = S * split.circumsolar_share
    expect = []
    for j in range(period.n_steps):
        sun = Sun(period.zenith_deg[j], period.azimuth_deg[j])
        one = trace_light(canopy, LightRequest(sun, sampling(1)), scene=scene)
        f_sun = one.sunlit_intercepted_fraction
        assert f_sun is not None
        expect.append((S[j] - C[j]) * f_sky + C[j] * f_sun)
    assert pl.par_diffuse_intercepted_mol_m2 == pytest.approx(math.fsum(expect), rel=1e-12)
    # the per-step weights: (1 - c_j) w_i over the sky, c_j on the sun; they sum to 1
    for j in range(period.n_steps):
        c = split.circumsolar_share[j]
        w = np.append((1 - c) * sky.sky.weights, c)
        assert math.fsum(w) == pytest.approx(1.0, abs=1e-15)
        f = np.append(sky.per_direction_intercepted, pl.step_intercepted_fraction[j])
        assert pl.step_diffuse_intercepted_mol_m2[j] == pytest.approx(S[j] * (w @ f),
                                                                      rel=1e-12, abs=1e-15)
    # per triangle and in total the light is conserved; the direct part is untouched
    area_m2 = 1.0
    assert pl.triangle_diffuse_mol.sum() == pytest.approx(
        pl.par_diffuse_intercepted_mol_m2 * area_m2, rel=1e-12)
    assert pl.triangle_mol.sum() == pytest.approx(pl.par_intercepted_mol_m2 * area_m2, rel=1e-12)
    assert pl.par_transmitted_mol_m2[0] + pl.par_intercepted_mol_m2 == pytest.approx(
        pl.par_incident_mol_m2, rel=1e-12)
    soc = engine.day(period, sky="soc", directions=6)
    assert np.array_equal(soc.step_transmission, pl.step_transmission)
    assert np.array_equal(soc.triangle_direct_mol, pl.triangle_direct_mol)
    assert soc.par_incident_mol_m2 == pl.par_incident_mol_m2
    # the maps weigh the same parts: the period's ground map averages to its transmission
    assert np.nanmean(pl.maps[0]) == pytest.approx(pl.transmission_by_height[0], rel=0.05)
    # a day result keeps its split through a project record
    back = day_from_record(day_record("x", pl), "test")[1]
    assert back.diffuse is not None and back.diffuse.model == "perez"
    assert np.array_equal(back.step_intercepted_mol_m2, pl.step_intercepted_mol_m2)
    assert np.array_equal(back.diffuse.f1, pl.diffuse.f1)


# --------------------------------------------------------------------------- command line


def test_cli_day_under_the_perez_sky(block, tmp_path, capsys):  # noqa: F811
    out = tmp_path / "steps.csv"
    code = main(["light", block, *FAST, *DAY, "--sky", "perez", "--json", "--steps", str(out)])
    cap = capsys.readouterr()
    assert code == EXIT_OK, cap.err
    assert "Perez et al. 1990" in cap.err
    data = json.loads(cap.out)
    p = data["period"]
    m = p["diffuse_model"]
    assert m["model"] == "perez" and m["horizon_par_mol_m2"] == 0.0
    assert m["isotropic_par_mol_m2"] + m["circumsolar_par_mol_m2"] == pytest.approx(
        p["par_diffuse_mol_m2"], rel=1e-12)
    assert 0.3 < m["circumsolar_par_mol_m2"] / p["par_diffuse_mol_m2"] < 0.7    # clear day
    assert data["diffuse"]["sky"] == "uoc" and data["diffuse"]["directions"] == 6
    head = out.read_text().splitlines()[0].split(",")
    assert head[-6:] == ["perez_f1", "perez_f2", "isotropic_w_m2", "circumsolar_w_m2",
                         "par_circumsolar_mol_m2", "par_diffuse_intercepted_mol_m2"]
    assert main(["light", block, *FAST, *DAY, "--sky", "perez"]) == EXIT_OK
    text = capsys.readouterr().out
    assert "circumsolar (traced with the sun)" in text and "of this sky's light" in text


@pytest.mark.parametrize("extra, says", [
    (["--sky", "perez"], "it needs a period"),
    (["--sky", "perez", "--sun-zenith", "30", "--sun-azimuth", "0"], "it needs a period"),
    (["--sky", "perez", "--sun-zenith", "30", "--sun-azimuth", "0", "--diffuse", "100"],
     "it needs a period"),
    (["--sky", "perez", "--sky-directions", "0"], "it needs a period"),
    (DAY + ["--sky", "perez", "--sky-directions", "0"], "at least 1, got 0 (--sky-directions)"),
])
def test_cli_bad_perez_combinations_are_one_line(block, capsys, extra, says):  # noqa: F811
    assert main(["light", block, *FAST, *extra]) == EXIT_FAIL
    err = capsys.readouterr().err
    assert says in err, err
    assert "Traceback" not in err
    lines = [x for x in err.splitlines() if x.startswith("error:")]
    assert len(lines) == 1
