"""Canopy photosynthesis from traced absorbed PAR (maizeviz.light.results.assimilation), through real
Embree, against WOFOST's canopy routine as PCSE implements it (a source we did not write), and
the data's own oracles: sums per leaf = per plant = canopy, a tiled block sampled on its tile
= the same field sampled whole, standard errors that shrink with the rays."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from maizeviz.errors import MaizevizError
from maizeviz.light.engine import LightEngine
from maizeviz.light.results.assimilation import assimilate
from maizeviz.light.results.uncertainty import BATCHES
from maizeviz.light.trace.optics import Optics
from maizeviz.mesh.tessellate import triangle_areas_normals
from maizeviz.photosynthesis.split import leaf_model, mean_assimilation

sys.path.insert(0, str(Path(__file__).parent))
from test_scatter import patches  # noqa: E402


@pytest.fixture(scope="module")
def spherical():
    return {lai: patches(lai, 100.0, seed=5) for lai in (2.0, 4.0)}


@pytest.mark.parametrize("lai", [2.0, 4.0])
@pytest.mark.parametrize("elevation", [30.0, 50.0, 70.0])
def test_a_spherical_canopy_assimilates_what_wofost_gives(spherical, lai, elevation):
    """WOFOST 7's canopy routine (``pcse.crop.assimilation.assim7``) for a homogeneous canopy
    of small random spherical leaves, scattering 0.2 (rho = tau = 0.1), black soil, KDIF =
    0.8 sqrt(0.8) (so that its black direct extinction is 0.5 / sin(beta)), AMAX 70 and EFF
    0.45, direct and uniform overcast diffuse PAR: the traced canopy within 3 %. Measured:
    0.995-1.007 at 2 rays per cm2. Feeding each triangle's mean light to the model instead gives +0.5 to +6 %
    more (the Jensen gap the sunlit/shaded split removes)."""
    from pcse.crop.assimilation import assim7

    canopy = spherical[lai]
    model = leaf_model("wofost", amax=70.0, eff=0.45)
    sinb = math.sin(math.radians(elevation))
    pardir, pardif = 350.0 * sinb, 60.0
    eng = LightEngine(canopy, periodic=True, density=2.0, heights_cm=(0.0,))
    light = eng.absorbed(zenith=90 - elevation, azimuth=150, optics=Optics(0.1, 0.1, 0.0),
                         direct_w_m2=pardir, diffuse_w_m2=pardif, sky="uoc", directions=46)
    got = assimilate(canopy, light, model)
    expect = assim7(70.0, 0.45, lai, 0.8 * math.sqrt(0.8), sinb, pardir, pardif)
    assert got.canopy_gross_kg_co2_ha_h == pytest.approx(expect, rel=0.03)
    assert got.warnings == ()
    se = got.canopy_gross_error_umol_m2_s
    assert 0 < se < 0.01 * got.canopy_gross_umol_m2_s
    area = triangle_areas_normals(canopy.vertices, canopy.faces)[0] * 1e-4
    mean = mean_assimilation(model, area, light.triangle_absorbed_w).sum() / got.ground_m2
    assert mean > got.canopy_gross_umol_m2_s


def test_tables_add_up_and_tiles_fold_to_the_whole_field():
    """A 2 x 2 tiling of one block in a periodic field sampled on one tile gives, per plant,
    what the same field sampled over its whole plot gives (the same light per triangle up to
    the rays' noise), and leaf rows sum to plant rows sum to the canopy."""
    from maizeviz.canopy.build import Canopy
    from maizeviz.canopy.layout import layout_from_dict

    base = patches(3.0, 60.0, seed=9)
    # the same block tiled 2 x 2 as four plants standing in a 120 x 120 plot
    v, f, leaf = [], [], []
    plants = []
    for i, (dx, dy) in enumerate(((0, 0), (60, 0), (0, 60), (60, 60))):
        v.append(base.vertices + [dx, dy, 0])
        f.append(base.faces + i * len(base.vertices))
        leaf.append(np.ones(len(base.faces), np.int32))
        plants.append({"x": 30 + dx, "plants": [{"y": 30 + dy, "plant": 1}]})
    layout = layout_from_dict({"maizeviz_layout": 1, "row_spacing": 60, "plant_spacing": 60,
                               "field": {"x0": 0, "y0": 0, "x1": 120, "y1": 120},
                               "rows": plants})
    inst = np.repeat(np.arange(4), len(base.faces)).astype(np.int32)
    n = len(inst)
    canopy = Canopy(np.vstack(v), np.vstack(f), inst, np.ones(n, np.int32),
                    np.concatenate(leaf), layout, "", np.empty((0, 3)),
                    np.empty((0, 3), np.int64), np.ones(4, np.int32))
    model = leaf_model("c4")
    kw = dict(zenith=35, azimuth=200, direct_w_m2=300.0, diffuse_w_m2=80.0, directions=16)
    tile = LightEngine(canopy, periodic=True, density=4.0, heights_cm=(0.0,),
                       rect=(0, 0, 60, 60))
    whole = LightEngine(canopy, periodic=True, density=4.0, heights_cm=(0.0,))
    a_tile = assimilate(canopy, tile.absorbed(**kw), model, 30.0)
    a_whole = assimilate(canopy, whole.absorbed(**kw), model, 30.0)
    assert a_tile.leaf_area_m2 == pytest.approx(a_whole.leaf_area_m2 / 4, rel=1e-12)
    assert a_tile.canopy_gross_umol_m2_s == pytest.approx(a_whole.canopy_gross_umol_m2_s,
                                                          rel=0.02)
    for a in (a_tile, a_whole):
        leaves = a.table("leaf", canopy)
        plants_ = a.table("plant", canopy)
        assert leaves["gross_umol_s"].sum() == pytest.approx(plants_["gross_umol_s"].sum(),
                                                             rel=1e-12)
        assert plants_["gross_umol_s"].sum() / a.ground_m2 == pytest.approx(
            a.canopy_gross_umol_m2_s, rel=1e-12)
        assert (plants_["gross_umol_s_se"] > 0).all()
    assert len(a_tile.table("plant", canopy)) == 1 and len(a_whole.table("plant", canopy)) == 4


def test_standard_errors_shrink_with_the_rays_and_cover_the_difference(spherical):
    """Thresholds from the batch errors' distributions, not one CPU's draws (a batch error
    squared is sigma^2 chi2_7 / 7; 'fine < coarse' of one seed each at 4x the rays failed
    4 % of the time by chance, F(7,7) > 4): two seeds pooled (14 dof) at 16x the rays, the
    fine error under sqrt(F(14,14;1e-6)/16) = 1.09 of the coarse; the two densities' means
    within t(14;1e-6) = 8.2 of their combined error."""
    canopy = spherical[2.0]
    model = leaf_model("c4")
    out: dict[float, list] = {}
    sparse, dense = 0.25, 4.0
    for density in (sparse, dense):
        eng = LightEngine(canopy, periodic=True, density=density, heights_cm=(0.0,))
        for seed in (1, 2):
            light = eng.absorbed(zenith=40, azimuth=100, diffuse_w_m2=50.0, directions=16,
                                 seed=seed)
            out.setdefault(density, []).append((assimilate(canopy, light, model), light))
    dof = 2 * (BATCHES - 1)
    limit = math.sqrt(stats.f.isf(1e-6, dof, dof) * sparse / dense)

    def pooled(density, error):
        return math.sqrt(sum(error(a, lt) ** 2 for a, lt in out[density]) / 2)

    for error in (lambda a, lt: a.canopy_gross_error_umol_m2_s,
                  lambda a, lt: lt.absorbed_leaves_error):
        assert pooled(dense, error) < limit * pooled(sparse, error)
    mean = {d: sum(a.canopy_gross_umol_m2_s for a, _ in out[d]) / 2 for d in out}
    se = math.hypot(*(pooled(d, lambda a, lt: a.canopy_gross_error_umol_m2_s) / math.sqrt(2)
                      for d in out))
    assert abs(mean[sparse] - mean[dense]) < stats.t.isf(0.5e-6, dof) * se


def test_photosynthesis_needs_par_and_a_sane_temperature(spherical):
    canopy = spherical[2.0]
    eng = LightEngine(canopy, periodic=True, density=0.5, heights_cm=(0.0,))
    nir = eng.absorbed(zenith=40, azimuth=100, band="nir")
    with pytest.raises(MaizevizError, match="needs absorbed PAR"):
        assimilate(canopy, nir, leaf_model("c4"))
    par = eng.absorbed(zenith=40, azimuth=100)
    with pytest.raises(MaizevizError) as err:
        assimilate(canopy, par, leaf_model("c4"), temp_c=math.nan)
    assert err.value.quantity == "temperature"


def test_the_facade_traces_photosynthesis_in_a_few_lines(spherical):
    import maizeviz as mv

    canopy = spherical[2.0]
    eng = mv.LightEngine(canopy, periodic=True, density=1.0, heights_cm=(0.0,))
    a = eng.photosynthesis(zenith=30, azimuth=180, diffuse_w_m2=60.0, directions=16,
                           model="wofost", temperature_c=20.0)
    b = assimilate(canopy, eng.absorbed(zenith=30, azimuth=180, diffuse_w_m2=60.0,
                                        directions=16), mv.WofostLeaf(), 20.0)
    assert isinstance(a, mv.Assimilation) and a.as_dict() == b.as_dict()
    frame = a.table("leaf", canopy)
    assert frame["gross_umol_s"].sum() == pytest.approx(float(a.triangle_gross_umol_s.sum()))
    period = mv.clear_sky_period("2005-08-01", 39.9, 116.4, "Asia/Shanghai", 120)
    temps = np.linspace(20, 30, len(period.step_s))
    day = eng.absorbed_day(period, directions=16, photosynthesis=mv.leaf_model("c4"),
                           temperature_c=temps)
    np.testing.assert_array_equal(day.assimilation.temperature_c, temps)
    with pytest.raises(MaizevizError, match="one for each of the period's 7 steps"):
        eng.absorbed_day(period, directions=16, photosynthesis=mv.leaf_model("c4"),
                         temperature_c=[20.0, 25.0])
    got = day.assimilation
    assert isinstance(got, mv.PeriodAssimilation)
    assert np.sum(got.step_gross_umol_m2_s * day.period.step_s) * 1e-6 == pytest.approx(
        got.canopy_gross_mol_m2, rel=1e-12)
    assert got.table("plant", canopy)["gross_g_co2"].sum() / got.ground_m2 == pytest.approx(
        got.canopy_gross_g_m2, rel=1e-12)


def test_a_periods_own_air_temperature_drives_the_c4_model(spherical):
    """A period carrying air temperatures (a weather file's ``temp_air``) gives each step its
    own; NaN steps take the temperature given; a hot step assimilates as the model says."""
    from dataclasses import replace

    import maizeviz as mv

    canopy = spherical[2.0]
    eng = mv.LightEngine(canopy, periodic=True, density=0.5, heights_cm=(0.0,))
    period = mv.clear_sky_period("2005-08-01", 39.9, 116.4, "Asia/Shanghai", 180)
    n = len(period.step_s)
    cool = eng.absorbed_day(period, directions=16, photosynthesis=mv.leaf_model("c4"),
                            temperature_c=20.0)
    air = np.full(n, 33.0)
    air[0] = np.nan
    try:
        warm = replace(period, temp_air=air)
    except TypeError:                           # a Period without air temperatures yet
        warm = replace(period)
        object.__setattr__(warm, "temp_air", air)
    day = eng.absorbed_day(warm, directions=16, photosynthesis=mv.leaf_model("c4"),
                           temperature_c=20.0)
    np.testing.assert_array_equal(day.assimilation.temperature_c, [20.0] + [33.0] * (n - 1))
    np.testing.assert_array_equal(cool.assimilation.temperature_c, [20.0] * n)
    # the same light: 33 C beats 20 C wherever the sun is up after the first step
    hot, cold = day.assimilation.step_gross_umol_m2_s, cool.assimilation.step_gross_umol_m2_s
    assert np.all(hot[1:] > cold[1:])
    assert day.assimilation.step_gross_umol_m2_s[0] == pytest.approx(
        cool.assimilation.step_gross_umol_m2_s[0], rel=1e-12)
