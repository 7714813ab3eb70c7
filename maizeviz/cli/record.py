"""``maizeviz record``: digitize with a Polhemus FASTRAK, stylus presses becoming points."""

from __future__ import annotations

import argparse
import signal
import sys
import threading

from maizeviz.cli.common import EXIT_OK, NUMBER_ARG, WHOLE_ARG, say
from maizeviz.digitizer.port import FastrakPort
from maizeviz.digitizer.recorder import Recorder
from maizeviz.digitizer.session import DEFAULT_COLS, Session
from maizeviz.errors import MaizevizError, check_range
from maizeviz.io.outputs import check_run_paths
from maizeviz.io.points import is_parquet_name

#: The subcommand.
NAME = "record"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        NAME, help="digitize with a Polhemus FASTRAK: stylus presses become points",
        description="Record stylus presses from a FASTRAK as points of plants, leaves and "
                    "cross-sections. Every point is on disk (fsync) before it is reported. "
                    "Controls, one per line on standard input: n next leaf, p next plant, "
                    "r end the row early (tip), u undo the last point, s pause or resume "
                    "(presses while paused are said and not recorded), q finish.")
    p.add_argument("--port", required=True, help="serial port, e.g. /dev/ttyUSB0")
    p.add_argument("--out", required=True, help="points CSV to append to")
    p.add_argument("--cols", type=WHOLE_ARG, default=None,
                   help=f"points per cross-section, margin to margin (default {DEFAULT_COLS}; "
                        "with --resume, the recording's own: a different value is refused)")
    p.add_argument("--resume", action="store_true", help="continue --out where it stopped")
    p.add_argument("--baud", type=WHOLE_ARG, default=115200, help="baud rate (default 115200)")
    p.add_argument("--reference-station", type=WHOLE_ARG, choices=(2, 3, 4), metavar="N",
                   help="a receiver fixed to the stalk: points are re-expressed in its frame")
    p.add_argument("--answer-timeout", type=NUMBER_ARG, default=1.0, metavar="S",
                   help="seconds to wait for each reply of the unit (default 1)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    check_range(args.answer_timeout, "the answer timeout", 0.01, 600, "answer_timeout", unit="s")
    check_range(args.baud, "the baud rate", 300, 4_000_000, "baud", whole=True)
    if is_parquet_name(args.out):
        raise MaizevizError(f"{args.out}: a recording is a CSV journal, written point by point; "
                            "record to a .csv file (maizeviz convert then writes it as Parquet)")
    check_run_paths([], [("the serial port", args.port)], appended=[("the recording", args.out)])
    session = Session(args.out, args.cols, args.resume, args.reference_station)
    for message in session.messages:
        say(f"note: {message}")
    if args.resume:
        q0 = session.pos
        say(f"resuming {args.out}: {session.count.points} points on disk, {session.cols} points "
            f"per cross-section; next point is plant {q0.plant} leaf {q0.leaf} row {q0.row} col "
            f"{q0.col}")
    port = FastrakPort(args.port, args.baud, args.answer_timeout)
    stations = (1,) if args.reference_station is None else (1, args.reference_station)
    try:
        config = port.configure(stations)
    except MaizevizError:
        session.close()
        port.close()
        raise
    for w in config.warnings:
        say(f"warning: {w}")
    recorder = Recorder(session, port)
    recorder.start()

    def read_stdin() -> None:
        try:
            for line in sys.stdin:
                recorder.control(line)
        except (OSError, ValueError):
            pass

    if sys.stdin is not None and not sys.stdin.closed:
        threading.Thread(target=read_stdin, daemon=True, name="controls").start()
    old = signal.signal(signal.SIGTERM, lambda signum, _frame: recorder.signal(signum))
    print(f"ready on {args.port}: press the stylus; controls n, p, r, u, s, q + Enter", flush=True)
    code = EXIT_OK
    try:
        while not recorder.finished:
            for update in recorder.poll(timeout=0.5):
                if update.kind in ("lost", "failed"):
                    say(f"error: {update.message}")
                elif update.kind in ("recorded", "refused", "control", "said", "paused",
                                     "resumed", "ignored"):
                    print(update.message, flush=True)
                code = update.code or code
    except KeyboardInterrupt:
        code = 130
    finally:
        signal.signal(signal.SIGTERM, old)
        recorder.close()
        print(session.summary(), flush=True)
    return code
