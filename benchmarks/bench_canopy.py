"""Rebuilding the 81-plant canopy at a new level: what the GUI's complexity slider calls.

Builds the bundled 3x3 block tiled 3x3 at K = 4 and at 36 triangles per leaf; prints the
seconds of each rebuild (best of 3), its peak traced memory (numpy included), the process's
peak resident memory, and each rebuild over an anchor measured in the same run (a fixed numpy
workload: 20 products of 400 x 400 matrices) so runs on busy machines stay comparable.
Targets: under 1 s per rebuild, under 1 GiB peak.

    python benchmarks/bench_canopy.py [--json] [--points maizeviz/resources/block3x3.csv]
"""

from __future__ import annotations

import argparse
import json
import resource
import time
import tracemalloc
from pathlib import Path

from anchors import matmul_anchor

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import plant_bases, tiled_layout
from maizeviz.io.points import read_points
from maizeviz.leaf.fit import fit_leaves
from maizeviz.leaf.grid import build_grids
from maizeviz.mesh.levels import parse_level

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--points", default=str(ROOT / "maizeviz" / "resources" / "block3x3.csv"))
    args = ap.parse_args()
    grids, _ = build_grids(read_points(args.points))
    leaves, _ = fit_leaves(grids)
    layout = tiled_layout(plant_bases(leaves), (3, 3))
    anchor_s = min(matmul_anchor() for _ in range(3))
    out = {"plants": len(layout.placements), "anchor_s": anchor_s, "levels": []}
    for text in ("K4", "36"):
        level = parse_level(text)
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            canopy = build_canopy(leaves, layout, level)
            times.append(time.perf_counter() - t0)
            del canopy
        tracemalloc.start()
        canopy = build_canopy(leaves, layout, level)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        out["levels"].append({"level": level.label, "triangles": canopy.n_triangles,
                              "rebuild_s": min(times), "rebuild_over_anchor": min(times) / anchor_s,
                              "peak_traced_mib": peak / 2**20})
        del canopy
    out["peak_rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    out["targets"] = {"rebuild_s": 1.0, "peak_mib": 1024}
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        for lv in out["levels"]:
            print(f"{lv['level']:>13}: {lv['triangles']:8d} triangles, rebuild {lv['rebuild_s']:.3f} s "
                  f"({lv['rebuild_over_anchor']:.1f}x anchor), peak {lv['peak_traced_mib']:.0f} MiB traced")
        print(f"process peak RSS {out['peak_rss_mib']:.0f} MiB; anchor {anchor_s:.3f} s")


if __name__ == "__main__":
    main()
