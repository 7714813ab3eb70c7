"""Sky radiance and its discretisation: weights, solid angles, the published turtle, analytic cases."""

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree
from scipy.special import expn

from maizeviz.errors import MaizevizError
from maizeviz.light.sources.sky import (
    MAX_SKY_DIRECTIONS,
    Sky,
    analytic_diffuse_transmission,
    equal_area_bands,
    make_sky,
    turtle_directions,
)
from maizeviz.light.sources.sun import Sun

KINDS = ("soc", "uoc")
SKIES = [(6, "turtle"), (16, "turtle"), (46, "turtle"), (145, "tregenza"), (1, "equal"),
         (2, "equal"), (16, "equal"), (46, "equal"), (100, "equal"), (145, "equal"),
         (1000, "equal")]

# den Dulk's turtle as shipped by Caribu (alinea.caribu.sky_tools.turtle): per elevation band,
# the weights (share of horizontal irradiance) for the standard and uniform overcast skies,
# and the cell solid angles of Dauzat's table (Vegestar, quoted in openalea.astk).
PUBLISHED_46 = {  # elevation: (directions, soc weight, uoc weight, solid angle sr)
    9.23: (10, 0.0043, 0.007, 0.1355),
    10.81: (5, 0.0055, 0.0086, 0.1476),
    26.57: (5, 0.014, 0.017, 0.1207),
    31.08: (10, 0.0197, 0.0224, 0.1375),
    47.41: (5, 0.0336, 0.0317, 0.1364),
    52.62: (5, 0.0399, 0.036, 0.1442),
    69.16: (5, 0.0495, 0.0405, 0.1378),
    90.0: (1, 0.0481, 0.0377, 0.1196),
}
PUBLISHED_16 = {  # elevation: (directions, soc weight, uoc weight)
    10.81: (5, 0.01777, 0.0251),
    26.57: (5, 0.0448, 0.0533),
    52.62: (5, 0.108, 0.0981),
    90.0: (1, 0.1468, 0.1173),
}

# |numeric - analytic| / analytic measured for exp(-0.5 L / cos zenith) (spherical leaves) at
# L = 1, 3, 5 under both skies, rounded up; the worst case sets the tolerance of each sky.
SPHERICAL_REL_TOL = {(16, "turtle"): 0.040, (46, "turtle"): 0.016, (145, "tregenza"): 0.003,
                     (16, "equal"): 0.032, (46, "equal"): 0.010, (145, "equal"): 0.003,
                     (1000, "equal"): 0.0005}


def elevations(sky):
    return np.round(90.0 - sky.zenith_deg, 2)


# --------------------------------------------------------------------------- every sky


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("n, split", SKIES)
def test_weights_sum_to_one_and_cells_cover_the_hemisphere(kind, n, split):
    sky = make_sky(kind, n, split)
    assert sky.n == n == len(sky.directions) == len(sky.zenith_deg)
    assert math.fsum(sky.weights) == 1.0
    assert abs(np.sum(sky.weights) - 1.0) <= 4e-16 * n
    assert np.all(sky.weights > 0)
    assert math.fsum(sky.solid_angle_sr) == pytest.approx(2 * math.pi, abs=1e-12)
    assert np.all(sky.solid_angle_sr > 0)


@pytest.mark.parametrize("n, split", SKIES)
def test_directions_are_unit_above_the_horizon_and_follow_the_sun_convention(n, split):
    sky = make_sky("soc", n, split)
    assert np.allclose(np.linalg.norm(sky.directions, axis=1), 1.0, atol=1e-15)
    assert np.all(sky.directions[:, 2] > 0)
    assert np.all((sky.zenith_deg >= 0) & (sky.zenith_deg < 90))
    assert np.all((sky.azimuth_deg >= 0) & (sky.azimuth_deg < 360))
    assert len(np.unique(np.round(sky.directions, 9), axis=0)) == n
    for north in (0.0, 30.0):
        field = sky.field_directions(north)
        for i in range(0, n, max(1, n // 7)):
            assert field[i] == pytest.approx(
                Sun(sky.zenith_deg[i], sky.azimuth_deg[i]).direction(north), abs=1e-15)


@pytest.mark.parametrize("n, split", SKIES)
def test_horizontal_leaves_transmit_exp_minus_lai_under_every_sky(n, split):
    for kind in KINDS:
        sky = make_sky(kind, n, split)
        for lai in (0.5, 1.0, 3.0, 5.0):
            # horizontal leaves: projection cos(zenith) per unit path 1 / cos(zenith) -> exp(-L)
            t = np.exp(-lai * np.cos(np.radians(sky.zenith_deg))
                       / np.cos(np.radians(sky.zenith_deg)))
            assert sky.transmission(t) == pytest.approx(math.exp(-lai), rel=1e-14)


@pytest.mark.parametrize("n, split", sorted(SPHERICAL_REL_TOL))
@pytest.mark.parametrize("kind", KINDS)
def test_spherical_leaves_approach_the_analytic_diffuse_transmission(kind, n, split):
    sky = make_sky(kind, n, split)
    tol = SPHERICAL_REL_TOL[(n, split)]
    for lai in (1.0, 3.0, 5.0):
        t = np.exp(-0.5 * lai / np.cos(np.radians(sky.zenith_deg)))
        assert sky.transmission(t) == pytest.approx(
            analytic_diffuse_transmission(lai, kind), rel=tol)


@pytest.mark.parametrize("kind", KINDS)
def test_finer_equal_skies_converge_to_the_analytic_value(kind):
    errors = []
    for n in (16, 46, 145, 1000, 4000):
        sky = make_sky(kind, n, "equal")
        t = np.exp(-0.5 * 3.0 / np.cos(np.radians(sky.zenith_deg)))
        errors.append(abs(sky.transmission(t) - analytic_diffuse_transmission(3.0, kind)))
    assert errors[-1] < 2e-5
    assert errors[-1] < errors[0] / 50


# --------------------------------------------------------------------------- analytic


def test_analytic_transmission_matches_exponential_integrals():
    # 2 int_0^1 exp(-x/mu) mu dmu = 2 E3(x); with (1 + 2 mu) / 3 weighting and 7/18
    # normalisation: 6/7 (E3(x) + 2 E4(x))
    for lai in (0.1, 1.0, 3.0, 5.0, 8.0):
        x = 0.5 * lai
        assert analytic_diffuse_transmission(lai, "uoc") == pytest.approx(2 * expn(3, x),
                                                                          rel=1e-10)
        assert analytic_diffuse_transmission(lai, "soc") == pytest.approx(
            6 / 7 * (expn(3, x) + 2 * expn(4, x)), rel=1e-10)
    assert analytic_diffuse_transmission(0.0, "soc") == pytest.approx(1.0, abs=1e-12)
    # G = 1 would be horizontal leaves seen from the zenith only; a brighter zenith (SOC)
    # favours short paths, so SOC transmits more than UOC
    assert analytic_diffuse_transmission(3.0, "soc") > analytic_diffuse_transmission(3.0, "uoc")


def test_analytic_transmission_refuses_bad_numbers():
    with pytest.raises(MaizevizError, match="leaf area index"):
        analytic_diffuse_transmission(-1.0, "soc")
    with pytest.raises(MaizevizError, match="G "):
        analytic_diffuse_transmission(1.0, "soc", G=0.0)
    with pytest.raises(MaizevizError, match="unknown sky kind 'clear'"):
        analytic_diffuse_transmission(1.0, "clear")


# --------------------------------------------------------------------------- turtle


def unit(p):
    return p / np.linalg.norm(p)


def icosahedral_turtle():
    """92 directions built from an icosahedron with a vertex at the zenith.

    Its 12 vertices V, its 20 face centres F, and for each pair of faces F1, F2 sharing an
    edge (V, W) the centres of the triangles (V, F1, F2) and (W, F1, F2): the star-split
    dodecahedron whose triangle centres den Dulk's turtle uses.
    """
    a = math.atan(0.5)

    def ring(az, z):
        return [math.cos(a) * math.sin(math.radians(az)), math.cos(a) * math.cos(math.radians(az)), z]

    v = np.array([[0, 0, 1.0], [0, 0, -1.0]] + [ring(72 * k, math.sin(a)) for k in range(5)]
                 + [ring(36 + 72 * k, -math.sin(a)) for k in range(5)])
    d = np.linalg.norm(v[:, None] - v[None], axis=2)
    near = np.isclose(d, d[d > 0].min())
    faces = [f for f in itertools.combinations(range(12), 3)
             if near[f[0], f[1]] and near[f[1], f[2]] and near[f[0], f[2]]]
    assert len(faces) == 20
    centre = {f: unit(v[list(f)].sum(0)) for f in faces}
    points = list(v) + list(centre.values())
    for i, j in zip(*np.nonzero(np.triu(near)), strict=True):
        f1, f2 = [f for f in faces if i in f and j in f]
        points += [unit(v[k] + centre[f1] + centre[f2]) for k in (i, j)]
    return np.array(points)


def test_turtle46_is_the_published_table():
    sky = make_sky("soc", 46)
    assert sky.split == "turtle"
    el = elevations(sky)
    assert {e: int(np.sum(el == e)) for e in sorted(set(el))} == \
        {e: PUBLISHED_46[e][0] for e in sorted(PUBLISHED_46)}
    # the bands come from the icosahedron: atan(1/2) for its vertices
    assert np.degrees(math.atan(0.5)) == pytest.approx(26.57, abs=0.005)
    geo = icosahedral_turtle()
    assert len(geo) == 92 and np.sum(geo[:, 2] > 1e-9) == 46
    cosang = np.clip(sky.directions @ geo.T, -1, 1)
    nearest = np.argmax(cosang, axis=1)
    assert len(set(nearest)) == 46
    off = np.degrees(np.arccos(cosang.max(axis=1)))
    # the icosahedron's 6 vertices and 10 face centres up to the table's 0.01 deg rounding;
    # the 30 star-split directions sit 0.066-0.072 deg from the plain triangle centres (the
    # published table is kept as it is)
    first = np.isin(el, (90.0, 26.57, 52.62, 10.81))
    assert off[first].max() < 0.006
    assert 0.06 < off[~first].min() and off[~first].max() < 0.075


def test_turtle16_and_6_are_the_first_directions_of_the_table():
    z46, a46 = turtle_directions(46)
    z16, a16 = turtle_directions(16)
    assert np.array_equal(z16, z46[:16]) and np.array_equal(a16, a46[:16])
    sky16 = make_sky("uoc", 16)
    el = elevations(sky16)
    assert {e: int(np.sum(el == e)) for e in sorted(set(el))} == \
        {e: PUBLISHED_16[e][0] for e in sorted(PUBLISHED_16)}
    assert sorted(set(elevations(make_sky("uoc", 6)))) == [26.57, 90.0]


@pytest.mark.parametrize("kind, column", [("soc", 1), ("uoc", 2)])
def test_turtle_weights_match_den_dulk_within_the_published_rounding(kind, column):
    for n, table, tol in ((46, PUBLISHED_46, 5e-4), (16, PUBLISHED_16, 1e-3)):
        sky = make_sky(kind, n)
        el = elevations(sky)
        for e, row in table.items():
            assert sky.weights[el == e] == pytest.approx(row[column], abs=tol), (n, e)


def test_turtle46_cells_match_the_published_solid_angles():
    sky = make_sky("uoc", 46)
    el = elevations(sky)
    for e, row in PUBLISHED_46.items():
        assert sky.solid_angle_sr[el == e] == pytest.approx(row[3], abs=1.5e-3), e


@pytest.mark.parametrize("kind", KINDS)
def test_turtle_cells_are_the_nearest_direction_regions(kind):
    # an independent partition: a Fibonacci lattice of equal solid-angle points on the
    # hemisphere, each given to its nearest direction
    sky = make_sky(kind, 46)
    m = 400_000
    i = np.arange(m)
    mu = (i + 0.5) / m
    phi = i * np.pi * (3 - math.sqrt(5))
    s = np.sqrt(1 - mu ** 2)
    pix = np.column_stack([s * np.sin(phi), s * np.cos(phi), mu])
    owner = cKDTree(sky.directions).query(pix)[1]
    d_omega = 2 * np.pi / m
    solid = np.bincount(owner, minlength=46) * d_omega
    lum = (1 + 2 * mu) / 3 if kind == "soc" else np.ones_like(mu)
    share = np.bincount(owner, weights=lum * mu, minlength=46)
    assert solid == pytest.approx(sky.solid_angle_sr, abs=2e-4)       # measured 9e-5
    assert share / share.sum() == pytest.approx(sky.weights, abs=8e-5)  # measured 3.3e-5


# --------------------------------------------------------------------------- band splits


def test_tregenza_has_its_145_patches():
    sky = make_sky("soc", 145)
    assert sky.split == "tregenza"
    el = elevations(sky)
    counts = {e: int(np.sum(el == e)) for e in sorted(set(el))}
    assert counts == {6.0: 30, 18.0: 30, 30.0: 24, 42.0: 24, 54.0: 18, 66.0: 12, 78.0: 6,
                      90.0: 1}
    # a patch spans 12 deg of altitude and 360 / m of azimuth
    band = el == 30.0
    expect = 2 * np.pi / 24 * (math.sin(math.radians(36)) - math.sin(math.radians(24)))
    assert sky.solid_angle_sr[band] == pytest.approx(expect, rel=1e-13)
    assert 0.0 in set(sky.azimuth_deg[el == 6.0])          # patch 1 points due north


@pytest.mark.parametrize("kind", KINDS)
def test_tregenza_patch_integrals_match_a_lattice(kind):
    # Fibonacci lattice points given to the patch whose altitude band and azimuth sector hold
    # them (Tregenza's definition), independently of the closed-form band integrals
    sky = make_sky(kind, 145)
    m = 400_000
    i = np.arange(m)
    mu = (i + 0.5) / m
    az = np.degrees(i * np.pi * (3 - math.sqrt(5))) % 360
    alt = np.degrees(np.arcsin(mu))
    band = np.minimum((alt // 12).astype(int), 7)
    per_band = np.array([30, 30, 24, 24, 18, 12, 6, 1])
    sector = np.round(az / (360 / per_band[band])).astype(int) % per_band[band]
    centre_alt = np.where(band == 7, 90.0, band * 12 + 6.0)
    centre_az = np.where(band == 7, 0.0, sector * 360 / per_band[band])
    key = np.round(centre_alt, 6) * 1000 + np.round(centre_az, 6)
    sky_key = np.round(90 - sky.zenith_deg, 6) * 1000 + np.round(sky.azimuth_deg, 6)
    order = np.argsort(sky_key)
    owner = order[np.searchsorted(sky_key[order], key)]
    assert np.array_equal(sky_key[owner], key)
    lum = (1 + 2 * mu) / 3 if kind == "soc" else np.ones_like(mu)
    share = np.bincount(owner, weights=lum * mu, minlength=145)
    solid = np.bincount(owner, minlength=145) * 2 * np.pi / m
    assert solid == pytest.approx(sky.solid_angle_sr, abs=1e-4)       # measured 3.1e-5
    assert share / share.sum() == pytest.approx(sky.weights, abs=3e-5)  # measured 9.5e-6


def test_equal_split_cells_have_equal_solid_angles():
    for n in (1, 2, 3, 7, 46, 145, 1000):
        sky = make_sky("uoc", n, "equal")
        assert sky.solid_angle_sr == pytest.approx(np.full(n, 2 * np.pi / n), rel=1e-12)
        assert sky.zenith_deg.min() == 0.0                   # the cap looks at the zenith
    # one direction: the whole hemisphere, straight up
    one = make_sky("soc", 1)
    assert one.weights[0] == 1.0 and one.directions[0] == pytest.approx([0, 0, 1])


@settings(max_examples=60, deadline=None)
@given(n=st.integers(min_value=1, max_value=3000), kind=st.sampled_from(KINDS))
def test_any_equal_split_sums_to_one_and_covers_two_pi(n, kind):
    sky = make_sky(kind, n, "equal")
    assert sky.n == n
    assert math.fsum(sky.weights) == 1.0
    assert np.all(sky.weights > 0)
    assert math.fsum(sky.solid_angle_sr) == pytest.approx(2 * math.pi, rel=1e-12)
    edges, counts = equal_area_bands(n)
    assert counts.sum() == n and counts.min() >= 1
    assert edges[0] == 1.0 and edges[-1] == 0.0 and np.all(np.diff(edges) < 0)
    assert np.all(sky.directions[:, 2] > 0)


def test_standard_overcast_puts_more_weight_near_the_zenith():
    soc, uoc = make_sky("soc", 46), make_sky("uoc", 46)
    assert soc.weights[0] > uoc.weights[0]             # both sorted from the zenith down
    assert soc.weights[-1] < uoc.weights[-1]


# --------------------------------------------------------------------------- bad requests


@pytest.mark.parametrize("args, message", [
    (dict(directions=0), "sky directions must be at least 1, got 0"),
    (dict(directions=-3), "sky directions must be at least 1, got -3"),
    (dict(directions=2.5), "sky directions must be a whole number, got 2.5"),
    (dict(directions="46"), "sky directions must be a whole number, got '46'"),
    (dict(directions=MAX_SKY_DIRECTIONS + 1),
     f"sky directions must be at most {MAX_SKY_DIRECTIONS}, got {MAX_SKY_DIRECTIONS + 1}"),
    (dict(kind="cie"), "unknown sky kind 'cie' (known: soc, uoc)"),
    (dict(split="hexagon"), "unknown sky split 'hexagon' (known: auto, turtle, tregenza, equal)"),
    (dict(directions=20, split="turtle"), "the turtle sky has 6, 16 or 46 directions, got 20"),
    (dict(directions=46, split="tregenza"), "the Tregenza sky has 145 directions, got 46"),
])
def test_bad_sky_requests_say_what_is_wrong_in_one_line(args, message):
    with pytest.raises(MaizevizError) as err:
        make_sky(**args)
    text = str(err.value)
    assert text.startswith(message)
    assert "\n" not in text and "--" not in text


def test_transmission_needs_one_value_per_direction_in_0_1():
    sky = make_sky("soc", 16)
    with pytest.raises(MaizevizError, match="16 directions but 15 transmissions"):
        sky.transmission(np.ones(15))
    with pytest.raises(MaizevizError, match="between 0 and 1"):
        sky.transmission(np.full(16, 1.5))
    with pytest.raises(MaizevizError, match="between 0 and 1"):
        sky.transmission(np.full(16, np.nan))


def test_a_sky_is_immutable_and_validated():
    sky = make_sky("soc", 46)
    with pytest.raises(ValueError):
        sky.weights[0] = 0.5
    with pytest.raises(AttributeError):
        sky.kind = "uoc"
    with pytest.raises(MaizevizError, match="sum to 1"):
        Sky("soc", "equal", [0.0, 45.0], [0.0, 0.0], [np.pi, np.pi], [0.5, 0.6])
    with pytest.raises(MaizevizError, match="unknown sky kind 'cie'"):
        Sky("cie", "equal", [0.0], [0.0], [2 * np.pi], [1.0])
    with pytest.raises(MaizevizError, match="unknown sky split 'auto'"):
        Sky("soc", "auto", [0.0], [0.0], [2 * np.pi], [1.0])
    with pytest.raises(MaizevizError, match="above the horizon"):
        Sky("soc", "equal", [0.0, 90.0], [0.0, 0.0], [np.pi, np.pi], [0.5, 0.5])
    assert "weights sum to 1.000000000000000" in sky.table()
    assert len(sky.table().splitlines()) == 46 + 3
