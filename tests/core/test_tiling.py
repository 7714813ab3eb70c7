"""A tiled canopy in a periodic field traced through its block (maizeviz.light.scene.tiling) gives
what the whole tiled canopy gives, ray for ray, through real Embree: the same first and second
hits on the same tile's triangles, the same hit heights, sensor planes, transmission, heatmaps,
per-leaf and per-plant light, sky and day; and a canopy that does not tile its block exactly
is traced whole."""

import numpy as np
import pytest

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for, layout_from_dict, layout_to_dict
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.engine import LightEngine
from maizeviz.light.report.heatmap import transmission_map
from maizeviz.light.scene.embree_scenes import BlockScene, CanopyScene, light_scene
from maizeviz.light.scene.periodic import Wrap, trace_wrapped
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.scene.tiling import block_tiling
from maizeviz.light.sources.irradiance import clear_sky_period
from maizeviz.light.sources.sky import make_sky
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.beam import trace_light
from maizeviz.light.trace.directions import trace_period, trace_sky
from maizeviz.mesh.levels import parse_level
from maizeviz.resources import example_points


@pytest.fixture(scope="module")
def leaves():
    return read_leaves(example_points()).leaves


@pytest.fixture(scope="module")
def tiled(leaves):
    """The bundled block tiled 3 x 3 at 36 triangles a leaf, and its two periodic scenes."""
    c = build_canopy(leaves, layout_for(leaves, (3, 3)), parse_level("36"))
    return c, light_scene(c, periodic=True, block=False), light_scene(c, periodic=True)


def test_the_block_scene_is_chosen_for_a_tiled_periodic_canopy(tiled):
    c, whole, block = tiled
    assert isinstance(block, BlockScene) and type(whole) is CanopyScene
    if block.packets:                # the block at the 9 tiles and a ring around, one BVH
        assert block.instanced is not None and len(block.instanced.offsets) >= 25
    assert block.tiling.shape == (3, 3)
    # the block and its neighbours' overhangs: 9 times fewer triangles, near enough
    assert block.n_triangles < whole.n_triangles / 7
    assert block.n_original == whole.n_original == c.n_triangles
    assert not isinstance(light_scene(c), BlockScene)                 # open field: whole


def _same(a, b):
    assert np.array_equal(a, b), f"{np.count_nonzero(a != b)} of {np.size(a)} differ"


@pytest.mark.parametrize("zenith, azimuth", [(0, 0), (22.34, 166.95), (48, 75), (74, 300)])
def test_sun_through_the_block_is_the_tiled_canopy_ray_for_ray(tiled, zenith, azimuth):
    c, whole, block = tiled
    req = LightRequest(Sun(zenith, azimuth), Sampling(density=2.0, periodic=True))
    a = trace_light(c, req, scene=whole)
    b = trace_light(c, req, scene=block)
    _same(a.first_z, b.first_z)                          # every ray's first hit height
    _same(a.first_hits, b.first_hits)                    # on the same tile's triangles
    _same(a.second_hits, b.second_hits)
    _same(a.sensor_lit, b.sensor_lit)                    # every sensor of every plane
    _same(a.transmission, b.transmission)
    for h in (0.0, 100.0):
        _same(transmission_map(a, h, 5.0).transmission, transmission_map(b, h, 5.0).transmission)
    assert a.leaf_rows(c) == b.leaf_rows(c)
    assert a.table("plant", c).equals(b.table("plant", c))


def test_any_sample_rectangle_and_density(tiled):
    """The block's field is the plot's: a rectangle across tiles, off the tile grid, works."""
    c, whole, block = tiled
    req = LightRequest(Sun(35, 230), Sampling((0.0, 80.0, 160.0), 3.3, (-150.3, -60.7, 40.1, 150.9),
                                              True))
    a, b = trace_light(c, req, scene=whole), trace_light(c, req, scene=block)
    _same(a.first_hits, b.first_hits)
    _same(a.sensor_lit, b.sensor_lit)
    _same(a.first_z, b.first_z)


def test_rays_in_any_direction_from_anywhere(tiled):
    """Scattered light's rays: any origin in (or beyond) the plot, any direction, long paths."""
    c, whole, block = tiled
    rng = np.random.default_rng(3)
    n = 20_000
    org = np.column_stack([rng.uniform(-400, 600, n), rng.uniform(-250, 350, n),
                           rng.uniform(0, 260, n)])
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    length = rng.uniform(0, 3000, n)
    got = []
    for scene in (whole, block):
        prim, cell, dist = trace_wrapped(scene, scene.wrap, org, d, length)
        hit = prim >= 0
        ids = np.full(n, -1, np.int64)
        ids[hit] = scene.resolve(prim[hit], cell[hit])
        got.append((ids, dist, trace_wrapped(scene, scene.wrap, org, d, length, any_hit=True)))
    (ia, da, oa), (ib, db, ob) = got
    assert 0.2 < np.mean(ia >= 0) < 0.95
    _same(ia, ib)
    _same(da, db)
    _same(oa, ob)
    _same(oa, ia >= 0)                                   # occlusion sees what hits see
    # the C kernel's wrapping (packets; the block's instances over the plot) and numpy's
    # (single queries; the block's own period) find the same triangles at the same distances
    for scene in (whole, block):
        if scene.packets:
            got = []
            for native in (True, False):
                prim, cell, dist = trace_wrapped(scene, scene.wrap, org, d, length,
                                                 native=native)
                hit = prim >= 0
                ids = np.full(n, -1, np.int64)
                ids[hit] = scene.resolve(prim[hit], cell[hit])
                got.append((ids, dist, trace_wrapped(scene, scene.wrap, org, d, length,
                                                     any_hit=True, native=native)))
            for x, y in zip(*got):
                _same(x, y)


def test_sky_and_day_through_the_block(tiled):
    c, whole, block = tiled
    smp = Sampling((0.0, 100.0), 1.0, None, True, 2)
    sky = make_sky("soc", 16)
    a, b = trace_sky(c, sky, smp, scene=whole), trace_sky(c, sky, smp, scene=block)
    _same(a.per_direction, b.per_direction)
    _same(a.triangle_share, b.triangle_share)
    _same(a.maps, b.maps)
    period = clear_sky_period("2005-08-01", 39.9, 116.4, "Asia/Shanghai", step_min=120)
    pa = trace_period(c, period, smp, a, scene=whole)
    pb = trace_period(c, period, smp, b, scene=block)
    _same(pa.step_transmission, pb.step_transmission)
    _same(pa.triangle_direct_mol, pb.triangle_direct_mol)
    _same(pa.maps, pb.maps)
    assert pa.table("plant", c).equals(pb.table("plant", c))


def test_other_tilings_and_stalks(leaves):
    c = build_canopy(leaves, layout_for(leaves, (2, 3)), parse_level("8"))
    req = LightRequest(Sun(30, 100), Sampling((0.0, 120.0), 2.0, None, True), classes=True)
    for stalks in (False, True):
        whole = light_scene(c, stalks, periodic=True, block=False)
        block = light_scene(c, stalks, periodic=True)
        assert isinstance(block, BlockScene)
        a = trace_light(c, req, with_stalks=stalks, scene=whole)
        b = trace_light(c, req, with_stalks=stalks, scene=block)
        _same(a.first_hits, b.first_hits)
        _same(a.second_hits, b.second_hits)
        _same(a.sensor_lit, b.sensor_lit)
        if stalks:
            assert a.first_hits[c.n_triangles:].sum() > 0   # stalk triangles were hit


def test_the_engine_traces_the_block_and_says_so(tiled):
    c, whole, _ = tiled
    eng = LightEngine(c, periodic=True, density=1.0, with_stalks=False)   # as ``whole``
    assert isinstance(eng.scene(), BlockScene)
    sun = eng.sun(zenith=30, azimuth=200)
    ref = trace_light(c, LightRequest(Sun(30, 200), Sampling(density=1.0, periodic=True)),
                      scene=whole)
    _same(sun.first_hits, ref.first_hits)
    assert not isinstance(eng.scene(periodic=False), BlockScene)


def test_canopies_that_do_not_tile_their_block_are_traced_whole(leaves):
    c = build_canopy(leaves, layout_for(leaves, (3, 3)), parse_level("4"))
    assert block_tiling(c) is not None
    # a layout document of the same stands (an edited layout): no tiles
    doc = layout_to_dict(c.layout)
    edited = build_canopy(leaves, layout_from_dict(doc, {lf.grid.plant for lf in leaves}),
                          parse_level("4"))
    assert block_tiling(edited) is None
    assert not isinstance(light_scene(edited, periodic=True), BlockScene)
    # one tile alone is its own plot
    one = build_canopy(leaves, layout_for(leaves, (1, 1)), parse_level("4"))
    assert block_tiling(one) is None
    # spacings whose block is not on the 2^-12 cm grid
    odd = build_canopy(leaves, layout_for(leaves, (3, 3), 60.3, 30.1), parse_level("4"))
    assert block_tiling(odd) is None


def test_the_grid_is_exact_in_float32():
    w = Wrap.of((-0.42, -0.38, 179.58, 89.62), (-180.42, -90.38, 359.58, 179.62))
    assert w.q == 2.0 ** -12 and w.w == 180.0 and w.h == 90.0
    big = Wrap.of((0, 0, 10_000, 10_000))
    assert big.q == 2.0 ** -8
