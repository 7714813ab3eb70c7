"""The sunlit share sampled from the leaves (``maizeviz/light/trace/sunlit.py``) with the forward
rays' first hits saying where to sample, through the real Embree: whatever hits it is given
(the rays', or any drawn independently of the points), every triangle's share stays in
[0, 1] and each leaf layer's sampled sunlit area keeps its mean (the share sampled without
hits, within the two estimates' standard errors over seeds), with fewer points; and the
triangles it leaves out cannot send the beam into the sample rectangle."""

import numpy as np
from test_leaf_invariants import leaves

from maizeviz.light.engine import LightEngine
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.beam import sampler
from maizeviz.light.trace.optics import Optics
from maizeviz.light.trace.scatter import scatter_beam
from maizeviz.light.trace.sunlit import geometry, sunlit_share

SEEDS = 40


def test_the_rays_hits_choose_the_points_not_the_answer():
    canopy = leaves(2.5, 6.0, 60.0, seed=3)
    eng = LightEngine(canopy, periodic=True, density=1.0, heights_cm=(0.0,))
    smp = sampler(canopy, eng.scene(), canopy.layout.bounds, 1.0, (0.0,), True)
    normals = eng._normals()
    toward = Sun(35.0, 150.0).direction(canopy.layout.north_deg)
    nf = len(normals)
    tally, _ = scatter_beam(smp, toward, Optics(0, 0, 0), normals, 0, 0.0, 99, 1)
    rays = np.bincount(np.concatenate(tally.first_hits), minlength=nf)
    drawn = np.random.default_rng(5).integers(0, 2, nf) * (np.random.default_rng(6)
                                                           .random(nf) < 0.2)
    area = geometry(canopy, nf).area_cm2
    z = canopy.vertices[canopy.faces][:, :, 2].mean(axis=1)
    layer = np.digitize(z, [50.0, 80.0, 100.0])            # 4 layers, top one mostly lit
    got = {}
    for name, hits in (("none", None), ("rays", rays), ("drawn", drawn)):
        sums, points = [], []
        for seed in range(SEEDS):
            share = sunlit_share(smp, canopy, normals, toward, seed, hits)
            assert np.all((share.fraction >= 0) & (share.fraction <= 1))
            sums.append(np.bincount(layer, share.fraction[:len(z)] * area[:len(z)], 4))
            points.append(share.points)
        got[name] = (np.array(sums), points[0])
    base, n_base = got["none"]
    for name in ("rays", "drawn"):
        sums, n = got[name]
        assert n < n_base
        se = np.sqrt(sums.var(axis=0, ddof=1) / SEEDS + base.var(axis=0, ddof=1) / SEEDS)
        diff = np.abs(sums.mean(axis=0) - base.mean(axis=0))
        assert np.all(diff <= 4 * se + 1e-9), (name, diff, se)
    assert base[:, 3].mean() > 100.0                       # the top layer is in the sun


def test_the_triangles_left_out_cannot_send_the_beam_into_the_rectangle():
    """The triangles the sampler leaves out (``_near_triangles``): no point of theirs, its beam
    carried down to the ground (wrapped across the plot in a periodic field), lands in the
    sample rectangle; in an open field and a periodic one, some are left out."""
    from maizeviz.light.trace.sunlit import _near_triangles

    canopy = leaves(2.0, 6.0, 80.0, seed=4)
    eng = LightEngine(canopy, periodic=True, density=1.0, heights_cm=(0.0,))
    toward = Sun(40.0, 120.0).direction(canopy.layout.north_deg)
    shift = toward[:2] / toward[2]
    tri = canopy.vertices[canopy.faces]
    rng = np.random.default_rng(8)
    r1, r2 = np.sqrt(rng.random((len(tri), 50))), rng.random((len(tri), 50))
    pts = ((1 - r1)[..., None] * tri[:, None, 0] + (r1 * (1 - r2))[..., None] * tri[:, None, 1]
           + (r1 * r2)[..., None] * tri[:, None, 2])              # (F, 50, 3)
    land = pts[..., :2] - shift * pts[..., 2:3]
    bx0, by0, bx1, by1 = canopy.layout.bounds
    x0, y0, x1, y1 = rect = (20.0, 30.0, 45.0, 50.0)
    for periodic in (False, True):
        smp = sampler(canopy, eng.scene(periodic), rect, 1.0, (0.0,), periodic)
        kept = np.zeros(len(tri), dtype=bool)
        kept[_near_triangles(smp, geometry(canopy, len(tri)), shift)] = True
        g = land.copy()
        if periodic:
            g[..., 0] = bx0 + np.mod(g[..., 0] - bx0, bx1 - bx0)
            g[..., 1] = by0 + np.mod(g[..., 1] - by0, by1 - by0)
        inside = ((g[..., 0] >= x0) & (g[..., 0] < x1) & (g[..., 1] >= y0)
                  & (g[..., 1] < y1)).any(axis=1)
        assert inside.any() and not (inside & ~kept).any()
        assert 0 < kept.sum() < len(tri)
