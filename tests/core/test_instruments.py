"""Virtual field instruments through real Embree, against what holds exactly.

The canopy: N small square leaves (2 cm) with normals uniform on the sphere (G = 0.5) at
uniform random places in a periodic 200 x 200 cm plot between 10 and 150 cm. A line of sight
from below the leaves to above them at zenith theta misses one leaf of area a with
probability 1 - a G / (A cos theta) (A the plot's area: the leaf's shadow along the line,
averaged over its orientations, over the plot; exact for a periodic plot whatever the line's
wraps), so its gap probability is (1 - a G / (A cos theta))^N, exp(-G LAI / cos theta) to
within 2e-4 here. A ring's expected gap fraction is that averaged over the ring in solid
angle (the analyser) or over its pixels (the photograph).

Thresholds: positions are drawn at random, so each position's ring gap fraction is an
independent draw with the expected mean. Its spread holds both errors, the lines of sight's
(binomial) and the canopy realisation's; the tests take the standard error of the mean over
positions measured in the same run, never below the binomial error of all the lines of
sight together sqrt(T (1 - T) / n), and allow 4.5 of it (a false failure about once in
150,000 per ring). The spread itself is bounded by the binomial variance of one line
(T (1 - T) for a [0, 1] quantity of mean T), which the tests check too.
"""

import math

import numpy as np
import pytest
from test_light_sky import random_leaves

from maizeviz.errors import MaizevizError
from maizeviz.instruments.analyser import (
    RING_CENTRES_DEG,
    RING_EDGES_DEG,
    AnalyserPosition,
    mean_tilt_deg,
    miller_lai,
    read_analyser,
    ring_directions,
)
from maizeviz.instruments.ceptometer import (
    Probe,
    extinction_ellipsoidal,
    lp80_lai,
    probe_azimuth,
    read_ceptometer,
)
from maizeviz.instruments.hemiphoto import hemiphoto
from maizeviz.instruments.sight import Sight
from maizeviz.light.engine import LightEngine
from maizeviz.light.scene.rays import sensor_offsets
from maizeviz.light.sources.sun import Sun

SIDE = 200.0
LAI = 2.0
LEAF_CM = 2.0
SIGMAS = 4.5


@pytest.fixture(scope="module")
def canopy():
    return random_leaves(LAI, LEAF_CM, seed=3, spherical=True, side=SIDE)


@pytest.fixture(scope="module")
def sight(canopy):
    return Sight.of(canopy, periodic=True)


def gap_exact(theta_deg):
    """Gap probability of a line of sight through the whole layer at zenith theta."""
    n = int(round(LAI * SIDE * SIDE / LEAF_CM ** 2))
    per_leaf = LEAF_CM ** 2 * 0.5 / (SIDE * SIDE * np.cos(np.radians(theta_deg)))
    return (1.0 - per_leaf) ** n


def ring_exact(lo, hi):
    """A ring's gap probability averaged in solid angle (uniform in cos theta)."""
    c = np.linspace(math.cos(math.radians(hi)), math.cos(math.radians(lo)), 20001)
    mid = 0.5 * (c[1:] + c[:-1])
    return float(np.mean(gap_exact(np.degrees(np.arccos(mid)))))


def check_rings(per_position, expected, lines_per_ring):
    """Mean ring gap fractions over positions (P, R) against ``expected`` (R,), within
    SIGMAS standard errors (see the module docstring)."""
    p = len(per_position)
    mean = per_position.mean(axis=0)
    se = per_position.std(axis=0, ddof=1) / math.sqrt(p)
    binomial = np.sqrt(expected * (1 - expected) / (p * lines_per_ring))
    bound = np.maximum(se, binomial)
    assert np.all(per_position.var(axis=0, ddof=1) <= expected * (1 - expected) * 1.5)
    assert np.all(np.abs(mean - expected) <= SIGMAS * bound), (mean, expected, bound)
    return bound


def test_analyser_rings_are_the_canopy_gap_probability_and_its_lai_the_canopys(sight):
    rng = np.random.default_rng(7)
    pos = [AnalyserPosition(*rng.uniform(0, SIDE, 2), heading_deg=float(rng.uniform(0, 360)))
           for _ in range(48)]
    r = read_analyser(sight, pos, rays_per_ring=400, seed=1)
    expected = np.array([ring_exact(lo, hi) for lo, hi in RING_EDGES_DEG])
    bound = check_rings(r.gap_fraction, expected, 400)
    # the above reading is the ring's solid angle (uniform sky), sampled exactly
    solid = [2 * math.pi * (math.cos(math.radians(lo)) - math.cos(math.radians(hi)))
             for lo, hi in RING_EDGES_DEG]
    assert np.allclose(r.above, solid, rtol=1e-12)
    # Miller's sum on the exact rings: the instrument's discretisation (ring averages, five
    # weights) is within 2 % of the canopy's LAI for this canopy
    lai_exact = miller_lai(expected)
    assert abs(lai_exact / LAI - 1) < 0.02
    # the measured LAI differs from it by the rings' sampling error, propagated
    dl = np.abs(2 * np.array([0.034, 0.104, 0.160, 0.218, 0.484]) *
                np.cos(np.radians(RING_CENTRES_DEG)) / expected)
    assert abs(r.lai - lai_exact) <= SIGMAS * math.sqrt(np.sum((dl * bound) ** 2))
    # spherical leaves: a mean tilt of 57.3 deg; the fit of five noisy contact numbers
    assert mean_tilt_deg(1.0) == pytest.approx(57.3, abs=0.1)
    assert abs(r.mta_deg - 57.3) < 10.0
    rec = r.as_dict()
    assert rec["instrument"] == "analyser" and len(rec["rings"]) == 5
    assert len(rec["positions"]) == 48


def test_a_view_cap_reads_its_sector_only(sight):
    rng = np.random.default_rng(0)
    for cap in (45.0, 90.0, 180.0, 270.0):
        d, zen = ring_directions(2, 500, 30.0, cap, rng)
        az = np.degrees(np.arctan2(d[:, 0], d[:, 1]))
        off = (az - 30.0 + 180.0) % 360.0 - 180.0
        assert np.all(np.abs(off) <= cap / 2 + 1e-9)
        assert np.all((zen >= 32.4) & (zen <= 43.4))
        assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    # in a homogeneous canopy a capped view sees the same gap probability
    pos = [AnalyserPosition(*rng.uniform(0, SIDE, 2), heading_deg=90.0) for _ in range(48)]
    r = read_analyser(sight, pos, view_cap_deg=90, rays_per_ring=300, seed=2)
    expected = np.array([ring_exact(lo, hi) for lo, hi in RING_EDGES_DEG])
    check_rings(r.gap_fraction, expected, 300)
    assert r.above == pytest.approx(np.array(
        [0.5 * math.pi * (math.cos(math.radians(lo)) - math.cos(math.radians(hi)))
         for lo, hi in RING_EDGES_DEG]), rel=1e-12)


def test_hemiphoto_ring_gap_fractions_are_the_canopy_gap_probability(sight, tmp_path):
    rng = np.random.default_rng(11)
    photos = [hemiphoto(sight, *rng.uniform(0, SIDE, 2), 0.0, size=96) for _ in range(40)]
    zen = photos[0].zenith_deg
    expected = np.array([gap_exact(zen[(zen >= lo) & (zen < hi)]).mean()
                         for lo, hi in RING_EDGES_DEG])
    per = np.array([ph.gap_fraction for ph in photos])
    check_rings(per, expected, int(photos[0].ring_pixels().min()))
    out = photos[0].save_png(tmp_path / "hemi.png")
    import matplotlib.image as mpimg

    img = mpimg.imread(out)
    assert img.shape[:2] == (96, 96)
    sky = photos[0].sky
    assert np.all(img[sky][:, :3] == 1.0)                       # sky white
    assert not np.any(np.all(img[~sky & (zen < 90)][:, :3] == 1.0, axis=1))
    rec = photos[0].as_dict()
    assert [r["ring"] for r in rec["rings"]] == [1, 2, 3, 4, 5]


def test_hemiphoto_above_the_canopy_is_all_sky_and_black_plants_without_colour(sight):
    top = hemiphoto(sight, 10.0, 10.0, sight.top + 1.0, size=32)
    assert top.openness == 1.0 and top.notes
    below = hemiphoto(sight, 10.0, 10.0, 0.0, size=48, colour=False)
    plant = ~below.sky & (below.zenith_deg < 90)
    assert plant.any() and np.all(below.image[plant] == 0)


@pytest.mark.parametrize("zenith, azimuth, height", [(0.0, 180.0, 0.0), (30.0, 180.0, 50.0),
                                                      (50.0, 120.0, 80.0), (60.0, 250.0, 0.0)])
def test_ceptometer_intercepts_what_the_engines_sensor_planes_do(canopy, zenith, azimuth,
                                                                  height):
    """Probes along the rows at the engine's sensor places (its grid at 1 sensor per cm2 over a
    20 x 80 cm rectangle, slid along the sun path as it slides it) intercept what the
    engine's transmission says; both are Embree's answers on the same paths, so they agree to
    within a grazing ray or two per thousand sensors."""
    engine = LightEngine(canopy, periodic=True)
    sun = Sun(zenith, azimuth)
    rect = (30.0, 20.0, 50.0, 100.0)
    t = engine.sun(sun, heights_cm=(height,), density=1.0, rect=rect,
                   classes=False).transmission[0]
    off = sensor_offsets(np.array([height]), sun.direction(canopy.layout.north_deg), rect,
                         1.0)[0]
    probes = [Probe(30.5 + i + off[0], 60.0 + off[1], height, probe_azimuth("along"))
              for i in range(20)]
    sight = Sight.of(canopy, periodic=True, scene=engine.scene(True))
    r = read_ceptometer(sight, probes, sun, beam_fraction=1.0, par_umol=1800.0)
    assert r.sensors_cm.shape == (20, 80, 3)
    assert abs(r.intercepted - (1.0 - t)) <= 2.0 / 1600
    assert np.all((r.par_umol == 0.0) | (r.par_umol == 1800.0))
    assert r.as_dict()["probes"][0]["sensors"] == 80


def test_ceptometer_sky_and_sun_readings_add_and_its_lai_is_near_the_canopys(sight):
    rng = np.random.default_rng(5)
    probes = [Probe(*rng.uniform(0, SIDE, 2), 0.0, probe_azimuth("across")) for _ in range(30)]
    sun = Sun(35.0, 160.0)
    beam = read_ceptometer(sight, probes, sun, beam_fraction=1.0)
    sky = read_ceptometer(sight, probes, sun, beam_fraction=0.0)
    mixed = read_ceptometer(sight, probes, sun, beam_fraction=0.6)
    assert mixed.tau == pytest.approx(0.6 * beam.tau + 0.4 * sky.tau, rel=1e-12)
    # the beam's transmission is the gap probability at the sun's zenith (2400 sensors)
    p = gap_exact(35.0)
    assert abs(beam.tau - p) <= SIGMAS * max(beam.tau_per_probe.std(ddof=1) / math.sqrt(30),
                                             math.sqrt(p * (1 - p) / 2400))
    # the LP-80's inversion of a beam's tau, fb = 1, spherical: -ln(tau) / (1.06 K A); with
    # a = 1 (nothing scattered, as here) A = 0.909, so on the exact tau it gives LAI / 0.963
    # (the equation's own fit), and on the measured one that within the sampling error
    a1 = 0.283 + 0.785 - 0.159
    assert lp80_lai(p, 35.0, 1.0, absorptivity=1.0) == pytest.approx(LAI / (1.06 * a1),
                                                                      rel=1e-3)
    assert lp80_lai(beam.tau, 35.0, 1.0, absorptivity=1.0) == pytest.approx(LAI, rel=0.1)


def test_lp80_inversion_by_hand():
    # Campbell's K: spherical 1 / (2 cos), horizontal leaves (x large) 1
    for z in (0.0, 30.0, 60.0):
        assert extinction_ellipsoidal(z, 1.0) == pytest.approx(0.5 / math.cos(math.radians(z)),
                                                               rel=1e-3)
    assert extinction_ellipsoidal(40.0, 1e4) == pytest.approx(1.0, rel=1e-3)
    # the manual's equation, evaluated by hand: tau 0.2, zenith 30, fb 0.7, x 1, a 0.9
    k = math.sqrt(1 + math.tan(math.radians(30)) ** 2) / (1 + 1.774 * 2.182 ** -0.733)
    a = 0.283 + 0.785 * 0.9 - 0.159 * 0.81
    want = ((1 - 1 / (2 * k)) * 0.7 - 1) * math.log(0.2) / (a * (1 - 0.47 * 0.7))
    assert lp80_lai(0.2, 30.0, 0.7) == pytest.approx(want, rel=1e-12)
    assert lp80_lai(1.0, 30.0, 0.7) == 0.0
    assert lp80_lai(0.0, 30.0, 0.7) == math.inf


@pytest.mark.parametrize("make, words", [
    (lambda s: read_analyser(s, [AnalyserPosition(1, 1)], view_cap_deg=100), "view cap"),
    (lambda s: read_analyser(s, [], rays_per_ring=10), "position"),
    (lambda s: Probe(0, 0, spacing_cm=0), "spacing"),
    (lambda s: Probe(0, 0, height_cm=-1), "height"),
    (lambda s: probe_azimuth("diagonal"), "orientation"),
    (lambda s: hemiphoto(s, 0, 0, size=3), "size"),
    (lambda s: hemiphoto(s, 0, 0, rings=[(30, 20)]), "ring"),
    (lambda s: read_ceptometer(s, [Probe(0, 0)], Sun(30, 180), beam_fraction=1.5), "beam"),
    (lambda s: lp80_lai(0.5, 30.0, 0.5, x=0.0), "parameter x"),
])
def test_bad_settings_are_one_line_naming_them(sight, make, words):
    with pytest.raises(MaizevizError) as info:
        make(sight)
    msg = str(info.value)
    assert words in msg and "\n" not in msg


def test_an_instrument_off_an_open_plot_says_so(canopy):
    """A place typed in mm or m lands beside the field: the reading is the open sky's, and it
    was given without a word (tau 1, LAI 0)."""
    open_field = Sight.of(canopy, periodic=False)
    far = 10 * SIDE
    cep = read_ceptometer(open_field, [Probe(far, far)], Sun(30, 180))
    assert cep.tau == 1.0 and any("outside the plot" in n for n in cep.notes)
    ana = read_analyser(open_field, [AnalyserPosition(far, 50.0)], rays_per_ring=50)
    assert any("position 1" in n and "outside the plot" in n for n in ana.notes)
    photo = hemiphoto(open_field, 50.0, -far, 0.0, size=16)
    assert any("outside the plot" in n for n in photo.notes)
    inside = read_ceptometer(open_field, [Probe(SIDE / 2, SIDE / 2)], Sun(30, 180))
    assert not any("outside" in n for n in inside.notes)
    periodic = read_ceptometer(Sight.of(canopy, periodic=True), [Probe(far, far)], Sun(30, 180))
    assert not any("outside" in n for n in periodic.notes)       # the plot repeats there


def test_a_ring_that_sees_no_sky_is_named_beside_its_infinite_lai(sight):
    """A ring that saw no gap made LAI inf with no note saying why. One line of sight a ring
    under LAI 2 finds leaves in the low rings (gap about exp(-1 / cos 68 deg) = 0.07 in
    ring 5); 2000 find gaps in every ring."""
    one = read_analyser(sight, [AnalyserPosition(SIDE / 2, SIDE / 2)], rays_per_ring=1)
    closed = [i + 1 for i in range(5) if one.transmission[i] == 0]
    named = [n for n in one.notes if "saw no sky" in n]
    assert closed and math.isinf(one.lai) and len(named) == 1
    assert all(f"{i} (" in named[0] for i in closed)
    many = read_analyser(sight, [AnalyserPosition(SIDE / 2, SIDE / 2)])
    assert math.isfinite(many.lai) and not any("saw no sky" in n for n in many.notes)
