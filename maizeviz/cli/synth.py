"""``maizeviz synth``: a digitized-looking block of parametric maize plants."""

from __future__ import annotations

import argparse

from maizeviz.canopy.layout import parse_shape
from maizeviz.cli.common import EXIT_OK, NUMBER_ARG, WHOLE_ARG, Progress, say
from maizeviz.io.outputs import check_run_paths
from maizeviz.io.points import write_points
from maizeviz.leaf.synth import iter_block_grids

#: Plants above which the time it takes is said first; seconds per plant (measured: 16 ms).
BIG_FIELD, SECONDS_PER_PLANT = 10_000, 0.016

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
    p.add_argument("--out", required=True,
                   help="points file to write: CSV, or Parquet if it ends in .parquet or .pq")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    rows, per_row = parse_shape(args.plants, "plants")
    check_run_paths([("the points file", args.out)])
    plants = iter_block_grids(rows, per_row, args.row_spacing, args.plant_spacing, args.seed,
                              grid_rows=args.sections, grid_cols=args.points_across)
    if rows * per_row > BIG_FIELD:
        say(f"about {rows * per_row * SECONDS_PER_PLANT / 60:.0f} min for {rows * per_row:,} "
            "plants")
    tick = Progress("making plants")
    count = [0, 0]

    def grids():
        for k, leaves in enumerate(plants, start=1):
            count[1] += len(leaves)
            yield from leaves
            if k % 100 == 0 or k == rows * per_row:
                tick(k, rows * per_row)
        count[0] = rows * per_row

    write_points(args.out, grids())
    say(f"wrote {count[1]} leaves of {count[0]} plants to {args.out}")
    return EXIT_OK
