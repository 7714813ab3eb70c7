"""The sunlit share sampled from the leaves (``maizeviz/light/trace/sunlit.py``) with the forward
rays' first hits saying where to sample, through the real Embree: whatever hits it is given
(the rays', or any drawn independently of the points), every triangle's share stays in
[0, 1] and each leaf layer's sampled sunlit area keeps its mean (the share sampled without
hits, within the two estimates' standard errors over seeds), with fewer points."""

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
