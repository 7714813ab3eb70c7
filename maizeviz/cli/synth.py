"""``maizeviz synth``: a digitized-looking block of parametric maize plants."""

from __future__ import annotations

import argparse

from maizeviz.canopy.layout import parse_shape
from maizeviz.cli.common import EXIT_OK, NUMBER_ARG, WHOLE_ARG, say
from maizeviz.io.outputs import check_run_paths
from maizeviz.io.points import write_points
from maizeviz.leaf.synth import block_grids

#: The subcommand.
NAME = "synth"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        NAME, help="write a realistic digitized block of synthetic maize plants",
        description="Write a points file of a block of parametric maize plants at silking "
                    "(about 245 cm, 16 leaves, 0.94 m2 of leaf each), digitized the way a "
                    "technician would, with 0.08 cm digitizer noise.")
    p.add_argument("--plants", default="3x3", metavar="RxP",
                   help="rows x plants per row (default 3x3)")
    p.add_argument("--seed", type=WHOLE_ARG, default=0, help="random seed (default 0)")
    p.add_argument("--row-spacing", type=NUMBER_ARG, default=60.0, metavar="CM")
    p.add_argument("--plant-spacing", type=NUMBER_ARG, default=30.0, metavar="CM")
    p.add_argument("--sections", type=WHOLE_ARG, default=13,
                   help="cross-sections of a long leaf (default 13)")
    p.add_argument("--points-across", type=WHOLE_ARG, default=5,
                   help="points per cross-section, margin to margin (default 5)")
    p.add_argument("--out", required=True, help="points CSV to write")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    rows, per_row = parse_shape(args.plants, "plants")
    check_run_paths([("the points file", args.out)])
    grids = block_grids(rows, per_row, args.row_spacing, args.plant_spacing, args.seed,
                        grid_rows=args.sections, grid_cols=args.points_across)
    write_points(args.out, grids)
    say(f"wrote {len(grids)} leaves of {rows * per_row} plants to {args.out}")
    return EXIT_OK
