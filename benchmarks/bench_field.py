"""A field of distinct plants, stage by stage: seconds and peak memory per triangle of
reading, building the canopy, building its Embree scene and tracing one sun, against Embree's
own BVH build of the same triangles in the same run (issue 30).

Runs in a fresh process for each field (``--points``, Parquet or CSV; e.g. written by
``maizeviz synth --plants 30x30 --out field.parquet``): the points are read (a large Parquet
file plant chunk by plant chunk, :mod:`maizeviz.canopy.field`), the canopy built at
``--level``, its scene (``LightEngine.scene``, periodic with ``--periodic``), one sun
(zenith 30 deg, azimuth 180 deg, ``--density`` rays per cm2, hit classes), as
``maizeviz light`` does. Each stage's peak resident memory (``VmHWM`` of /proc, reset between
stages through ``/proc/self/clear_refs``) is divided by the canopy's triangles; each stage's
CPU seconds count this process and its finished workers (a field's chunk processes).

The anchor: the same float32 vertices and uint32 triangles (the periodic scene's, copies of
the overhangs included) given to a bare Embree scene with the same flags, its BVH build timed
alone (``rtcCommitScene``), just before the scene's own build (on a loaded machine the two
far apart in time differ by the load); the target is the scene stage within 1.3x of it, and
the peak of every stage at most 150 bytes a triangle for K = 4 of 900 plants. A second anchor,
a fixed numpy pass (sorting 4 million float64) timed before and after, says how fast the
machine ran numpy at the time (the machine is shared: read seconds over it).

    python benchmarks/bench_field.py --points field.parquet [--level K4] [--periodic]
        [--density 4] [--row-spacing 60 --plant-spacing 30] [--json]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

CHILD = r"""
import gc, json, resource, sys, time
import numpy as np

def cpu():
    # CPU seconds of this process and of its finished workers (a field's chunk processes)
    a, b = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime

def numpy_anchor():
    # seconds of a fixed numpy pass (sorting 4 million float64, single-threaded): how fast
    # this machine runs numpy right now; a stage's seconds over it compare across loads
    x = np.random.default_rng(0).random(1 << 22)
    best = float("inf")
    for _ in range(3):
        t = time.perf_counter()
        np.sort(x)
        best = min(best, time.perf_counter() - t)
    return best

def status():
    d = {}
    with open("/proc/self/status") as fh:
        for line in fh:
            k, v = line.split(":", 1)
            if k in ("VmRSS", "VmHWM"):
                d[k] = int(v.split()[0]) * 1024
    return d

def reset():
    with open("/proc/self/clear_refs", "w") as fh:
        fh.write("5")

args = json.loads(sys.argv[1])
from maizeviz.canopy.field import canopy_of
from maizeviz.canopy.layout import layout_for
from maizeviz.cli.common import load_leaves
from maizeviz.light.engine import LightEngine
from maizeviz.light.sources.sun import Sun
from maizeviz.mesh.levels import parse_level
import embreex.rtcore_scene, maizeviz.mesh.embree_fill
out = {"points": args["points"], "level": args["level"], "periodic": args["periodic"],
       "baseline_mb": status()["VmRSS"] / 2**20}
stages = {}

def workers_cpu():
    # CPU seconds of a field's worker processes (started by forkserver: not our children)
    return getattr(leaves, "worker_cpu_s", 0.0) if "leaves" in globals() else 0.0

def stage(name, fn):
    gc.collect()
    reset()
    t, c, w = time.perf_counter(), cpu(), workers_cpu()
    got = fn()
    s = status()
    w_after = getattr(got[0], "worker_cpu_s", 0.0) if name == "read" else workers_cpu()
    stages[name] = {"s": time.perf_counter() - t, "cpu_s": cpu() - c + w_after - w,
                    "peak_bytes": s["VmHWM"], "after_bytes": s["VmRSS"]}
    return got

out["numpy_anchor_s"] = numpy_anchor()

leaves, skipped = stage("read", lambda: load_leaves(args["points"]))
layout = layout_for(leaves, (1, 1), args["row_spacing"], args["plant_spacing"])
canopy = stage("canopy", lambda: canopy_of(leaves, layout, parse_level(args["level"])))
out["worker_cpu_s"] = getattr(leaves, "worker_cpu_s", 0.0)
del leaves
F = canopy.n_triangles
out.update(triangles=F, plants=len(layout.placements), canopy_bytes=canopy.nbytes)
# the anchor first, beside the scene's build in time (the machine's load moves): the same
# float32 vertices and uint32 triangles the scene will hold (a periodic field's: the canopy on
# its grid, then the copies of the overhangs), given to a bare Embree scene with the same flags
from maizeviz.mesh.embree_fill import compact, fill
def anchor():
    if args["periodic"]:
        from maizeviz.light.scene.periodic import Wrap, overhang_copies, snap
        wrap = Wrap.of(canopy.layout.bounds)
        cv, cf, _, _ = overhang_copies(canopy.vertices, canopy.faces, wrap, wrap.q)
        v = np.vstack([snap(canopy.vertices, wrap.q), cv]).astype(np.float32)
        f = np.vstack([canopy.faces, cf + len(canopy.vertices)]).astype(np.int32)
    else:
        v, f = canopy.vertices.astype(np.float32), np.ascontiguousarray(canopy.faces, np.int32)
    bare = embreex.rtcore_scene.EmbreeScene(robust=False)
    compact(bare)
    assert fill(bare, v, f)
    del v, f
    t = time.perf_counter()
    bare.run(np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32))   # the BVH
    return time.perf_counter() - t
out["embree_bvh_s"] = anchor()
gc.collect()
engine = LightEngine(canopy, periodic=args["periodic"], density=args["density"])
scene = stage("scene", engine.scene)
res = stage("sun", lambda: engine.sun(Sun(30.0, 180.0), classes=True))
out["rays"] = res.rays
out["transmission"] = [round(float(t), 5) for t in res.transmission]
for k, st in stages.items():
    st["peak_bytes_per_triangle"] = st["peak_bytes"] / F
    st["after_bytes_per_triangle"] = st["after_bytes"] / F
out["stages"] = stages
out["peak_bytes_per_triangle"] = max(st["peak_bytes"] for st in stages.values()) / F
out["scene_over_embree_bvh"] = stages["scene"]["s"] / out["embree_bvh_s"]
out["numpy_anchor_end_s"] = numpy_anchor()
out["whole_s"] = sum(st["s"] for st in stages.values())
out["whole_cpu_s"] = sum(st["cpu_s"] for st in stages.values())
out["peak_gib"] = max(st["peak_bytes"] for st in stages.values()) / 2**30
print(json.dumps(out))
"""


def run(points: str, level: str, periodic: bool, density: float, row_spacing: float = 60.0,
        plant_spacing: float = 30.0) -> dict:
    """The stages of one field in a fresh process."""
    arg = json.dumps({"points": points, "level": level, "periodic": periodic,
                      "density": density, "row_spacing": row_spacing,
                      "plant_spacing": plant_spacing})
    done = subprocess.run([sys.executable, "-c", CHILD, arg], capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(done.stderr[-3000:])
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", required=True)
    ap.add_argument("--level", default="K4")
    ap.add_argument("--periodic", action="store_true")
    ap.add_argument("--density", type=float, default=4.0)
    ap.add_argument("--row-spacing", type=float, default=60.0)
    ap.add_argument("--plant-spacing", type=float, default=30.0)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    out = run(args.points, args.level, args.periodic, args.density, args.row_spacing,
              args.plant_spacing)
    if args.json:
        print(json.dumps(out, indent=1))
        return
    print(f"{out['plants']:,} plants, {out['triangles']:,} triangles at {out['level']}"
          f"{' (periodic)' if out['periodic'] else ''}, {out['rays']:,} rays")
    for name, st in out["stages"].items():
        print(f"{name:>8}: {st['s']:7.2f} s ({st['cpu_s']:7.2f} s of CPU), peak "
              f"{st['peak_bytes_per_triangle']:6.1f} B a triangle ({st['peak_bytes'] / 2**30:.2f} GiB)")
    print(f"numpy anchor (sorting 4 M float64): {out['numpy_anchor_s'] * 1e3:.0f} ms before, "
          f"{out['numpy_anchor_end_s'] * 1e3:.0f} ms after")
    print(f"Embree's own BVH build {out['embree_bvh_s']:.2f} s; scene / that "
          f"{out['scene_over_embree_bvh']:.2f} (target 1.3); peak "
          f"{out['peak_bytes_per_triangle']:.0f} B a triangle (target 150 at K = 4, 900 plants)")


if __name__ == "__main__":
    main()
