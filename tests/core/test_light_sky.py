"""Diffuse light through real Embree: random canopies against their analytic transmission,
sky weights, the shared scene, progress and cancellation.

Tolerances were measured on these scenes (3 seeds each, L = 1 and 3, 2 cm and 5 cm leaves in a
periodic 200 x 200 cm plot, 0.25 sensors per cm2) and rounded up by about half:

- horizontal leaves, both skies, 46 directions: |T / exp(-L) - 1| <= 0.015 measured -> 0.03;
- spherical leaves, direct sun at 0, 30, 60 deg: |T / exp(-0.5 L / cos) - 1| <= 0.042 -> 0.06;
- spherical leaves, uniform sky, 46 directions: |T / analytic - 1| <= 0.017 -> 0.03 (it holds
  the turtle's own discretisation error, 0.016 at most in test_sky.py); against Beer-Lambert
  over the same 46 directions with G_i and L from the mesh, <= 0.013 -> 0.03.

The leaves near the plot edge overhang it; the periodic scene (light_scene(periodic=True))
copies the overhangs to the opposite side, so these cases also check that wrapping.
"""

import math

import numpy as np
import pytest

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.layout import layout_from_dict
from maizeviz.errors import MaizevizError
from maizeviz.light.report.beer_lambert import beer_lambert_sky
from maizeviz.light.scene.embree_scenes import light_scene
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.sources.sky import analytic_diffuse_transmission, make_sky
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.beam import trace_light
from maizeviz.light.trace.directions import trace_sky

SIDE = 200.0


def plot(x0=0.0, y0=0.0, x1=100.0, y1=100.0):
    return layout_from_dict({"maizeviz_layout": 1, "row_spacing": 60, "plant_spacing": 30,
                             "field": {"x0": x0, "y0": y0, "x1": x1, "y1": y1},
                             "rows": [{"x": (x0 + x1) / 2, "plants": [{"y": (y0 + y1) / 2,
                                                                        "plant": 1}]}]})


def squares(centres, normals, size):
    """Square leaves (centres (n, 3) cm, unit normals (n, 3), edge ``size`` cm): vertices
    (4n, 3), faces (2n, 3). Leaves near the plot edge overhang it; the periodic scene copies
    the overhang to the opposite side."""
    helper = np.where(np.abs(normals[:, [2]]) < 0.9, [[0.0, 0, 1]], [[1.0, 0, 0]])
    a = np.cross(normals, helper)
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(normals, a)
    h = size / 2
    corners = np.stack([centres - h * a - h * b, centres + h * a - h * b,
                        centres + h * a + h * b, centres - h * a + h * b], 1)
    k = np.arange(len(corners))[:, None] * 4
    return corners.reshape(-1, 3), np.concatenate([k + [0, 1, 2], k + [0, 2, 3]])


def random_leaves(lai, size, seed, spherical, side=SIDE, z=(10.0, 150.0)):
    """Leaves of total leaf area index ``lai`` scattered uniformly over a side x side plot (to
    be traced as a periodic field): horizontal, or with normals uniform on the sphere (the
    spherical leaf angle distribution)."""
    rng = np.random.default_rng(seed)
    n = int(round(lai * side * side / size ** 2))
    centres = np.column_stack([rng.uniform(0, side, n), rng.uniform(0, side, n),
                               rng.uniform(*z, n)])
    if spherical:
        normals = rng.normal(size=(n, 3))
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    else:
        normals = np.tile([0.0, 0.0, 1.0], (n, 1))
    v, f = squares(centres, normals, size)
    return Canopy.from_triangles(v, f, plot(0, 0, side, side), np.ones(len(f), np.int32))


def whole_plot(heights=(0.0,), density=0.25, threads=2):
    return Sampling(heights, density, (0, 0, SIDE, SIDE), True, threads)


@pytest.mark.parametrize("lai", [1.0, 3.0])
def test_random_horizontal_leaves_transmit_exp_minus_lai_under_both_skies(lai):
    c = random_leaves(lai, 5.0, seed=1, spherical=False)
    scene = light_scene(c, periodic=True)
    for kind in ("soc", "uoc"):
        sky = trace_sky(c, make_sky(kind, 46), whole_plot(), scene=scene)
        assert sky.transmission[0] == pytest.approx(math.exp(-lai), rel=0.03), kind
        # every direction alike for horizontal leaves, up to the noise of one realisation of
        # the leaves seen along one direction (18 % at most measured at L = 3)
        assert np.all(np.abs(sky.per_direction[:, 0] / math.exp(-lai) - 1) < 0.3)


@pytest.mark.parametrize("lai", [1.0, 3.0])
def test_spherical_leaves_direct_and_uniform_sky_match_the_turbid_medium(lai):
    c = random_leaves(lai, 2.0, seed=0, spherical=True)
    scene = light_scene(c, periodic=True)
    for zenith in (0.0, 30.0, 60.0):
        r = trace_light(c, LightRequest(Sun(zenith, 37.0),
                                        Sampling((0.0,), 0.25, (0, 0, SIDE, SIDE), True, 2),
                                        classes=False), scene=scene)
        expect = math.exp(-0.5 * lai / math.cos(math.radians(zenith)))
        assert r.transmission[0] == pytest.approx(expect, rel=0.06), zenith
    sky = trace_sky(c, make_sky("uoc", 46), whole_plot(), scene=scene)
    assert sky.transmission[0] == pytest.approx(analytic_diffuse_transmission(lai, "uoc"),
                                                rel=0.03)
    # Beer-Lambert under the same 46 directions, G_i and L from this mesh (G_i about 0.5)
    bl = beer_lambert_sky(c, sky.sky, (0.0,))
    assert bl.G == pytest.approx(0.5, abs=0.01) and bl.lai_above[0] == pytest.approx(lai)
    assert sky.transmission[0] == pytest.approx(bl.transmission[0], rel=0.03)


def test_sky_result_is_the_weighted_sum_of_its_directions():
    c = random_leaves(2.0, 5.0, seed=3, spherical=True, side=100.0)
    sky = make_sky("soc", 16)
    assert math.fsum(sky.weights) == 1.0
    res = trace_sky(c, sky, Sampling((0.0, 80.0, 200.0), 0.5, (0, 0, 100, 100), True, 1))
    assert res.per_direction.shape == (16, 3)
    for k in range(3):
        assert res.transmission[k] == pytest.approx(math.fsum(sky.weights * res.per_direction[:, k]),
                                                    abs=1e-15)
    assert res.transmission[2] == 1.0 and res.transmission[0] <= res.transmission[1]
    # no stalks: diffuse light either reaches the ground or is intercepted by a leaf first
    assert res.intercepted_fraction + res.transmission[0] == pytest.approx(1.0, abs=1e-12)
    assert res.triangle_share.sum() == pytest.approx(res.intercepted_fraction, abs=1e-12)
    # each direction is traced exactly like the sun
    d = 5
    one = trace_light(c, LightRequest(Sun(sky.zenith_deg[d], sky.azimuth_deg[d]),
                                      Sampling((0.0, 80.0, 200.0), 0.5, (0, 0, 100, 100), True)))
    assert np.array_equal(one.transmission, res.per_direction[d])
    m = res.transmission_map(80.0)
    assert m.x_edges[0] == 0 and m.x_edges[-1] == 100 and m.rays.sum() == res.rays
    assert np.average(m.transmission, weights=m.rays) == pytest.approx(res.transmission[1],
                                                                       abs=0.01)


def test_beer_lambert_under_a_sky_weights_each_direction():
    c = Canopy.from_triangles(np.array([[0, 0, 50], [100, 0, 50], [100, 100, 50], [0, 100, 50]],
                                       float), np.array([[0, 1, 2], [0, 2, 3]]), plot(),
                              np.array([1, 1]))
    sky = make_sky("soc", 46)
    bl = beer_lambert_sky(c, sky, (0.0, 60.0))
    cos = np.cos(np.radians(sky.zenith_deg))
    assert bl.G == pytest.approx(math.fsum(sky.weights * cos))
    assert bl.transmission[0] == pytest.approx(math.fsum(sky.weights * np.exp(-1.0)))
    assert bl.transmission[1] == pytest.approx(1.0, abs=1e-15)


def test_threads_agree_and_progress_counts_directions_and_cancels():
    c = random_leaves(2.0, 5.0, seed=4, spherical=True, side=100.0)
    sky = make_sky("uoc", 16)
    smp = dict(heights_cm=(0.0, 60.0), density=0.5, rect=(0, 0, 100, 100), periodic=True)
    seen = []
    one = trace_sky(c, sky, Sampling(**smp, threads=1), progress=lambda d, t: seen.append((d, t)))
    two = trace_sky(c, sky, Sampling(**smp, threads=2))
    assert seen == [(i, 16) for i in range(1, 17)]
    assert np.array_equal(one.per_direction, two.per_direction)
    assert np.array_equal(one.triangle_share, two.triangle_share)
    for threads in (1, 2):
        calls = []
        with pytest.raises(InterruptedError):
            trace_sky(c, sky, Sampling(**smp, threads=threads),
                      progress=lambda d, t, calls=calls: calls.append(d) or d < 3)
        assert calls[-1] == 3


def test_a_non_periodic_field_warns_once_for_all_low_directions():
    c = random_leaves(1.0, 5.0, seed=5, spherical=False, side=100.0)
    res = trace_sky(c, make_sky("soc", 46), Sampling((0.0,), 0.25, (30, 30, 70, 70), False, 1))
    edge = [w for w in res.warnings if "plot edge" in w]
    assert len(edge) == 1 and "of 46 sky directions" in edge[0]


@pytest.mark.parametrize("kind, n, says", [
    ("soc", 0, "at least 1"), ("soc", -3, "at least 1"), ("haze", 46, "unknown sky kind"),
    ("soc", 10_001, "at most"),
])
def test_bad_skies_are_refused_naming_the_quantity(kind, n, says):
    with pytest.raises(MaizevizError, match=says) as err:
        make_sky(kind, n)
    assert err.value.quantity in ("sky", "sky_directions")
