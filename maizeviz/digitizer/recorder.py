"""A digitizing session as one loop: the port's reader thread and the technician's controls
feed one queue; :meth:`Recorder.poll` turns what is queued into journal lines and updates.

The command line (``maizeviz record``) polls with a timeout; the app polls from a GUI timer.
Nothing is handled after the session finished (``q``) or the port vanished, so a control and a
record arriving in the same poll can never act on a closed session.

While paused (:meth:`Recorder.pause`, queued like a control, so presses made before it still
count) a press is not recorded, and each such press is said. The stylus's live position (the
answers to the reader's polls) is kept in :attr:`Recorder.live`, in the recording's frame,
with its distance from the last point recorded.

:func:`plant_sections` reads a session's history back as the finished cross-sections of each
leaf, which is what a live view of the plant needs to re-fit only the leaf that changed.
"""

from __future__ import annotations

import queue
from dataclasses import dataclass
from typing import Literal

import numpy as np

from maizeviz.digitizer.geometry import to_reference_frame
from maizeviz.digitizer.live import Live
from maizeviz.digitizer.port import FastrakPort, PortLost
from maizeviz.digitizer.protocol import TRUST_ERRORS, Garbled, Record
from maizeviz.digitizer.session import Position, Session
from maizeviz.errors import MaizevizError

#: What an update is about: a point recorded, a press refused, a garbled record, a control
#: applied, a message from elsewhere (the demo), recording paused or resumed, a press not
#: recorded because paused, the session finished (q), the port lost, a write that failed, a
#: signal (SIGTERM) received. A program showing a recorder adds its own (the app's
#: :mod:`maizeviz_app.digitizing`): recording began, the connection failed, a press far from
#: the point before it, a short cross-section, the next point's place changed.
UpdateKind = Literal["recorded", "refused", "garbled", "control", "said", "paused", "resumed",
                     "ignored", "finished", "lost", "failed", "signal", "started",
                     "unconnected", "jump", "short", "moved"]
#: The control that pauses or resumes recording (the technician's other controls are the
#: session's: :data:`maizeviz.digitizer.session.CONTROLS`).
PAUSE_KEY = "s"
#: Kinds after which the recorder handles nothing more.
FINAL_KINDS = ("finished", "lost", "failed", "signal")


@dataclass(frozen=True)
class Update:
    """One thing that happened, with the line to show the technician (may be empty)."""

    kind: UpdateKind
    message: str = ""
    code: int = 0


@dataclass(frozen=True)
class LiveTip:
    """Where the stylus tip is now.

    Attributes
    ----------
    xyz : (3,) tuple of float, cm, in the recording's frame (the plant's with a reference
        receiver)
    distance : float or None, cm from the last point recorded (None before the first)
    trustworthy : bool, no built-in-test letter that makes a point untrustworthy
    note : str, why not trustworthy ('' when it is)
    time : float, ``time.monotonic()`` of the answer
    """

    xyz: tuple[float, float, float]
    distance: float | None
    trustworthy: bool
    note: str
    time: float


class Recorder:
    """A session journal fed by a configured port.

    Parameters
    ----------
    session : the journal (opened, resumed if asked)
    port : a configured :class:`FastrakPort`; its reader starts with :meth:`start`
    """

    def __init__(self, session: Session, port: FastrakPort | None):
        self.session = session
        self.port = port
        self.events: queue.Queue = queue.Queue()
        self.final: Update | None = None
        self.paused = False
        #: Presses made while paused (not recorded).
        self.ignored = 0
        #: The stylus's last live position (None until the first answer to a poll).
        self.live: LiveTip | None = None

    @property
    def finished(self) -> bool:
        return self.final is not None

    def start(self, live_every: float | None = None) -> None:
        """Start the port's reader thread, its events going to this recorder's queue; with
        ``live_every`` (s) it also polls for the stylus's live position."""
        if self.port is not None:
            self.port.start_reader(self.events.put, live_every=live_every)

    def pause(self, on: bool = True) -> None:
        """Pause (or resume) recording, from any thread: queued, so a press made before the
        pause is still recorded and one made after it is not."""
        self.events.put(("pause", bool(on)))

    # thread-safe producers -------------------------------------------------------------
    def control(self, key: str) -> None:
        """Queue a technician's control (n, p, r, u, q; s pauses or resumes), from any
        thread."""
        self.events.put(("control", key))

    def say(self, message: str) -> None:
        """Queue a message to pass on (a demo's instructions), from any thread."""
        self.events.put(("say", message))

    def signal(self, signum: int) -> None:
        """Queue the end of the session by a signal (SIGTERM), from a signal handler."""
        self.events.put(("signal", signum))

    # the loop --------------------------------------------------------------------------
    def poll(self, timeout: float = 0.0, limit: int = 2000) -> list[Update]:
        """Handle up to ``limit`` queued events, waiting up to ``timeout`` s for the first.

        Returns the updates in order; the last is final (``finished``, ``lost``, ``failed``,
        ``signal``) when the session ended, and later calls return nothing.
        """
        out: list[Update] = []
        for k in range(limit):
            if self.final is not None:
                break
            try:
                ev = self.events.get(timeout=timeout) if k == 0 and timeout > 0 else \
                    self.events.get_nowait()
            except queue.Empty:
                break
            update = self._handle(ev)
            if update is None:
                continue
            out.append(update)
            if update.kind in FINAL_KINDS:
                self.final = update
        return out

    def _handle(self, ev: object) -> Update | None:
        try:
            return self._apply(ev)
        except MaizevizError as exc:                # the journal cannot be written (disk full)
            return Update("failed", str(exc), 1)

    def _apply(self, ev: object) -> Update | None:
        if isinstance(ev, Live):
            self._live(ev)
            return None
        if isinstance(ev, tuple):
            kind, value = ev
            if kind == "signal":
                return Update("signal", f"stopped by signal {value}", 128 + int(value))
            if kind == "say":
                return Update("said", str(value))
            if kind == "pause":
                return self._pause(bool(value))
            key = str(value)
            if not key.strip():
                return None
            if key.strip().lower() == PAUSE_KEY:
                return self._pause(not self.paused)
            msg = self.session.control(key)
            if msg == "quit":
                return Update("finished", "finished")
            return Update("control", msg)
        if isinstance(ev, PortLost):
            return Update("lost", f"{ev.message} Every point reported recorded is on disk "
                                  f"({self.session.count.points}); resume the recording to "
                                  "go on", 1)
        if self.paused and isinstance(ev, Record) and ev.station == 1:
            # (a reference record goes on to the session, which pairs it only with a press)
            self.ignored += 1
            where = "" if ev.position is None else \
                " at " + " ".join(f"{v:.1f}" for v in ev.position) + " cm"
            return Update("ignored", f"paused: the press{where} was NOT recorded "
                                     f"({self.ignored} while paused); resume to record")
        said = self.session.on_event(ev)
        if isinstance(ev, Garbled):
            return Update("garbled", f"garbled record skipped ({ev.reason}); "
                                     f"{self.session.count.garbled} so far: check the cable if "
                                     "this repeats")
        if not said:
            return None
        return Update("recorded" if said.startswith("recorded") else "refused", said)

    def _pause(self, on: bool) -> Update | None:
        if on == self.paused:
            return None
        self.paused = on
        if on:
            self.ignored = 0
            return Update("paused", "paused: presses are not recorded until you resume")
        return Update("resumed", "resumed: the next press is recorded at plant "
                                 f"{self.session.pos.plant} leaf {self.session.pos.leaf} row "
                                 f"{self.session.pos.row} col {self.session.pos.col}")

    def _live(self, ev: Live) -> None:
        """Keep the stylus's position from a poll's answer, in the recording's frame."""
        tip = ev.stylus
        if tip.position is None:
            return
        xyz = np.asarray(tip.position, float)
        bad = [r for r in ev.records if not r.trustworthy]
        ref_station = self.session.reference_station
        if ref_station is not None:
            ref = ev.station(ref_station)
            if ref is None or ref.position is None or ref.angles is None:
                return
            xyz = to_reference_frame(xyz, ref.position, ref.angles)
        if not np.all(np.isfinite(xyz)):
            return
        last = self.session.history[-1][1] if self.session.history else None
        distance = None if last is None else float(np.linalg.norm(xyz - np.asarray(last)))
        note = "; ".join(f"station {r.station}: {TRUST_ERRORS[r.error]}" for r in bad)
        self.live = LiveTip((float(xyz[0]), float(xyz[1]), float(xyz[2])), distance, not bad,
                            note, ev.time)

    def close(self) -> None:
        """Stop the reader, close the port and the journal (idempotent)."""
        if self.port is not None:
            self.port.close()
        self.session.close()


def plant_sections(history: list[tuple], plant: int,
                   current: Position | None = None) -> dict[int, dict[int, np.ndarray]]:
    """The finished cross-sections of each leaf of ``plant``.

    Parameters
    ----------
    history : [(Position, (x, y, z) cm)]
        A session's recorded points that are not undone, in recording order
        (:attr:`Session.history`).
    current : Position, optional
        Where the next point goes (:attr:`Session.pos`). The row it points into is still being
        digitized and is left out; every other row counts as finished whatever its number of
        points (a row ended with ``r``, a tip collapsed to one point).

    Returns
    -------
    {leaf: {row: (k, 3) float64, cm}}, points of each row in column order; every leaf of the
    plant with at least one point appears, possibly with no finished row.
    """
    rows: dict[int, dict[int, list]] = {}
    for p, xyz in history:
        if p.plant == plant:
            rows.setdefault(p.leaf, {}).setdefault(p.row, []).append(xyz)
    if current is not None and current.plant == plant and current.col > 0:
        rows.get(current.leaf, {}).pop(current.row, None)
    return {leaf: {r: np.asarray(v, dtype=np.float64).reshape(-1, 3) for r, v in sorted(rs.items())}
            for leaf, rs in sorted(rows.items())}
