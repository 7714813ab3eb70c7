"""The ``maizeviz`` command: headless subcommands; with none, the desktop app.

Exit codes: 0 all done; 1 nothing could be done (bad file, every leaf refused, bad request);
2 bad command-line usage; 3 done, but some leaves were skipped (listed on stderr).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
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


# ----------------------------------------------------------------------------------- main
def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="maizeviz",
        description="Digitized maize plants: leaf surfaces, mesh complexity, canopies, light. "
                    "Without a subcommand, opens the desktop app.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    _add_leaf(sub)
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
