"""``maizeviz canopy``: lay out digitized plants as a canopy and measure it (Table 2)."""

from __future__ import annotations

import argparse
import json
import time

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.export import export_canopy
from maizeviz.canopy.field import canopy_of
from maizeviz.canopy.layout import CanopyLayout, save_layout
from maizeviz.canopy.measures import (
    TABLE2_COLUMNS,
    CanopyMeasures,
    check_cover_resolution,
    measure_canopy,
    table2_row,
)
from maizeviz.cli.common import (
    NUMBER_ARG,
    Progress,
    add_canopy_options,
    add_level_options,
    canopy_setup,
    check_canopy_costs,
    check_export,
    check_input_options,
    fmt_table,
    input_name,
    is_mesh,
    leaves_summary,
    levels_from,
    mesh_setup,
    say,
)
from maizeviz.cost import check, cover_cost, mesh_cost
from maizeviz.io.outputs import check_run_paths
from maizeviz.mesh.levels import CANOPY_LEVELS

#: The subcommand.
NAME = "canopy"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        NAME, help="lay out digitized plants as a canopy and measure it (Table 2)",
        description="Build a canopy from digitized plants, tiled or from a layout file, and "
                    "report leaf area, projected area, ground cover and LAI.")
    add_canopy_options(p)
    add_level_options(p, CANOPY_LEVELS)
    p.add_argument("--with-stalks", action="store_true",
                   help="stalk cylinders shade the ground in the ground cover (never leaf "
                        "area nor LAI; they are always in exports)")
    p.add_argument("--cover-resolution", type=NUMBER_ARG, default=0.5, metavar="CM",
                   help="pixel edge of the vertical-ray grid measuring ground cover (default 0.5)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--export", metavar="PATH",
                   help="write the canopy mesh: .ply .obj .vtk .vtu .vtp .stl")
    p.add_argument("--save-layout", metavar="JSON", help="write the layout used as a layout file")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    check_input_options(args)
    levels = levels_from(args)
    check_export(args.export, levels)
    check_cover_resolution(args.cover_resolution)            # before the file is read
    check_run_paths([("the mesh export", args.export), ("the saved layout", args.save_layout)],
                    [(input_name(args.points), args.points), ("the layout file", args.layout)])
    if is_mesh(args.points):
        return _run_mesh(args)
    leaves, skipped, layout = canopy_setup(args)
    check_canopy_costs(leaves, layout, levels, args.force,
                       [cover_cost(layout, args.cover_resolution)])
    if args.save_layout:
        save_layout(args.save_layout, layout)
    runs = []
    for level in levels:
        variants = [args.preserve_area]
        if args.levels is not None and level.triangles is not None and args.preserve_area:
            variants.append(False)                     # the paper's splitting, widths untouched
        for preserve in variants:
            t0 = time.perf_counter()
            canopy = canopy_of(leaves, layout, level, preserve, Progress(f"building {level}"))
            runs.append(_measured(args, canopy, level.variant_label(preserve), t0, preserve))
    _report(args, runs, layout)
    return leaves_summary(len(leaves), skipped)


def _run_mesh(args: argparse.Namespace) -> int:
    """A mesh file as the canopy: measured (and exported) as it is."""
    t0 = time.perf_counter()
    canopy = mesh_setup(args)
    check([[mesh_cost(canopy.n_triangles), cover_cost(canopy.layout, args.cover_resolution)]],
          args.force)
    _report(args, [_measured(args, canopy, canopy.level, t0, True)], canopy.layout)
    return leaves_summary(canopy.n_leaves, [])


def _measured(args: argparse.Namespace, canopy: Canopy, label: str, t0: float,
              preserve: bool) -> tuple[CanopyMeasures, dict]:
    """Measures of a built canopy (exported if asked) and its JSON record."""
    t1 = time.perf_counter()
    m = measure_canopy(canopy, args.cover_resolution, args.with_stalks)
    rec = dict(m.as_dict(), level=label, build_s=t1 - t0, measure_s=time.perf_counter() - t1,
               preserve_area=preserve)
    if args.export:
        path = export_canopy(args.export, canopy)
        say(f"wrote {canopy.n_triangles} leaf triangles of {canopy.n_plants} plants "
            f"(and their stalks) to {path}")
    return m, rec


def _report(args: argparse.Namespace, runs: list[tuple[CanopyMeasures, dict]],
            layout: CanopyLayout) -> None:
    if args.json:
        records = [d for _, d in runs]
        print(json.dumps(records[0] if len(records) == 1 else {"levels": records}, indent=1))
    else:
        first = runs[0][0]
        x0, y0, x1, y1 = layout.bounds
        print(f"canopy: {first.plants} plants on {first.ground_area_m2:.2f} m2 "
              f"(x {x0:.0f}..{x1:.0f} cm, y {y0:.0f}..{y1:.0f} cm)")
        rows = [table2_row(m, float(d["build_s"]), str(d["level"])) for m, d in runs]
        print(fmt_table([h for _, h in TABLE2_COLUMNS],
                        [[r[k] for k, _ in TABLE2_COLUMNS] for r in rows]))
        print(f"ground cover: vertical rays every {args.cover_resolution:g} cm inside the plot")
