"""Parallel efficiency of light tracing: threads 1 to 16, and Dask workers where Dask is
installed, measured in the same run.

Workload: the bundled block tiled 3 x 3 at ``--level`` (periodic field, traced through the
block's scene), the standard overcast sky in ``--directions`` directions at ``--density`` rays
per cm2, six sensor planes: directions run in parallel (``Sampling.threads``; Embree and the
packet kernel release the GIL). For each thread count t:

- seconds: best of ``--repeat``
- efficiency: T(1) / (t T(t)) (1.0: perfect)
- core_efficiency: T(1) / (min(t, cores) T(t)): past the machine's cores extra threads can only
  share them, so this is the figure to read there ("oversubscribed" marks those rows)

Dask (``--dask``, needs ``maizeviz[sweep]``): a local cluster of w single-threaded worker
processes for w = 1 .. cores, each keeping its own canopy and scene (built before timing), the
directions spread over the workers; efficiency T(1 worker) / (w T(w)).

This machine has 2 cores: only t <= 2 (and w <= 2) measure parallel speed; the rows beyond
show what oversubscription costs, not what more cores would give.

    python benchmarks/bench_scaling.py [--json] [--level K1] [--directions 16] [--dask]
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np
from anchors import best

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.scene.embree_scenes import light_scene
from maizeviz.light.scene.request import Sampling
from maizeviz.light.sources.sky import Sky, make_sky
from maizeviz.light.trace.directions import trace_sky
from maizeviz.mesh.levels import parse_level
from maizeviz.resources import example_points

_WORKER: dict = {}


def _canopy(level: str):
    leaves = read_leaves(example_points()).leaves
    return build_canopy(leaves, layout_for(leaves, (3, 3)), parse_level(level))


def _worker_setup(level: str) -> int:
    """Build the canopy and its scene once in a Dask worker."""
    if _WORKER.get("level") != level:
        canopy = _canopy(level)
        _WORKER.update(level=level, canopy=canopy, scene=light_scene(canopy, periodic=True))
    return os.getpid()


def _worker_trace(level: str, zenith: list[float], azimuth: list[float], weights: list[float],
                  density: float) -> float:
    """Trace some of the sky's directions on the worker's kept scene; seconds spent."""
    _worker_setup(level)
    w = np.array(weights)
    sky = Sky("soc", "equal", np.array(zenith), np.array(azimuth),
              np.full(len(zenith), 2 * np.pi / len(zenith)), w / w.sum())   # a part of it
    t0 = time.perf_counter()
    trace_sky(_WORKER["canopy"], sky, Sampling(density=density, periodic=True, threads=1),
              scene=_WORKER["scene"])
    return time.perf_counter() - t0



def dask_rows(args, sky: Sky, cores: int) -> list[dict]:
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        return [{"dask": "not installed"}]
    rows = []
    for workers in range(1, cores + 1):
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            client.run(_worker_setup, args.level)
            parts = np.array_split(np.arange(sky.n), max(workers, sky.n // 2))

            def run(parts=parts):
                futures = [client.submit(_worker_trace, args.level,
                                         sky.zenith_deg[p].tolist(), sky.azimuth_deg[p].tolist(),
                                         sky.weights[p].tolist(), args.density, pure=False)
                           for p in parts if len(p)]
                client.gather(futures)
            rows.append({"workers": workers, "seconds": round(best(run, args.repeat), 3)})
    for r in rows:
        r["efficiency"] = round(rows[0]["seconds"] / (r["workers"] * r["seconds"]), 2)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--level", default="K1")
    ap.add_argument("--density", type=float, default=4.0)
    ap.add_argument("--directions", type=int, default=16)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--max-threads", type=int, default=16)
    ap.add_argument("--dask", action="store_true")
    args = ap.parse_args()
    cores = os.cpu_count() or 1

    canopy = _canopy(args.level)
    scene = light_scene(canopy, periodic=True)
    sky = make_sky("soc", args.directions, "equal" if args.directions not in (6, 16, 46)
                   else "auto")
    rows = []
    t = 1
    while t <= args.max_threads:
        smp = Sampling(density=args.density, periodic=True, threads=t)
        secs = best(lambda smp=smp: trace_sky(canopy, sky, smp, scene=scene), args.repeat)
        rows.append({"threads": t, "seconds": round(secs, 3),
                     **({"oversubscribed": True} if t > cores else {})})
        t *= 2
    for r in rows:
        r["efficiency"] = round(rows[0]["seconds"] / (r["threads"] * r["seconds"]), 2)
        r["core_efficiency"] = round(rows[0]["seconds"] / (min(r["threads"], cores)
                                                           * r["seconds"]), 2)
    out = {"cores": cores, "level": args.level, "triangles": canopy.n_triangles,
           "scene": type(scene).__name__, "directions": sky.n, "threads": rows,
           "note": f"{cores} cores here: rows past {cores} threads show oversubscription only"}
    if args.dask:
        out["dask"] = dask_rows(args, sky, cores)
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        print(f"{cores} cores, {args.level} ({canopy.n_triangles:,} triangles, "
              f"{out['scene']}), {sky.n} sky directions at {args.density:g} rays/cm2")
        for r in rows:
            print(f"  threads {r['threads']:>2}: {r['seconds']:7.3f} s  efficiency "
                  f"{r['efficiency']:.2f}  per core {r['core_efficiency']:.2f}"
                  f"{'  (oversubscribed)' if r.get('oversubscribed') else ''}")
        for r in out.get("dask", []):
            print(f"  dask {r}")
        print(f"  note: {out['note']}")


if __name__ == "__main__":
    main()
