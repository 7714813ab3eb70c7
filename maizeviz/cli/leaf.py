"""``maizeviz leaf``: fit NURBS surfaces through digitized leaves and mesh them (Table 1)."""

from __future__ import annotations

import argparse
import json

from maizeviz.cli.common import (
    WHOLE_ARG,
    Progress,
    add_level_options,
    check_export,
    fmt_table,
    leaves_summary,
    levels_from,
    load_leaves,
    say,
)
from maizeviz.cost import check, leaves_cost
from maizeviz.io.meshfile import write_mesh
from maizeviz.io.outputs import check_run_paths
from maizeviz.mesh.levels import (
    DEFAULT_LEVELS,
    LeafMeasures,
    measure_leaves,
    mesh_leaves,
    reference_areas,
)
from maizeviz.mesh.tessellate import LeafMesh, merge_meshes
from maizeviz.progress import ProgressCallback, scaled

#: The subcommand.
NAME = "leaf"
#: Files with at least this many leaves get progress bars (on a terminal): 2,000 leaves take
#: a few seconds.
LONG_FILE_LEAVES = 2000
#: Leaves meshed and measured at a time; their meshes are dropped once measured (unless
#: exported), so memory follows the leaves, not the leaves times the triangles of a level
#: (K = 4 meshes take 60 kB a leaf).
LEAF_BATCH = 4096


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        NAME, help="fit NURBS surfaces through digitized leaves and mesh them",
        description="Fit a NURBS surface through every leaf of a points file and mesh it at "
                    "the chosen complexity. Areas in cm2, lengths in cm.")
    p.add_argument("points", help="points file, CSV or Parquet (plant,leaf,row,col,x,y,z in cm)")
    add_level_options(p, DEFAULT_LEVELS)
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--export", metavar="PATH",
                   help="write the meshes: .ply .obj .vtk .vtu .vtp .stl (plant/leaf ids kept "
                        "as cell data where the format allows)")
    p.add_argument("--degree", type=WHOLE_ARG, default=3, help="NURBS degree in u and v (default 3)")
    p.add_argument("--params", choices=("chord", "centripetal"), default="chord",
                   help="data parameters (default chord length)")
    p.add_argument("--strict", action="store_true",
                   help="stop at the first bad leaf instead of skipping it")
    p.add_argument("--force", action="store_true",
                   help="run work estimated to take longer than 15 min (what would not fit in "
                        "memory is refused anyway)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    levels = levels_from(args)
    check_export(args.export, levels)
    check_run_paths([("the mesh export", args.export)], [("the points file", args.points)])
    leaves, skipped = load_leaves(args.points, args.strict, args.degree, args.params,
                                  progress=_bar("gathering leaves"))
    quantity = "level" if args.levels is not None else \
        "triangles" if args.triangles is not None else "interp"
    check([[leaves_cost(leaves, level, quantity, LEAF_BATCH, keep=bool(args.export))]
           for level in levels], args.force)                 # before any mesh is made
    reference_areas(leaves)           # every leaf's, once, for all levels (kept in leaf.cache)
    per_level = []
    n = len(leaves)
    for level in levels:
        bar = _bar(f"{level}: meshing and measuring")       # 2 n steps: mesh, then measure
        measured: list[LeafMeasures] = []
        exported: list[LeafMesh] = []
        for s in range(0, n, LEAF_BATCH):
            part = leaves[s:s + LEAF_BATCH]
            meshes = mesh_leaves(part, level, args.preserve_area, scaled(bar, 2 * s, 2 * n))
            measured += measure_leaves(part, meshes, scaled(bar, 2 * s + len(part), 2 * n))
            if args.export:                                 # one level (check_export)
                exported += meshes
        per_level.append((level, measured))
        if args.export and leaves:
            path = write_mesh(args.export, *merge_meshes(exported))
            say(f"wrote {sum(m.n_triangles for m in exported)} triangles of "
                f"{len(leaves)} leaves to {path}")

    skipped_json = [{"plant": e.plant, "leaf": e.leaf, "error": e.detail} for e in skipped]
    if args.json:
        out: dict
        if args.levels is not None:
            out = {"levels": [str(lv) for lv in levels], "leaves": [
                {"plant": lf.grid.plant, "leaf": lf.grid.leaf, "rows": lf.grid.shape[0],
                 "cols": lf.grid.shape[1], "notes": list(lf.grid.notes),
                 "levels": [ms[i].as_dict() for _, ms in per_level]}
                for i, lf in enumerate(leaves)]}
        else:
            out = {"level": str(levels[0]),
                   "leaves": [dict(ms.as_dict(), notes=list(lf.grid.notes))
                              for lf, ms in zip(leaves, per_level[0][1])]}
        out["skipped"] = skipped_json
        print(json.dumps(out, indent=1))
    elif args.levels is not None:
        for i, lf in enumerate(leaves):
            print(f"plant {lf.grid.plant}, leaf {lf.grid.leaf} ({lf.grid.shape[0]} x "
                  f"{lf.grid.shape[1]} points)")
            print(fmt_table(
                ["level", "triangles", "area cm2", "area err %", "projected cm2",
                 "max dev cm"],
                [[ms[i].level, ms[i].triangles, f"{ms[i].area_cm2:.1f}",
                  f"{ms[i].area_error_pct:+.1f}", f"{ms[i].projected_area_cm2:.1f}",
                  f"{ms[i].max_deviation_cm:.2f}"] for _, ms in per_level]))
            print()
    else:
        ms = per_level[0][1]
        print(f"level: {levels[0]}")
        print(fmt_table(
            ["plant", "leaf", "rows x cols", "triangles", "area cm2", "projected cm2",
             "max dev cm"],
            [[m.plant, m.leaf, f"{m.rows} x {m.cols}", m.triangles, f"{m.area_cm2:.1f}",
              f"{m.projected_area_cm2:.1f}", f"{m.max_deviation_cm:.2f}"] for m in ms]))
        if ms:
            print(f"total: {len(ms)} leaves, {sum(m.triangles for m in ms)} triangles, "
                  f"{sum(m.area_cm2 for m in ms):.1f} cm2 of leaf")
    return leaves_summary(len(leaves), skipped)


def _bar(label: str) -> ProgressCallback:
    """A terminal progress bar for work over :data:`LONG_FILE_LEAVES` leaves or more (counted
    in leaves or in steps of a leaf)."""
    bar = Progress(label)
    return lambda done, total: bar(done, total) if total >= LONG_FILE_LEAVES else None
