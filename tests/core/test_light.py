"""Direct light through real Embree: analytic scenes, Beer-Lambert, bad requests, the CLI."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.layout import layout_from_dict
from maizeviz.cli import EXIT_FAIL, EXIT_OK, main
from maizeviz.errors import MaizevizError
from maizeviz.light.report.beer_lambert import beer_lambert
from maizeviz.light.report.heatmap import transmission_map
from maizeviz.light.scene.rays import ray_grid
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.sources.sun import Sun, sun_at
from maizeviz.light.trace.beam import trace_light

BLOCK = str(Path(__file__).resolve().parents[2] / "maizeviz/resources/block3x3.csv")


def plot(x0=0, y0=0, x1=100, y1=100):
    return layout_from_dict({"maizeviz_layout": 1, "row_spacing": 60, "plant_spacing": 30,
                             "field": {"x0": x0, "y0": y0, "x1": x1, "y1": y1},
                             "rows": [{"x": (x0 + x1) / 2, "plants": [{"y": (y0 + y1) / 2,
                                                                        "plant": 1}]}]})


def squares(specs):
    """Horizontal squares (x0, y0, size, z) -> vertices, faces (2 triangles each, upper face up)."""
    v, f = [], []
    for k, (x, y, a, z) in enumerate(specs):
        v += [[x, y, z], [x + a, y, z], [x + a, y + a, z], [x, y + a, z]]
        f += [[4 * k, 4 * k + 1, 4 * k + 2], [4 * k, 4 * k + 2, 4 * k + 3]]
    return np.array(v, float), np.array(f)


def canopy_of(specs, layout=None):
    v, f = squares(specs)
    leaf = np.repeat(np.arange(1, len(specs) + 1), 2)
    return Canopy.from_triangles(v, f, layout or plot(), leaf)


def test_vertical_sun_shades_exactly_the_overlap():
    c = canopy_of([(30, 40, 20, 80)])                      # 20 x 20 cm leaf at 80 cm
    # overlap: x 30..50, y 40..60 = 400
    req = LightRequest(Sun(0, 0),
                       Sampling(heights_cm=(0, 50, 79.9, 80.1, 100), density=4, rect=(20, 20, 60, 60)))
    r = trace_light(c, req)
    expect = 1 - 400 / 1600
    assert r.transmission[0] == pytest.approx(expect, abs=1e-12)
    assert r.transmission[:3] == pytest.approx([expect] * 3, abs=1e-12)
    assert list(r.transmission[3:]) == [1.0, 1.0]
    rows = r.leaf_rows(c)
    assert rows[0]["sunlit_area_cm2"] == pytest.approx(400, rel=1e-9)
    assert rows[0]["second_class_area_cm2"] == 0


def test_45_degree_sun_shifts_the_shadow():
    # sun from the east (azimuth 90) at 45 deg: the shadow of a leaf at 30 cm falls 30 cm west
    c = canopy_of([(60, 40, 20, 30)])
    r = trace_light(c, LightRequest(Sun(45, 90),
                                    Sampling(heights_cm=(0,), density=16, rect=(20, 30, 60, 70))))
    # shadow x 30..50, y 40..60, fully inside the 40 x 40 rectangle
    assert r.transmission[0] == pytest.approx(1 - 400 / 1600, abs=2e-3)
    # a rectangle east of the shadow sees full sun
    r2 = trace_light(c, LightRequest(Sun(45, 90),
                                     Sampling(heights_cm=(0,), density=16, rect=(52, 30, 90, 70))))
    assert r2.transmission[0] == 1.0


def test_stacked_leaves_direct_and_second_class_areas():
    c = canopy_of([(20, 20, 40, 100), (30, 30, 40, 60), (10, 10, 10, 20)])
    r = trace_light(c, LightRequest(Sun(0, 0),
                                    Sampling(heights_cm=(0,), density=4, rect=(0, 0, 100, 100))))
    rows = {row["leaf"]: row for row in r.leaf_rows(c)}
    assert rows[1]["sunlit_area_cm2"] == pytest.approx(1600, rel=1e-9)        # top: all direct
    assert rows[1]["second_class_area_cm2"] == 0
    # middle: 30..70 overlaps the top 20..60 over 30 x 30 -> 900 second class, 700 direct
    assert rows[2]["sunlit_area_cm2"] == pytest.approx(700, rel=1e-9)
    assert rows[2]["second_class_area_cm2"] == pytest.approx(900, rel=1e-9)
    assert rows[3]["sunlit_area_cm2"] == pytest.approx(100, rel=1e-9)
    assert r.transmission[0] == pytest.approx(1 - (1600 + 700 + 100) / 10000, abs=1e-12)


def test_tilted_leaf_sunlit_area_is_its_surface_area():
    # a 20 x 20 leaf tilted 60 deg about the x axis, vertical sun: lit area = the leaf's area
    t = math.radians(60)
    v = np.array([[40, 40, 50], [60, 40, 50], [60, 40 + 20 * math.cos(t), 50 + 20 * math.sin(t)],
                  [40, 40 + 20 * math.cos(t), 50 + 20 * math.sin(t)]])
    c = Canopy.from_triangles(v, np.array([[0, 1, 2], [0, 2, 3]]), plot(), np.array([1, 1]))
    r = trace_light(c, LightRequest(Sun(0, 0),
                                    Sampling(heights_cm=(0,), density=25, rect=(30, 30, 70, 70))))
    row = r.leaf_rows(c)[0]
    assert row["sunlit_area_cm2"] == pytest.approx(400, rel=0.02)
    assert row["sunlit_intercepted_cm2"] == pytest.approx(200, rel=0.02)   # its shadow


@pytest.mark.parametrize("lai", [0.5, 2.0, 4.0])
def test_random_horizontal_leaves_transmit_exp_minus_lai(lai):
    rng = np.random.default_rng(int(lai * 10))
    side, a = 300.0, 6.0
    # centres uniform over the plot extended by a leaf, so density is uniform inside
    n = int(round(lai * (side + a) ** 2 / a**2))
    xy = rng.uniform(-a, side, (n, 2))
    z = rng.uniform(10, 200, n)
    c = canopy_of([(x, y, a, h) for (x, y), h in zip(xy, z)], plot(0, 0, side, side))
    r = trace_light(c, LightRequest(Sun(0, 0),
                                    Sampling(heights_cm=(0, 105), density=1, rect=(0, 0, side, side))))
    assert r.transmission[0] == pytest.approx(math.exp(-lai), abs=0.02)
    # half the leaves lie above 105 cm: T(105) ~ exp(-lai * 95 / 190)
    assert r.transmission[1] == pytest.approx(math.exp(-lai * 95 / 190), abs=0.03)


def test_single_leaf_sensor_planes_are_exact_at_every_height():
    """The issue's case: a leaf at 100 cm over x 50..150, a 45 deg sun from the east, the
    rectangle x 0..100 under the leaf's west half. At height h the shadow covers x h-50..h+50,
    so T(h) = 1 - overlap / 100: 0.5 on the ground, 0 at 50 cm, 1 above the leaf. Rays landing
    on the ground rectangle (version 0.1) say 0.5 at every height below the leaf."""
    v = np.array([[50, -20, 100], [150, -20, 100], [150, 120, 100], [50, 120, 100]], float)
    c = Canopy.from_triangles(v, np.array([[0, 1, 2], [0, 2, 3]]), plot(-200, -50, 300, 150),
                              np.array([1, 1]))
    heights = tuple(float(h) for h in range(0, 100, 5)) + (100.5, 130.0)
    for density in (1.0, 4.0):
        r = trace_light(c, LightRequest(Sun(45, 90),
                                        Sampling(heights, density, rect=(0, 20, 100, 80))))
        expect = [1 - (min(h + 50, 100) - max(h - 50, 0)) / 100 if h < 100 else 1.0
                  for h in heights]
        assert r.transmission == pytest.approx(expect, abs=1e-12), density
        k50 = heights.index(50.0)
        assert r.transmission[k50] == 0.0
        assert np.mean(r.first_z < 50) == pytest.approx(0.5, abs=1e-12)   # the old sampling
        # the map at 50 cm is the rectangle's own x, y: all of it dark
        m = transmission_map(r, 50.0, 10.0)
        assert m.x_edges[0] == 0 and m.x_edges[-1] == 100 and np.all(m.transmission == 0)
        g = transmission_map(r, 0.0, 10.0)
        assert np.all(g.transmission[:5] == 0) and np.all(g.transmission[5:] == 1)   # x < 50 dark


def _random_squares(seed, n=60):
    rng = np.random.default_rng(seed)
    return canopy_of([(x, y, s, h) for x, y, s, h in zip(
        rng.uniform(0, 90, n), rng.uniform(0, 90, n), rng.uniform(2, 15, n),
        rng.uniform(5, 150, n))])


@settings(max_examples=12, deadline=None)
@given(st.integers(0, 2**31), st.floats(0, 30), st.floats(0, 30), st.floats(31, 100),
       st.floats(31, 100), st.booleans(), st.sampled_from([0.7, 1.0, 2.3]))
def test_vertical_sun_transmission_never_increases_downward(seed, x0, y0, x1, y1, periodic,
                                                            density):
    """Under a vertical sun each sensor's path contains the path of the sensor above it: on any
    rectangle T is monotone exactly, and 1 above the canopy."""
    heights = tuple(np.sort(np.random.default_rng(seed).uniform(0, 200, 10)))
    r = trace_light(_random_squares(seed), LightRequest(Sun(0, 0),
                                                        Sampling(heights, density, (x0, y0, x1, y1), periodic),
                                                        classes=False))
    t = r.transmission
    assert np.all((0 <= t) & (t <= 1))
    assert np.all(np.diff(t) >= 0), "transmission increased going down"
    assert np.all(t[np.asarray(heights) > 150 + 15] == 1.0)


@settings(max_examples=15, deadline=None)
@given(st.floats(0, 70), st.floats(0, 360), st.integers(0, 2**31),
       st.sampled_from([0.7, 1.0, 2.3]))
def test_periodic_field_transmission_never_increases_downward(zenith, azimuth, seed, density):
    """In a periodic field sampled over its whole period every height's grid lies on the sun
    paths of the others (sensor_offsets), so T is monotone as in the continuum, at any sun."""
    heights = tuple(np.sort(np.random.default_rng(seed).uniform(0, 200, 10)))
    r = trace_light(_random_squares(seed), LightRequest(Sun(zenith, azimuth),
                                                        Sampling(heights, density, (0, 0, 100, 100), True),
                                                        classes=False))
    t = r.transmission
    assert np.all((0 <= t) & (t <= 1))
    assert np.all(np.diff(t) >= 0), "transmission increased going down"
    assert np.all(t[np.asarray(heights) > 150 + 15] == 1.0)


def test_sensor_planes_outside_a_periodic_period_can_rise_downward():
    """Not a bug: below a leaf whose shadow leaves the rectangle lower down, the lower plane is
    brighter (the single-leaf case); only periodic full-period sampling is monotone."""
    v = np.array([[50, -20, 100], [150, -20, 100], [150, 120, 100], [50, 120, 100]], float)
    c = Canopy.from_triangles(v, np.array([[0, 1, 2], [0, 2, 3]]), plot(-200, -50, 300, 150),
                              np.array([1, 1]))
    r = trace_light(c, LightRequest(Sun(45, 90), Sampling((0, 50), 1, rect=(0, 20, 100, 80))))
    assert r.transmission[0] > r.transmission[1]


def test_periodic_field_stops_rays_that_leave_the_plot():
    rng = np.random.default_rng(3)
    n = 400
    specs = [(x, y, 8, h) for x, y, h in zip(rng.uniform(-8, 100, n), rng.uniform(-8, 100, n),
                                             rng.uniform(5, 150, n))]
    c = canopy_of(specs)
    low = Sun(65, 180)
    open_ = trace_light(c, LightRequest(low, Sampling((0,), 1, (30, 30, 70, 70), periodic=False)))
    wrapped = trace_light(c, LightRequest(low, Sampling((0,), 1, (30, 30, 70, 70), periodic=True)))
    assert any("overestimated" in w for w in open_.warnings)
    assert not wrapped.warnings
    assert wrapped.transmission[0] < 0.5 * open_.transmission[0]


@pytest.mark.parametrize("azimuth", [90.0, 270.0, 0.0, 180.0])
def test_periodic_rays_wrap_in_every_direction(azimuth):
    """A horizontal strip over half of a periodic plot, low sun: T(0) is exactly one half,
    whichever plot edge the rays leave by (rays stuck on an edge would count as sunlit)."""
    along_x = azimuth in (90.0, 270.0)
    v = np.array([[0, 0, 10], [50, 0, 10], [50, 100, 10], [0, 100, 10]], float)
    if not along_x:
        v = v[:, [1, 0, 2]]
    c = Canopy.from_triangles(v, np.array([[0, 1, 2], [0, 2, 3]]), plot(), np.array([1, 1]))
    r = trace_light(c, LightRequest(Sun(80, azimuth),
                                    Sampling((0,), 1, (0, 0, 100, 100), periodic=True)))
    assert r.transmission[0] == pytest.approx(0.5, abs=0.011)


def test_beer_lambert_from_mesh():
    c = canopy_of([(0, 0, 50, 100), (50, 50, 50, 20)])
    bl = beer_lambert(c, Sun(0, 0), [0, 50, 150])
    assert bl.G == pytest.approx(1.0)
    assert bl.lai_above == pytest.approx([0.5, 0.25, 0.0])
    assert bl.transmission == pytest.approx(np.exp(-bl.lai_above))


def test_sun_from_pvlib_beijing():
    s = sun_at("2005-08-01", "12:00", 39.9, 116.4, "Asia/Shanghai")
    assert s.zenith_deg == pytest.approx(22.35, abs=0.02)
    assert s.azimuth_deg == pytest.approx(166.95, abs=0.02)
    noon = sun_at("2005-08-01", None, 39.9, 116.4, "Asia/Shanghai", solar_noon=True)
    assert noon.azimuth_deg == pytest.approx(180, abs=0.01)
    assert "12:20:4" in noon.when
    d = Sun(30, 90).direction()
    assert d == pytest.approx([0.5, 0, math.cos(math.radians(30))])
    assert Sun(30, 90).direction(north_deg=90) == pytest.approx([0, 0.5, math.cos(math.radians(30))])


@pytest.mark.parametrize("make, match", [
    (lambda: Sun(95, 0), "below the horizon"),
    (lambda: sun_at("2005-08-01", "23:00", 39.9, 116.4, "Asia/Shanghai"), "below the horizon"),
    # no zone: the clock is UTC, Beijing's noon is its night; the error names the zone
    (lambda: sun_at("2005-08-01", "12:00", 39.9, 116.4), "read as UTC, as no time zone"),
    # an offset written after the time is a zone: no UTC hint then
    (lambda: sun_at("2005-08-01", "12:00-05:00", 39.9, 116.4), "at 2005-08-01T12:00:00-05:00: no direct light"),
    (lambda: sun_at("2005-13-01", "12:00", 39.9, 116.4, "UTC"), "YYYY-MM-DD"),
    (lambda: sun_at("2005-08-01", "12:00", 39.9, 116.4, "Mars/Olympus"), "time zone"),
    (lambda: sun_at("2005-08-01", "12:00", 99, 116.4, "UTC"), "latitude"),
])
def test_bad_suns(make, match):
    with pytest.raises(MaizevizError, match=match):
        make()


@pytest.mark.parametrize("req, match", [
    (dict(rect=(200, 200, 300, 300)), "not inside the plot"),
    (dict(rect=(50, 50, 40, 60)), "x1 > x0"),
    (dict(density=0), "density must be > 0"),
    (dict(density=1e7), "rays.*limit"),
    (dict(heights_cm=(-5,)), "heights must be from 0 to"),
    (dict(heights_cm=(1e308,)), "heights must be from 0 to 10,000 cm"),
    (dict(heights_cm=()), "at least one height"),
])
def test_bad_requests(req, match):
    c = canopy_of([(30, 40, 20, 80)])
    base = dict(heights_cm=(0,), density=1, rect=(10, 10, 90, 90))
    base.update(req)
    with pytest.raises(MaizevizError, match=match):
        trace_light(c, LightRequest(Sun(10, 0), Sampling(**base)))


def test_heights_above_canopy_fine_and_empty_canopy_refused():
    c = canopy_of([(30, 40, 20, 80)])
    r = trace_light(c, LightRequest(Sun(10, 0), Sampling((0, 500), 1, (10, 10, 90, 90))))
    assert r.transmission[1] == 1.0 and any("above the canopy top" in w for w in r.warnings)
    empty = Canopy.from_triangles(np.zeros((0, 3)), np.zeros((0, 3), int), plot(), np.zeros(0))
    with pytest.raises(MaizevizError, match="empty"):
        trace_light(empty, LightRequest(Sun(10, 0)))


def test_threads_give_the_same_answer_and_cancel_works(monkeypatch):
    import maizeviz.light.trace.beam as tr
    monkeypatch.setattr(tr, "CHUNK", 1000)
    rng = np.random.default_rng(1)
    c = canopy_of([(x, y, 10, h) for x, y, h in zip(rng.uniform(0, 90, 80), rng.uniform(0, 90, 80),
                                                    rng.uniform(5, 150, 80))])
    req = dict(heights_cm=(0, 50, 100), density=4, rect=(0, 0, 100, 100))
    one = trace_light(c, LightRequest(Sun(30, 200), Sampling(**req, threads=1)))
    two = trace_light(c, LightRequest(Sun(30, 200), Sampling(**req, threads=2)))
    assert np.array_equal(one.transmission, two.transmission)
    assert np.array_equal(one.first_hits, two.first_hits)
    seen = []
    with pytest.raises(InterruptedError):
        trace_light(c, LightRequest(Sun(30, 200), Sampling(**req)), progress=lambda d, t: seen.append(d) or d < 3)
    assert seen[-1] == 3


def test_ray_grid_density():
    pts, cell = ray_grid((0, 0, 180, 90), 4)
    assert len(pts) == 180 * 90 * 4 and cell == pytest.approx(0.25)


def test_cli_light_json_heatmaps_and_csv(tmp_path, capsys):
    out = tmp_path / "maps"
    leafcsv, plantcsv = tmp_path / "leaf.csv", tmp_path / "plant.csv"
    code = main(["light", BLOCK, "--tile", "3x3", "--triangles", "36", "--date", "2005-08-01",
                 "--time", "12:00", "--lat", "39.9", "--lon", "116.4", "--tz", "Asia/Shanghai",
                 "--heights", "0,100,225", "--density", "1", "--json", "--heatmaps", str(out),
                 "--check", "--periodic", "--leaf-light", str(leafcsv), "--plant-light",
                 str(plantcsv)])
    cap = capsys.readouterr()
    assert code == EXIT_OK, cap.err
    assert "sun: zenith 22.3" in cap.err
    data = json.loads(cap.out)
    assert data["sun"]["zenith_deg"] == pytest.approx(22.35, abs=0.02)
    t = data["transmission"]
    assert 0.02 < t[0] < 0.12 and t[0] <= t[1] <= t[2] <= 1
    assert data["rays"] == 180 * 90
    assert set(data["seconds"]) >= {"scene", "trace"}
    assert len(data["beer_lambert"]["transmission"]) == 3
    pngs = sorted(out.glob("*.png"))
    assert len(pngs) == 3 and all(p.stat().st_size > 10_000 for p in pngs)
    rows = (out / "transmission_36_triangles_h0cm.csv").read_text().splitlines()
    assert rows[0].startswith("x_cm,y_cm,height_cm,transmission,rays") and len(rows) == 36 * 18 + 1
    leaf_lines = leafcsv.read_text().splitlines()
    assert "sunlit_area_cm2" in leaf_lines[0] and len(leaf_lines) > 20
    assert "leaves_lit" in plantcsv.read_text().splitlines()[0]


def test_cli_light_levels_and_explicit_sun(capsys):
    code = main(["light", BLOCK, "--tile", "3x3", "--sun-zenith", "30", "--sun-azimuth", "180",
                 "--levels", "standard,36,4", "--density", "0.5", "--heights", "0,150"])
    out = capsys.readouterr().out
    assert code == EXIT_OK
    assert "standard" in out and "36 triangles" in out and "4 triangles" in out
    assert "trace s" in out


@pytest.mark.parametrize("argv, says", [
    (["--sun-zenith", "95", "--sun-azimuth", "0"], "below the horizon"),
    (["--sun-zenith", "30"], "both"),
    ([], "where is the sun"),
    (["--sun-zenith", "30", "--sun-azimuth", "0", "--date", "2005-08-01"], "not both"),
    (["--sun-zenith", "30", "--sun-azimuth", "0", "--density", "0"], "density"),
    (["--sun-zenith", "30", "--sun-azimuth", "0", "--rect", "1,2,3"], "needs 4 numbers, got '1,2,3' (--rect)"),
    (["--sun-zenith", "30", "--sun-azimuth", "0", "--rect", "900,0,1000,50"], "not inside"),
    (["--sun-zenith", "30", "--sun-azimuth", "0", "--heights", "0,abc"], "--heights"),
    (["--date", "2005-08-01", "--time", "23:30", "--lat", "39.9", "--lon", "116.4", "--tz",
      "Asia/Shanghai"], "below the horizon"),
])
def test_cli_light_bad_input(capsys, argv, says):
    assert main(["light", BLOCK, *argv]) == EXIT_FAIL
    err = capsys.readouterr().err
    assert says in err and "Traceback" not in err


@pytest.mark.parametrize("periodic", [False, True])
def test_occlusion_queries_agree_with_nearest_hits(periodic):
    """The tracer's occlusion mode (sensor planes) and its nearest-hit mode (ground rays) see
    the same triangles along the same paths, wrapped or not."""
    from maizeviz.light.scene.embree_scenes import light_scene
    from maizeviz.light.scene.rays import Tracer

    c = _random_squares(7, n=120)
    scene = light_scene(c)
    rng = np.random.default_rng(7)
    for zenith, azimuth in ((0, 0), (40, 75), (75, 200), (85, 310)):
        s = Sun(zenith, azimuth).direction()
        org = np.column_stack([rng.uniform(0, 100, 3000), rng.uniform(0, 100, 3000),
                               rng.uniform(0, 160, 3000)])
        length = rng.uniform(0, 600, 3000)
        up = Tracer(scene, s, c.layout.bounds, periodic, 3000)
        blocked = up.occluded(org.copy(), length)
        _, dist = up.trace(org.copy(), length, ids=True)
        assert np.mean(blocked == np.isfinite(dist)) > 0.999
        assert blocked.any() and not blocked.all()


@pytest.mark.parametrize("periodic", [False, True])
def test_sensor_planes_by_occlusion_and_by_the_ray_family_agree(monkeypatch, periodic):
    """A sensor's path to the sun is asked either as an occlusion query or as the first hit of
    the ray of the same family through it; both give the same planes."""
    import maizeviz.light.trace.beam as tr

    c = _random_squares(9, n=150)
    heights = (0.0, 20.0, 55.5, 100.0, 140.0, 400.0)
    for zenith, azimuth in ((0, 0), (25, 160), (55, 300), (78, 45)):
        req = LightRequest(Sun(zenith, azimuth), Sampling(heights, 2.0, (10, 5, 90, 95), periodic))
        results = []
        for cost in (1e-9, 1e9):                    # never / always the ray family
            monkeypatch.setattr(tr, "OCCLUSION_COST", cost)
            results.append(trace_light(c, req))
        occ, fam = results
        assert np.abs(occ.transmission - fam.transmission).max() <= 2 / occ.rays
        for k in range(len(heights)):
            assert np.mean(occ.lit(k) != fam.lit(k)) <= 2 / occ.rays
        assert np.array_equal(occ.first_hits, fam.first_hits)


def test_a_rectangle_of_whole_periods_answers_every_plane_by_its_ground_rays(monkeypatch):
    """In a periodic field, a sample rectangle spanning whole periods needs no query of its own
    for any sensor: the family ray through a sensor is one of the rectangle's ground rays
    moved by whole periods. The same sensors, ray for ray, as the family's box; within 2 rays
    of a query per sensor (a path asked from its two ends); the same first and second hits."""
    import maizeviz.light.trace.beam as tr

    calls = {"occluded": 0}
    occluded = tr.Tracer.occluded

    def count_occluded(self, *a, **k):
        calls["occluded"] += 1
        return occluded(self, *a, **k)

    monkeypatch.setattr(tr.Tracer, "occluded", count_occluded)
    c = _random_squares(4, n=150)                     # leaves overhang the 100 cm plot's edges
    rect = c.layout.bounds                           # the plot: the periodic field's period
    heights = (0.0, 20.0, 55.5, 100.0, 140.0, 400.0)
    for zenith, azimuth in ((0, 0), (25, 160), (55, 300), (78, 45), (86, 200)):
        req = LightRequest(Sun(zenith, azimuth), Sampling(heights, 2.0, rect, periodic=True))
        runs = []
        for wrap, cost in ((True, 0.7), (False, 1e9), (False, 1e-9)):
            monkeypatch.setattr(tr, "WRAP_FAMILY", wrap)
            monkeypatch.setattr(tr, "OCCLUSION_COST", cost)
            calls.update(occluded=0)
            runs.append(trace_light(c, req))
            if wrap:
                assert calls["occluded"] == 0, "a sensor was asked on its own"
        periods, box, occ = runs
        assert 0 < periods.transmission[1] < 1
        for k in range(len(heights)):
            assert np.array_equal(periods.lit(k), box.lit(k)), (zenith, k)
            assert np.mean(periods.lit(k) != occ.lit(k)) <= 2 / occ.rays
        assert np.array_equal(periods.transmission, box.transmission)
        assert np.array_equal(periods.first_hits, box.first_hits)
        assert np.array_equal(periods.second_hits, box.second_hits)


def test_a_leaf_overhanging_a_periodic_plot_shades_the_opposite_edge():
    """A leaf hanging 20 cm over the east edge of a periodic 100 cm plot stands, in the
    infinite field, 20 cm inside its west edge too: its light is counted on the leaf itself."""
    from maizeviz.light.scene.embree_scenes import light_scene

    c = canopy_of([(90, 40, 30, 50)])                       # x 90..120 over the edge at 100
    req = LightRequest(Sun(0, 0), Sampling((0, 60), 4, (0, 0, 100, 100), periodic=True))
    r = trace_light(c, req)
    assert r.transmission[0] == pytest.approx(1 - 900 / 10000, abs=1e-12)
    m = transmission_map(r, 0.0, 10.0)
    assert np.all(m.transmission[[0, 1, 9], 4:7] == 0)      # x 0..20 and 90..100 shaded
    assert len(r.first_hits) == c.n_triangles
    rows = r.leaf_rows(c)
    assert rows[0]["sunlit_area_cm2"] == pytest.approx(900, rel=1e-9)
    # an open field has no such copy; a scene built for one is said to miss the overhang
    assert trace_light(c, LightRequest(Sun(0, 0),
                                       Sampling((0,), 4, (0, 0, 100, 100)))).transmission[0] \
        == pytest.approx(1 - 300 / 10000, abs=1e-12)
    plain = trace_light(c, req, scene=light_scene(c))
    assert any("overhanging" in w for w in plain.warnings)
    with pytest.raises(MaizevizError, match="cannot trace an open field"):
        trace_light(c, LightRequest(Sun(0, 0), Sampling((0,), 4, (0, 0, 100, 100))),
                    scene=light_scene(c, periodic=True))
