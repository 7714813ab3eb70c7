"""The ``maizeviz`` command: headless subcommands; with none, the desktop app.

Exit codes: 0 all done; 1 nothing could be done (bad file, every leaf refused, bad request);
2 bad command-line usage; 3 done, but some leaves were skipped (listed on stderr).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import traceback

from maizeviz.errors import LeafError, MaizevizError
from maizeviz.leaf.reconstruct import DEFAULT_LEVELS

EXIT_OK, EXIT_FAIL, EXIT_USAGE, EXIT_PARTIAL = 0, 1, 2, 3


def _say(msg: str) -> None:
    print(msg, file=sys.stderr)


# ----------------------------------------------------------------------------------- leaf
def _add_leaf(sub):
    p = sub.add_parser(
        "leaf", help="fit NURBS surfaces through digitized leaves and mesh them",
        description="Fit a NURBS surface through every leaf of a points file and mesh it at "
                    "the chosen complexity. Areas in cm2, lengths in cm.")
    p.add_argument("points", help="points CSV (plant,leaf,row,col,x,y,z in cm)")
    _add_level_options(p, DEFAULT_LEVELS)
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--export", metavar="PATH",
                   help="write the meshes: .ply .obj .vtk .vtu .vtp .stl (plant/leaf ids kept "
                        "as cell data where the format allows)")
    p.add_argument("--degree", type=int, default=3, help="NURBS degree in u and v (default 3)")
    p.add_argument("--params", choices=("chord", "centripetal"), default="chord",
                   help="data parameters (default chord length)")
    p.add_argument("--strict", action="store_true",
                   help="stop at the first bad leaf instead of skipping it")
    p.set_defaults(run=_run_leaf)


def load_leaves(path, strict=False, degree=3, method="chord"):
    """Read, grid and fit a points file, saying skipped lines and repairs on stderr.

    Returns (leaves, skipped errors).
    """
    from maizeviz.leaf.reconstruct import read_leaves

    found = read_leaves(path, strict, degree, method)
    for problem in found.problems:
        _say(f"warning: {problem}")
    for note in found.notes:
        _say(f"note: {note}")
    return found.leaves, found.skipped


def _fmt_table(headers, rows) -> str:
    cells = [headers] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def _run_leaf(args) -> int:
    from maizeviz.io.export import export_meshes
    from maizeviz.leaf.reconstruct import measure, mesh_leaves

    levels = _levels_from(args)
    if args.export and len(levels) > 1:
        raise MaizevizError("--export writes one level: use it with --interp or --triangles")
    leaves, skipped = load_leaves(args.points, args.strict, args.degree, args.params)
    per_level = []
    for level in levels:
        try:
            meshes = mesh_leaves(leaves, level, args.preserve_area)
        except ValueError as exc:
            raise MaizevizError(f"{level}: {exc}") from None
        per_level.append((level, meshes, [measure(lf, m) for lf, m in zip(leaves, meshes)]))

    if args.export and leaves:
        path = export_meshes(args.export, per_level[0][1])
        _say(f"wrote {sum(m.n_triangles for m in per_level[0][1])} triangles of "
             f"{len(leaves)} leaves to {path}")

    skipped_json = [{"plant": e.plant, "leaf": e.leaf, "error": e.detail} for e in skipped]
    if args.json:
        if args.levels is not None:
            out = {"levels": [str(lv) for lv in levels], "leaves": [
                {"plant": lf.grid.plant, "leaf": lf.grid.leaf, "rows": lf.grid.shape[0],
                 "cols": lf.grid.shape[1], "notes": list(lf.grid.notes),
                 "levels": [ms[i].as_dict() for _, _, ms in per_level]}
                for i, lf in enumerate(leaves)]}
        else:
            out = {"level": str(levels[0]),
                   "leaves": [dict(ms.as_dict(), notes=list(lf.grid.notes))
                              for lf, ms in zip(leaves, per_level[0][2])]}
        out["skipped"] = skipped_json
        print(json.dumps(out, indent=1))
    elif args.levels is not None:
        for i, lf in enumerate(leaves):
            print(f"plant {lf.grid.plant}, leaf {lf.grid.leaf} ({lf.grid.shape[0]} x "
                  f"{lf.grid.shape[1]} points)")
            print(_fmt_table(
                ["level", "triangles", "area cm2", "area err %", "projected cm2",
                 "max dev cm"],
                [[ms[i].level, ms[i].triangles, f"{ms[i].area_cm2:.1f}",
                  f"{ms[i].area_error_pct:+.1f}", f"{ms[i].projected_area_cm2:.1f}",
                  f"{ms[i].max_deviation_cm:.2f}"] for _, _, ms in per_level]))
            print()
    else:
        ms = per_level[0][2]
        print(f"level: {levels[0]}")
        print(_fmt_table(
            ["plant", "leaf", "rows x cols", "triangles", "area cm2", "projected cm2",
             "max dev cm"],
            [[m.plant, m.leaf, f"{m.rows} x {m.cols}", m.triangles, f"{m.area_cm2:.1f}",
              f"{m.projected_area_cm2:.1f}", f"{m.max_deviation_cm:.2f}"] for m in ms]))
        if ms:
            print(f"total: {len(ms)} leaves, {sum(m.triangles for m in ms)} triangles, "
                  f"{sum(m.area_cm2 for m in ms):.1f} cm2 of leaf")
    return _summary(len(leaves), skipped)


def _summary(done: int, skipped: list[LeafError]) -> int:
    for e in skipped:
        _say(f"skipped: {e}")
    if skipped:
        _say(f"{done} leaves done, {len(skipped)} skipped")
    if done == 0:
        _say("error: no leaf could be processed")
        return EXIT_FAIL
    return EXIT_PARTIAL if skipped else EXIT_OK


# --------------------------------------------------------------------------------- canopy
def _add_level_options(p, default_levels):
    lv = p.add_mutually_exclusive_group()
    lv.add_argument("--interp", type=int, metavar="K",
                    help="K points interpolated between data points (0 = standard mesh; "
                         "default 4, the paper's reference mesh)")
    lv.add_argument("--triangles", type=int, metavar="N",
                    help="at most N triangles per leaf (inverse multi-line segment splitting)")
    lv.add_argument("--levels", nargs="?", const=default_levels, metavar="LIST",
                    help=f"compare levels (default {default_levels})")
    p.add_argument("--no-preserve-area", dest="preserve_area", action="store_false",
                   help="below the standard mesh, do not widen cross-sections to keep the "
                        "smooth surface's area")


def _add_canopy_options(p):
    p.add_argument("points", help="points CSV of the digitized plants (field coordinates, cm)")
    p.add_argument("--tile", default="1x1", metavar="AxB",
                   help="repeat the digitized block A times across rows (x) and B times along "
                        "them (y); the paper uses 3x3 (default 1x1)")
    p.add_argument("--block", metavar="RxP",
                   help="rows x plants per row of the digitized block (default: inferred from "
                        "the stalk positions)")
    p.add_argument("--row-spacing", type=float, default=60.0, metavar="CM",
                   help="distance between rows along x, cm (default 60)")
    p.add_argument("--plant-spacing", type=float, default=30.0, metavar="CM",
                   help="distance between plants in a row along y, cm (default 30)")
    p.add_argument("--layout", metavar="JSON", help="a layout file instead of tiling")
    p.add_argument("--strict", action="store_true",
                   help="stop at the first bad leaf instead of skipping it")


def _add_canopy(sub):
    p = sub.add_parser(
        "canopy", help="lay out digitized plants as a canopy and measure it (Table 2)",
        description="Build a canopy from digitized plants, tiled or from a layout file, and "
                    "report leaf area, projected area, ground cover and LAI.")
    _add_canopy_options(p)
    _add_level_options(p, "K4,standard,36,4")
    p.add_argument("--with-stalks", action="store_true",
                   help="count stalk cylinders in the measures (they are always in exports)")
    p.add_argument("--cover-resolution", type=float, default=0.5, metavar="CM",
                   help="pixel edge of the vertical-ray grid measuring ground cover (default 0.5)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--export", metavar="PATH",
                   help="write the canopy mesh: .ply .obj .vtk .vtu .vtp .stl")
    p.add_argument("--save-layout", metavar="JSON", help="write the layout used as a layout file")
    p.set_defaults(run=_run_canopy)


class Progress:
    """A progress callback for the core: a bar on stderr when it is a terminal, else silent."""

    def __init__(self, label: str):
        self.label = label
        self.tty = sys.stderr.isatty()
        self.last = -1

    def __call__(self, done, total):
        if not self.tty or total <= 0:
            return None
        pct = int(100 * done / total)
        if pct != self.last:
            self.last = pct
            bar = "#" * (pct // 4)
            sys.stderr.write(f"\r{self.label} [{bar:<25}] {pct:3d}%")
            if done >= total:
                sys.stderr.write("\n")
            sys.stderr.flush()
        return None


def _levels_from(args, default_k=4):
    from maizeviz.leaf.reconstruct import Level, parse_levels

    if args.levels is not None:
        try:
            return parse_levels(args.levels)
        except ValueError as exc:
            raise MaizevizError(str(exc)) from None
    if args.triangles is not None:
        if args.triangles < 1:
            raise MaizevizError(f"--triangles must be >= 1, got {args.triangles}")
        return [Level(triangles=args.triangles)]
    k = default_k if args.interp is None else args.interp
    if k < 0:
        raise MaizevizError(f"--interp must be >= 0, got {k}")
    return [Level(interp=k)]


def canopy_setup(args):
    """Leaves and layout from the canopy options; warnings on stderr. -> (leaves, skipped, layout)"""
    from maizeviz.canopy.layout import load_layout, parse_shape, tiled_layout
    from maizeviz.canopy.scene import plant_bases

    tile = parse_shape(args.tile, "--tile")
    block = parse_shape(args.block, "--block") if args.block else None
    leaves, skipped = load_leaves(args.points, args.strict)
    if not leaves:
        for e in skipped:
            _say(f"skipped: {e}")
        raise MaizevizError("no leaf could be reconstructed; the canopy is empty")
    plants = {lf.grid.plant for lf in leaves}
    if args.layout:
        layout = load_layout(args.layout, plants)
    else:
        layout = tiled_layout(plant_bases(leaves), tile, args.row_spacing, args.plant_spacing,
                              block)
    for w in layout.warnings:
        _say(f"note: {w}")
    return leaves, skipped, layout


def _run_canopy(args) -> int:
    from maizeviz.canopy.layout import save_layout
    from maizeviz.canopy.measures import measure_canopy
    from maizeviz.canopy.scene import build_canopy
    from maizeviz.io.export import export_canopy

    levels = _levels_from(args)
    if args.export and len(levels) > 1:
        raise MaizevizError("--export writes one level: use it with --interp or --triangles")
    if args.cover_resolution <= 0:
        raise MaizevizError(f"--cover-resolution must be > 0 cm, got {args.cover_resolution}")
    leaves, skipped, layout = canopy_setup(args)
    if args.save_layout:
        save_layout(args.save_layout, layout)
    runs = []
    for level in levels:
        variants = [(level, args.preserve_area)]
        if args.levels is not None and level.triangles is not None and args.preserve_area:
            variants.append((level, False))        # the paper's splitting, widths untouched
        for lv, preserve in variants:
            t0 = time.perf_counter()
            try:
                canopy = build_canopy(leaves, layout, lv, preserve, Progress(f"building {lv}"))
            except ValueError as exc:
                raise MaizevizError(f"{lv}: {exc}") from None
            t1 = time.perf_counter()
            m = measure_canopy(canopy, args.cover_resolution, args.with_stalks)
            label = lv.label + ("" if preserve or lv.triangles is None else ", widths unscaled")
            d = dict(m.as_dict(), level=label, build_s=t1 - t0,
                     measure_s=time.perf_counter() - t1, preserve_area=preserve)
            runs.append(d)
            if args.export:
                path = export_canopy(args.export, canopy)
                _say(f"wrote {canopy.n_triangles} leaf triangles of {canopy.n_plants} plants "
                     f"(and their stalks) to {path}")
    if args.json:
        print(json.dumps(runs[0] if len(runs) == 1 else {"levels": runs}, indent=1))
    else:
        x0, y0, x1, y1 = layout.bounds
        print(f"canopy: {runs[0]['plants']} plants on {runs[0]['ground_area_m2']:.2f} m2 "
              f"(x {x0:.0f}..{x1:.0f} cm, y {y0:.0f}..{y1:.0f} cm)")
        print(_fmt_table(
            ["level", "triangles", "leaf area m2", "projected m2", "ground cover m2", "LAI",
             "build s"],
            [[r["level"], r["triangles"], f"{r['leaf_area_m2']:.2f}",
              f"{r['projected_area_m2']:.2f}", f"{r['ground_cover_m2']:.2f}",
              f"{r['lai']:.2f}", f"{r['build_s']:.2f}"] for r in runs]))
        print(f"ground cover: vertical rays every {args.cover_resolution:g} cm inside the plot")
    return _summary(len(leaves), skipped)


# ---------------------------------------------------------------------------------- light
def _floats(text, what, count=None):
    try:
        vals = [float(v) for v in str(text).split(",") if v.strip()]
    except ValueError:
        raise MaizevizError(f"{what} must be numbers separated by commas, got '{text}'") from None
    if count is not None and len(vals) != count:
        raise MaizevizError(f"{what} needs {count} numbers, got '{text}'")
    return vals


def _add_light(sub):
    p = sub.add_parser(
        "light", help="direct sunlight through the canopy with Embree (Table 3)",
        description="Trace parallel sun rays through a canopy: transmission at several heights "
                    "inside a sample rectangle, sunlit and second-class area per leaf, per mesh "
                    "level with timings.")
    _add_canopy_options(p)
    _add_level_options(p, "K4,standard,36,4")
    sun = p.add_argument_group("sun (explicit angles, or place + date + time through pvlib)")
    sun.add_argument("--sun-zenith", type=float, metavar="DEG", help="zenith angle, degrees")
    sun.add_argument("--sun-azimuth", type=float, metavar="DEG",
                     help="azimuth, degrees clockwise from north (field y = north by default)")
    sun.add_argument("--date", help="YYYY-MM-DD")
    sun.add_argument("--time", help="local clock time HH:MM")
    sun.add_argument("--solar-noon", action="store_true", help="the true solar noon of --date")
    sun.add_argument("--lat", type=float, help="latitude, degrees north")
    sun.add_argument("--lon", type=float, help="longitude, degrees east")
    sun.add_argument("--tz", default="UTC", help="time zone, e.g. Asia/Shanghai (default UTC)")
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
    p.set_defaults(run=_run_light)


def _sun_from(args):
    from maizeviz.light.sun import Sun, sun_at

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


def _write_rows(path, rows):
    import csv

    if not rows:
        rows = [{}]
    try:
        with open(path, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(r for r in rows if r)
    except OSError as exc:
        raise MaizevizError(f"{path}: cannot write ({exc.strerror or exc})") from None


def _run_light(args) -> int:
    from maizeviz.canopy.scene import build_canopy
    from maizeviz.light.heatmap import write_heatmaps
    from maizeviz.light.transmission import (LightRequest, beer_lambert, leaf_light, plant_light,
                                             trace_light)

    levels = _levels_from(args)
    sun = _sun_from(args)
    heights = tuple(_floats(args.heights, "--heights"))
    rect = tuple(_floats(args.rect, "--rect", 4)) if args.rect else None
    if args.heatmap_bin <= 0:
        raise MaizevizError(f"--heatmap-bin must be > 0 cm, got {args.heatmap_bin}")
    _say(f"sun: zenith {sun.zenith_deg:.2f} deg, azimuth {sun.azimuth_deg:.2f} deg"
         + (f" ({sun.when})" if sun.when else ""))
    leaves, skipped, layout = canopy_setup(args)
    want_classes = bool(args.leaf_light or args.plant_light)
    records = []
    for level in levels:
        t0 = time.perf_counter()
        try:
            canopy = build_canopy(leaves, layout, level, args.preserve_area,
                                  Progress(f"building {level}"))
        except ValueError as exc:
            raise MaizevizError(f"{level}: {exc}") from None
        canopy_s = time.perf_counter() - t0
        req = LightRequest(sun, heights, args.density, rect, args.periodic, args.threads,
                           classes=want_classes or len(levels) == 1)
        res = trace_light(canopy, req, Progress(f"tracing {level}"), args.with_stalks)
        for w in res.warnings:
            if not records or w not in records[-1]["warnings"]:
                _say(f"warning: {w}")
        rec = {"level": level.label, "triangles": canopy.n_triangles,
               "sun": {"zenith_deg": sun.zenith_deg, "azimuth_deg": sun.azimuth_deg,
                       "when": sun.when or None},
               "heights_cm": list(map(float, res.heights_cm)),
               "transmission": list(map(float, res.transmission)), "rays": res.rays,
               "density_per_cm2": res.rays / ((res.rect[2] - res.rect[0]) *
                                              (res.rect[3] - res.rect[1])),
               "rect_cm": list(res.rect), "periodic": args.periodic, "threads": args.threads,
               "seconds": dict(canopy=canopy_s, scene=res.seconds["build"],
                               trace=res.seconds["trace"],
                               second_hits=res.seconds.get("second", 0.0)),
               "warnings": list(res.warnings)}
        if args.check:
            bl, g, lai = beer_lambert(canopy, sun, heights)
            rec["beer_lambert"] = {"G": g, "lai_above": list(map(float, lai)),
                                   "transmission": list(map(float, bl))}
        if res.first_hits is not None:
            rec["sunlit_intercepted_fraction"] = float(
                res.first_hits.sum() * res.ray_area_cm2 /
                ((res.rect[2] - res.rect[0]) * (res.rect[3] - res.rect[1])))
        if args.heatmaps:
            paths = write_heatmaps(args.heatmaps, res, args.heatmap_bin)
            _say(f"wrote {len(paths) // 2} transmission maps (PNG + CSV) to {args.heatmaps}")
        if want_classes:
            rows = leaf_light(canopy, res)
            for r in rows:
                r["level"] = level.label
            if args.leaf_light:
                _write_rows(args.leaf_light if len(levels) == 1 else
                            _suffixed(args.leaf_light, level), rows)
            if args.plant_light:
                _write_rows(args.plant_light if len(levels) == 1 else
                            _suffixed(args.plant_light, level), plant_light(rows))
        records.append(rec)

    if args.json:
        print(json.dumps(records[0] if len(records) == 1 else {"levels": records}, indent=1))
    else:
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
        print(_fmt_table(head, rows))
        if args.check:
            import math
            bl = records[0]["beer_lambert"]
            t0, b0 = records[0]["transmission"][0], bl["transmission"][0]
            omega = math.log(t0) / math.log(b0) if 0 < t0 < 1 and 0 < b0 < 1 else float("nan")
            print(f"Beer-Lambert with G = {bl['G']:.3f} and L(h) from the {records[0]['level']} "
                  f"mesh; effective clumping at {heights[0]:g} cm: ln T / ln T_BL = {omega:.2f} "
                  "(1: random foliage; below 1: clumped, T above Beer-Lambert, as in most row "
                  "crops (0.7-1); above 1: more regular than random)")
        print()
        t_ref = records[0]["seconds"]["scene"] + records[0]["seconds"]["trace"]
        print(_fmt_table(
            ["level", "triangles", "canopy s", "scene s", "trace s", "scene+trace vs first"],
            [[r["level"], r["triangles"], f"{r['seconds']['canopy']:.2f}",
              f"{r['seconds']['scene']:.2f}", f"{r['seconds']['trace']:.3f}",
              f"{(r['seconds']['scene'] + r['seconds']['trace']) / t_ref:.0%}"] for r in records]))
    return _summary(len(leaves), skipped)


def _suffixed(path, level):
    from pathlib import Path

    p = Path(path)
    tag = "".join(c if c.isalnum() else "_" for c in level.label).strip("_")
    return p.with_name(f"{p.stem}_{tag}{p.suffix}")


# --------------------------------------------------------------------------------- record
def _add_record(sub):
    p = sub.add_parser(
        "record", help="digitize with a Polhemus FASTRAK: stylus presses become points",
        description="Record stylus presses from a FASTRAK as points of plants, leaves and "
                    "cross-sections. Every point is on disk (fsync) before it is reported. "
                    "Controls, one per line on standard input: n next leaf, p next plant, "
                    "r end the row early (tip), u undo the last point, q finish.")
    p.add_argument("--port", required=True, help="serial port, e.g. /dev/ttyUSB0")
    p.add_argument("--out", required=True, help="points CSV to append to")
    p.add_argument("--cols", type=int, default=5,
                   help="points per cross-section, margin to margin (default 5)")
    p.add_argument("--resume", action="store_true", help="continue --out where it stopped")
    p.add_argument("--baud", type=int, default=115200, help="baud rate (default 115200)")
    p.add_argument("--reference-station", type=int, choices=(2, 3, 4), metavar="N",
                   help="a receiver fixed to the stalk: points are re-expressed in its frame")
    p.add_argument("--answer-timeout", type=float, default=1.0, metavar="S",
                   help="seconds to wait for each reply of the unit (default 1)")
    p.set_defaults(run=_run_record)


def _run_record(args) -> int:
    import queue
    import signal
    import threading

    from maizeviz.digitizer.port import FastrakPort, PortLost
    from maizeviz.digitizer.session import Session

    session = Session(args.out, args.cols, args.resume, args.reference_station)
    if args.resume:
        q0 = session.pos
        _say(f"resuming {args.out}: {session.count.points} points on disk; next point is plant "
             f"{q0.plant} leaf {q0.leaf} row {q0.row} col {q0.col}")
    port = FastrakPort(args.port, args.baud, args.answer_timeout)
    stations = (1,) if args.reference_station is None else (1, args.reference_station)
    try:
        config = port.configure(stations)
    except MaizevizError:
        session.close()
        port.close()
        raise
    for w in config.warnings:
        _say(f"warning: {w}")
    events: queue.Queue = queue.Queue()
    port.start_reader(events.put)

    def read_stdin():
        try:
            for line in sys.stdin:
                events.put(("control", line))
        except (OSError, ValueError):
            pass

    if sys.stdin is not None and not sys.stdin.closed:
        threading.Thread(target=read_stdin, daemon=True, name="controls").start()
    stop = {"signal": None}

    def on_signal(signum, _frame):
        stop["signal"] = signum
        events.put(("signal", signum))

    old = signal.signal(signal.SIGTERM, on_signal)
    print(f"ready on {args.port}: press the stylus; controls n, p, r, u, q + Enter", flush=True)
    code = EXIT_OK
    try:
        while True:
            try:
                ev = events.get(timeout=0.5)
            except queue.Empty:
                continue
            if isinstance(ev, tuple) and ev[0] == "signal":
                code = 128 + ev[1]
                break
            if isinstance(ev, tuple) and ev[0] == "control":
                msg = session.control(ev[1]) if ev[1].strip() else None
                if msg == "quit":
                    break
                if msg:
                    print(msg, flush=True)
                continue
            if isinstance(ev, PortLost):
                _say(f"error: {ev.message}; every point reported recorded is on disk")
                code = EXIT_FAIL
                break
            msg = session.on_event(ev)
            if msg:
                print(msg, flush=True)
    except KeyboardInterrupt:
        code = 130
    finally:
        signal.signal(signal.SIGTERM, old)
        port.close()
        session.close()
        print(session.summary(), flush=True)
    return code


def _add_sim(sub):
    p = sub.add_parser(
        "fastrak-sim", help="a pretend FASTRAK on a pseudo-terminal (prints its path)",
        description="Open a pseudo-terminal that behaves like a FASTRAK and, with --replay, "
                    "press the stylus at every point of a points file once a recorder has "
                    "configured it.")
    p.add_argument("--replay", metavar="CSV", help="points file to replay as stylus presses")
    p.add_argument("--pace", type=float, default=1.0, metavar="S",
                   help="seconds between presses (default 1.0; the unit ignores < 0.333)")
    p.add_argument("--reference", action="store_true",
                   help="a second receiver on the stalk (station 2) that sways while replaying")
    p.add_argument("--faults", action="store_true",
                   help="inject garbled bytes, truncated records, BIT errors and finally pull "
                        "the port")
    p.add_argument("--noise", type=float, default=0.08, help="position noise, cm (default 0.08)")
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(run=_run_sim)


def _run_sim(args) -> int:
    from maizeviz.digitizer.replay import replay_points
    from maizeviz.digitizer.simulator import FastrakSimulator

    stations = (1, 2) if args.reference else (1,)
    with FastrakSimulator(stations, args.noise, args.seed) as sim:
        print(f"FASTRAK simulator on {sim.path}", flush=True)
        if not args.replay:
            print("no --replay: answering commands until Ctrl-C", flush=True)
            try:
                while True:
                    time.sleep(1)
            except KeyboardInterrupt:
                return EXIT_OK
        print(f"waiting for a recorder: maizeviz record --port {sim.path} --out OUT.csv",
              flush=True)
        try:
            replay_points(sim, args.replay, pace=args.pace, faults=args.faults,
                          sway=args.reference, say=lambda m: print(m, flush=True))
        except KeyboardInterrupt:
            return 130
    return EXIT_OK


# ---------------------------------------------------------------------------------- synth
def _add_synth(sub):
    p = sub.add_parser(
        "synth", help="write a realistic digitized block of synthetic maize plants",
        description="Write a points file of a block of parametric maize plants at silking "
                    "(about 245 cm, 16 leaves, 0.94 m2 of leaf each), digitized the way a "
                    "technician would, with 0.08 cm digitizer noise.")
    p.add_argument("--plants", default="3x3", metavar="RxP",
                   help="rows x plants per row (default 3x3)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--row-spacing", type=float, default=60.0, metavar="CM")
    p.add_argument("--plant-spacing", type=float, default=30.0, metavar="CM")
    p.add_argument("--sections", type=int, default=13,
                   help="cross-sections of a long leaf (default 13)")
    p.add_argument("--points-across", type=int, default=5,
                   help="points per cross-section, margin to margin (default 5)")
    p.add_argument("--out", required=True, help="points CSV to write")
    p.set_defaults(run=_run_synth)


def _run_synth(args) -> int:
    from maizeviz.canopy.layout import parse_shape
    from maizeviz.synth import block_grids

    rows, per_row = parse_shape(args.plants, "--plants")
    if args.row_spacing <= 0 or args.plant_spacing <= 0:
        raise MaizevizError("spacings must be positive numbers of cm")
    if args.sections < 2 or args.points_across < 2:
        raise MaizevizError("--sections and --points-across must be at least 2")
    grids = block_grids(rows, per_row, args.row_spacing, args.plant_spacing, args.seed,
                        grid_rows=args.sections, grid_cols=args.points_across)
    _write_grids(args.out, grids)
    _say(f"wrote {len(grids)} leaves of {rows * per_row} plants to {args.out}")
    return EXIT_OK


def _write_grids(path, grids):
    from maizeviz.io.points import write_points

    try:
        write_points(path, grids)
    except OSError as exc:
        raise MaizevizError(f"{path}: cannot write ({exc.strerror or exc})") from None


# ------------------------------------------------------------------------ import-phenomenal
def _add_import(sub):
    p = sub.add_parser(
        "import-phenomenal", help="turn a Phenomenal/PhenoTrack3D plant into leaf point grids",
        description="Import a plant segmented by the Phenomenal pipeline (JSON, optionally "
                    "gzip-compressed, mm) as a points file (cm): each leaf's midrib and "
                    "surface voxels become cross-sections of 5 points.")
    p.add_argument("file", help="Phenomenal plant, .json or .json.gz")
    p.add_argument("--out", required=True, help="points CSV to write")
    p.add_argument("--plant", type=int, default=1, help="plant id to give it (default 1)")
    p.add_argument("--at", metavar="X,Y", help="move the stalk base to x,y (cm)")
    p.set_defaults(run=_run_import)


def _run_import(args) -> int:
    import numpy as np
    from dataclasses import replace

    from maizeviz.io.phenomenal import load_phenomenal, phenomenal_grids

    grids, warnings = phenomenal_grids(load_phenomenal(args.file), args.plant)
    for w in warnings:
        _say(f"warning: {w}")
    if args.at:
        try:
            x, y = (float(v) for v in args.at.split(","))
        except ValueError:
            raise MaizevizError(f"--at must be X,Y in cm, got '{args.at}'") from None
        base = np.median([g.points[0, g.points.shape[1] // 2, :2] for g in grids], axis=0)
        grids = [replace(g, points=g.points + [x - base[0], y - base[1], 0.0]) for g in grids]
    _write_grids(args.out, grids)
    _say(f"wrote {len(grids)} leaves of plant {args.plant} to {args.out}")
    return EXIT_OK


# ----------------------------------------------------------------------------------- main
def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="maizeviz",
        description="Digitized maize plants: leaf surfaces, mesh complexity, canopies, light. "
                    "Without a subcommand, opens the desktop app.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    _add_leaf(sub)
    _add_canopy(sub)
    _add_light(sub)
    _add_record(sub)
    _add_sim(sub)
    _add_synth(sub)
    _add_import(sub)
    return parser


def _no_command(parser, argv) -> int:
    """No subcommand: the desktop app where there is a screen, else the headless report."""
    rest = [a for a in argv if a != "--debug"]
    try:
        from app.main import has_screen, run
    except ImportError as exc:                     # the GUI packages are not installed
        _say(f"note: the desktop app is unavailable ({exc}); running the headless report")
        has_screen, run = (lambda: False), None
    if has_screen():
        return run(rest)
    from pathlib import Path

    example = Path(__file__).resolve().parents[1] / "resources" / "block3x3.csv"
    _say("no screen (DISPLAY is not set): the headless report on the bundled example follows; "
         "for the window run 'xvfb-run -a maizeviz --screenshot app.png' or use a desktop")
    return main(["canopy", str(example), "--tile", "3x3", "--levels"])


def main(argv=None) -> int:
    parser = build_parser()
    tokens = list(sys.argv[1:] if argv is None else argv)
    commands = set(parser._subparsers._group_actions[0].choices)
    first = next((t for t in tokens if t != "--debug"), None)
    if first not in commands and first not in ("-h", "--help"):
        return _no_command(parser, tokens)           # the app, with its own options
    args = parser.parse_args(tokens)
    debug = args.debug or bool(os.environ.get("MAIZEVIZ_DEBUG"))
    try:
        return args.run(args)
    except (MaizevizError, LeafError) as exc:
        _say(f"error: {exc}")
        return EXIT_FAIL
    except KeyboardInterrupt:
        _say("interrupted")
        return 130
    except BrokenPipeError:
        return EXIT_OK
    except Exception as exc:  # a bug: say so in one line unless asked for the traceback
        if debug:
            traceback.print_exc()
        else:
            _say(f"internal error: {type(exc).__name__}: {exc} (run with --debug and report it)")
        return EXIT_FAIL


if __name__ == "__main__":
    sys.exit(main())
