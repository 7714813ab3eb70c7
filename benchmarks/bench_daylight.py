"""A day of light against single suns, measured in the same run.

The bundled block tiled 3 x 3 at 36 triangles per leaf, periodic field, the central 180 x 90 cm
rectangle at 1 sensor per cm2, sensor planes at 0, 50, 100, 150, 200 cm; Beijing 2005-08-01, a
clear day at 30-minute steps (the sun traced at every step with the sun up) plus the standard
overcast sky in 46 directions, all on both cores:

- directions: sun steps + sky directions traced by the period computation
- rays: rays per direction (and sensors per plane)
- seconds: the whole period computation, including its one scene build
- seconds_single_sun: one standalone noon sun (scene build + tracing, as ``maizeviz light``
  pays for a sun), best of ``--repeat``
- cost_per_direction_ratio: seconds / (directions x seconds_single_sun) (target <= 1.0: the
  scene is built once and shared by every direction, directions run on both cores)
- build_s: the Embree scene build
- seconds_single_sun_trace, cost_per_direction_ratio_trace: the same without any scene build
  (tracing only), a stricter comparison

    python benchmarks/bench_daylight.py [--json] [--threads 2] [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import plant_bases, tiled_layout
from maizeviz.io.points import read_points
from maizeviz.leaf.fit import fit_leaves
from maizeviz.leaf.grid import build_grids
from maizeviz.light.scene.embree_scenes import light_scene
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.sources.irradiance import clear_sky_period
from maizeviz.light.sources.sky import make_sky
from maizeviz.light.sources.sun import sun_at
from maizeviz.light.trace.beam import trace_light
from maizeviz.light.trace.directions import trace_period
from maizeviz.mesh.levels import parse_level

ROOT = Path(__file__).resolve().parents[1]
HEIGHTS = (0.0, 50.0, 100.0, 150.0, 200.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--threads", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--level", default="36")
    ap.add_argument("--density", type=float, default=1.0)
    args = ap.parse_args()

    grids, _ = build_grids(read_points(ROOT / "maizeviz" / "resources" / "block3x3.csv"))
    leaves, _ = fit_leaves(grids)
    layout = tiled_layout(plant_bases(leaves), (3, 3))
    canopy = build_canopy(leaves, layout, parse_level(args.level))
    period = clear_sky_period("2005-08-01", 39.9, 116.4, "Asia/Shanghai", step_min=30)
    sky = make_sky("soc", 46)
    sampling = Sampling(HEIGHTS, args.density, None, True, args.threads)
    noon = sun_at("2005-08-01", "12:00", 39.9, 116.4, "Asia/Shanghai")
    req = LightRequest(noon, Sampling(HEIGHTS, args.density, None, True, args.threads),
                       classes=False)

    single, single_trace, builds, periods = [], [], [], []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        r = trace_light(canopy, req)                           # builds its own scene
        single.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        scene = light_scene(canopy, periodic=True)
        builds.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        trace_light(canopy, req, scene=scene)
        single_trace.append(time.perf_counter() - t0)
    for _ in range(max(1, args.repeat - 1)):
        t0 = time.perf_counter()
        pl = trace_period(canopy, period, sampling, sky)      # builds one scene for all
        periods.append(time.perf_counter() - t0)
    directions = pl.n_steps + sky.n
    seconds, build_s = min(periods), min(builds)
    one, one_trace = min(single), min(single_trace)
    out = {"directions": directions, "rays": r.rays, "seconds": seconds,
           "seconds_single_sun": one, "cost_per_direction_ratio": seconds / (directions * one),
           "build_s": build_s,
           "seconds_single_sun_trace": one_trace,
           "cost_per_direction_ratio_trace": (seconds - build_s) / (directions * one_trace),
           "sun_steps": pl.n_steps, "sky_directions": sky.n, "threads": args.threads,
           "triangles": canopy.n_triangles, "heights_cm": list(HEIGHTS),
           "par_incident_mol_m2": pl.par_incident_mol_m2,
           "fraction_intercepted": pl.fraction_intercepted,
           "targets": {"cost_per_direction_ratio": 1.0}}
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        for k, v in out.items():
            print(f"{k:>32}: {v:,.4f}" if isinstance(v, float) else f"{k:>32}: {v}")


if __name__ == "__main__":
    main()
