"""Embree scene build: maizeviz's fill by memory copy against Embree's own BVH build.

On the bundled 3 x 3 block tiled 3 x 3 (81 plants) at K = 4 (2.68 million triangles: the canopy of the
issue's K = 4 sun light), in the same run:

- bvh_s: Embree's BVH build alone (``rtcCommitScene`` through embreex's first query) for a
  scene whose buffers are already filled: the anchor, Embree's own limit
- copy_fill_s: filling Embree's buffers by memory copy (:mod:`maizeviz.mesh.embree_fill`)
- embreex_fill_s: embreex's ``TriangleMesh`` filling the same buffers element by element
- build_over_bvh: (copy fill + BVH) over BVH, what a RayScene costs over Embree's own build
  (target <= 1.3)
- embreex_build_over_bvh: the same with embreex's fill (about 4-5 before)

    python benchmarks/bench_scene.py [--json] [--level K4] [--tile 3]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from embreex.mesh_construction import TriangleMesh
from embreex.rtcore_scene import EmbreeScene

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.leaf.fit import read_leaves
from maizeviz.mesh.embree_fill import fill
from maizeviz.mesh.levels import parse_level
from maizeviz.resources import example_points


def timed_build(vertices, faces, by_copy: bool) -> tuple[float, float]:
    """(fill seconds, BVH build seconds) of one scene."""
    scene = EmbreeScene(robust=False)
    t0 = time.perf_counter()
    if by_copy:
        assert fill(scene, vertices, faces), "the copy fill is not available here"
    else:
        TriangleMesh(scene, vertices, faces)
    t1 = time.perf_counter()
    scene.run(np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32))   # commit
    return t1 - t0, time.perf_counter() - t1


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--level", default="K4")
    ap.add_argument("--tile", type=int, default=3)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    leaves = read_leaves(example_points()).leaves
    canopy = build_canopy(leaves, layout_for(leaves, (args.tile, args.tile)),
                          parse_level(args.level))
    v = np.ascontiguousarray(canopy.vertices, np.float32)
    f = np.ascontiguousarray(canopy.faces, np.int32)
    copy = min((timed_build(v, f, True) for _ in range(args.repeat)), key=sum)
    slow = min((timed_build(v, f, False) for _ in range(max(1, args.repeat - 1))), key=sum)
    bvh = min(copy[1], slow[1])
    out = {"triangles": int(len(f)), "level": args.level, "tile": args.tile,
           "bvh_s": round(bvh, 3), "copy_fill_s": round(copy[0], 3),
           "embreex_fill_s": round(slow[0], 3),
           "build_over_bvh": round((copy[0] + copy[1]) / bvh, 2),
           "embreex_build_over_bvh": round((slow[0] + slow[1]) / bvh, 2),
           "fill_speedup": round(slow[0] / copy[0], 1)}
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        for k, val in out.items():
            print(f"{k:>24}: {val}")


if __name__ == "__main__":
    main()
