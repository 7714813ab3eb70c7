"""Absorbed light with scattering (maizeviz.light.trace.scatter), through real Embree, against
references we did not write: exact interception with black leaves, the Beer-Lambert law of a
random spherical canopy (the values Helios' homogeneous-canopy test uses), a leaf's
transmittance, two parallel plates in closed form, de Pury & Farquhar's scattered-beam
formula, and the energy balance."""

import math

import numpy as np
import pytest
from scipy import stats
from square_leaves import spherical_normals, square_corners

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.layout import layout_from_dict
from maizeviz.errors import MaizevizError
from maizeviz.light.engine import LightEngine
from maizeviz.light.results.uncertainty import BATCHES
from maizeviz.light.trace.optics import DEFAULT_OPTICS, Optics, optics_for


def plot(x0=0.0, y0=0.0, x1=100.0, y1=100.0):
    return layout_from_dict({"maizeviz_layout": 1, "row_spacing": 60, "plant_spacing": 30,
                             "field": {"x0": x0, "y0": y0, "x1": x1, "y1": y1},
                             "rows": [{"x": (x0 + x1) / 2, "plants": [{"y": (y0 + y1) / 2,
                                                                        "plant": 1}]}]})


def plates(heights, size=100.0):
    """Horizontal squares covering the whole 100 x 100 cm plot, one leaf each."""
    v, f = [], []
    for k, z in enumerate(heights):
        v += [[0, 0, z], [size, 0, z], [size, size, z], [0, size, z]]
        f += [[4 * k, 4 * k + 1, 4 * k + 2], [4 * k, 4 * k + 2, 4 * k + 3]]
    leaf = np.repeat(np.arange(1, len(heights) + 1), 2)
    return Canopy.from_triangles(np.array(v, float), np.array(f), plot(), leaf)


def patches(lai, width, height=(20.0, 120.0), side=2.0, seed=1):
    """A homogeneous canopy of square patches (``side`` cm) with normals uniform on the
    sphere (a spherical leaf angle distribution), leaf area index ``lai`` over a square plot of
    ``width`` cm, in a slab between the two heights (cm)."""
    rng = np.random.default_rng(seed)
    n = int(round(lai * width * width / side**2))
    centre = np.column_stack([rng.uniform(0, width, n), rng.uniform(0, width, n),
                              rng.uniform(*height, n)])
    corners = square_corners(centre, spherical_normals(rng, n), side)
    v = corners.reshape(-1, 3)
    base = 4 * np.arange(n)[:, None]
    f = np.vstack([np.hstack([base, base + 1, base + 2]), np.hstack([base, base + 2, base + 3])])
    return Canopy.from_triangles(v, f, plot(0, 0, width, width), np.ones(len(f), np.int32))


@pytest.fixture(scope="module")
def homogeneous():
    return patches(2.0, 100.0)


# ----------------------------------------------------------------------------- black leaves
def test_black_leaves_absorb_what_the_direct_light_intercepts(homogeneous):
    """Black leaves: the ground gets exactly what the sun's rays bring down; the leaves' direct
    beam, sampled from each triangle (.sunlit), is what those rays intercept, within the two
    estimates' standard errors, as a canopy and layer by layer, never more than a triangle's
    whole area intercepts."""
    eng = LightEngine(homogeneous, periodic=True, density=4.0, heights_cm=(0.0,))
    sun = eng.sun(zenith=36, azimuth=120, classes=True)
    got = eng.absorbed(zenith=36, azimuth=120, optics=Optics(0, 0, 0), direct_w_m2=500.0)
    b = got.balance
    assert b.absorbed_ground / b.incident == pytest.approx(sun.transmission[0], rel=1e-15, abs=0)
    assert b.reflected_top == b.unresolved == b.escaped_sides == 0.0 and got.events == 0
    per_ray = 500.0 * sun.ray_area_cm2 * 1e-4
    rays_w = sun.first_hits * per_ray
    # the rays' own error: binomial over the rays, in W
    rays_se = math.sqrt(rays_w.sum() * per_ray * sun.transmission[0])
    se = math.hypot(got.batches.error(), rays_se)
    assert abs(got.triangle_absorbed_w.sum() - rays_w.sum()) < 4 * se
    # matched to the rays' total (the grid's, less noisy): equal up to rounding
    assert got.triangle_absorbed_w.sum() == pytest.approx(rays_w.sum(), rel=1e-12)
    z = homogeneous.vertices[homogeneous.faces][:, :, 2].mean(axis=1)
    layer = np.digitize(z, [40.0, 60.0, 80.0, 100.0])
    for k in range(5):
        part = layer == k
        err = math.hypot(got.batches.error(part.astype(float)),
                         math.sqrt(rays_w[part].sum() * per_ray))
        assert abs(got.triangle_absorbed_w[part].sum() - rays_w[part].sum()) < 4 * err
    from maizeviz.mesh.tessellate import triangle_areas_normals

    area, normal = triangle_areas_normals(homogeneous.vertices, homogeneous.faces)
    s = np.asarray(got.sun_direction)
    whole = 500.0 / s[2] * np.abs(normal @ s) * area * 1e-4
    assert np.all(got.triangle_absorbed_w <= whole * (1 + 1e-12))
    assert np.all(got.triangle_sunlit_cm2 <= area * (1 + 1e-12))


@pytest.mark.parametrize("periodic, width, rect", [(True, 100.0, None),
                                                    (False, 400.0, (150, 150, 250, 250))])
def test_a_spherical_canopy_of_lai_2_intercepts_helios_direct_value(periodic, width, rect):
    """Helios' homogeneous canopy: LAI 2, zenith 36 deg: 1 - exp(-0.5 / cos(36) * 2) = 0.7095
    of the direct beam intercepted (tolerance 0.01)."""
    canopy = patches(2.0, width, seed=4)
    eng = LightEngine(canopy, periodic=periodic, density=4.0, heights_cm=(0.0,), rect=rect)
    got = eng.absorbed(zenith=36, azimuth=30, optics=Optics(0, 0, 0))
    expect = 1 - math.exp(-0.5 / math.cos(math.radians(36)) * 2.0)
    assert expect == pytest.approx(0.7095, abs=5e-5)
    assert got.fraction_absorbed == pytest.approx(expect, abs=0.01)


def test_a_spherical_canopy_of_lai_2_intercepts_helios_uniform_sky_value(homogeneous):
    """The same canopy under a uniform overcast sky: 0.7806 of the diffuse light
    intercepted (Helios' value; tolerance 0.01), traced from 145 sky directions."""
    eng = LightEngine(homogeneous, periodic=True, density=1.0, heights_cm=(0.0,))
    got = eng.absorbed(optics=Optics(0, 0, 0), direct_w_m2=0.0, diffuse_w_m2=100.0,
                       sky="uoc", directions=145)
    assert got.directions == 145
    assert got.fraction_absorbed == pytest.approx(0.7806, abs=0.01)


# ------------------------------------------------------------------------- analytic scenes
def test_leaves_that_scatter_everything_absorb_nothing(homogeneous):
    eng = LightEngine(homogeneous, periodic=True, density=1.0, heights_cm=(0.0,))
    got = eng.absorbed(zenith=36, azimuth=30, optics=Optics(0.5, 0.5, 0.0))
    assert got.balance.absorbed_leaves == 0.0 and not got.triangle_absorbed_w.any()
    b = got.balance
    assert b.absorbed_ground + b.reflected_top + b.unresolved == pytest.approx(b.incident,
                                                                               rel=0.02)


def test_one_horizontal_leaf_over_black_ground_transmits_tau_of_the_beam():
    eng = LightEngine(plates([50.0]), periodic=True, density=16.0, heights_cm=(0.0,))
    n = eng.absorbed(zenith=30, azimuth=200, optics=Optics(0.10, 0.05, 0.0),
                     direct_w_m2=1.0)
    b = n.balance
    sigma = math.sqrt(0.05 * 0.95 / n.rays)
    assert b.absorbed_ground == pytest.approx(0.05, abs=4 * sigma)
    assert b.reflected_top == pytest.approx(0.10, abs=4 * math.sqrt(0.1 * 0.9 / n.rays))
    assert b.absorbed_leaves == pytest.approx(0.85, abs=1e-12)       # deposited, not drawn


def test_two_parallel_gray_plates_match_the_closed_form():
    """Infinite parallel plates (view factor 1) over black ground: with D the light going
    down between them and U up, D = tau + rho U and U = rho D."""
    rho, tau = 0.3, 0.2
    eng = LightEngine(plates([40.0, 80.0]), periodic=True, density=16.0, heights_cm=(0.0,))
    got = eng.absorbed(zenith=20, azimuth=10, optics=Optics(rho, tau, 0.0), direct_w_m2=1.0)
    down = tau / (1 - rho**2)
    up = rho * down
    a = 1 - rho - tau
    per_ray = got.balance.incident / got.rays
    lower = got.triangle_absorbed_w[:2].sum() / (per_ray * got.rays)
    upper = got.triangle_absorbed_w[2:].sum() / (per_ray * got.rays)
    tol = 2 / math.sqrt(got.rays)            # about 10 standard errors
    assert upper == pytest.approx(a * (1 + up), abs=tol)
    assert lower == pytest.approx(a * down, abs=tol)
    assert got.balance.absorbed_ground == pytest.approx(tau * down, abs=tol)
    assert got.balance.reflected_top == pytest.approx(rho + tau * up, abs=tol)


def test_a_spherical_canopy_absorbs_what_de_pury_and_farquhar_give():
    """Direct beam absorbed with scattering by a deep spherical canopy over black soil:
    (1 - rho_cb) (1 - exp(-k'_b L)), k'_b = k_b sqrt(1 - sigma) (de Pury & Farquhar 1997,
    after Goudriaan 1977), within 3%."""
    lai, zenith, sigma = 3.0, 36.0, 0.15
    canopy = patches(lai, 100.0, seed=7)
    eng = LightEngine(canopy, periodic=True, density=4.0, heights_cm=(0.0,))
    got = eng.absorbed(zenith=zenith, azimuth=60, optics=Optics(sigma / 2, sigma / 2, 0.0))
    kb = 0.5 / math.cos(math.radians(zenith))
    rho_h = (1 - math.sqrt(1 - sigma)) / (1 + math.sqrt(1 - sigma))
    rho_cb = 1 - math.exp(-2 * rho_h * kb / (1 + kb))
    expect = (1 - rho_cb) * (1 - math.exp(-kb * math.sqrt(1 - sigma) * lai))
    assert got.fraction_absorbed == pytest.approx(expect, rel=0.02)
    assert got.balance.reflected_top / got.balance.incident == pytest.approx(rho_cb, abs=0.005)


def test_the_energy_balance_closes_with_optics_on(homogeneous):
    eng = LightEngine(homogeneous, periodic=True, density=2.0, heights_cm=(0.0,))
    for band in ("par", "nir"):
        got = eng.absorbed(zenith=40, azimuth=100, band=band, diffuse_w_m2=50.0,
                           directions=16)
        b = got.balance
        assert b.incident == pytest.approx(1000 * (0.48 if band == "par" else 0.52) + 50.0)
        assert abs(b.closure) < 5 / math.sqrt(got.rays)
        assert b.unresolved < 1e-3 * b.incident
        assert b.escaped_sides == 0.0                                     # periodic


def test_an_open_field_loses_light_through_its_sides():
    eng = LightEngine(patches(2.0, 100.0, seed=2), periodic=False, density=2.0,
                      heights_cm=(0.0,), rect=(30, 30, 70, 70))
    got = eng.absorbed(zenith=50, azimuth=90, band="nir")
    assert got.balance.escaped_sides > 0 and abs(got.balance.closure) < 0.05


# ----------------------------------------------------------------------------- the inputs
@pytest.mark.parametrize("kw, quantity", [
    (dict(reflectance=-0.1, transmittance=0.1, ground_reflectance=0.1), "reflectance"),
    (dict(reflectance=0.7, transmittance=0.4, ground_reflectance=0.1), "transmittance"),
    (dict(reflectance=0.1, transmittance=math.nan, ground_reflectance=0.1), "transmittance"),
    (dict(reflectance=0.1, transmittance=0.1, ground_reflectance=2.0), "ground_reflectance"),
])
def test_impossible_optics_are_one_line(kw, quantity):
    with pytest.raises(MaizevizError) as err:
        Optics(**kw)
    assert err.value.quantity == quantity and "\n" not in str(err.value)


def test_band_defaults_and_overrides():
    assert optics_for("nir") == DEFAULT_OPTICS["nir"]
    assert optics_for("par", reflectance=0.2).reflectance == 0.2
    with pytest.raises(MaizevizError, match="unknown band 'uv'"):
        optics_for("uv")


# ------------------------------------------------------------------------- the command line
def run_cli(capsys, *argv):
    from maizeviz.cli import main

    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


BASE = ["light", None, "--tile", "3x3", "--levels", "36", "--sun-zenith", "30",
        "--sun-azimuth", "150", "--periodic", "--density", "1", "--json"]


def cli_args(**extra):
    from maizeviz.resources import example_points

    args = [str(example_points()) if a is None else a for a in BASE]
    for k, v in extra.items():
        args += [f"--{k.replace('_', '-')}", str(v)]
    return args


def test_the_cli_with_all_optics_0_gives_todays_interception(capsys):
    import json

    code, out, err = run_cli(capsys, *cli_args(reflectance=0, transmittance=0,
                                               ground_reflectance=0, irradiance=480))
    assert code == 0, err
    doc = json.loads(out)
    b = doc["balance"]
    assert set(b) >= {"incident", "absorbed_leaves", "absorbed_ground", "reflected_top"}
    # the rays' interception; the leaves' direct beam sampled from each triangle (.sunlit)
    se = doc["absorbed"]["absorbed_leaves_se"] / b["incident"]
    assert abs(b["absorbed_leaves"] / b["incident"] - doc["sunlit_intercepted_fraction"]) < 4 * se
    # black stalks absorb what they intercept (sampled as the leaves are)
    assert abs(b["absorbed_stalks"] / b["incident"]
               - doc["stalks"]["sun_intercepted_fraction"]) < 4 * se
    assert b["incident"] == 480.0 and b["reflected_top"] == 0.0
    assert doc["absorbed"]["absorbed_leaves_umol_m2_s"] == pytest.approx(
        b["absorbed_leaves"] * 4.57)


def test_the_cli_nir_balance_closes_and_leaf_rows_carry_absorbed_light(capsys, tmp_path):
    import csv
    import json

    leaves = tmp_path / "leaves.csv"
    code, out, err = run_cli(capsys, *cli_args(band="nir", leaf_light=leaves))
    assert code == 0, err
    b = json.loads(out)["balance"]
    assert b["incident"] == pytest.approx(520.0)
    assert abs(b["closure_fraction"]) < 0.02 and b["reflected_top"] > 0.2 * b["incident"]
    assert "closure" not in b                      # named by what it is: a fraction
    rows = list(csv.DictReader(leaves.open()))
    assert rows and all(float(r["absorbed_w"]) >= 0 for r in rows)
    per_leaf = [float(r["absorbed_w_m2_leaf"]) for r in rows]
    assert 0 < np.median(per_leaf) < 520


@pytest.mark.parametrize("extra, message", [
    (dict(reflectance=1.2), "the reflectance must be a number from 0 to 1, got 1.2"),
    (dict(reflectance=0.7, transmittance=0.5), "cannot reflect and transmit more"),
    (dict(ground_reflectance="nan"), "the ground reflectance must be a number from 0 to 1"),
    (dict(irradiance=-5), "irradiance"),
])
def test_the_cli_refuses_impossible_optics_in_one_line(capsys, extra, message):
    code, out, err = run_cli(capsys, *cli_args(**extra))
    assert code != 0 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], err


def test_the_cli_asks_for_a_sun_for_absorbed_light(capsys):
    from maizeviz.resources import example_points

    code, out, err = run_cli(capsys, "light", example_points(), "--sky", "soc", "--band", "nir")
    assert code != 0 and "absorbed light with scattering needs a sun" in err


def test_per_plant_tables_add_up_to_the_balance(homogeneous):
    eng = LightEngine(homogeneous, periodic=True, density=1.0)
    got = eng.absorbed(zenith=30, azimuth=150, band="nir")
    x0, y0, x1, y1 = got.rect
    area_m2 = (x1 - x0) * (y1 - y0) * 1e-4
    table = got.table("plant", homogeneous)
    assert table["absorbed_w"].sum() == pytest.approx(got.balance.absorbed_leaves * area_m2)
    assert (table["sunlit_area_cm2"] <= table["leaf_area_cm2"] + 1e-9).all()
    assert "absorbed_umol_s" not in table                         # NIR: no photon count
    assert list(got.table("balance").columns[:2]) == ["band", "incident"]
    # the result knows its canopy: a leaf table without passing it back is the same table
    assert got.table("leaf").equals(got.table("leaf", homogeneous))
    with pytest.raises(MaizevizError, match="needs the canopy") as info:
        got.with_canopy(None).table("leaf")                   # one read back, say
    assert info.value.quantity == "canopy"
    assert got.table().equals(got.table("balance"))            # the default: the balance


# ----------------------------------------------------------------------------- the sky per ray
#: Standard error (W/m2) of the leaves' absorbed light, the sky drawn per ray against every
#: direction traced (hypot of the two), 100 W/m2 of uniform-overcast diffuse, 46 directions,
#: 2 rays/cm2 on :func:`homogeneous`: the root mean square of the batches' errors over seeds
#: 101-120 (per ray 0.168 and 0.098, every direction 0.060 and 0.029).
SKY_PER_RAY_SIGMA = {"par": 0.178, "nir": 0.103}


@pytest.mark.parametrize("band", ["par", "nir"])
def test_a_sky_drawn_per_ray_gives_the_directions_answers_within_their_errors(homogeneous,
                                                                               band):
    """Leaves that scatter, in a periodic field: the sky's directions drawn per ray (4 rays a
    cell, one beam's work) give what tracing every direction over the whole grid gives, within
    their standard errors (batches); black leaves and open fields keep the exact
    direction-by-direction tracing."""
    eng = LightEngine(homogeneous, periodic=True, density=2.0, heights_cm=(0.0,))
    kw = dict(direct_w_m2=0.0, diffuse_w_m2=100.0, sky="uoc", directions=46, band=band)
    per_ray = eng.absorbed(**kw, seed=1)
    every = eng.absorbed(**kw, seed=2, sky_passes=0)
    assert per_ray.directions == every.directions == 46
    # Thresholds from the estimators' own errors, not from one CPU's draws (the CPU changes
    # which draws are made: Embree's kernels round a hit's distance differently): sigma, the
    # true standard error of the difference, measured as the root mean square of the batches'
    # standard errors over seeds 101-120 (each 7 degrees of freedom: 280 in all, sigma within
    # 6 % at one standard deviation; taken 18 % up, three of them). The difference is normal:
    # within z(1e-6) sigma. The reported error (8 batches each) is sigma sqrt(chi2_7 / 7) at
    # worst: within sqrt(chi2_7(1e-6) / 7) = 2.41 sigma.
    sigma = 1.18 * SKY_PER_RAY_SIGMA[band]
    se = math.hypot(per_ray.absorbed_leaves_error, every.absorbed_leaves_error)
    gap = abs(per_ray.balance.absorbed_leaves - every.balance.absorbed_leaves)
    assert gap < stats.norm.isf(0.5e-6) * sigma
    assert se < math.sqrt(stats.chi2.isf(1e-6, BATCHES - 1) / (BATCHES - 1)) * sigma
    assert abs(per_ray.balance.closure) < 5 / math.sqrt(4 * per_ray.rays)
    # per plant too (one plant here), and the events are a fraction of the directions'
    assert per_ray.events < every.events / 4
    black = Optics(0, 0, 0)
    a = eng.absorbed(**{**kw, "band": "par"}, optics=black)
    b = eng.absorbed(**{**kw, "band": "par"}, optics=black, sky_passes=0)
    np.testing.assert_array_equal(a.triangle_absorbed_w, b.triangle_absorbed_w)


def test_the_balances_errors_shrink_with_the_rays_and_cover_two_seeds(homogeneous):
    """Each part of the energy balance has a standard error from the batches: they shrink
    with the rays, and two seeds' parts differ by no more than their errors allow.

    Thresholds from the estimates' own distributions, not one CPU's draws: a batch error
    squared is sigma^2 chi2_7 / 7; two seeds pooled, 14 degrees of freedom. With 16 times the
    rays sigma^2 is 16 times smaller, so fine^2 / coarse^2 < F(14, 14; 1e-6) / 16 = 1.09^2
    (the plain fine <= coarse of one seed each, at 8 times the rays, fails 0.7 % of the time
    by chance). The unresolved part is a handful of rays at the sparse density, whose batch
    errors are no chi2: it is only required to have one. Two seeds' parts differ by less
    than t(14; 1e-6) = 8.2 of their pooled error."""
    out = {}
    dense, sparse = 4.0, 0.25
    for density in (sparse, dense):
        eng = LightEngine(homogeneous, periodic=True, density=density, heights_cm=(0.0,))
        out[density] = [eng.absorbed(zenith=35, azimuth=60, diffuse_w_m2=80.0, directions=16,
                                     seed=seed) for seed in (1, 2)]

    def pooled(results, name):
        return math.sqrt(sum(r.balance_errors[name] ** 2 for r in results) / len(results))

    dof = 2 * (BATCHES - 1)
    assert all(r.balance_errors["unresolved"] >= 0 for r in out[sparse] + out[dense])
    for name in ("absorbed_leaves", "absorbed_ground", "reflected_top"):
        coarse, fine = pooled(out[sparse], name), pooled(out[dense], name)
        limit = math.sqrt(stats.f.isf(1e-6, dof, dof) * sparse / dense)
        assert fine < limit * coarse or coarse == 0.0, name
    a, b = out[dense]
    for name in ("absorbed_leaves", "absorbed_ground", "reflected_top"):
        se = math.hypot(a.balance_errors[name], b.balance_errors[name])
        gap = abs(getattr(a.balance, name) - getattr(b.balance, name))
        assert gap < stats.t.isf(0.5e-6, dof) * se + 1e-12, name
