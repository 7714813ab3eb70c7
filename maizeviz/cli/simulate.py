"""``maizeviz fastrak-sim``: a pretend FASTRAK on a pseudo-terminal, replaying a points file."""

from __future__ import annotations

import argparse
import time

from maizeviz.cli.common import EXIT_OK, NUMBER_ARG, WHOLE_ARG
from maizeviz.digitizer.replay import replay_points
from maizeviz.digitizer.simulator import FastrakSimulator
from maizeviz.errors import check_range

#: The subcommand.
NAME = "fastrak-sim"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        NAME, help="a pretend FASTRAK on a pseudo-terminal (prints its path)",
        description="Open a pseudo-terminal that behaves like a FASTRAK and, with --replay, "
                    "press the stylus at every point of a points file once a recorder has "
                    "configured it.")
    p.add_argument("--replay", metavar="CSV", help="points file to replay as stylus presses")
    p.add_argument("--pace", type=NUMBER_ARG, default=1.0, metavar="S",
                   help="seconds between presses (default 1.0; the unit ignores < 0.333)")
    p.add_argument("--reference", action="store_true",
                   help="a second receiver on the stalk (station 2) that sways while replaying")
    p.add_argument("--faults", action="store_true",
                   help="inject garbled bytes, truncated records, BIT errors and finally pull "
                        "the port")
    p.add_argument("--noise", type=NUMBER_ARG, default=0.08, help="position noise, cm (default 0.08)")
    p.add_argument("--seed", type=WHOLE_ARG, default=0)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    check_range(args.pace, "the pace", 0, 3600, "pace", unit="s")
    check_range(args.noise, "the position noise", 0, 100, "noise", unit="cm")
    check_range(args.seed, "the random seed", 0, 2**32 - 1, "seed", whole=True)
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
