"""``maizeviz light``: direct sunlight through the canopy with Embree (Table 3)."""

from __future__ import annotations

import argparse
import json
import os
import time

from maizeviz.canopy.scene import build_canopy
from maizeviz.cli.common import (
    Progress,
    add_canopy_options,
    add_level_options,
    canopy_setup,
    check_canopy_costs,
    check_outputs,
    floats,
    fmt_table,
    leaves_summary,
    levels_from,
    say,
    suffixed,
    write_rows,
)
from maizeviz.cost import heatmap_cost, light_cost
from maizeviz.errors import MaizevizError
from maizeviz.io.atomic import refuse_overwriting_inputs
from maizeviz.light.beer_lambert import beer_lambert, clumping
from maizeviz.light.heatmap import write_heatmaps
from maizeviz.light.leaf_light import leaf_light, plant_light
from maizeviz.light.request import LightRequest
from maizeviz.light.sun import Sun, sun_at
from maizeviz.light.transmission import trace_light
from maizeviz.mesh.levels import CANOPY_LEVELS

#: The subcommand.
NAME = "light"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        NAME, help="direct sunlight through the canopy with Embree (Table 3)",
        description="Trace parallel sun rays through a canopy: transmission at several heights "
                    "inside a sample rectangle, sunlit and second-class area per leaf, per mesh "
                    "level with timings.")
    add_canopy_options(p)
    add_level_options(p, CANOPY_LEVELS)
    sun = p.add_argument_group("sun (explicit angles, or place + date + time through pvlib)")
    sun.add_argument("--sun-zenith", type=float, metavar="DEG", help="zenith angle, degrees")
    sun.add_argument("--sun-azimuth", type=float, metavar="DEG",
                     help="azimuth, degrees clockwise from north (field y = north by default)")
    sun.add_argument("--date", help="YYYY-MM-DD")
    sun.add_argument("--time", help="local clock time HH:MM (or HH:MM+08:00 with its offset)")
    sun.add_argument("--solar-noon", action="store_true", help="the true solar noon of --date")
    sun.add_argument("--lat", type=float, help="latitude, degrees north")
    sun.add_argument("--lon", type=float, help="longitude, degrees east")
    sun.add_argument("--tz", default=None,
                     help="time zone, e.g. Asia/Shanghai (default UTC, or the offset of --time)")
    p.add_argument("--heights", default="0,50,100,150,200,225", metavar="CM,...",
                   help="heights of the sample planes, cm (default 0,50,100,150,200,225)")
    p.add_argument("--density", type=float, default=4.0,
                   help="rays per cm2 of the sample rectangle (default 4)")
    p.add_argument("--rect", metavar="X0,Y0,X1,Y1",
                   help="sample rectangle on the ground, cm (default: the central tile)")
    p.add_argument("--periodic", action="store_true",
                   help="rays leaving the plot sideways re-enter on the other side (infinite field)")
    p.add_argument("--threads", type=int, default=os.cpu_count() or 1,
                   help="tracing threads (default: all cores)")
    p.add_argument("--with-stalks", action="store_true", help="stalks intercept light too")
    p.add_argument("--check", action="store_true",
                   help="print Beer-Lambert exp(-G L(h)/cos theta) from the mesh beside each value")
    p.add_argument("--json", action="store_true", help="print JSON instead of tables")
    p.add_argument("--heatmaps", metavar="DIR", help="write a transmission map PNG + CSV per height")
    p.add_argument("--heatmap-bin", type=float, default=5.0, metavar="CM",
                   help="heatmap bin size, cm (default 5)")
    p.add_argument("--leaf-light", metavar="CSV",
                   help="write sunlit and second-class area of every lit leaf")
    p.add_argument("--plant-light", metavar="CSV", help="the same summed per plant")
    p.set_defaults(run=run)


def sun_from(args: argparse.Namespace) -> Sun:
    """The sun of the command line: explicit angles, or a place and time through pvlib."""
    explicit = args.sun_zenith is not None or args.sun_azimuth is not None
    place = any(v is not None for v in (args.date, args.time, args.lat, args.lon)) or args.solar_noon
    if explicit and place:
        raise MaizevizError("give either --sun-zenith/--sun-azimuth or a place and time, not both")
    if explicit:
        if args.sun_zenith is None or args.sun_azimuth is None:
            raise MaizevizError("give both --sun-zenith and --sun-azimuth")
        return Sun(args.sun_zenith, args.sun_azimuth)
    if not place:
        raise MaizevizError("where is the sun? give --sun-zenith and --sun-azimuth, or --date, "
                            "--time (or --solar-noon), --lat, --lon and --tz")
    if args.date is None or args.lat is None or args.lon is None:
        raise MaizevizError("a sun from a place needs --date, --lat and --lon (and --time or "
                            "--solar-noon, --tz)")
    return sun_at(args.date, args.time, args.lat, args.lon, args.tz, args.solar_noon)


def run(args: argparse.Namespace) -> int:
    levels = levels_from(args)
    sun = sun_from(args)
    heights = tuple(floats(args.heights, "heights", "heights"))
    rect = tuple(floats(args.rect, "the sample rectangle", "rect", 4)) if args.rect else None
    if not args.heatmap_bin > 0:
        raise MaizevizError(f"the heatmap bin must be > 0 cm, got {args.heatmap_bin}",
                            quantity="heatmap_bin")
    check_outputs(args.leaf_light, args.plant_light)
    refuse_overwriting_inputs([("the leaf light table", args.leaf_light),
                               ("the plant light table", args.plant_light)],
                              [args.points, args.layout])
    say(f"sun: zenith {sun.zenith_deg:.2f} deg, azimuth {sun.azimuth_deg:.2f} deg"
        + (f" ({sun.when})" if sun.when else ""))
    leaves, skipped, layout = canopy_setup(args)
    sampled = rect or layout.centre_bounds
    work = [light_cost(sampled, args.density, len(heights))]            # type: ignore[arg-type]
    if args.heatmaps:
        work.append(heatmap_cost(sampled, args.heatmap_bin, len(heights)))  # type: ignore[arg-type]
    check_canopy_costs(leaves, layout, levels, args.force, work)
    want_classes = bool(args.leaf_light or args.plant_light)
    records: list[dict] = []
    for level in levels:
        t0 = time.perf_counter()
        canopy = build_canopy(leaves, layout, level, args.preserve_area,
                              Progress(f"building {level}"))
        canopy_s = time.perf_counter() - t0
        req = LightRequest(sun, heights, args.density, rect, args.periodic, args.threads,  # type: ignore[arg-type]
                           classes=want_classes or len(levels) == 1)
        res = trace_light(canopy, req, Progress(f"tracing {level}"), args.with_stalks)
        for w in res.warnings:
            if not records or w not in records[-1]["warnings"]:
                say(f"warning: {w}")
        rec = {"level": level.label, "triangles": canopy.n_triangles,
               "sun": {"zenith_deg": sun.zenith_deg, "azimuth_deg": sun.azimuth_deg,
                       "when": sun.when or None},
               "heights_cm": list(map(float, res.heights_cm)),
               "transmission": list(map(float, res.transmission)), "rays": res.rays,
               "density_per_cm2": res.density_per_cm2,
               "rect_cm": list(res.rect), "periodic": args.periodic, "threads": args.threads,
               "seconds": dict(canopy=canopy_s, scene=res.seconds["build"],
                               trace=res.seconds["trace"],
                               second_hits=res.seconds.get("second", 0.0)),
               "warnings": list(res.warnings)}
        if args.check:
            bl = beer_lambert(canopy, sun, heights)
            rec["beer_lambert"] = {"G": bl.G, "lai_above": list(map(float, bl.lai_above)),
                                   "transmission": list(map(float, bl.transmission))}
        if res.sunlit_intercepted_fraction is not None:
            rec["sunlit_intercepted_fraction"] = res.sunlit_intercepted_fraction
        if args.heatmaps:
            paths = write_heatmaps(args.heatmaps, res, args.heatmap_bin)
            say(f"wrote {len(paths) // 2} transmission maps (PNG + CSV) to {args.heatmaps}")
        if want_classes:
            rows = leaf_light(canopy, res)
            for r in rows:
                r["level"] = level.label
            if args.leaf_light:
                write_rows(args.leaf_light if len(levels) == 1 else
                           suffixed(args.leaf_light, level.label), rows)
            if args.plant_light:
                write_rows(args.plant_light if len(levels) == 1 else
                           suffixed(args.plant_light, level.label), plant_light(rows))
        records.append(rec)

    if args.json:
        print(json.dumps(records[0] if len(records) == 1 else {"levels": records}, indent=1))
    else:
        _print_tables(records, sun, heights, args)
    return leaves_summary(len(leaves), skipped)


def _print_tables(records: list[dict], sun: Sun, heights: tuple[float, ...],
                  args: argparse.Namespace) -> None:
    r0 = records[0]
    rc = ", ".join(f"{v:.1f}" for v in r0["rect_cm"])
    print(f"direct light: {r0['rays']:,} rays over x0,y0,x1,y1 = {rc} cm "
          f"({r0['density_per_cm2']:.2f} per cm2), sun zenith {sun.zenith_deg:.2f} deg, "
          f"azimuth {sun.azimuth_deg:.2f} deg{', periodic field' if args.periodic else ''}")
    head = ["height cm"] + [r["level"] for r in records]
    if args.check:
        head += ["Beer-Lambert"]
    rows = []
    for i, h in enumerate(heights):
        row = [f"{h:g}"] + [f"{r['transmission'][i]:.3f}" for r in records]
        if args.check:
            row.append(f"{records[0]['beer_lambert']['transmission'][i]:.3f}")
        rows.append(row)
    print(fmt_table(head, rows))
    if args.check:
        bl = records[0]["beer_lambert"]
        omega = clumping(records[0]["transmission"][0], bl["transmission"][0])
        print(f"Beer-Lambert with G = {bl['G']:.3f} and L(h) from the {records[0]['level']} "
              f"mesh; effective clumping at {heights[0]:g} cm: ln T / ln T_BL = {omega:.2f} "
              "(1: random foliage; below 1: clumped, T above Beer-Lambert, as in most row "
              "crops (0.7-1); above 1: more regular than random)")
    print()
    t_ref = records[0]["seconds"]["scene"] + records[0]["seconds"]["trace"]
    print(fmt_table(
        ["level", "triangles", "canopy s", "scene s", "trace s", "scene+trace vs first"],
        [[r["level"], r["triangles"], f"{r['seconds']['canopy']:.2f}",
          f"{r['seconds']['scene']:.2f}", f"{r['seconds']['trace']:.3f}",
          f"{(r['seconds']['scene'] + r['seconds']['trace']) / t_ref:.0%}"] for r in records]))
