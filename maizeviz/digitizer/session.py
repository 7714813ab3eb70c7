"""A digitizing session: stylus presses become points of plants, leaves and cross-sections.

Every point is appended to the output CSV (the points format plus ``status,time,station,error``
columns) and flushed to disk with fsync *before* it counts as recorded, so killing the process
at any moment loses nothing that was reported recorded. Nothing is ever rewritten: an undo
appends a line with ``status = undone`` for the point it takes back, and the controls (next
leaf, next plant, end of row) append a line with the position they lead to, so ``--resume``
continues exactly where the session stopped. Readers of the points format skip undone points
and control lines.
"""

from __future__ import annotations

import csv
import io
import os
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from maizeviz.digitizer.geometry import to_reference_frame
from maizeviz.digitizer.protocol import TRUST_ERRORS, Garbled, Record
from maizeviz.errors import MaizevizError

COLUMNS = ("plant", "leaf", "row", "col", "x", "y", "z", "status", "time", "station", "error")
CONTROLS = {"n": "next_leaf", "p": "next_plant", "r": "end_row", "u": "undo", "q": "quit"}
#: Free space (bytes) a session needs before it starts.
MIN_FREE_BYTES = 1 << 20


class SessionError(MaizevizError):
    """The session cannot record (output not writable, disk full, bad resume file)."""


@dataclass
class Position:
    plant: int = 1
    leaf: int = 1
    row: int = 0
    col: int = 0


@dataclass
class Counters:
    points: int = 0
    undone: int = 0
    refused: int = 0
    garbled: int = 0
    leaves: set = field(default_factory=set)
    plants: set = field(default_factory=set)


class Session:
    """Turns stylus records into journal lines.

    Parameters
    ----------
    path : output CSV
    cols : points per cross-section; after ``cols`` presses the next row starts
    resume : continue an existing file where it stopped (else the file must not exist or
        be empty)
    reference_station : re-express stylus points in this receiver's frame (motion compensation)
    """

    def __init__(self, path, cols: int, resume: bool = False,
                 reference_station: int | None = None, start: Position | None = None):
        if cols < 1:
            raise SessionError(f"--cols must be >= 1, got {cols}")
        self.path = Path(path)
        self.cols = cols
        self.reference_station = reference_station
        self.pos = start or Position()
        self.count = Counters()
        self.history: list[tuple] = []          # (position, xyz) of recorded, not undone points
        self._pending: Record | None = None     # a stylus record waiting for its reference
        self.messages: list[str] = []
        self._open(resume)

    # ---------------------------------------------------------------------- journal
    def _open(self, resume: bool) -> None:
        p = self.path
        if p.is_dir():
            raise SessionError(f"{p} is a folder; give a file name with --out")
        exists = p.exists() and p.stat().st_size > 0
        if exists and not resume:
            raise SessionError(f"{p} already holds points; use --resume to continue it, or "
                               "another --out")
        folder = p.parent if str(p.parent) else Path(".")
        if folder.exists() and not folder.is_dir():
            raise SessionError(f"{folder} is a file, not a folder; cannot write {p.name} in it")
        try:
            free = shutil.disk_usage(folder).free
        except OSError:
            raise SessionError(f"{folder}: no such folder") from None
        if free < MIN_FREE_BYTES and not str(p).startswith("/dev/"):
            raise SessionError(f"{folder}: only {free} bytes free; free some space first")
        if exists:
            self._replay_journal()
        try:
            self.fh = open(p, "a", newline="")
            if not exists:
                self._write_line(COLUMNS)
            else:
                self.fh.flush()
                os.fsync(self.fh.fileno())
        except OSError as exc:
            raise SessionError(f"{p}: cannot write ({exc.strerror or exc}); nothing was "
                               "recorded") from None

    def _write_line(self, values) -> None:
        buf = io.StringIO()
        csv.writer(buf).writerow(values)
        self.fh.write(buf.getvalue())
        self.fh.flush()
        os.fsync(self.fh.fileno())

    def _replay_journal(self) -> None:
        try:
            with open(self.path, newline="") as fh:
                rows = list(csv.DictReader(fh))
        except (OSError, UnicodeDecodeError, csv.Error) as exc:
            raise SessionError(f"{self.path}: cannot resume ({exc})") from None
        try:
            for r in rows:
                status = (r.get("status") or "recorded").strip()
                pos = Position(int(r["plant"]), int(r["leaf"]), int(r["row"]), int(r["col"]))
                if status == "recorded":
                    xyz = (float(r["x"]), float(r["y"]), float(r["z"]))
                    self.history.append((pos, xyz))
                    self._advance_after_point(pos)
                elif status == "undone":
                    if self.history:
                        last, _ = self.history.pop()
                        self.pos = Position(last.plant, last.leaf, last.row, last.col)
                elif status in CONTROLS.values():
                    self.pos = pos
        except (KeyError, TypeError, ValueError) as exc:
            raise SessionError(f"{self.path}: not a maizeviz recording, cannot resume "
                               f"({exc})") from None
        self.count.points = len(self.history)
        for p, _ in self.history:
            self.count.leaves.add((p.plant, p.leaf))
            self.count.plants.add(p.plant)

    def _advance_after_point(self, p: Position) -> None:
        self.pos = Position(p.plant, p.leaf, p.row, p.col + 1)
        if self.pos.col >= self.cols:
            self.pos = Position(p.plant, p.leaf, p.row + 1, 0)

    # ---------------------------------------------------------------------- events
    def on_event(self, event) -> str | None:
        """Handle one reader event; returns a line for the technician, or None."""
        if isinstance(event, Garbled):
            self.count.garbled += 1
            return None
        if not isinstance(event, Record):
            return None
        if self.reference_station is None:
            if event.station != 1:
                return None
            return self._point(event, event.position)
        if event.station == 1:
            if self._pending is not None:
                self.count.refused += 1
                self._pending = event
                return "refused: the previous press had no reference record"
            self._pending = event
            return None
        if event.station == self.reference_station and self._pending is not None:
            stylus, self._pending = self._pending, None
            if not event.trustworthy:
                self.count.refused += 1
                return (f"refused: reference receiver error '{event.error}' "
                        f"({TRUST_ERRORS[event.error]}); press again")
            if event.position is None or event.angles is None:
                self.count.refused += 1
                return "refused: the reference record has no position or angles"
            xyz = to_reference_frame(stylus.position, event.position, event.angles)
            return self._point(stylus, tuple(xyz))
        return None

    def _point(self, rec: Record, xyz) -> str:
        if not rec.trustworthy:
            self.count.refused += 1
            return (f"refused: error '{rec.error}' ({TRUST_ERRORS[rec.error]}); move the "
                    "transmitter closer and press again")
        if xyz is None or not np.all(np.isfinite(xyz)):
            self.count.refused += 1
            return "refused: the record has no usable position"
        p = self.pos
        try:
            self._write_line([p.plant, p.leaf, p.row, p.col, *(f"{v:.3f}" for v in xyz),
                              "recorded", f"{time.time():.3f}", rec.station, rec.error.strip()])
        except OSError as exc:
            raise SessionError(f"{self.path}: cannot write ({exc.strerror or exc}); the last "
                               f"point was NOT recorded; {self.count.points} points are safe "
                               "on disk") from None
        self.history.append((p, tuple(xyz)))
        self.count.points += 1
        self.count.leaves.add((p.plant, p.leaf))
        self.count.plants.add(p.plant)
        self._advance_after_point(p)
        return (f"recorded plant {p.plant} leaf {p.leaf} row {p.row} col {p.col}: "
                f"{xyz[0]:.2f} {xyz[1]:.2f} {xyz[2]:.2f} cm")

    def control(self, key: str) -> str:
        """Apply a technician's control (n, p, r, u, q); returns what happened."""
        key = key.strip().lower()
        if key not in CONTROLS:
            return f"unknown control '{key}': n next leaf, p next plant, r end row, u undo, q quit"
        action = CONTROLS[key]
        p = self.pos
        if action == "quit":
            return "quit"
        if action == "undo":
            if not self.history:
                return "nothing to undo"
            last, xyz = self.history.pop()
            self._write_line([last.plant, last.leaf, last.row, last.col,
                              *(f"{v:.3f}" for v in xyz), "undone", f"{time.time():.3f}", "", ""])
            self.count.points -= 1
            self.count.undone += 1
            self.pos = Position(last.plant, last.leaf, last.row, last.col)
            return (f"undone: plant {last.plant} leaf {last.leaf} row {last.row} col {last.col}; "
                    "press again there")
        if action == "end_row":
            if p.col == 0:
                return f"row {p.row} is empty; nothing to end"
            self.pos = Position(p.plant, p.leaf, p.row + 1, 0)
        elif action == "next_leaf":
            self.pos = Position(p.plant, p.leaf + 1, 0, 0)
        elif action == "next_plant":
            self.pos = Position(p.plant + 1, 1, 0, 0)
        q = self.pos
        self._write_line([q.plant, q.leaf, q.row, q.col, "", "", "", action,
                          f"{time.time():.3f}", "", ""])
        return f"{action.replace('_', ' ')}: next point is plant {q.plant} leaf {q.leaf} row {q.row}"

    def summary(self) -> str:
        c = self.count
        return (f"{c.points} points, {len(c.leaves)} leaves, {len(c.plants)} plants recorded "
                f"in {self.path}; {c.undone} undone, {c.refused} refused, {c.garbled} garbled")

    def close(self) -> None:
        try:
            self.fh.close()
        except (OSError, AttributeError):
            pass
