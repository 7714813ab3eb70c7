"""`maizeviz leaf FILE --interp 0 --json` on large points files: seconds per stage, per leaf,
peak memory, and how they scale from a 20 MB file to a 200 MB one.

Writes points files of about ``--small-mb`` and ``--large-mb`` megabytes (a synthetic 3 x 3
block, ``maizeviz.leaf.synth.block_grids``, repeated with shifted plant ids by
``bench_read_points.write_points_file``) and runs the whole command on each in a fresh
process: the CLI itself (``maizeviz.cli.main``, stdout to a file), with the core functions it
calls wrapped to time each stage: read, grid, fit, reference areas, mesh, measure, JSON out.
Reports seconds per stage and per leaf, peak resident memory (``resource.getrusage``) above
the interpreter with maizeviz imported, and the ratio of per-leaf times between the two files
(linear scaling: about 1). ``--levels K4,standard,36,4`` runs on the small file too.

The anchor is the per-leaf measure before batching (trimesh's closest point, 18 triangles per
surface point, taken from git at ``--anchor-rev``), timed on ``--anchor-leaves`` leaves of the
small file in the same process as the batched measure of those leaves: the speed-up is that
per-leaf time over the batched one of the whole small file, and the largest difference of the
two results is reported. Absolute times mean little on a shared machine; the ratios do.

    python benchmarks/bench_leaf_scaling.py [--json] [--small-mb 20] [--large-mb 200]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_read_points import old_module, write_points_file  # noqa: E402

CHILD = r"""
import json, resource, sys, time
import numpy as np
import maizeviz.cli
import maizeviz.cli.leaf as cli_leaf
import maizeviz.leaf.fit as fit
from maizeviz.leaf.nurbs import fit_surfaces  # scipy and the rest imported before the baseline

path, out_path, argv = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
stages = {}
counts = {}

def timed(module, name, stage):
    inner = getattr(module, name)
    def wrapper(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return inner(*args, **kwargs)
        finally:
            stages[stage] = stages.get(stage, 0.0) + time.perf_counter() - t0
    setattr(module, name, wrapper)

timed(fit, "read_points", "read")
timed(fit, "build_grids", "grid")
timed(fit, "fit_leaves", "fit")
timed(cli_leaf, "reference_areas", "reference_areas")
timed(cli_leaf, "mesh_leaves", "mesh")
timed(cli_leaf, "measure_leaves", "measure")

class TimedJson:
    def dumps(self, *args, **kwargs):
        t0 = time.perf_counter()
        text = json.dumps(*args, **kwargs)
        stages["json"] = stages.get("json", 0.0) + time.perf_counter() - t0
        counts["leaves"] = len(args[0]["leaves"])
        return text

cli_leaf.json = TimedJson()
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t0 = time.perf_counter()
with open(out_path, "w") as out:
    sys.stdout = out
    code = maizeviz.cli.main(["leaf", path, *argv])
    sys.stdout = sys.__stdout__
total = time.perf_counter() - t0
after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
stages["other"] = total - sum(stages.values())
print(json.dumps({"exit": code, "seconds": total, "stages": stages, "leaves": counts["leaves"],
                  "peak_bytes": (after - before) * 1024}))
"""

ANCHOR = r"""
import importlib.util, json, sys, time
import numpy as np
from maizeviz.leaf.fit import Leaf, read_leaves
from maizeviz.mesh.levels import (DEVIATION_K, REFERENCE_K, Level, _sample, measure_leaves,
                                  mesh_leaves)
from maizeviz.mesh.tessellate import mesh_grid

path, old_file, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
spec = importlib.util.spec_from_file_location("old_measures", old_file)
old = sys.modules["old_measures"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(old)

def old_measure(leaf, mesh):
    # maizeviz.mesh.levels.measure before batching: one leaf, its own samples
    pts, u, v = _sample(leaf.surface, DEVIATION_K)
    ref_pts, ru, rv = _sample(leaf.surface, REFERENCE_K)
    return (old.area(mesh), old.projected_area(mesh),
            old.max_deviation(mesh, pts[0], u[0], v[0]),
            old.area(mesh_grid(ref_pts[0], ru[0], rv[0])))

leaves = read_leaves(path).leaves
pick = np.linspace(0, len(leaves) - 1, min(count, len(leaves))).astype(int)
sample = [leaves[i] for i in pick]
meshes = mesh_leaves(sample, Level(interp=0))
old.max_deviation(meshes[0], *(x[0] for x in _sample(sample[0].surface, DEVIATION_K)))  # warm
t0 = time.perf_counter()
before = np.array([old_measure(Leaf(lf.grid, lf.surface), m) for lf, m in zip(sample, meshes)])
old_s = time.perf_counter() - t0
t0 = time.perf_counter()
now = measure_leaves([Leaf(lf.grid, lf.surface) for lf in sample], meshes)
new_s = time.perf_counter() - t0
now = np.array([(m.area_cm2, m.projected_area_cm2, m.max_deviation_cm, m.reference_area_cm2)
                for m in now])
diff = np.abs(now - before)
print(json.dumps({"leaves": len(sample), "old_s_per_leaf": old_s / len(sample),
                  "batched_sample_s_per_leaf": new_s / len(sample),
                  "max_abs_diff": {"area_cm2": diff[:, 0].max(), "projected_cm2": diff[:, 1].max(),
                                   "deviation_cm": diff[:, 2].max(),
                                   "reference_cm2": diff[:, 3].max()},
                  "max_rel_diff_areas": float((diff[:, [0, 1, 3]]
                                               / np.abs(before[:, [0, 1, 3]])).max())}))
"""


def run_child(code: str, *args: str) -> dict:
    out = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                         cwd=ROOT)
    if out.returncode:
        raise SystemExit(f"the benchmark child failed: {out.stderr.strip()[-800:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def run_leaf(path: Path, argv: list[str], tmp: Path) -> dict:
    """``maizeviz leaf path *argv`` in a fresh process, timed by stage."""
    res = run_child(CHILD, str(path), str(tmp / "out.json"), json.dumps(argv))
    n = res["leaves"]
    res.update(file_bytes=path.stat().st_size, s_per_leaf=res["seconds"] / n,
               stage_ms_per_leaf={k: 1e3 * v / n for k, v in res["stages"].items()},
               peak_bytes_per_leaf=res["peak_bytes"] / n)
    return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--small-mb", type=float, default=20.0, help="size of the small file (MB)")
    ap.add_argument("--large-mb", type=float, default=200.0, help="size of the large file (MB)")
    ap.add_argument("--levels", default="K4,standard,36,4",
                    help="levels compared on the small file ('' to skip)")
    ap.add_argument("--anchor-leaves", type=int, default=300,
                    help="leaves measured one at a time the old way")
    ap.add_argument("--anchor-rev", default="55e603c",
                    help="git revision of the per-leaf measure (default: the last before "
                         "batching)")
    args = ap.parse_args(argv)
    result: dict = {}
    with tempfile.TemporaryDirectory(prefix="bench-leaf-scaling-") as tmp_name:
        tmp = Path(tmp_name)
        small, large = tmp / "small.csv", tmp / "large.csv"
        write_points_file(small, args.small_mb)
        result["small"] = run_leaf(small, ["--interp", "0", "--json"], tmp)
        old = old_module(args.anchor_rev, "maizeviz/mesh/measures.py", tmp)
        if old is not None and args.anchor_leaves > 0:
            a = run_child(ANCHOR, str(small), str(old), str(args.anchor_leaves))
            batched = result["small"]["stages"]["measure"] / result["small"]["leaves"]
            a["batched_file_s_per_leaf"] = batched
            a["speedup_vs_per_leaf"] = a["old_s_per_leaf"] / batched
            a["speedup_same_sample"] = a["old_s_per_leaf"] / a["batched_sample_s_per_leaf"]
            result["anchor"] = a
        if args.levels:
            result["small_levels"] = run_leaf(small, ["--levels", args.levels, "--json"], tmp)
        small.unlink()
        write_points_file(large, args.large_mb)
        result["large"] = run_leaf(large, ["--interp", "0", "--json"], tmp)
    s, lg = result["small"], result["large"]
    result["large_over_small"] = {
        "bytes": lg["file_bytes"] / s["file_bytes"], "leaves": lg["leaves"] / s["leaves"],
        "s_per_leaf": lg["s_per_leaf"] / s["s_per_leaf"],
        "stage_s_per_leaf": {k: lg["stages"][k] / lg["leaves"] / (v / s["leaves"])
                             for k, v in s["stages"].items() if v > 0},
        "peak_memory_per_leaf": lg["peak_bytes_per_leaf"] / s["peak_bytes_per_leaf"]}
    if args.json:
        print(json.dumps(result, indent=1))
        return 0
    for name in ("small", "small_levels", "large"):
        if name not in result:
            continue
        r = result[name]
        stages = "  ".join(f"{k} {v:.1f}" for k, v in r["stages"].items())
        print(f"{name:12s} {r['file_bytes'] / 1e6:6.1f} MB {r['leaves']:>8,} leaves "
              f"{r['seconds']:7.1f} s ({1e3 * r['s_per_leaf']:.2f} ms/leaf), peak "
              f"{r['peak_bytes'] / 1e6:7.0f} MB; s: {stages}")
    if "anchor" in result:
        a = result["anchor"]
        print(f"measure per leaf: old {1e3 * a['old_s_per_leaf']:.1f} ms, batched "
              f"{1e3 * a['batched_file_s_per_leaf']:.2f} ms (x{a['speedup_vs_per_leaf']:.0f}); "
              f"largest difference {a['max_abs_diff']}")
    r = result["large_over_small"]
    print(f"large / small: leaves x{r['leaves']:.1f}, time per leaf x{r['s_per_leaf']:.2f}, "
          f"peak memory per leaf x{r['peak_memory_per_leaf']:.2f} (linear: about 1)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
