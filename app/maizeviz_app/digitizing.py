"""The digitizing session the digitizer panel shows, free of Qt: the recorder, its process, what
is on disk, the counts and the warnings. The panel binds to it and decides nothing.

The promise (issue 35, item 1): a press the FASTRAK accepted is on disk, or the technician is
told at once, whatever the GUI thread is doing. So the app records as the command line does:
``maizeviz record`` runs in a process of its own (:class:`DigitizingSession.start`), reading the
port and journaling every press (fsync) with no thread of the app on its path. The window only
shows what is on disk: :meth:`DigitizingSession.poll`, called from a GUI timer, tails the
journal (:class:`~maizeviz.digitizer.journal_tail.JournalTail`) for the points, undos and
where the next point goes, and reads the recorder's events (``--events json`` on its standard
output: refused presses, garbled records, pauses, the stylus's live position, a lost port) from
a queue that two reader threads fill without ever waiting on the GUI. A frozen window therefore
delays what is shown, never what is recorded; if the recorder itself ends unexpectedly the
next poll says so. The controls (N, P, R, U, S, q) are lines on the recorder's standard input;
when the app goes away (a crash), the input ends and the recorder finishes (``--end-with-input``),
leaving a journal that *resume* continues.

The Demo runs a simulated FASTRAK (:class:`~maizeviz.digitizer.simulator.FastrakSimulator`) in
the app's process, replaying the bundled block; its recorder is the same separate process.

:meth:`DigitizingSession.attach` also accepts an in-process
:class:`~maizeviz.digitizer.recorder.Recorder` without a port (scripts and tests driving the
controls only: no press can arrive, so none can be lost).
"""

from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, cast

from maizeviz.digitizer.feedback import JUMP_CM, jump, jump_message, short_message
from maizeviz.digitizer.journal_tail import JournalTail
from maizeviz.digitizer.recorder import FINAL_KINDS, LiveTip, Recorder, Update
from maizeviz.digitizer.session import Counters, Position

if TYPE_CHECKING:
    from maizeviz.digitizer.recorder import UpdateKind
    from maizeviz.digitizer.simulator import FastrakSimulator

#: Seconds between the recorder's polls for the stylus's live position.
LIVE_EVERY_S = 0.1
#: Seconds the window waits, when closing, for the recorder to finish by itself.
CLOSE_WAIT_S = 10.0
#: Update kinds this session adds to the recorder's: recording began ("started"), the
#: connection failed ("unconnected"), a press far from the point before it ("jump"), a
#: cross-section shorter than the others before the tip ("short").
EXTRA_KINDS = ("started", "unconnected", "jump", "short")
#: What ended a session, in the window's words.
STOP_REASONS = {"finished": "finished", "lost": "port lost", "failed": "cannot write",
                "signal": "stopped", "unconnected": "could not connect"}


class DigitizingSession:
    """One digitizing session at a time: connect, record, stop.

    Attributes
    ----------
    state : "idle", "connecting", "recording" or "stopping"
    path : Path or None, the recording
    cols : int, points per cross-section
    count : Counters, points on disk (and leaves, plants), undone, refused, garbled
    live : LiveTip or None, where the stylus tip is now
    paused : bool
    warnings : list of str, the checks said during the session (jumps, short sections)
    final : Update or None, how the session ended (kind ``finished``, ``lost``, ``failed``,
        ``signal`` or ``unconnected``)
    sim : the Demo's simulated FASTRAK, or None
    """

    def __init__(self, jump_cm: float = JUMP_CM):
        self.jump_cm = jump_cm
        self.state = "idle"
        self.path: Path | None = None
        self.cols = 5
        self.reference_station: int | None = None
        self.live: LiveTip | None = None
        self.paused = False
        self.warnings: list[str] = []
        self.final: Update | None = None
        self.sim: FastrakSimulator | None = None
        self.demo_file: Path | None = None
        self.demo_pace = 0.5
        self.port_name = ""
        self._counts = Counters()
        self._recorder: Recorder | None = None
        self._proc: subprocess.Popen | None = None
        self._lines: queue.Queue = queue.Queue()
        self._readers: list[threading.Thread] = []
        self._replay: threading.Thread | None = None
        self._tail: JournalTail | None = None
        self._ending: Update | None = None
        self._errors: list[str] = []
        self._summary = ""
        self._silent = 0                      # points already on disk when a resume began
        self._write = threading.Lock()        # the controls' pipe: GUI and demo threads
        self._eof = 0

    # ------------------------------------------------------------------ what is on disk
    @property
    def history(self) -> list[tuple]:
        """[(Position, (x, y, z) cm)]: the points on disk, not undone, in order."""
        if self._recorder is not None:
            return self._recorder.session.history
        return self._tail.history if self._tail is not None else []

    @property
    def pos(self) -> Position:
        """Where the next point goes."""
        if self._recorder is not None:
            return self._recorder.session.pos
        return self._tail.pos if self._tail is not None else Position()

    @property
    def count(self) -> Counters:
        if self._recorder is not None:
            return self._recorder.session.count
        return self._counts

    @property
    def recording(self) -> bool:
        return self.state in ("recording", "stopping") and self.final is None

    @property
    def active(self) -> bool:
        """Connecting, recording or stopping: something runs."""
        return self.state != "idle"

    def summary(self) -> str:
        """The session in one line (the recorder's own words once it has finished)."""
        if self._recorder is not None:
            return self._recorder.session.summary()
        if self._summary:
            return self._summary
        c = self.count
        return (f"{c.points} point{'s' if c.points != 1 else ''}, {len(c.leaves)} "
                f"{'leaf' if len(c.leaves) == 1 else 'leaves'}, {len(c.plants)} plant"
                f"{'s' if len(c.plants) != 1 else ''} recorded in {self.path}; {c.undone} "
                f"undone, {c.refused} refused, {c.garbled} garbled")

    # ------------------------------------------------------------------------ start
    def start(self, port: str, out, cols: int, resume: bool = False,
              reference_station: int | None = None, baud: int = 115200,
              answer_timeout: float = 1.0, demo: bool = False,
              live_every: float | None = LIVE_EVERY_S) -> None:
        """Start the recorder process on ``port`` (with ``demo``: on a simulated FASTRAK made
        here). Returns at once; ``poll`` says when recording began (``started``) or why not
        (``unconnected``)."""
        if self.active:
            raise RuntimeError("a digitizing session is already running")
        _check_out(Path(out))
        self._reset()
        self.path = Path(out)
        self.cols = cols
        self.reference_station = reference_station
        if demo:
            from maizeviz.digitizer.simulator import FastrakSimulator

            self.sim = FastrakSimulator(stations=(1, reference_station) if reference_station
                                        else (1,))
            port = self.sim.path
            self._lines.put(("say", f"demo: simulated FASTRAK on {port}"))
        self.port_name = port
        args = [sys.executable, "-m", "maizeviz", "record", "--port", port, "--out", str(out),
                "--cols", str(cols), "--baud", str(baud), "--answer-timeout",
                str(answer_timeout), "--events", "json", "--end-with-input"]
        if live_every is not None:
            args += ["--live", str(live_every)]
        if resume:
            args.append("--resume")
        if reference_station is not None:
            args += ["--reference-station", str(reference_station)]
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self._proc = subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                      stderr=subprocess.PIPE, text=True, bufsize=1, env=env,
                                      start_new_session=True)   # a Ctrl-C in a terminal
        self.state = "connecting"                               # stops the app, not it
        for name, stream in (("out", self._proc.stdout), ("err", self._proc.stderr)):
            t = threading.Thread(target=_pump, args=(stream, name, self._lines),
                                 name=f"recorder-{name}", daemon=True)
            t.start()
            self._readers.append(t)

    def attach(self, recorder: Recorder) -> None:
        """Show an in-process recorder (its port, if any, configured and reading)."""
        if self.active:
            raise RuntimeError("a digitizing session is already running")
        self._reset()
        self._recorder = recorder
        self.path = recorder.session.path
        self.cols = recorder.session.cols
        self.reference_station = recorder.session.reference_station
        self.state = "recording"

    def _reset(self) -> None:
        self.final = self._ending = self.live = None
        self.paused = False
        self.warnings = []
        self._counts = Counters()
        self._errors = []
        self._summary = ""
        self._tail = None
        self._recorder = None
        self._lines = queue.Queue()
        self._readers = []
        self._eof = 0
        self._silent = 0

    # -------------------------------------------------------------------- controls
    def control(self, key: str) -> None:
        """A technician's control (n, p, r, u, q; s pauses or resumes), from any thread."""
        if self._recorder is not None:
            self._recorder.control(key)
        else:
            self._send(key)

    def pause(self, on: bool) -> None:
        """Pause or resume recording (presses while paused are said, not recorded)."""
        if self._recorder is not None:
            self._recorder.pause(on)
        elif on != self.paused:
            self._send("s")

    def say(self, message: str) -> None:
        """A message to pass on (the demo's), from any thread."""
        if self._recorder is not None:
            self._recorder.say(message)
        else:
            self._lines.put(("say", message))

    def _send(self, line: str) -> bool:
        proc = self._proc
        if proc is None or proc.stdin is None:
            return False
        with self._write:
            try:
                proc.stdin.write(line.strip() + "\n")
                proc.stdin.flush()
                return True
            except (OSError, ValueError):           # the recorder has ended
                return False

    # ------------------------------------------------------------------------ poll
    def poll(self) -> list[Update]:
        """What happened since the last call, in order (GUI thread, or a script's loop).

        The last update is final when the session ended (:attr:`final` is set then).
        """
        if self.state == "idle" or self.final is not None:
            return []
        if self._recorder is not None:
            return self._poll_recorder()
        out: list[Update] = []
        exited = self._proc is not None and self._proc.poll() is not None
        while True:
            try:
                source, line = self._lines.get_nowait()
            except queue.Empty:
                break
            self._line(source, line, out)
        if self._tail is not None:
            for kind, what in self._tail.read():
                self._journaled(kind, what, out)
        if exited and self._eof >= 2:
            out.append(self._end())
        return out

    def _poll_recorder(self) -> list[Update]:
        rec = self._recorder
        assert rec is not None
        out: list[Update] = []
        for update in rec.poll(limit=2000):
            out.append(update)
            if update.kind == "recorded":
                self._check(out)
        self.live = rec.live
        self.paused = rec.paused
        if rec.final is not None:
            self.final = rec.final
            self.state = "stopping"
        return out

    def _line(self, source: str, line: str | None, out: list[Update]) -> None:
        if line is None:                             # a pipe closed: the process is ending
            self._eof += 1
            return
        if source == "say":
            out.append(Update("said", line))
            return
        if source == "err":
            line = line.rstrip("\n")
            if line.startswith("error: "):
                self._errors.append(line.removeprefix("error: "))
            elif line.strip():
                out.append(Update("said", line))
            return
        try:
            ev = json.loads(line)
            kind, message = str(ev["kind"]), str(ev.get("message", ""))
        except (ValueError, KeyError, TypeError):
            if line.strip():
                out.append(Update("said", line.rstrip("\n")))
            return
        self._event(kind, message, ev, out)

    def _event(self, kind: str, message: str, ev: dict, out: list[Update]) -> None:
        """One of the recorder's events (``maizeviz record --events json``)."""
        if kind == "ready":
            self._ready(ev, out)
        elif kind == "live":
            x, y, z = (float(v) for v in ev["xyz"])
            self.live = LiveTip((x, y, z), ev.get("distance"),
                                bool(ev.get("trustworthy", True)), str(ev.get("note", "")),
                                time.monotonic())
        elif kind == "summary":
            self._summary = message
            self._counts.refused = int(ev.get("refused", self._counts.refused))
            self._counts.garbled = int(ev.get("garbled", self._counts.garbled))
        elif kind == "recorded":
            pass                                     # the journal says it (see _journaled)
        elif kind in ("note", "warning"):
            out.append(Update("said", f"{kind}: {message}"))
        elif kind in FINAL_KINDS:
            self._ending = Update(cast("UpdateKind", kind), message, int(ev.get("code", 0)))
            if kind != "finished":
                out.append(self._ending)             # said now; the end follows the exit
        else:
            if kind == "refused":
                self._counts.refused += 1
            elif kind == "garbled":
                self._counts.garbled += 1
            elif kind == "paused":
                self.paused = True
            elif kind == "resumed":
                self.paused = False
            out.append(Update(cast("UpdateKind", kind), message))

    def _ready(self, ev: dict, out: list[Update]) -> None:
        self.cols = int(ev.get("cols", self.cols))
        self.state = "recording"
        assert self.path is not None
        self._tail = JournalTail(self.path, self.cols)
        self._silent = int(ev.get("points", 0))     # a resumed file's points: no beeps
        out.append(Update("started", f"recording to {self.path}"))
        if self.sim is not None and self.demo_file is not None:
            self._start_replay()

    def _journaled(self, kind: str, what, out: list[Update]) -> None:
        history = self.history
        c = self._counts
        c.points = len(history)
        c.undone = self._tail.undos if self._tail is not None else 0
        if kind != "recorded":
            out.append(Update("moved", ""))
            return
        p, xyz = what
        c.leaves.add((p.plant, p.leaf))
        c.plants.add(p.plant)
        if self._silent > 0:
            self._silent -= 1
            return
        out.append(Update("recorded", f"recorded plant {p.plant} leaf {p.leaf} row {p.row} col "
                                      f"{p.col}: {xyz[0]:.2f} {xyz[1]:.2f} {xyz[2]:.2f} cm"))
        self._check(out)

    def _check(self, out: list[Update]) -> None:
        """The checks of the press just recorded: a jump, a short section before it."""
        history = self.history
        d = jump(history, self.jump_cm)
        if d is not None:
            msg = jump_message(history, d, self.jump_cm)
            self.warnings.append(msg)
            out.append(Update("jump", msg))
        p = history[-1][0]
        if p.col == 0 and p.row > 0:
            n = sum(1 for q, _ in history if (q.plant, q.leaf, q.row) == (p.plant, p.leaf,
                                                                          p.row - 1))
            if 0 < n < self.cols:
                msg = short_message(p.plant, p.leaf, p.row - 1, n, self.cols)
                self.warnings.append(msg)
                out.append(Update("short", msg))

    def _end(self) -> Update:
        """The process has ended and its pipes are drained: how the session ended."""
        code = self._proc.returncode if self._proc is not None else 0
        if self.state == "connecting":
            why = "; ".join(self._errors) or f"the recorder ended (exit {code})"
            final = Update("unconnected", why, code or 1)
        elif self._ending is not None:
            final = self._ending
        elif code == 0:
            final = Update("finished", "finished")
        else:
            said = f": {'; '.join(self._errors)}" if self._errors else ""
            final = Update("failed", f"the recorder stopped unexpectedly (exit {code}){said}; "
                                     f"every point shown ({self.count.points}) is on disk: "
                                     "resume the file to go on", 1)
        self.final = final
        self.state = "stopping"
        return final

    # ------------------------------------------------------------------------- stop
    def stop(self) -> None:
        """Ask the recorder to finish (it journals what it holds first); while connecting,
        give up the connection. Returns at once: ``poll`` gives the end."""
        if self._recorder is not None:
            self._recorder.control("q")
            return
        proc = self._proc
        if proc is None or proc.poll() is not None:
            return
        if self.state == "connecting":
            proc.terminate()                 # the recorder gives up the port and the file
        else:
            self._send("q")
            with self._write:
                try:
                    proc.stdin.close()           # type: ignore[union-attr]
                except (OSError, ValueError):
                    pass
        if self.state != "connecting":
            self.state = "stopping"

    def close(self, timeout: float = CLOSE_WAIT_S) -> list[Update]:
        """Stop and wait: the recorder process, its reader threads, the demo's simulator and
        replay all end here (the window closing). Returns the updates not yet polled."""
        self.stop()
        proc = self._proc
        if proc is not None:
            try:
                proc.wait(timeout)
            except subprocess.TimeoutExpired:
                proc.terminate()
                try:
                    proc.wait(3)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
        self._close_demo()
        for t in self._readers:
            t.join(timeout=5)
        late = self.poll() if self.state != "idle" else []
        if self._recorder is not None:
            self._recorder.close()
        self.release()
        return late

    def _close_demo(self) -> None:
        sim, self.sim = self.sim, None
        if sim is not None:
            sim.close()
        replay, self._replay = self._replay, None
        if replay is not None:
            replay.join(timeout=5)

    def release(self) -> None:
        """After the end was polled: let go of the process (waited for), the threads and the
        demo; the counts and the history stay readable."""
        proc, self._proc = self._proc, None
        if proc is not None:
            try:
                proc.wait(5)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            for stream in (proc.stdin, proc.stdout, proc.stderr):
                try:
                    if stream is not None:
                        stream.close()
                except (OSError, ValueError):
                    pass
        self._close_demo()
        for t in self._readers:
            t.join(timeout=5)
        self._readers = []
        if self._recorder is not None:
            self._recorder.close()
        self.state = "idle"

    # ------------------------------------------------------------------------- demo
    def _start_replay(self) -> None:
        from maizeviz.digitizer.replay import replay_points

        sim, path, pace = self.sim, self.demo_file, self.demo_pace
        sway = self.reference_station is not None

        def say(msg: str) -> None:
            for key in ("n", "p", "q"):
                if f"type {key} " in msg:
                    self.control(key)
                    return
            self.say(msg)

        def run() -> None:
            try:
                replay_points(sim, path, pace=pace, sway=sway, say=say, wait=False)
            except Exception as exc:  # noqa: BLE001 - said in the panel
                self.say(f"demo stopped: {exc}")

        self._replay = threading.Thread(target=run, name="fastrak-demo", daemon=True)
        self._replay.start()


def _check_out(path: Path) -> None:
    """Refuse at once what the recorder would refuse about the file's place (one line)."""
    from maizeviz.digitizer.session import SessionError
    from maizeviz.io.points import is_parquet_name

    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise SessionError(f"{folder}: no such folder" if not folder.exists() else
                           f"{folder} is a file, not a folder; cannot write {path.name} in it")
    if path.is_dir():
        raise SessionError(f"{path} is a folder; give a file name for the recording")
    if is_parquet_name(str(path)):
        raise SessionError(f"{path}: a recording is a CSV journal, written point by point; "
                           "record to a .csv file")


def _pump(stream, name: str, lines: queue.Queue) -> None:
    """Copy a pipe's lines to the queue; None when it closes (never waits on the GUI)."""
    try:
        for line in stream:
            lines.put((name, line))
    except (OSError, ValueError):
        pass
    lines.put((name, None))

