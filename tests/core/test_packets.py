"""Embree's ray packets (maizeviz.mesh.packets, the C kernel _packets.c) against embreex's
single rays, through real Embree: the same triangle and the same float32 distance for every
ray, coherent or not, in order or in tiles; whole light computations identical either way;
the kernel compiled into a cache folder, and its absence falls back."""

import numpy as np
import pytest

import maizeviz.mesh.raytrace as raytrace
from maizeviz.canopy.layout import layout_for
from maizeviz.canopy.scene import build_canopy
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.scene.scenes import light_scene
from maizeviz.light.sources.sky import make_sky
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.diffuse import trace_sky
from maizeviz.light.trace.direct import trace_light
from maizeviz.mesh import packets
from maizeviz.mesh.levels import parse_level
from maizeviz.mesh.raytrace import RayScene
from maizeviz.resources import example_points

needs_kernel = pytest.mark.skipif(packets.kernel() is None,
                                  reason="no C compiler or Embree library for the packets")


@pytest.fixture(scope="module")
def canopy():
    leaves = read_leaves(example_points()).leaves
    return build_canopy(leaves, layout_for(leaves, (3, 3)), parse_level("36"))


@pytest.fixture(scope="module")
def scenes(canopy):
    both = (RayScene(canopy.vertices, canopy.faces, packets=False),
            RayScene(canopy.vertices, canopy.faces))
    return both


def grid_rays(canopy, toward, nx=300, ny=200, z=None):
    """A grid of parallel rays laid out row by row (ny a row) over the central tile."""
    x0, y0, x1, y1 = canopy.layout.centre_bounds
    i, j = np.divmod(np.arange(nx * ny), ny)
    org = np.empty((nx * ny, 3))
    org[:, 0] = x0 + (i + 0.5) * (x1 - x0) / nx
    org[:, 1] = y0 + (j + 0.5) * (y1 - y0) / ny
    org[:, 2] = 0.0 if z is None else z
    top = float(canopy.vertices[:, 2].max()) + 1.0
    return org, np.full(len(org), (top - org[0, 2]) / toward[2])


@needs_kernel
def test_packets_give_embreex_hits_ray_for_ray(canopy, scenes):
    single, packed = scenes
    assert packed.packets and not single.packets
    rng = np.random.default_rng(5)
    s = Sun(35, 140).direction()
    org, length = grid_rays(canopy, s)
    down_org = org + length[:, None] * s                    # from above, toward the ground
    n = len(org)
    rand_org = np.column_stack([rng.uniform(-150, 330, n), rng.uniform(-80, 170, n),
                                rng.uniform(0, 260, n)])
    rand_dir = rng.normal(size=(n, 3))
    rand_dir /= np.linalg.norm(rand_dir, axis=1, keepdims=True)
    cases = [(down_org, np.tile(-s, (n, 1)), length, 200),      # sunlight, a grid
             (org, np.tile(s, (n, 1)), length, 200),            # sensors toward the sun
             (rand_org, rand_dir, rng.uniform(0, 400, n), 0)]   # scattered light
    for o, d, t, row in cases:
        p1, t1 = single.first_hit(o, d, t)
        assert 0.05 < np.mean(p1 >= 0) < 0.98
        for kwargs in ({}, {"row": row}):
            p2, t2 = packed.first_hit(o, d, t, **kwargs)
            np.testing.assert_array_equal(p1, p2)
            np.testing.assert_array_equal(t1, t2)
            np.testing.assert_array_equal(single.distance(o, d, t), packed.distance(o, d, t,
                                                                                    **kwargs))
            np.testing.assert_array_equal(single.occluded(o, d, t), packed.occluded(o, d, t,
                                                                                    **kwargs))
        u1 = single.first_hit(o, d)                              # unbounded rays
        u2 = packed.first_hit(o, d)
        np.testing.assert_array_equal(u1[0], u2[0])
        np.testing.assert_array_equal(u1[1], u2[1])
    k = packets.kernel()
    for width in (4, 8, 16):                                     # every packet width
        for coherent in (False, True):
            p, t = packets.intersect(k, packed._handle, cases[0][0], -s[None], cases[0][2],
                                     coherent=coherent, width=width, row=200)
            np.testing.assert_array_equal(p, single.first_hit(*cases[0][:3])[0])
            b = packets.occluded(k, packed._handle, cases[1][0], s[None], cases[1][2],
                                 coherent=coherent, width=width, row=7)
            np.testing.assert_array_equal(b, single.occluded(*cases[1][:3]))


@needs_kernel
@pytest.mark.parametrize("periodic", [False, True])
def test_light_is_the_same_through_packets_or_single_rays(canopy, monkeypatch, periodic):
    req = LightRequest(Sun(28, 200), Sampling(density=2.0, periodic=periodic, threads=2))
    sky = make_sky("soc", 6)
    fast = trace_light(canopy, req), trace_sky(canopy, sky, req.sampling)
    monkeypatch.setattr(raytrace._packets, "kernel", lambda: None)
    scene = light_scene(canopy, periodic=periodic)
    assert not scene.packets
    slow = trace_light(canopy, req, scene=scene), trace_sky(canopy, sky, req.sampling,
                                                            scene=scene)
    np.testing.assert_array_equal(fast[0].first_hits, slow[0].first_hits)
    np.testing.assert_array_equal(fast[0].second_hits, slow[0].second_hits)
    np.testing.assert_array_equal(fast[0].first_z, slow[0].first_z)
    np.testing.assert_array_equal(fast[0].sensor_lit, slow[0].sensor_lit)
    np.testing.assert_array_equal(fast[1].triangle_share, slow[1].triangle_share)
    np.testing.assert_array_equal(fast[1].maps, slow[1].maps)


def test_the_kernel_is_compiled_into_the_cache_and_its_absence_falls_back(tmp_path,
                                                                          monkeypatch):
    monkeypatch.setenv("MAIZEVIZ_CACHE", str(tmp_path))
    if packets.build() is not None:                           # a C compiler is here
        assert packets.compiled_path().parent == tmp_path
        assert packets.compiled_path().exists()
    monkeypatch.setenv("MAIZEVIZ_CACHE", str(tmp_path / "none"))
    monkeypatch.setenv("CC", "false")                          # a compiler that fails
    assert packets.build() is None
    monkeypatch.setattr(raytrace._packets, "kernel", lambda: None)
    scene = RayScene(np.array([[0, 0, 1.0], [1, 0, 1], [0, 1, 1]]), np.array([[0, 1, 2]]))
    assert not scene.packets
    prim, t = scene.first_hit(np.array([[0.2, 0.2, 0.0]]), np.array([[0, 0, 1.0]]))
    assert prim[0] == 0 and t[0] == pytest.approx(1.0)
