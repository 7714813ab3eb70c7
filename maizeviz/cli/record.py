"""``maizeviz record``: digitize with a Polhemus FASTRAK, stylus presses becoming points."""

from __future__ import annotations

import argparse
import json
import queue
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
    p.add_argument("--live", type=NUMBER_ARG, metavar="S",
                   help="also ask the unit where the stylus tip is every S seconds (shown with "
                        "--events json; a poll's answer is never taken for a press)")
    p.add_argument("--events", choices=("text", "json"), default="text",
                   help="json: every event (ready, recorded, refused, garbled, control, "
                        "paused, live, lost, summary...) as one JSON object per line on "
                        "standard output, for a program driving the recorder (the app)")
    p.add_argument("--end-with-input", action="store_true",
                   help="finish (as q) when standard input ends: the program driving the "
                        "recorder has gone, so no press is taken that nobody sees")
    p.set_defaults(run=run)


class _Emitter:
    """Says one event: a JSON line (``--events json``) or, for the technician, its text.

    JSON lines are written by a thread of their own: a program that reads them slowly (a
    frozen window) or not at all (it has died) must never hold up the journal, so the loop that
    writes each press to disk never waits on standard output.
    """

    def __init__(self, as_json: bool):
        self.as_json = as_json
        self._lines: queue.Queue = queue.Queue()
        self._writer: threading.Thread | None = None
        if as_json:
            self._writer = threading.Thread(target=self._write, name="events", daemon=True)
            self._writer.start()

    def __call__(self, kind: str, message: str = "", **more) -> None:
        if self.as_json:
            self._lines.put(json.dumps({"kind": kind, "message": message, **more}))
        elif kind in ("note", "warning"):
            say(f"{kind}: {message}")
        elif kind in ("lost", "failed"):
            say(f"error: {message}")
        elif kind not in ("garbled", "live", "finished", "signal"):
            print(message, flush=True)

    def _write(self) -> None:
        while (line := self._lines.get()) is not None:
            try:
                print(line, flush=True)
            except (OSError, ValueError):          # nobody reads any more: keep recording
                return

    def close(self, timeout: float = 5.0) -> None:
        """Write what is queued (up to ``timeout`` s)."""
        if self._writer is not None:
            self._lines.put(None)
            self._writer.join(timeout)


def _check(args: argparse.Namespace) -> None:
    check_range(args.answer_timeout, "the answer timeout", 0.01, 600, "answer_timeout", unit="s")
    check_range(args.baud, "the baud rate", 300, 4_000_000, "baud", whole=True)
    if args.live is not None:
        check_range(args.live, "the live poll interval", 0.02, 60, "live", unit="s")
    if is_parquet_name(args.out):
        raise MaizevizError(f"{args.out}: a recording is a CSV journal, written point by point; "
                            "record to a .csv file (maizeviz convert then writes it as Parquet)")
    check_run_paths([], [("the serial port", args.port)], appended=[("the recording", args.out)])


def _connect(args: argparse.Namespace, session: Session, emit: _Emitter) -> FastrakPort:
    """Open and configure the port; a start that fails leaves no header-only file."""
    port = FastrakPort(args.port, args.baud, args.answer_timeout)
    stations = (1,) if args.reference_station is None else (1, args.reference_station)
    # SIGTERM while connecting (the app's Stop): give up the port and the file
    before = signal.signal(signal.SIGTERM, lambda _signum, _frame: port.cancel())
    try:
        config = port.configure(stations)
    except MaizevizError:
        port.close()
        session.discard_if_unused()          # (the error stays the one line said)
        raise
    finally:
        signal.signal(signal.SIGTERM, before)
    for w in config.warnings:
        emit("warning", w)
    return port


def _read_controls(recorder: Recorder, end_with_input: bool) -> None:
    """The technician's controls, one per line of standard input (a thread)."""
    def read() -> None:
        try:
            for line in sys.stdin:
                recorder.control(line)
        except (OSError, ValueError):
            pass
        if end_with_input:                    # the program driving us has gone
            recorder.control("q")

    if sys.stdin is not None and not sys.stdin.closed:
        threading.Thread(target=read, daemon=True, name="controls").start()


def _loop(recorder: Recorder, emit: _Emitter) -> int:
    """Handle events until the session ends; returns the exit code."""
    code = EXIT_OK
    shown = None
    while not recorder.finished:
        for update in recorder.poll(timeout=0.5):
            emit(update.kind, update.message, code=update.code)
            code = update.code or code
        live = recorder.live
        if emit.as_json and live is not None and live is not shown:
            shown = live
            emit("live", "", xyz=list(live.xyz), distance=live.distance,
                 trustworthy=live.trustworthy, note=live.note)
    return code


def run(args: argparse.Namespace) -> int:
    _check(args)
    emit = _Emitter(args.events == "json")
    try:
        return _record(args, emit)
    finally:
        emit.close()


def _record(args: argparse.Namespace, emit: _Emitter) -> int:
    session = Session(args.out, args.cols, args.resume, args.reference_station)
    for message in session.messages:
        emit("note", message)
    if args.resume:
        q0 = session.pos
        emit("note", f"resuming {args.out}: {session.count.points} points on disk, "
                     f"{session.cols} points per cross-section; next point is plant {q0.plant} "
                     f"leaf {q0.leaf} row {q0.row} col {q0.col}")
    port = _connect(args, session, emit)
    recorder = Recorder(session, port)
    recorder.start(live_every=args.live)
    _read_controls(recorder, args.end_with_input)
    old = signal.signal(signal.SIGTERM, lambda signum, _frame: recorder.signal(signum))
    if emit.as_json:
        emit("ready", f"ready on {args.port}", cols=session.cols, points=session.count.points)
    else:
        print(f"ready on {args.port}: press the stylus; controls n, p, r, u, s, q + Enter",
              flush=True)
    code = EXIT_OK
    try:
        code = _loop(recorder, emit)
    except KeyboardInterrupt:
        code = 130
    finally:
        signal.signal(signal.SIGTERM, old)
        recorder.close()
        emit("summary", session.summary(), points=session.count.points,
             refused=session.count.refused, garbled=session.count.garbled)
    return code
