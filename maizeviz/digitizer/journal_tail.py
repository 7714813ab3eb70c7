"""Following a recording as another process writes it: what is on disk, line by line.

The app's window shows only what the recorder has journaled (the recorder runs in a process of
its own, see ``docs/fastrak.md``); :class:`JournalTail` reads the lines appended since the last
call and replays them with the points reader's rules (:class:`JournalReplay`), so the points,
the undos and the position of the next point are the file's, as a resume would see them.
"""

from __future__ import annotations

from pathlib import Path

from maizeviz.digitizer.session import DEFAULT_COLS, JournalReplay, Position

#: Bytes read at most per call (a day of digitizing is some 6 MB).
CHUNK = 1 << 20


class JournalTail(JournalReplay):
    """Reads a growing recording.

    Parameters
    ----------
    path : the recording (it may not exist yet)
    cols : points per cross-section (where the next point goes after a full row)

    Attributes
    ----------
    history : [(Position, (x, y, z) cm)], points on disk and not undone, in order
    """

    def __init__(self, path, cols: int):
        super().__init__(str(path), cols)
        self.path = Path(path)
        self.offset = 0
        self.lineno = 0
        self.undos = 0
        self._rest = b""
        self._new: list[tuple[str, object]] = []

    @property
    def pos(self) -> Position:
        """Where the next point goes."""
        return self.pos_after(self.cols or DEFAULT_COLS)

    def commit(self, outcome) -> None:
        kind = outcome[0]
        before = len(self.history)
        super().commit(outcome)
        if kind == "point":
            self._new.append(("recorded", self.history[-1]))
        elif kind == "undo" and len(self.history) < before:
            self.undos += 1
            self._new.append(("undone", self.pos))
        elif kind == "control":
            self._new.append(("control", self.pos))

    def read(self) -> list[tuple[str, object]]:
        """The lines appended since the last call, as ``("recorded", (Position, xyz))``,
        ``("undone", next Position)`` or ``("control", next Position)``; only whole lines
        (a line being written is read once its line end is on disk)."""
        try:
            with open(self.path, "rb") as fh:
                fh.seek(self.offset)
                data = fh.read(CHUNK)
        except FileNotFoundError:
            return []
        self.offset += len(data)
        data = self._rest + data
        cut = data.rfind(b"\n") + 1
        self._rest = data[cut:]
        for line in data[:cut].splitlines(keepends=True):
            self.lineno += 1
            self.feed(self.lineno, line.decode("utf-8", "replace"), True)
        if self.pending is not None:          # the recorder writes whole lines: no discard
            self.commit(self.pending)         # mark can follow (see Session._repair)
            self.pending = None
        out, self._new = self._new, []
        return out
