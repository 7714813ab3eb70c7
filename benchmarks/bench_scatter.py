"""Absorbed PAR with scattering against the black-leaf run, in the same run.

On the bundled 3 x 3 block tiled 3 x 3 (81 plants) at ``--level`` (default K = 4, 2.68 M
triangles), periodic field, a noon-like sun (zenith 30 deg), ``--density`` rays per cm2 over
the central tile, on the engine's kept scene (its build is not counted on either side):

- sun_s: today's black-leaf run, the direct light of the same sun (``LightEngine.sun``,
  no hit classes): the anchor
- black_s: absorbed light with black leaves and ground (every optical value 0: the primary
  beam only, equal to the interception of direct light)
- scatter_s: the same with the maize PAR optics, scattering followed to ``--depth``
  (default 3)
- cost_ratio: scatter_s / sun_s (target <= 3); black_ratio: black_s / sun_s; the same
  in the process's CPU time (``*_ratio_cpu``: every thread's, steadier on a shared machine)
- rays_per_s: primary and scattered rays traced per second with scattering
- closure: the energy balance's closure (0 up to Monte Carlo noise)

and the diffuse light of a ``--sky-directions`` uniform overcast sky (``--sky-density`` rays
per cm2, default 1), for PAR and NIR at the default depth (20):

- sky_black_s: the black-leaf sky (``LightEngine.sky``: every direction over the whole grid):
  the anchor of the sky
- sky_par_s, sky_nir_s: absorbed diffuse light with the maize optics, the sky's directions
  drawn per ray (4 rays per cell); sky_par_ratio, sky_nir_ratio: against the anchor (target
  <= 2)
- sky_par_all_s, sky_nir_all_s: the same traced direction by direction over the whole grid
  (``sky_passes=0``, before); the answers of both ways, with their standard errors
  (``*_absorbed``, ``*_se``, fractions of the diffuse light), agree within them

    python benchmarks/bench_scatter.py [--json] [--level K4] [--density 4] [--depth 3]
        [--sky-directions 145] [--sky-density 1]
"""

from __future__ import annotations

import argparse
import json
import time

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.engine import LightEngine
from maizeviz.light.trace.optics import DEFAULT_OPTICS, Optics
from maizeviz.mesh.levels import parse_level
from maizeviz.resources import example_points

CPU: dict[str, float] = {}


def best(fn, repeat: int, name: str = ""):
    """Shortest wall time of ``repeat`` calls and the last answer; the shortest CPU time
    of the process (all its threads: steadier on a shared machine) kept in ``CPU[name]``."""
    out = None
    times, cpu = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    if name:
        CPU[name] = min(cpu)
    return min(times), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--level", default="K4")
    ap.add_argument("--density", type=float, default=4.0)
    ap.add_argument("--depth", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--sky-directions", type=int, default=145)
    ap.add_argument("--sky-density", type=float, default=1.0)
    ap.add_argument("--no-sky", action="store_true", help="leave the sky part out")
    args = ap.parse_args()

    leaves = read_leaves(example_points()).leaves
    canopy = build_canopy(leaves, layout_for(leaves, (3, 3)), parse_level(args.level))
    eng = LightEngine(canopy, periodic=True, density=args.density, heights_cm=(0.0,),
                      threads=args.threads)
    eng.scene()
    eng.absorbed(zenith=30, azimuth=150, optics=Optics(0, 0, 0))   # normals, warm caches
    sun_s, _ = best(lambda: eng.sun(zenith=30, azimuth=150, classes=False), args.repeat,
                    "sun")
    black_s, black = best(lambda: eng.absorbed(zenith=30, azimuth=150,
                                               optics=Optics(0, 0, 0)), args.repeat, "black")
    scatter_s, lit = best(lambda: eng.absorbed(zenith=30, azimuth=150,
                                               optics=DEFAULT_OPTICS["par"],
                                               depth=args.depth), args.repeat, "scatter")
    out = {"triangles": canopy.n_triangles, "rays": lit.rays, "depth": args.depth,
           "sun_s": round(sun_s, 3), "black_s": round(black_s, 3),
           "scatter_s": round(scatter_s, 3), "cost_ratio": round(scatter_s / sun_s, 2),
           "black_ratio": round(black_s / sun_s, 2),
           "cost_ratio_cpu": round(CPU["scatter"] / CPU["sun"], 2),
           "black_ratio_cpu": round(CPU["black"] / CPU["sun"], 2),
           "rays_per_s": round((lit.rays + lit.events) / scatter_s),
           "black_fraction_absorbed": round(black.fraction_absorbed, 4),
           "fraction_absorbed": round(lit.fraction_absorbed, 4),
           "reflected_top": round(lit.balance.reflected_top / lit.balance.incident, 4),
           "closure": round(lit.balance.closure, 5)}
    if not args.no_sky:
        out.update(sky_part(canopy, args))
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        for k, v in out.items():
            print(f"{k:>24}: {v}")


def sky_part(canopy, args) -> dict:
    """The sky: black leaves against absorbed PAR and NIR, per ray and direction by
    direction (each timed once: the direction-by-direction NIR sky takes about a minute)."""
    from maizeviz.light.sources.sky import make_sky

    sky = make_sky("uoc", args.sky_directions)
    eng = LightEngine(canopy, periodic=True, density=args.sky_density, heights_cm=(0.0,),
                      threads=args.threads)
    eng.scene()
    black_s, _ = best(lambda: eng.sky(sky), 1)
    out: dict = {"sky_directions": sky.n, "sky_density": args.sky_density,
                 "sky_black_s": round(black_s, 3)}
    for band in ("par", "nir"):
        for label, passes in ((band, 4), (f"{band}_all", 0)):
            secs, got = best(lambda p=passes, b=band: eng.absorbed(
                direct_w_m2=0.0, diffuse_w_m2=1.0, sky=sky, band=b, sky_passes=p), 1)
            out[f"sky_{label}_s"] = round(secs, 3)
            out[f"sky_{label}_absorbed"] = round(got.balance.absorbed_leaves, 5)
            out[f"sky_{label}_se"] = round(got.absorbed_leaves_error, 5)
        out[f"sky_{band}_ratio"] = round(out[f"sky_{band}_s"] / black_s, 2)
    return out


if __name__ == "__main__":
    main()
