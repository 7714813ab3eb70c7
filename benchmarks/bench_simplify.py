"""The canopy of 900 distinct synthetic plants at 8 triangles a leaf against the same canopy
at the standard level (issue 30: within 2x), and against the leaf-by-leaf splitting.

Writes the block ``maizeviz synth --plants 30x30`` writes (14,400 leaves), reads and fits it
once, then builds the canopy (``build_canopy``, one placement per plant) at the standard level
and at 8 triangles (reference areas cleared before each build, as in a fresh process) in
turns, best of ``--repeat``: wall seconds and CPU seconds of the process. The ratio 8 triangles
/ standard is the target's; the anchor is the splitting this replaced, leaf by leaf
(``tests/core/simplify_oracle.py``), timed on ``--oracle-leaves`` leaves and scaled to all of
them.

    python benchmarks/bench_simplify.py [--json] [--plants 30x30] [--repeat 3]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from anchors import report

ROOT = Path(__file__).resolve().parents[1]


def timed(fn) -> tuple[float, float]:
    """(wall s, process CPU s) of ``fn()``."""
    w, c = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - w, time.process_time() - c


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--plants", default="30x30")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--oracle-leaves", type=int, default=1500)
    args = ap.parse_args()

    from maizeviz.canopy.build import build_canopy
    from maizeviz.canopy.layout import layout_for, parse_shape
    from maizeviz.io.points import write_points
    from maizeviz.leaf.fit import read_leaves
    from maizeviz.leaf.synth import block_grids
    from maizeviz.mesh.levels import parse_level, reference_areas

    rows, per_row = parse_shape(args.plants, "plants")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "points.csv"
        write_points(path, block_grids(rows, per_row))
        leaves = read_leaves(path).leaves
    layout = layout_for(leaves, (1, 1), 60.0, 30.0, None, None)
    out: dict = {"plants": len(layout.placements), "leaves": len(leaves)}
    best: dict[str, tuple[float, float]] = {}
    for _ in range(args.repeat):
        for text in ("standard", "8"):
            for lf in leaves:
                lf.cache.pop("reference_area_cm2", None)
            got = timed(lambda t=text: build_canopy(leaves, layout, parse_level(t)))
            old = best.get(text, (float("inf"),) * 2)
            best[text] = (min(old[0], got[0]), min(old[1], got[1]))
    for text, (wall, cpu) in best.items():
        out[f"canopy_{text}_s"], out[f"canopy_{text}_cpu_s"] = round(wall, 3), round(cpu, 3)
    out["ratio_8_over_standard"] = round(best["8"][0] / best["standard"][0], 2)
    out["ratio_8_over_standard_cpu"] = round(best["8"][1] / best["standard"][1], 2)

    sys.path.insert(0, str(ROOT / "tests" / "core"))
    from simplify_oracle import simplify as oracle_simplify

    few = leaves[:args.oracle_leaves]
    targets = reference_areas(few)
    wall, cpu = timed(lambda: [oracle_simplify(
        lf.grid.points, lf.surface.params_u[0], lf.surface.params_v[0], 8,
        lf.grid.tip_collapsed, float(t), lf.grid.plant, lf.grid.leaf)
        for lf, t in zip(few, targets)])
    scale = len(leaves) / len(few)
    out["leaf_by_leaf_splitting_s (scaled)"] = round(wall * scale, 2)
    out["leaf_by_leaf_over_canopy_8"] = round(wall * scale / best["8"][0], 1)
    out["target"] = "ratio_8_over_standard <= 2"
    report(out, args.json)


if __name__ == "__main__":
    main()
