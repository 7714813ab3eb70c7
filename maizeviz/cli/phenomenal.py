"""``maizeviz import-phenomenal``: a plant segmented by Phenomenal (PhenoTrack3D) as leaf grids."""

from __future__ import annotations

import argparse

from maizeviz.cli.common import EXIT_OK, WHOLE_ARG, floats, say
from maizeviz.errors import check_range
from maizeviz.io.outputs import check_run_paths
from maizeviz.io.phenomenal import load_phenomenal
from maizeviz.io.points import write_points
from maizeviz.leaf.phenomenal import move_plant, phenomenal_grids

#: The subcommand.
NAME = "import-phenomenal"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        NAME, help="turn a Phenomenal/PhenoTrack3D plant into leaf point grids",
        description="Import a plant segmented by the Phenomenal pipeline (JSON, optionally "
                    "gzip-compressed, mm) as a points file (cm): each leaf's midrib and "
                    "surface voxels become cross-sections of 5 points.")
    p.add_argument("file", help="Phenomenal plant, .json or .json.gz")
    p.add_argument("--out", required=True,
                   help="points file to write: CSV, or Parquet if it ends in .parquet or .pq")
    p.add_argument("--plant", type=WHOLE_ARG, default=1, help="plant id to give it (default 1)")
    p.add_argument("--at", metavar="X,Y", help="move the stalk base to x,y (cm)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    check_range(args.plant, "the plant id", 0, 2**31 - 1, "plant", whole=True)
    check_run_paths([("the points file", args.out)], [("the Phenomenal plant", args.file)])
    grids, warnings = phenomenal_grids(load_phenomenal(args.file), args.plant)
    for w in warnings:
        say(f"warning: {w}")
    if args.at:
        x, y = floats(args.at, "the stalk position X,Y", "at", 2)
        grids = move_plant(grids, x, y)
    write_points(args.out, grids)
    say(f"wrote {len(grids)} leaves of plant {args.plant} to {args.out}")
    return EXIT_OK
