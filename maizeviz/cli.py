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
    lv = p.add_mutually_exclusive_group()
    lv.add_argument("--interp", type=int, metavar="K",
                    help="K points interpolated between data points (0 = standard mesh; "
                         "default 4, the paper's reference mesh)")
    lv.add_argument("--triangles", type=int, metavar="N",
                    help="at most N triangles per leaf (inverse multi-line segment splitting)")
    lv.add_argument("--levels", nargs="?", const="K4,K1,standard,36,8,4,3", metavar="LIST",
                    help="compare levels per leaf, the paper's Table 1 "
                         "(default K4,K1,standard,36,8,4,3)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--export", metavar="PATH",
                   help="write the meshes: .ply .obj .vtk .vtu .vtp .stl (plant/leaf ids kept "
                        "as cell data where the format allows)")
    p.add_argument("--degree", type=int, default=3, help="NURBS degree in u and v (default 3)")
    p.add_argument("--params", choices=("chord", "centripetal"), default="chord",
                   help="data parameters (default chord length)")
    p.add_argument("--no-preserve-area", dest="preserve_area", action="store_false",
                   help="below the standard mesh, do not widen cross-sections to keep the "
                        "smooth surface's area")
    p.add_argument("--strict", action="store_true",
                   help="stop at the first bad leaf instead of skipping it")
    p.set_defaults(run=_run_leaf)


def load_leaves(path, strict=False, degree=3, method="chord"):
    """Read, grid and fit a points file; report problems on stderr.

    Returns (leaves, skipped errors).
    """
    from maizeviz.io.points import read_points
    from maizeviz.leaf.grid import build_grids
    from maizeviz.leaf.reconstruct import fit_leaves

    if degree < 1:
        raise MaizevizError(f"--degree must be >= 1, got {degree}")
    table = read_points(path)
    for problem in table.problems:
        _say(f"warning: {table.source}: {problem}")
    if strict and table.problems:
        raise MaizevizError(f"{table.source}: {table.problems[0]}")
    grids, errors = build_grids(table, strict=strict)
    for g in grids:
        for note in g.notes:
            _say(f"note: plant {g.plant}, leaf {g.leaf}: {note}")
    leaves, fit_errors = fit_leaves(grids, degree, method, strict=strict)
    return leaves, errors + fit_errors


def _fmt_table(headers, rows) -> str:
    cells = [headers] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def _run_leaf(args) -> int:
    from maizeviz.io.export import export_meshes
    from maizeviz.leaf.reconstruct import Level, measure, mesh_leaves, parse_levels

    if args.levels is not None:
        try:
            levels = parse_levels(args.levels)
        except ValueError as exc:
            raise MaizevizError(str(exc)) from None
        if args.export:
            raise MaizevizError("--export writes one level: use it with --interp or --triangles")
    elif args.triangles is not None:
        if args.triangles < 1:
            raise MaizevizError(f"--triangles must be >= 1, got {args.triangles}")
        levels = [Level(triangles=args.triangles)]
    else:
        k = 4 if args.interp is None else args.interp
        if k < 0:
            raise MaizevizError(f"--interp must be >= 0, got {k}")
        levels = [Level(interp=k)]

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
    _add_synth(sub)
    _add_import(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return EXIT_OK
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
