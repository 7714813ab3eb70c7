"""A digitizing session: stylus presses become points of plants, leaves and cross-sections.

Every point is appended to the output CSV (the points format plus ``status,time,station,error``
columns) and flushed to disk with fsync *before* it counts as recorded, so killing the process
at any moment loses nothing that was reported recorded. Nothing is ever rewritten: an undo
appends a line with ``status = undone`` for the point it takes back, and the controls (next
leaf, next plant, end of row) append a line with the position they lead to, so resuming
continues exactly where the session stopped. Readers of the points format skip undone points
and control lines.

A point counts as recorded only when its whole line, line end included, is on disk. A last
line without its line end (the disk filled up, the power went, the process was killed in
mid-write) was never reported recorded: before anything else is written, it is ended with a
line end and followed by a ``discarded`` line, which tells every reader to skip the line just
above it. The next press therefore never runs into the torn line.

One recorder at a time: a session holds an exclusive ``flock`` on ``.<name>.lock`` beside the
file, which holds its process id; the kernel drops the lock when the process ends, however it
ends, so a lock file left behind by a killed recorder is no obstacle.
"""

from __future__ import annotations

import csv
import errno
import fcntl
import io
import os
import shutil
import stat
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from maizeviz.digitizer.geometry import to_reference_frame
from maizeviz.digitizer.protocol import TRUST_ERRORS, Garbled, Record
from maizeviz.errors import MaizevizError, PointsFileError
from maizeviz.io.inputs import file_kind
from maizeviz.io.points import (
    DISCARDED,
    JOURNAL_COLUMNS,
    LineParser,
    file_lines,
    open_regular,
    refuse_binary,
    shown,
    text_of,
    zero_tail,
)

COLUMNS = JOURNAL_COLUMNS
CONTROLS = {"n": "next_leaf", "p": "next_plant", "r": "end_row", "u": "undo", "q": "quit"}
#: Points per cross-section of a new recording unless told.
DEFAULT_COLS = 5
#: Free space (bytes) a session needs before it starts.
MIN_FREE_BYTES = 1 << 20
#: The header line the recorder writes (csv's CR LF line end).
HEADER = (",".join(COLUMNS) + "\r\n").encode("ascii")
#: Most lines a recording may hold to be resumed: a day of digitizing is some 20,000 (each
#: point replayed takes about 300 bytes of memory).
MAX_JOURNAL_LINES = 1_000_000


def _count(n: int, word: str) -> str:
    """``1 point``, ``2 points``."""
    return f"{n} {word}{'' if n == 1 else 's'}"


class SessionError(MaizevizError):
    """The session cannot record (output not writable, disk full, bad resume file)."""


class JournalInUse(SessionError):
    """Another recorder holds the file; :attr:`pid` is its process id (None if unknown)."""

    def __init__(self, message: str, pid: int | None):
        super().__init__(message)
        self.pid = pid


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


# --------------------------------------------------------------------------- the lock
def lock_path(path: Path) -> Path:
    """``.<name>.lock`` beside the recording."""
    return path.with_name(f".{path.name}.lock")


def _read_pid(fd: int) -> int | None:
    try:
        text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
        return int(text.split()[0]) if text else None
    except (OSError, ValueError, IndexError):
        return None


def acquire_lock(path: Path) -> tuple[int, Path]:
    """Lock ``path`` for this process: flock on its lock file, which then holds our pid.

    Returns (file descriptor of the lock file, its path); the lock lasts until
    :func:`release_lock` or the end of the process.

    Raises
    ------
    JournalInUse
        Another process (or another session of this one) holds the lock.
    SessionError
        The lock file cannot be made (a read-only folder).
    """
    lp = lock_path(path)
    for _ in range(5):
        try:
            fd = os.open(lp, os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o644)
        except OSError as exc:
            raise SessionError(f"{path}: cannot write its lock file {lp.name} "
                               f"({exc.strerror or exc}); nothing was recorded") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            pid = _read_pid(fd)
            os.close(fd)
            if exc.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise SessionError(f"{path}: cannot lock it ({exc.strerror or exc})") from None
            who = "an unknown process" if pid is None else (
                f"this program (pid {pid})" if pid == os.getpid() else f"pid {pid}")
            raise JournalInUse(f"{path} is being recorded by another recorder, {who}; stop "
                               "that one first, or record into another file", pid) from None
        try:
            same = os.fstat(fd).st_ino == os.stat(lp).st_ino
        except FileNotFoundError:
            same = False
        if not same:                    # its holder removed it as we opened it: try again
            os.close(fd)
            continue
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode("ascii"), 0)
        except OSError as exc:
            release_lock(fd, lp)
            raise SessionError(f"{path}: cannot write its lock file {lp.name} "
                               f"({exc.strerror or exc}); nothing was recorded") from None
        return fd, lp
    raise SessionError(f"{path}: its lock file {lp.name} keeps changing; is another recorder "
                       "starting?")


def release_lock(fd: int, lp: Path) -> None:
    """Remove the lock file (while still holding it, so no one locks a removed file) and
    let go."""
    try:
        if os.fstat(fd).st_ino == os.stat(lp).st_ino:
            os.unlink(lp)
    except OSError:
        pass
    try:
        os.close(fd)
    except OSError:
        pass


# ------------------------------------------------------------------------- the replay
class JournalReplay(LineParser):
    """Replays a recording with the points reader's rules: the points it keeps, where the
    next point goes, and any torn last line.

    A line the reader skips (an unknown status, a line of the wrong length, an id out of
    range, an undo of a point that is not recorded) changes nothing here either: the next
    point goes where it went before that line. An undo takes back the latest recording of
    its point, as the reader's does, and the next point goes there (as after the recorder's
    own undo).

    Attributes
    ----------
    history : list of (Position, (x, y, z) cm), points recorded and not undone, in order: the
        points :func:`maizeviz.io.points.read_points` keeps, in the same order
    problems : lines that were skipped, with the reason (the points reader says the same)
    width : points per cross-section the recording shows, or None: the last row that ended
        by itself (a point at col 0 right after the previous row's last point, no other line
        in between) had ``width`` points
    least_width : points per cross-section the recording needs at least (largest col + 1)
    bad_leaf_lines : {(plant, leaf): first message}: leaves with a line the reader cannot
        read (every point of such a leaf is refused when the file is read)
    """

    def __init__(self, source: str, cols: int | None):
        super().__init__(source, max_points=MAX_JOURNAL_LINES, max_lines=MAX_JOURNAL_LINES)
        self.cols = cols
        self.history: list[tuple] = []
        self.controls = 0
        self.width: int | None = None
        self.least_width = 0
        self.bad_leaf_lines: dict[tuple[int, int], str] = {}
        self._moved_to: Position | None = None   # where a control or an undo leads
        self._after: Position | None = None      # else: the next point follows this one
        self._previous: Position | None = None   # the line just before was this point

    @property
    def pos(self) -> Position:
        """Where the next point goes for :attr:`cols` (after a point with ``cols`` None: its
        next col; :meth:`pos_after` gives it for a width)."""
        if self._moved_to is None and self._after is not None and not self.cols:
            p = self._after
            return Position(p.plant, p.leaf, p.row, p.col + 1)
        return self.pos_after(self.cols or DEFAULT_COLS)

    def pos_after(self, cols: int) -> Position:
        """Where the next point goes in a recording of ``cols`` points per cross-section."""
        if self._moved_to is not None:
            return self._moved_to
        if self._after is not None:
            return _after(self._after, cols)
        return Position()

    def _discard(self, lineno: int) -> None:
        """A torn line marked when an earlier session resumed: skipped without a word."""
        self.pending = None

    def commit(self, outcome) -> None:
        kind, payload, lineno = outcome
        previous, self._previous = self._previous, None
        if kind == "point":
            plant, leaf, row, col, coords, _ = payload
            p = Position(plant, leaf, row, col)
            if previous is not None and col == 0 and (previous.plant, previous.leaf,
                                                      previous.row + 1) == (plant, leaf, row):
                self.width = previous.col + 1             # the row ended by itself
            self.least_width = max(self.least_width, col + 1)
            self.history.append((p, tuple(coords)))
            self._after, self._moved_to, self._previous = p, None, p
        elif kind == "undo":
            key = Position(*payload)
            for k in range(len(self.history) - 1, -1, -1):
                if self.history[k][0] == key:          # the latest recording of that point
                    del self.history[k]
                    self._moved_to = key
                    break
            else:
                self._note(f"line {lineno}: undoes plant {key.plant} leaf {key.leaf} row "
                           f"{key.row} col {key.col}, which is not recorded; skipped")
        elif kind == "control":
            self.controls += 1
            status, key = payload
            if key is None:
                self._note(f"line {lineno}: unreadable '{status}' line; skipped")
            else:
                self._moved_to = Position(*key)
        elif kind == "bad":
            (plant, leaf), message = payload
            self.bad_leaf_lines.setdefault((plant, leaf), message)
            self._note(f"plant {plant}, leaf {leaf}: {message}; skipped")
        elif kind == "problem":
            self._note(payload)
        # "torn": the session reports and repairs it itself

    def close(self) -> None:
        """Commit the last line (the file has ended)."""
        if self.pending is not None:
            self.commit(self.pending)
            self.pending = None
        if self.dropped:
            self.problems.append(f"... and {self.dropped:,} more lines skipped")


def _key(p: Position) -> tuple[int, int, int, int]:
    return (p.plant, p.leaf, p.row, p.col)


def _after(p: Position, cols: int) -> Position:
    """The position after a point at ``p``: the next col, or the next row after ``cols``."""
    if p.col + 1 >= cols:
        return Position(p.plant, p.leaf, p.row + 1, 0)
    return Position(p.plant, p.leaf, p.row, p.col + 1)


def _describe_fragment(text: str) -> str:
    """The point a torn line was about, in words, from the fields that survived."""
    fields = text.rstrip("\r\n").split(",")
    if len(fields) > 7 and fields[7] and not "recorded".startswith(fields[7]):
        return f"a '{shown(fields[7], 20)}' line"
    try:
        plant, leaf, row, col = (int(f) for f in fields[:4])
    except ValueError:
        return "the line (too little of it is left to say which point)"
    return f"the point at plant {plant}, leaf {leaf}, row {row}, col {col}"


# ------------------------------------------------------------------------- the session
class Session:
    """Turns stylus records into journal lines.

    Parameters
    ----------
    path : output CSV
    cols : points per cross-section; after ``cols`` presses the next row starts. None: when
        resuming, the recording's own (refused when no row of it has ended yet), else
        :data:`DEFAULT_COLS`; given when resuming, it must agree with the recording
    resume : continue an existing recording where it stopped (else the file must not exist,
        be empty, or hold no point yet, as after a start that failed)
    reference_station : re-express stylus points in this receiver's frame (motion compensation)

    Attributes
    ----------
    messages : list of str
        What the technician should know about the file before the first press: a torn
        last line found and marked not recorded, lines skipped in the replay.
    """

    def __init__(self, path, cols: int | None = None, resume: bool = False,
                 reference_station: int | None = None, start: Position | None = None):
        if cols is not None and (isinstance(cols, bool) or not isinstance(cols, int)
                                 or not 1 <= cols <= 10_000):
            raise SessionError(f"points per cross-section must be a whole number from 1 to "
                               f"10000, got {cols}", quantity="cols")
        self.path = Path(path)
        # None while resuming: the recording's own, known once it is replayed (_width)
        self.cols: int = DEFAULT_COLS if cols is None and not resume else cols  # type: ignore[assignment]
        self.reference_station = reference_station
        self.pos = start or Position()
        self.count = Counters()
        self.history: list[tuple] = []          # (position, xyz) of recorded, not undone points
        self._held: Counter = Counter()         # how often each position is in the history
        self._pending: Record | None = None     # a stylus record waiting for its reference
        self.messages: list[str] = []
        self.fd: int | None = None
        self._lock: tuple | None = None
        self._tail = ""                         # what follows the file's last line end
        self._unmarked = False                  # a torn line is ended but not yet marked
        self._torn_line: tuple | None = None    # (line number, text) found when opening
        self._zeros = 0                         # zero bytes ending the file (a power cut)
        self._size = 0                          # the file's bytes before them
        self._made = False                      # this session made the file (or its header)
        self._wrote = False                     # a point or a control line written since
        self._open(resume)

    # ---------------------------------------------------------------------- journal
    def _check_place(self) -> None:
        """The file can be a recording: a regular file (or none yet) in a folder with room."""
        p = self.path
        folder = p.parent if str(p.parent) else Path(".")
        if folder.exists() and not folder.is_dir():
            raise SessionError(f"{folder} is a file, not a folder; cannot write {p.name} in it")
        try:
            st = os.stat(p)
        except FileNotFoundError:
            st = None
        except OSError as exc:
            raise SessionError(f"{p}: cannot write ({exc.strerror or exc}); nothing was "
                               "recorded") from None
        if st is not None and stat.S_ISDIR(st.st_mode):
            raise SessionError(f"{p} is a folder; give a file name for the recording")
        if st is not None and not stat.S_ISREG(st.st_mode):
            raise SessionError(f"{p}: cannot write a recording there: it is "
                               f"{file_kind(st.st_mode) or 'not a regular file'}, and a "
                               "recording must be a regular file")
        try:
            free = shutil.disk_usage(folder).free
        except OSError:
            raise SessionError(f"{folder}: no such folder") from None
        if free < MIN_FREE_BYTES:
            raise SessionError(f"{folder}: only {free} bytes free; free some space first "
                               f"(a recording needs {MIN_FREE_BYTES // 1024} KiB to start)")

    def _open(self, resume: bool) -> None:
        self._check_place()
        if not resume:
            self._examine(resume)        # "already holds points" even while another records it
        self._lock = acquire_lock(self.path)
        try:
            state, replay = self._examine(resume)
            if replay is not None:
                self._adopt(replay, resume)
            flags = os.O_WRONLY | os.O_APPEND | os.O_CREAT | getattr(os, "O_CLOEXEC", 0)
            try:
                if state == "rewrite":             # nothing in it but a header cut short
                    flags |= os.O_TRUNC
                self.fd = os.open(self.path, flags, 0o644)
                if state in ("new", "rewrite"):
                    self._append(HEADER)
                    self._made = True
                elif self._zeros:                  # nothing in them: appending must follow
                    os.ftruncate(self.fd, self._size)  # the last line, not a run of zeros
                    os.fsync(self.fd)
            except OSError as exc:
                raise SessionError(f"{self.path}: cannot write ({exc.strerror or exc}); nothing "
                                   "was recorded") from None
            if self._zeros:
                self.messages.append(
                    f"the file ended in {self._zeros:,} zero bytes (as a power cut leaves a file "
                    "being written); they held nothing and are removed, every line before them "
                    "is kept")
            if self.cols is None:                  # resuming a recording that holds no line
                self.cols = DEFAULT_COLS
            if self._tail or self._unmarked:
                try:
                    self._repair(announce=True)
                except OSError as exc:
                    raise SessionError(f"{self.path}: cannot end its torn last line "
                                       f"({exc.strerror or exc}); nothing was recorded; free "
                                       "some space and resume") from None
        except BaseException:
            self.close()
            raise

    def _examine(self, resume: bool) -> tuple[str, JournalReplay | None]:
        """What the file holds: "new" (nothing), "rewrite" (only a header cut short), or
        "append" (a recording, with its replay).

        Raises
        ------
        SessionError
            The file is not a recording, or (not resuming) it already holds points.
        """
        p = self.path
        try:
            size = os.stat(p).st_size
        except FileNotFoundError:
            return "new", None
        try:
            with open_regular(p, SessionError, "recording")[0] as fh:
                self._zeros = zero_tail(fh, size)
                size -= self._zeros
                head = fh.read(min(size, len(HEADER) + 2))
        except OSError as exc:
            raise SessionError(f"{p}: cannot be read ({exc.strerror or exc})") from None
        self._size = size
        if size <= len(HEADER) + 1:
            core = head.strip(b" \t\r\n")
            if not core:
                return "rewrite", None
            if HEADER.rstrip(b"\r\n").startswith(core):
                return ("append" if head in (HEADER, HEADER[:-2] + b"\n") else "rewrite"), None
        replay = self._replay(resume)
        points = len(replay.history)
        if not resume and points:
            raise SessionError(f"{p} already holds points ({points} recorded); resume it to "
                               "continue, or record into another file", quantity="resume")
        return "append", replay

    def _adopt(self, replay: JournalReplay, resume: bool) -> None:
        """Take over the position and points of a replayed recording (when resuming) and
        what it says about the file."""
        if resume:
            self.cols = self._width(replay)
            self.history = replay.history
            self.pos = replay.pos_after(self.cols)
            self.count.points = len(self.history)
            for q, _ in self.history:
                self.count.leaves.add((q.plant, q.leaf))
                self.count.plants.add(q.plant)
                self._held[_key(q)] += 1
            self._check_next(replay)
        self.messages.extend(replay.problems)
        if replay.torn is not None:
            self._tail = replay.torn[1]
            self._torn_line = replay.torn

    def _check_next(self, replay: JournalReplay) -> None:
        """Refuse to resume where the next press would lose points: on a point the recording
        already holds (the leaf would then be refused as a whole), or on a leaf the reader
        refuses for an unreadable line."""
        q = self.pos
        where = f"plant {q.plant} leaf {q.leaf} row {q.row} col {q.col}"
        if self._held[_key(q)]:
            raise SessionError(f"cannot resume {self.path}: the next point would be {where}, "
                               "which the recording already holds, and a point recorded twice "
                               "makes its whole leaf unreadable; record into another file",
                               quantity="resume")
        bad = replay.bad_leaf_lines.get((q.plant, q.leaf))
        if bad is not None:
            raise SessionError(f"cannot resume {self.path}: the next point would be {where}, "
                               f"on a leaf the file already makes unreadable ({bad}); correct "
                               "that line, or record into another file", quantity="resume")

    def _width(self, replay: JournalReplay) -> int:
        """The points per cross-section of a resumed recording: the one it shows, or the one
        given if it agrees.

        Raises
        ------
        SessionError
            The width given contradicts the recording's; or none is given and no row of the
            recording has ended yet, so its width is not known.
        """
        shown_width, least = replay.width, replay.least_width
        if self.cols is None:
            if shown_width is not None:
                return shown_width
            if not replay.history:
                return DEFAULT_COLS
            raise SessionError(f"{self.path}: no cross-section of the recording is finished yet, "
                               f"so its points per cross-section are not known (at least "
                               f"{least}): give the points per cross-section to resume it",
                               quantity="cols")
        if shown_width is not None and shown_width != self.cols or self.cols < least:
            was = shown_width if shown_width is not None else f"at least {least}"
            raise SessionError(f"{self.path} was recorded with {was} points per cross-section, "
                               f"not {self.cols}; resume it without giving them (or with "
                               f"{was})", quantity="cols")
        return self.cols

    def _replay(self, resume: bool) -> JournalReplay:
        """Read the whole recording with the points reader's rules; refuse anything else."""
        p = self.path
        replay = JournalReplay(str(p), self.cols)
        try:
            fh, _ = open_regular(p, SessionError, "recording")
            with fh:
                refuse_binary(fh, str(p), self._size)
                lines = file_lines(fh, str(p), limit=self._size)
                for lineno, (text, terminated) in enumerate(lines, 1):
                    replay.feed(lineno, text, terminated)
                    if replay.header is not None and not replay.journal:
                        break
            if replay.carry:
                raise PointsFileError(f"line {replay.carry_start}: a quote is never closed")
            replay.close()
        except PointsFileError as exc:
            raise SessionError(self._not_a_recording(resume, str(exc).removeprefix(f"{p}: "))) from None
        except OSError as exc:
            raise SessionError(f"{p}: cannot be read ({exc.strerror or exc})") from None
        if replay.header is None or not replay.journal:
            found = ",".join(replay.header or [])[:80]
            raise SessionError(self._not_a_recording(
                resume, f"{p}: its header is '{found}', a recording's is '{','.join(COLUMNS)}'"))
        return replay

    def _not_a_recording(self, resume: bool, why: str) -> str:
        if resume:
            return (f"cannot resume {self.path}: not a maizeviz recording ({why}); "
                    "record into another file")
        return (f"{self.path} already holds data and is not a maizeviz recording ({why}); "
                "resuming cannot continue it either: record into another file")

    def _append(self, data: bytes) -> None:
        """Write all of ``data`` (whole lines) at the end of the file and fsync it.

        Raises OSError; what part of ``data`` reached the file before the error is kept in
        ``_tail`` (the text after the last line end), repaired before the next write.
        """
        fd = self.fd
        if fd is None:
            raise OSError(errno.EBADF, "the recording is closed")
        done = 0
        try:
            while done < len(data):
                n = os.write(fd, data[done:])
                if n <= 0:                                 # pragma: no cover - POSIX says > 0
                    raise OSError(errno.EIO, "write made no progress")
                done += n
            os.fsync(fd)
        except OSError:
            written = data[:done]
            cut = written.rfind(b"\n")
            rest = written[cut + 1:].decode("utf-8", "replace")
            self._tail = rest if cut >= 0 else self._tail + rest
            raise
        self._tail = ""

    def _repair(self, announce: bool = False) -> None:
        """End a torn last line and mark it not recorded: a line end, then a line whose status
        ``discarded`` takes back the line above it (see :mod:`maizeviz.io.points`). Blanks
        after the last line end only need the line end."""
        torn = self._torn_line
        mark = bool(self._tail.strip()) or self._unmarked
        data = b"\r\n" if self._tail else b""
        if mark:
            buf = io.StringIO()
            csv.writer(buf).writerow(["", "", "", "", "", "", "", DISCARDED,
                                      f"{time.time():.3f}", "", ""])
            data += buf.getvalue().encode("ascii")
            self._unmarked = True
        self._append(data)                        # OSError: the callers say what was lost
        self._unmarked = False
        self._torn_line = None
        if announce and mark and torn is not None:
            lineno, text = torn
            shown = text_of(text.rstrip("\r\n").split(","), 60)
            self.messages.append(
                f"line {lineno} was cut short ('{shown}', no line end): "
                f"{_describe_fragment(text)} was NOT recorded; that line is now marked "
                f"discarded and every reader skips it; {self.count.points} points are kept")

    def _write_line(self, values) -> None:
        if self._tail or self._unmarked:
            self._repair()
        self._wrote = True
        buf = io.StringIO()
        csv.writer(buf).writerow(values)
        self._append(buf.getvalue().encode("utf-8"))

    def _advance_after_point(self, p: Position) -> None:
        self.pos = _after(p, self.cols)

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
        if self._held[_key(p)]:           # only after a hand-edited recording was resumed
            self.count.refused += 1
            return (f"refused: plant {p.plant} leaf {p.leaf} row {p.row} col {p.col} is already "
                    "recorded, and a point recorded twice makes its leaf unreadable; press n "
                    "or p to move on, or u to take the last point back")
        try:
            self._write_line([p.plant, p.leaf, p.row, p.col, *(f"{v:.3f}" for v in xyz),
                              "recorded", f"{time.time():.3f}", rec.station, rec.error.strip()])
        except OSError as exc:
            raise SessionError(f"{self.path}: cannot write ({exc.strerror or exc}); the last "
                               f"point was NOT recorded; {self.count.points} points are safe "
                               "on disk") from None
        self.history.append((p, tuple(xyz)))
        self._held[_key(p)] += 1
        self.count.points += 1
        self.count.leaves.add((p.plant, p.leaf))
        self.count.plants.add(p.plant)
        self._advance_after_point(p)
        return (f"recorded plant {p.plant} leaf {p.leaf} row {p.row} col {p.col}: "
                f"{xyz[0]:.2f} {xyz[1]:.2f} {xyz[2]:.2f} cm")

    def control(self, key: str) -> str:
        """Apply a technician's control (n, p, r, u, q); returns what happened.

        Raises
        ------
        SessionError
            The control could not be written; the session is where it was before.
        """
        key = key.strip().lower()
        if key not in CONTROLS:
            return (f"unknown control '{key[:20]}': n next leaf, p next plant, r end row, u undo, "
                    "s pause or resume, q quit")
        action = CONTROLS[key]
        p = self.pos
        if action == "quit":
            return "quit"
        if action == "undo":
            if not self.history:
                return "nothing to undo"
            last, xyz = self.history[-1]
            self._write_control([last.plant, last.leaf, last.row, last.col,
                                 *(f"{v:.3f}" for v in xyz), "undone", f"{time.time():.3f}",
                                 "", ""], "the undo")
            self.history.pop()
            self._held[_key(last)] -= 1
            self.count.points -= 1
            self.count.undone += 1
            self.pos = Position(last.plant, last.leaf, last.row, last.col)
            return (f"undone: plant {last.plant} leaf {last.leaf} row {last.row} col {last.col}; "
                    "press again there")
        if action == "end_row":
            if p.col == 0:
                return f"row {p.row} is empty; nothing to end"
            q = Position(p.plant, p.leaf, p.row + 1, 0)
        elif action == "next_leaf":
            q = Position(p.plant, p.leaf + 1, 0, 0)
        else:
            q = Position(p.plant + 1, 1, 0, 0)
        self._write_control([q.plant, q.leaf, q.row, q.col, "", "", "", action,
                             f"{time.time():.3f}", "", ""], f"'{action.replace('_', ' ')}'")
        self.pos = q
        return f"{action.replace('_', ' ')}: next point is plant {q.plant} leaf {q.leaf} row {q.row}"

    def _write_control(self, values, what: str) -> None:
        try:
            self._write_line(values)
        except OSError as exc:
            raise SessionError(f"{self.path}: cannot write ({exc.strerror or exc}); {what} was "
                               f"NOT recorded; {self.count.points} points are safe on disk") from None

    def summary(self) -> str:
        c = self.count
        leaves = f"{len(c.leaves)} {'leaf' if len(c.leaves) == 1 else 'leaves'}"
        return (f"{_count(c.points, 'point')}, {leaves}, {_count(len(c.plants), 'plant')} "
                f"recorded in {self.path}; {c.undone} undone, {c.refused} refused, "
                f"{c.garbled} garbled")

    def close(self) -> None:
        """Close the file and let go of the lock; safe to call twice."""
        fd, self.fd = self.fd, None
        if fd is not None:
            try:
                os.close(fd)
            except OSError:
                pass
        lock, self._lock = self._lock, None
        if lock is not None:
            release_lock(*lock)

    def discard_if_unused(self) -> bool:
        """Close the session; if it made the file and wrote nothing after the header (a
        Connect that failed), remove the file too, so no header-only file is left behind.
        Returns True when the file was removed."""
        removed = False
        if self.fd is not None and self._made and not self._wrote:
            try:                                # while the lock is still held
                os.unlink(self.path)
                removed = True
            except OSError:
                pass
        self.close()
        return removed

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()
