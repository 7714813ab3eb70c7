"""Light end to end on the bundled example at K = 4, as a user runs it, measured in the same
run as the anchor (benchmarks/anchors.py).

Fresh processes of the command line (``maizeviz light``, the bundled 3 x 3 block tiled 3 x 3:
81 plants, 2,678,400 triangles at K = 4, periodic field, density 4, the six default planes):

- cli_sun_s: noon sun of Beijing on 2005-08-01 from the date and place (pvlib), the whole
  process: reading and fitting the points, meshing, the Embree scene, tracing, JSON
  (issue 20's target: 1.5 s)
- cli_sun_angles_s: the same sun given as angles (no pvlib import)
- cli_day_s: that day at 30-minute steps (29 steps with the sun up) plus the standard overcast
  sky in 46 directions (target: 5 s)
- cli_day_36_s: the same day as benchmarks/bench_daylight.py traces it: 36 triangles a leaf,
  1 ray per cm2, five planes
- *_seconds: the JSON's own split (canopy, scene, trace, second hits)
- cli_*_single_rays_s: the same with MAIZEVIZ_PACKETS=0 (embreex's single rays)
- bvh_s: the anchor, Embree's BVH build of the same 2,678,400 triangles in this process
  (benchmarks/bench_scene.py's, buffers already filled); cli_sun_over_bvh: the whole sun
  process over it (target 1.5: the command's start, imports and fitting are not to cost more
  than half a scene build)

In one process (``LightEngine``), the block scene (maizeviz.light.scene.tiling) against the whole
tiled canopy, same engine otherwise:

- build_block_s / build_whole_s: the periodic scene's build
- sun_block_s / sun_whole_s: the noon sun on the kept scene (hit classes included)
- day_block_s / day_whole_s: the day (29 steps + 46 sky directions) on the kept scene
- block_speedup_first_sun: (build + sun) whole / block, what a user's first sun gains

With ``--sun-only``, the noon sun's process and the anchor alone (cli_sun_s, bvh_s,
cli_sun_over_bvh), a minute where the whole takes several.

    python benchmarks/bench_end_to_end.py [--json] [--repeat 3] [--threads 2] [--sun-only]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from anchors import matmul_anchor, report
from bench_scene import timed_build

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.engine import LightEngine
from maizeviz.light.scene.embree_scenes import light_scene
from maizeviz.light.sources.sun import sun_at
from maizeviz.mesh.levels import parse_level
from maizeviz.resources import example_points

PLACE = ["--date", "2005-08-01", "--lat", "39.9", "--lon", "116.4", "--tz", "Asia/Shanghai"]


def cli(args: list[str], env: dict | None = None) -> tuple[float, dict]:
    """Seconds of a fresh ``maizeviz light`` process, and its JSON."""
    exe = Path(sys.executable).with_name("maizeviz")
    cmd = [str(exe), "light", str(example_points()), "--tile", "3x3", "--periodic", "--json",
           *args]
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, **(env or {})},
                          check=True)
    return time.perf_counter() - t0, json.loads(done.stdout)


def best_cli(args: list[str], repeat: int, env: dict | None = None) -> tuple[float, dict]:
    runs = [cli(args, env) for _ in range(repeat)]
    return min(runs, key=lambda r: r[0])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--sun-only", action="store_true",
                    help="only the noon sun's process against Embree's BVH build")
    args = ap.parse_args()
    threads = ["--threads", str(args.threads)]
    out: dict[str, object] = {"anchor_s": round(matmul_anchor(), 3), "cores": os.cpu_count()}

    sun_args = [*PLACE, "--time", "12:00", *threads]
    for name, a, env in (("cli_sun", sun_args, None),
                         ("cli_sun_angles", ["--sun-zenith", "22.34", "--sun-azimuth", "166.95",
                                             *threads], None),
                         ("cli_day", [*PLACE, "--day", "--step", "30", *threads], None),
                         ("cli_day_36", [*PLACE, "--day", "--step", "30", "--triangles", "36",
                                         "--density", "1", "--heights", "0,50,100,150,200",
                                         *threads], None),
                         ("cli_sun_single_rays", sun_args, {"MAIZEVIZ_PACKETS": "0"})):
        if args.sun_only and name != "cli_sun":
            continue
        s, doc = best_cli(a, args.repeat, env)
        out[f"{name}_s"] = round(s, 2)
        secs = doc.get("seconds") or doc.get("day", {}).get("seconds")
        if secs:
            out[f"{name}_seconds"] = {k: round(v, 3) for k, v in secs.items()}
    out["cli_sun_over_anchor"] = round(out["cli_sun_s"] / out["anchor_s"], 1)   # type: ignore[operator]

    leaves = read_leaves(example_points()).leaves
    canopy = build_canopy(leaves, layout_for(leaves, (3, 3)), parse_level("K4"))
    noon = sun_at("2005-08-01", "12:00", 39.9, 116.4, "Asia/Shanghai")
    v = np.ascontiguousarray(canopy.vertices, np.float32)
    f = np.ascontiguousarray(canopy.faces, np.int32)
    out["bvh_s"] = round(min(timed_build(v, f, True)[1] for _ in range(args.repeat)), 3)
    out["cli_sun_over_bvh"] = round(out["cli_sun_s"] / out["bvh_s"], 2)   # type: ignore[operator]
    if args.sun_only:
        out["targets"] = {"cli_sun_s": 1.5, "cli_sun_over_bvh": 1.5}
        report(out, args.json)
        return
    for name, block in (("block", True), ("whole", False)):
        eng = LightEngine(canopy, periodic=True, threads=args.threads)
        t0 = time.perf_counter()
        eng._scenes[True] = light_scene(canopy, periodic=True, block=block)
        out[f"build_{name}_s"] = round(time.perf_counter() - t0, 3)
        sun_s, day_s = [], []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            eng.sun(noon)
            sun_s.append(time.perf_counter() - t0)
            eng._sky = None                                  # trace the sky every time
            t0 = time.perf_counter()
            eng.day(date="2005-08-01", lat=39.9, lon=116.4, tz="Asia/Shanghai")
            day_s.append(time.perf_counter() - t0)
        out[f"sun_{name}_s"] = round(min(sun_s), 3)
        out[f"day_{name}_s"] = round(min(day_s), 3)
    out["block_speedup_first_sun"] = round(
        (out["build_whole_s"] + out["sun_whole_s"])                            # type: ignore[operator]
        / (out["build_block_s"] + out["sun_block_s"]), 1)                      # type: ignore[operator]
    out["block_speedup_day"] = round(out["day_whole_s"] / out["day_block_s"], 2)  # type: ignore[operator]
    out["targets"] = {"cli_sun_s": 1.5, "cli_day_s": 5.0, "cli_sun_over_bvh": 1.5}
    report(out, args.json)


if __name__ == "__main__":
    main()
