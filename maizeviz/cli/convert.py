"""``maizeviz convert``: a points file as CSV or as Parquet, the same records."""

from __future__ import annotations

import argparse

from maizeviz.cli.common import EXIT_OK, say
from maizeviz.io.outputs import check_run_paths

#: The subcommand.
NAME = "convert"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        NAME, help="write a points file as CSV or as Parquet (the same points)",
        description="Read a points file (CSV or Parquet) with every check the other commands "
                    "make, and write its points, as read, to --out: Parquet when its name ends "
                    "in .parquet or .pq (about a third of the CSV's size, read about 20 times "
                    "faster), CSV otherwise. Lines the reader skips are skipped here too.")
    p.add_argument("points", help="points file (CSV or Parquet)")
    p.add_argument("--out", required=True, help="points file to write (.csv, .parquet, .pq)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from maizeviz.io.parquet import write_table
    from maizeviz.io.points import read_points

    check_run_paths([("the points file written", args.out)], [("the points file", args.points)])
    table = read_points(args.points)
    for problem in table.problems:
        say(f"warning: {problem}")
    write_table(args.out, table)
    say(f"wrote {len(table):,} points to {args.out}")
    return EXIT_OK
