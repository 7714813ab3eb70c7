"""NURBS fit + mesh speed against geomdl, measured in the same run.

For a 13x5 and a 40x9 leaf grid at degree 3x3: the time of geomdl's
``fitting.interpolate_surface`` + evaluation at the K = 4 parameters divided by the time of
maizeviz's fit + K = 4 mesh, and the largest distance between the two surfaces' points. Then
the seconds to fit and mesh 1,500 different leaves (an 81-plant canopy) at K = 4.

    python benchmarks/bench_nurbs.py [--json]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from geomdl import fitting

from maizeviz.leaf.fit import fit_leaves
from maizeviz.leaf.grid import LeafGrid
from maizeviz.leaf.nurbs import fit_surface, refine_parameters
from maizeviz.leaf.synth import LeafShape, leaf_points
from maizeviz.mesh.levels import Level, mesh_leaves
from maizeviz.mesh.tessellate import mesh_grid


def best_of(fn, repeat, number=1):
    """Shortest mean time of ``number`` calls over ``repeat`` rounds (s)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - t0) / number)
    return min(times)


def grid(rows, cols, seed):
    pts = leaf_points(LeafShape(length=90.0), rows, cols, rng=np.random.default_rng(seed))
    pts[-1] += np.linspace(-0.2, 0.2, cols)[:, None] * [0, 1, 0]   # geomdl cannot take a collapsed tip
    return pts


def case(rows, cols):
    pts = grid(rows, cols, 0)

    def ours():
        s = fit_surface(pts)
        u = refine_parameters(s.params_u[0], 4)
        v = refine_parameters(s.params_v[0], 4)
        return mesh_grid(s.evaluate_grid(u, v)[0], u, v)

    mesh = ours()
    u, v = mesh.u, mesh.v

    def theirs():
        surf = fitting.interpolate_surface(pts.reshape(-1, 3).tolist(), rows, cols, 3, 3)
        return np.array(surf.evaluate_list([(a, b) for a in u for b in v]))

    ref = theirs().reshape(len(u), len(v), 3)
    t_theirs = best_of(theirs, 3)
    t_ours = best_of(ours, 5, number=max(1, int(0.2 / max(t_theirs / 50, 1e-5))))
    return {"grid": f"{rows}x{cols}", "maizeviz_s": t_ours, "geomdl_s": t_theirs,
            "speedup_vs_geomdl": t_theirs / t_ours,
            "max_diff_cm": float(np.abs(mesh.vertices - ref).max())}


def canopy_leaves(count=1500, seed=1):
    rng = np.random.default_rng(seed)
    grids = []
    for i in range(count):
        shape = LeafShape(length=rng.uniform(25, 100), width=rng.uniform(4, 11),
                          azimuth_deg=rng.uniform(0, 360), curvature_deg=rng.uniform(20, 90))
        rows = int(np.clip(round(13 * min(1.0, shape.length / 60)), 5, 13))
        grids.append(LeafGrid(i // 16 + 1, i % 16 + 1, leaf_points(shape, rows, 5, rng=rng), True))
    return grids


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    cases = [case(13, 5), case(40, 9)]
    grids = canopy_leaves()

    def all_leaves():
        leaves, errors = fit_leaves(grids)
        assert not errors
        return mesh_leaves(leaves, Level(interp=4))

    meshes = all_leaves()
    seconds = best_of(all_leaves, 3)
    out = {"cases": cases, "leaves_1500_s": seconds,
           "triangles_1500": int(sum(m.n_triangles for m in meshes)),
           "targets": {"speedup_13x5": 50, "speedup_40x9": 200, "max_diff_cm": 1e-9,
                       "leaves_1500_s": 1.0}}
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        for c in cases:
            print(f"{c['grid']:>6}: {c['speedup_vs_geomdl']:7.0f}x geomdl "
                  f"({c['maizeviz_s'] * 1e3:.2f} ms vs {c['geomdl_s'] * 1e3:.1f} ms), "
                  f"max diff {c['max_diff_cm']:.1e} cm")
        print(f"1,500 leaves fitted and meshed at K=4: {seconds:.3f} s "
              f"({out['triangles_1500']} triangles)")


if __name__ == "__main__":
    main()
