"""Read and write the digitized points format.

CSV with a header; required columns ``plant,leaf,row,col,x,y,z`` (any order, any case), other
columns are kept as text in :attr:`PointsTable.extra`. ``x, y, z`` are centimetres, z up.

A ``status`` column (written by ``maizeviz record``) is honoured: ``undone`` lines take back the
latest recording of that point, control lines (``next_leaf``, ``next_plant``, ``end_row``)
carry no point, and a ``discarded`` line takes back the line just above it: a line the
recorder was cut off while writing (a crash, a full disk), terminated when the recording was
resumed. In a recording (the header is exactly :data:`JOURNAL_COLUMNS`) a last line without
its line end is such a cut-off line too, skipped with a note and never read as a point, and
every line must have all its fields: two lines run together, or a line cut short, are
skipped with a note.

A row whose ids cannot be read is reported and skipped; a row whose coordinates cannot be read
marks its leaf as bad (the leaf is refused later with the line number), so one bad press never
takes the other leaves down with it.

Reading streams: the file is read line by line into compact arrays (64 bytes for each point
kept), so memory follows the points kept, not the size of the file. Limits (each message says
which was reached and why it is there; pass a larger value to lift it):

- :data:`MAX_LINE_BYTES` bytes in a line (a points line is under 100 bytes);
- :data:`MAX_POINTS` points and :data:`MAX_LINES` lines in a file;
- ids within :data:`MAX_ID` and row / col within :data:`MAX_INDEX`.
"""

from __future__ import annotations

import csv
import io
import math
import warnings
from array import array
from pathlib import Path

import numpy as np

from maizeviz.errors import PointsFileError
from maizeviz.io.atomic import atomic_open
from maizeviz.io.inputs import open_input
from maizeviz.io.points_table import (  # noqa: F401 - shared names, read from here too
    MAX_ID,
    MAX_INDEX,
    MAX_LINES,
    MAX_POINTS,
    PARQUET_SUFFIXES,
    REQUIRED,
    PointsTable,
    is_parquet_name,
    shown,
)
from maizeviz.numbers import number, whole

ID_COLUMNS = ("plant", "leaf", "row", "col")
#: The header ``maizeviz record`` writes; a file with exactly this header is a recording.
JOURNAL_COLUMNS = ("plant", "leaf", "row", "col", "x", "y", "z", "status", "time", "station",
                   "error")
#: Status of a point line, of an undo, of the controls, and of the mark that takes back a
#: cut-off line.
RECORDED, UNDONE, DISCARDED = "recorded", "undone", "discarded"
CONTROL_STATUSES = ("next_leaf", "next_plant", "end_row")
#: Statuses of a point line, in a recording as in any file with a status column (docs/cli.md).
POINT_STATUSES = ("", RECORDED, "ok")

#: Longest line read (bytes). A points line is under 100 bytes; 10,000 leaves room for long
#: extra columns and stops a file without line ends (binary data, one huge field) early.
MAX_LINE_BYTES = 10_000
#: Problem lines and bad-leaf messages kept for the report; the rest are counted.
MAX_MESSAGES = 1000
#: Leaves with unreadable lines before the file is taken for something else.
MAX_BAD_LEAVES = 100_000
_BINARY_SNIFF = 4096
#: Bytes read at a time; blocks of plain numeric lines are parsed by numpy in one go.
BLOCK_BYTES = 1 << 20
#: Files at least this large read their numeric blocks through pyarrow (whose import costs
#: about what numpy takes to parse 4 MB).
COLUMNAR_BYTES = 4 << 20
#: What a block of plain numeric lines may hold, besides its delimiter.
_NUMERIC = b"0123456789+-.eE \r\n"



class _BadValue(ValueError):
    """A field that is a number but out of range; ``str`` says why."""


def _parse_int(text: str) -> int:
    """A whole number written as ``3``, ``3.0`` or `` 3 ``; ValueError otherwise (``1_000``
    too: :mod:`maizeviz.numbers`)."""
    try:
        return whole(text)
    except ValueError:
        pass
    value = number(text)
    if not math.isfinite(value) or value != int(value):
        raise ValueError
    return int(value)


def _parse_id(text: str, what: str, limit: int, low: int) -> int:
    """A whole number within ``low..limit``; :class:`_BadValue` names ``what`` and the range."""
    value = _parse_int(text)
    if not low <= value <= limit:
        raise _BadValue(f"{what} {shown(text)} is beyond the range {low:,}..{limit:,}")
    return value


# ----------------------------------------------------------------------------- opening
def open_regular(path: Path, error=PointsFileError, what: str = "points file"):
    """Open ``path`` for reading in binary, refusing anything but a regular file (see
    :func:`maizeviz.io.inputs.open_input`). Returns ``(binary file, size in bytes)``."""
    return open_input(path, what, error)


def _looks_binary(head: bytes) -> bool:
    """NUL bytes, or many control characters, in the first bytes of a file."""
    if b"\x00" in head:
        return True
    controls = sum(head.count(bytes([c])) for c in range(32) if c not in (9, 10, 12, 13))
    return controls > len(head) // 10


def refuse_binary(fh, source: str, size: int | None = None) -> None:
    """Raise :class:`PointsFileError` when the first bytes of a binary file (opened by
    :func:`open_regular`), of its first ``size`` bytes if given, are not text; reads nothing
    away."""
    head = fh.peek(_BINARY_SNIFF)[:_BINARY_SNIFF if size is None else min(size, _BINARY_SNIFF)]
    if _looks_binary(head):
        raise PointsFileError(f"{source}: not a CSV text file (binary content)")


def zero_tail(fh, size: int) -> int:
    """How many NUL bytes end the file (``size`` bytes long, opened by :func:`open_regular`);
    the file is left at its start.

    A power cut while a file grows can leave its new length on disk without its data: the
    file then ends in zero bytes, its lines before them intact. Readers read up to the zeros
    and say how many bytes they leave; the recorder removes them before it appends.
    """
    n, pos = 0, size
    while pos > 0:
        k = min(1 << 16, pos)
        fh.seek(pos - k)
        block = fh.read(k)
        kept = block.rstrip(b"\x00")
        n += len(block) - len(kept)
        if kept or len(block) < k:
            break
        pos -= k
    fh.seek(0)
    return n


def zero_tail_note(zeros: int) -> str:
    """The note a reader gives for a file ending in ``zeros`` NUL bytes."""
    return (f"the file ends in {zeros:,} zero bytes (as a power cut leaves a file being "
            "written): read up to them, the lines before them are kept")


def check_not_only_zeros(source: str, size: int, zeros: int) -> None:
    """A file of nothing but zero bytes is no text file at all."""
    if size and zeros == size:
        raise PointsFileError(f"{source}: not a CSV text file (only zero bytes)")


def _decode(raw: bytes) -> str:
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")              # decodes every byte


def file_blocks(fh, max_line: int = MAX_LINE_BYTES, size: int | None = None,
                limit: int | None = None):
    """Blocks of whole lines of a binary file, about ``size`` bytes each, from its first
    ``limit`` bytes (all of it when None).

    A block ends with a line end, or with the file (or its limit), or with a line longer than
    ``max_line`` (whose first ``max_line + 1`` bytes the block holds: the line checks refuse
    it).
    """
    size = size or BLOCK_BYTES
    left = -1 if limit is None else limit
    while left:
        block = fh.read(size if left < 0 else min(size, left))
        if not block:
            return
        if not block.endswith(b"\n"):
            more = max_line + 1 if left < 0 else min(max_line + 1, left - len(block))
            if more:
                block += fh.readline(more)
        if left > 0:
            left -= len(block)
        yield block


def raw_line_text(raw: bytes, lineno: int, source: str, max_line: int = MAX_LINE_BYTES) -> str:
    """The text of one physical line (its line end kept), refusing over-long or binary lines."""
    body = len(raw) - 1 if raw.endswith(b"\n") else len(raw)
    if body > max_line:
        raise PointsFileError(
            f"{source}: line {lineno} is longer than {max_line:,} bytes; not a readable "
            "CSV file of points (a points line is under 100 bytes)")
    if b"\x00" in raw:
        raise PointsFileError(f"{source}: line {lineno}: binary content (a NUL byte); not "
                              "a CSV text file")
    if lineno == 1 and raw.startswith(b"\xef\xbb\xbf"):
        raw = raw[3:]
    return _decode(raw)


def file_lines(fh, source: str, max_line: int = MAX_LINE_BYTES, limit: int | None = None):
    """(text, terminated) for each physical line of a binary file (of its first ``limit``
    bytes), bounded in length."""
    lineno = 0
    for block in file_blocks(fh, max_line, limit=limit):
        for raw in io.BytesIO(block):
            lineno += 1
            yield raw_line_text(raw, lineno, source, max_line), raw.endswith(b"\n")


def _text_lines(text: str, source: str, max_line: int):
    """(text, terminated) for each line of a string, split at LF only as the file reader does."""
    for lineno, line in enumerate(io.StringIO(text), start=1):
        if len(line) - line.endswith("\n") > max_line:
            raise PointsFileError(
                f"{source}: line {lineno} is longer than {max_line:,} characters; not a "
                "readable CSV file of points (a points line is under 100 bytes)")
        if "\x00" in line:
            raise PointsFileError(f"{source}: line {lineno}: binary content (a NUL byte); not "
                                  "a CSV text file")
        yield line, line.endswith("\n")


# ----------------------------------------------------------------------------- parsing
class LineParser:
    """Turns physical lines into compact arrays; one instance reads one file.

    :meth:`feed` classifies each line into an outcome, ``(kind, payload, line number)`` with
    kind ``point``, ``problem``, ``bad`` (a leaf with an unreadable line), ``undo`` or
    ``control``, and :meth:`commit` applies it. Lines of files with a ``status`` column are
    committed one line late, so that a ``discarded`` mark can take back the line just above it
    (the recorder's resume subclasses this to replay a recording with the same rules).
    """

    def __init__(self, source: str, max_points: int, max_lines: int):
        self.source = source
        self.max_points = max_points
        self.max_lines = max_lines
        self.header: list[str] | None = None
        self.header_line = 0
        self.delimiter = ","
        self.ids = array("q")
        self.xyz = array("d")
        self.lines = array("q")
        self.extra: dict[str, list] = {}
        self.problems: list[str] = []
        self.dropped = 0                          # problem lines not kept in ``problems``
        self.bad_leaves: dict = {}
        self.undone: list = []                    # (ids, points before it)
        self.pending: tuple | None = None         # (kind, payload, lineno) not yet committed
        self.data_lines = 0
        self.carry = ""                           # a quoted field running over line ends
        self.carry_start = 0
        self.torn: tuple[int, str] | None = None  # (line number, text) of a cut-off last line
        self.journal = False
        self.columnar = False                     # blocks through pyarrow (_numbers)

    # ------------------------------------------------------------------ header
    def _set_header(self, lineno: int, text: str) -> None:
        first = text.strip()
        if "," not in first:
            self.delimiter = ";" if ";" in first else ("\t" if "\t" in first else ",")
        fields = self._split(text)
        names = [f.strip() for f in fields]
        header = [n.lower() for n in names]
        missing = [c for c in REQUIRED if c not in header]
        if missing:
            found = shown(",".join(header), 80)
            raise PointsFileError(
                f"{self.source}: line {lineno}: missing column(s) {', '.join(missing)}; "
                f"a points file needs the header plant,leaf,row,col,x,y,z (found '{found}')")
        named = [h for h in header if h]
        if len(set(named)) != len(named):     # one of them would be lost
            twice = sorted({h for h in named if named.count(h) > 1})
            raise PointsFileError(f"{self.source}: line {lineno}: columns named alike "
                                  f"('{shown(','.join(twice), 80)}'; names are read without "
                                  "case): rename one")
        self.header = header
        self.header_line = lineno
        self.index = [header.index(name) for name in REQUIRED]
        # extra columns by their own name (its case kept), their cells kept exactly
        self.extra_index = {names[k]: k for k, h in enumerate(header)
                            if h and h not in REQUIRED}
        self.extra = {h: [] for h in self.extra_index}
        self.status_col = header.index("status") if "status" in header else None
        self.journal = tuple(header) == JOURNAL_COLUMNS

    def _split(self, text: str) -> list[str]:
        text = text.rstrip("\r\n")
        if '"' not in text:
            if "\r" in text:
                raise PointsFileError(f"{self.source}: not a readable CSV file (a carriage "
                                      "return inside a line: old Mac line ends?)")
            return text.split(self.delimiter)
        try:
            return next(csv.reader(io.StringIO(text, newline=""), delimiter=self.delimiter),
                        [])
        except csv.Error as exc:
            raise PointsFileError(f"{self.source}: not a readable CSV file ({exc})") from None

    # ------------------------------------------------------------------ lines
    def feed(self, lineno: int, text: str, terminated: bool) -> None:
        if lineno > self.max_lines:
            raise PointsFileError(
                f"{self.source}: more than {self.max_lines:,} lines; reading more would take "
                "many minutes (split the file by plant)")
        # a quoted field may run over line ends, except in a recording: the recorder never
        # writes one, and a torn line's open quote must not swallow the lines after it
        if self.carry or (text.count('"') % 2 and terminated and not self.journal):
            joined = self._carried(lineno, text, terminated)
            if joined is None:
                return                              # the quoted field goes on
            lineno, text = joined
        if not terminated:
            self.torn = (lineno, text)
        if self.header is None:
            if text.strip() and any(f.strip() for f in self._split(text)):
                self._set_header(lineno, text)
            return
        if not text.strip():
            return
        fields = self._split(text)
        if not any(f.strip() for f in fields):
            return
        self.data_lines += 1
        if self.status_col is None:
            self.commit(self._outcome(lineno, fields))
            return
        if not terminated and self.journal:
            if self.journal and not any(f.strip() for f in fields[:len(REQUIRED)]):
                self._discard(lineno)                # a repair cut short after its line end
                return
            self._settle(("torn", f"line {lineno}: cut short (no line end): the recorder "
                          "was stopped while writing it, so it was never recorded; skipped",
                          lineno))
            return
        outcome = self._outcome(lineno, fields)
        if outcome[0] == "discard":
            self._discard(lineno)
        elif outcome[0] == "unfinished":
            self._note(outcome[1])                  # a repair mark cut short: wait for the next
        else:
            self._settle(outcome)

    def _carried(self, lineno: int, text: str, terminated: bool) -> tuple[int, str] | None:
        """Add a line to a quoted field running over line ends: the whole record (its first
        line's number and text) once the field closes, else None."""
        if not self.carry:
            self.carry_start = lineno
        self.carry += text
        if len(self.carry) > MAX_LINE_BYTES:
            raise PointsFileError(
                f"{self.source}: line {self.carry_start}: a quoted field runs over more "
                f"than {MAX_LINE_BYTES:,} bytes; not a readable CSV file of points")
        if self.carry.count('"') % 2 and terminated:
            return None
        joined = (self.carry_start, self.carry)
        self.carry = ""
        return joined

    def _settle(self, outcome) -> None:
        """Commit the line before, then hold this one until the next line is seen."""
        if self.pending is not None:
            self.commit(self.pending)
        self.pending = outcome

    def _discard(self, lineno: int) -> None:
        if self.pending is None:
            return
        _, _, was = self.pending
        self.pending = None
        self._note(f"line {was}: cut short by a crash or a full disk and marked not recorded "
                   f"when the recording was resumed (line {lineno}); skipped")

    def _outcome(self, lineno: int, fields: list[str]):
        """What one data line means: ("point", ...), ("problem", text), ("bad", ...), ..."""
        header = self.header
        assert header is not None                     # data lines come after the header
        if self.journal and not any(f.strip() for f in fields[:len(REQUIRED)]):
            col = self.status_col
            status = fields[col].strip().lower() if col is not None and \
                len(fields) == len(header) else ""
            if status == DISCARDED:
                return ("discard", None, lineno)
            return ("unfinished", f"line {lineno}: an unfinished mark ('{text_of(fields)}'); "
                    "skipped", lineno)
        if len(fields) != len(header) and self.journal:
            return ("problem", f"line {lineno}: {len(fields)} fields where a recording line has "
                    f"{len(header)} (a line cut short, or two lines run together); skipped",
                    lineno)
        if len(fields) < len(header):
            fields = fields + [""] * (len(header) - len(fields))
        if self.status_col is not None:
            status = fields[self.status_col].strip().lower()
            if status == DISCARDED:
                return ("discard", None, lineno)
            if status == UNDONE:
                _, key = self._control(lineno, fields, status)[1]
                if key is None:
                    return ("problem", f"line {lineno}: unreadable undo line; skipped", lineno)
                return ("undo", key, lineno)
            if self.journal and status not in POINT_STATUSES:
                if status in CONTROL_STATUSES:
                    return self._control(lineno, fields, status)
                return ("problem", f"line {lineno}: unknown status '{shown(status, 20)}'; skipped",
                        lineno)
            if status not in POINT_STATUSES:
                return self._control(lineno, fields, status)   # controls carry no point
        return self._point(lineno, fields)

    def _control(self, lineno: int, fields: list[str], status: str):
        """A control line: the position it leads to (None when unreadable)."""
        try:
            key = tuple(_parse_id(fields[self.index[k]], ID_COLUMNS[k],
                                  MAX_ID if k < 2 else MAX_INDEX, -MAX_ID if k < 2 else 0)
                        for k in range(4))
        except (ValueError, OverflowError):
            key = None
        return ("control", (status, key), lineno)

    def _point(self, lineno: int, fields: list[str]):
        p, lf, r, c, x, y, z = (fields[i] for i in self.index)
        try:
            plant = _parse_id(p, "plant id", MAX_ID, -MAX_ID)
            leaf = _parse_id(lf, "leaf id", MAX_ID, -MAX_ID)
        except _BadValue as exc:
            return ("problem", f"line {lineno}: {exc}; line skipped", lineno)
        except (ValueError, OverflowError):
            return ("problem", f"line {lineno}: plant/leaf id is not an integer "
                    f"('{shown(p)}', '{shown(lf)}'); line skipped", lineno)
        try:
            row = _parse_int(r)
            col = _parse_int(c)
        except (ValueError, OverflowError):
            return ("bad", ((plant, leaf), f"line {lineno}: row/col is not a whole number "
                    f"('{shown(r)}', '{shown(c)}')"), lineno)
        if row < 0 or col < 0:
            return ("bad", ((plant, leaf), f"line {lineno}: row {shown(r)}, col "
                    f"{shown(c)}: negative index"), lineno)
        if row > MAX_INDEX or col > MAX_INDEX:
            return ("bad", ((plant, leaf), f"line {lineno}: row {shown(r)}, col "
                    f"{shown(c)}: beyond {MAX_INDEX:,}, the largest cross-section "
                    "index"), lineno)
        coords = []
        for axis, value in zip("xyz", (x, y, z)):
            try:
                coords.append(number(value))
            except ValueError:
                return ("bad", ((plant, leaf), f"row {row}, col {col} (line {lineno}): {axis} is "
                        f"not a number ('{shown(value)}')"), lineno)
        extras = [fields[i] for i in self.extra_index.values()]
        return ("point", (plant, leaf, row, col, coords, extras), lineno)

    def _note(self, text: str) -> None:
        if len(self.problems) < MAX_MESSAGES:
            self.problems.append(text)
        else:
            self.dropped += 1

    def commit(self, outcome) -> None:
        kind = outcome[0]
        if kind == "point":
            plant, leaf, row, col, coords, extras = outcome[1]
            if self.points >= self.max_points:
                raise PointsFileError(
                    f"{self.source}: line {outcome[2]}: more than {self.max_points:,} points; "
                    "that many would take over "
                    f"{self.max_points * 64 / 1e9:.1f} GB of memory (split the file by plant)")
            self.ids.extend((plant, leaf, row, col))
            self.xyz.extend(coords)
            self.lines.append(outcome[2])
            for h, v in zip(self.extra, extras):
                self.extra[h].append(v)
        elif kind in ("problem", "torn"):
            self._note(outcome[1])
        elif kind == "bad":
            key, message = outcome[1]
            msgs = self.bad_leaves.get(key)
            if msgs is None:
                if len(self.bad_leaves) >= MAX_BAD_LEAVES:
                    raise PointsFileError(
                        f"{self.source}: more than {MAX_BAD_LEAVES:,} leaves with unreadable "
                        "lines; this does not look like a points file")
                msgs = self.bad_leaves[key] = []
            if len(msgs) < 5:
                msgs.append(message)
            elif len(msgs) == 5:
                msgs.append("more lines like these")
        elif kind == "undo":
            self.undone.append((outcome[1], self.points))

    # ------------------------------------------------------------------ blocks
    def feed_block(self, block: bytes, lineno: int) -> int:
        """Feed a block of whole lines that follows line ``lineno``; returns the last line
        number. Plain numeric lines go through :meth:`_fast`, the rest line by line."""
        pos = 0
        while pos < len(block):
            if self._fast_ok():
                rest = block[pos:] if pos else block
                done = self._fast(rest, lineno)
                if done:
                    return lineno + done
                for raw in io.BytesIO(rest):
                    lineno += 1
                    self.feed(lineno, raw_line_text(raw, lineno, self.source), raw.endswith(b"\n"))
                return lineno
            end = block.find(b"\n", pos)
            end = len(block) if end < 0 else end + 1
            lineno += 1
            raw = block[pos:end]
            self.feed(lineno, raw_line_text(raw, lineno, self.source), raw.endswith(b"\n"))
            pos = end
        return lineno

    def _fast_ok(self) -> bool:
        return (self.header is not None and self.status_col is None and not self.extra_index
                and len(self.header) == len(REQUIRED) and not self.carry)

    def _fast(self, block: bytes, lineno: int) -> int:
        """Parse a block of plain numeric lines with numpy; returns the lines taken (0: the
        block is not plain, read it line by line)."""
        delim = self.delimiter.encode()
        if block.translate(None, _NUMERIC + delim) or \
                (b"\r" in block and block.count(b"\r") != block.count(b"\r\n")):
            return 0                                   # quotes, words, nan, blanks in lines...
        ends = np.flatnonzero(np.frombuffer(block, np.uint8) == 10)
        n = len(ends) + (0 if block.endswith(b"\n") else 1)
        lengths = np.diff(np.concatenate([[-1], ends, [len(block) - 1]]))[:n]
        if not n or lengths.max() > MAX_LINE_BYTES + 1 or lineno + n > self.max_lines:
            return 0                                   # the line-by-line checks say why
        values = _numbers(block, self.delimiter, len(REQUIRED), self.columnar)
        if values is None or len(values[0]) != n or \
                not all(np.isfinite(c).all() for c in values):
            return 0
        limits = ((MAX_ID, -MAX_ID), (MAX_ID, -MAX_ID), (MAX_INDEX, 0), (MAX_INDEX, 0))
        for k, (high, low) in zip(self.index[:4], limits):
            c = values[k]
            if not (np.all(c == np.floor(c)) and c.max() <= high and c.min() >= low):
                return 0
        ids = np.column_stack([values[k] for k in self.index[:4]]).astype(np.int64)
        xyz = np.column_stack([values[k] for k in self.index[4:]])
        if self.points + n > self.max_points:
            return 0
        # appended in place (an array grows by a share of its size: no copy of the whole)
        self.ids.frombytes(_bytes_of(np.ascontiguousarray(ids, dtype=np.int64)))
        self.xyz.frombytes(_bytes_of(np.ascontiguousarray(xyz)))
        self.lines.frombytes(_bytes_of(np.arange(lineno + 1, lineno + n + 1, dtype=np.int64)))
        self.data_lines += n
        if not block.endswith(b"\n"):
            self.torn = (lineno + n, "")
        return n

    @property
    def points(self) -> int:
        """Points kept so far."""
        return len(self.lines)

    # ------------------------------------------------------------------ result
    def finish(self) -> PointsTable:
        if self.carry:                               # an unclosed quote at the end of the file
            text, self.carry = self.carry, ""
            self.feed(self.carry_start, text, False)
        if self.pending is not None:
            self.commit(self.pending)
            self.pending = None
        if self.header is None:
            raise PointsFileError(f"{self.source}: the file is empty")
        if self.dropped:
            self.problems.append(f"... and {self.dropped:,} more lines skipped")
        n = len(self.lines)
        ids = np.frombuffer(self.ids, dtype=np.int64).reshape(-1, 4) if n else \
            np.empty((0, 4), np.int64)
        xyz = np.frombuffer(self.xyz, dtype=np.float64).reshape(-1, 3) if n else \
            np.empty((0, 3), np.float64)
        lines = np.frombuffer(self.lines, dtype=np.int64) if n else np.empty(0, np.int64)
        extra = self.extra
        if self.undone:
            keep = _undo_mask(ids, self.undone)
            ids, xyz, lines = ids[keep], xyz[keep], lines[keep]
            extra = {h: [v for v, k in zip(vals, keep) if k] for h, vals in extra.items()}
        if not len(lines) and not self.bad_leaves:
            if self.problems:
                raise PointsFileError(f"{self.source}: no readable point; first problem: "
                                      f"{self.problems[0]}")
            if self.data_lines:
                raise PointsFileError(f"{self.source}: no point: every line is a control or "
                                      "an undone point")
            raise PointsFileError(f"{self.source}: header only, no points")
        return PointsTable(ids=ids, xyz=xyz, line=lines, extra=extra, problems=self.problems,
                           bad_leaves=self.bad_leaves, source=self.source)


def _bytes_of(a: np.ndarray) -> memoryview:
    """The bytes of a C-contiguous array, without a copy."""
    return a.data.cast("B")


def _numbers(block: bytes, delimiter: str, columns: int, columnar: bool
             ) -> list[np.ndarray] | None:
    """The numbers of a block of plain numeric lines, one (lines,) float64 array per column, or
    None where the block does not parse as such (a line with another number of fields, a
    field that is not a number); blank lines are left out (the caller counts lines and finds
    them missing).

    ``columnar``: through pyarrow's CSV reader (C++, on its own threads), which reads a number
    as Python's ``float`` does (both round correctly; both refuse ``1e``, ``.``, ``1.2.3``) and
    an empty field as NaN; otherwise (or without pyarrow) numpy's ``loadtxt``, about 15 times
    slower but without pyarrow's 0.3 s import.
    """
    try:
        if not columnar:
            raise ImportError
        import pyarrow as pa
        import pyarrow.csv as pacsv
    except ImportError:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                values = np.loadtxt(io.BytesIO(block), delimiter=delimiter, comments=None,
                                    dtype=np.float64, ndmin=2, encoding="latin-1")
        except (ValueError, Warning):
            return None
        if values.shape[1] != columns:
            return None
        return [values[:, k] for k in range(columns)]
    names = [str(i) for i in range(columns)]
    try:
        table = pacsv.read_csv(
            pa.py_buffer(block),
            read_options=pacsv.ReadOptions(column_names=names, block_size=1 << 18),
            parse_options=pacsv.ParseOptions(delimiter=delimiter, quote_char=False,
                                             double_quote=False),
            convert_options=pacsv.ConvertOptions(
                column_types=dict.fromkeys(names, pa.float64()), quoted_strings_can_be_null=False))
    except (pa.ArrowInvalid, pa.ArrowTypeError, ValueError):
        return None
    return [table.column(k).to_numpy(zero_copy_only=False) for k in range(columns)]


def text_of(fields: list[str], limit: int = 40) -> str:
    """A line's fields joined back, shortened for a message."""
    return shown(",".join(fields), limit)


def _undo_mask(ids: np.ndarray, undone: list) -> np.ndarray:
    """Points kept after each undo took back the latest recording of its point before it.

    ids : (N, 4) int64; undone : [((plant, leaf, row, col), points before the undo)].
    Returns (N,) bool.
    """
    keep = np.ones(len(ids), dtype=bool)
    for key, before in undone:
        hit = np.flatnonzero(keep[:before] & np.all(ids[:before] == key, axis=1))
        if len(hit):
            keep[hit[-1]] = False
    return keep


def _parse_stream(lines, source: str, max_points: int, max_lines: int) -> PointsTable:
    parser = LineParser(source, max_points, max_lines)
    for lineno, (text, terminated) in enumerate(lines, start=1):
        parser.feed(lineno, text, terminated)
    return parser.finish()


def read_points(path: str | Path, max_points: int = MAX_POINTS,
                max_lines: int = MAX_LINES) -> PointsTable:
    """Read a points CSV file, streaming (memory follows the points kept), or a Parquet
    points file (:mod:`maizeviz.io.parquet`: taken by its content, whatever its name).

    Blocks of plain numeric lines (no status or extra column, no quote, no blank line, every
    value a number and every id in range) are parsed by numpy in one go; any other block goes
    line by line, so every message is the one the line-by-line reading gives.

    Raises
    ------
    PointsFileError
        The file is missing, not a regular file (a FIFO, a device, a socket), empty, binary,
        has no header or lacks a required column, has a line over :data:`MAX_LINE_BYTES`,
        more than ``max_points`` points or ``max_lines`` lines, or not one line could be read.
    """
    path = Path(path)
    source = str(path)
    fh, size = open_regular(path)
    with fh:
        if fh.peek(4)[:4] == b"PAR1":
            return read_points_parquet(path, max_points, max_lines)
        try:
            zeros = zero_tail(fh, size)
            check_not_only_zeros(source, size, zeros)
            refuse_binary(fh, source, size - zeros)
            parser = LineParser(source, max_points, max_lines)
            parser.columnar = size >= COLUMNAR_BYTES
            lineno = 0
            for block in file_blocks(fh, limit=size - zeros):
                lineno = parser.feed_block(block, lineno)
            table = parser.finish()
            if zeros:
                table.problems.append(zero_tail_note(zeros))
            return table
        except OSError as exc:
            raise PointsFileError(f"{path}: cannot be read ({exc.strerror or exc})") from None


def read_points_parquet(path: str | Path, max_points: int = MAX_POINTS,
                        max_lines: int = MAX_LINES) -> PointsTable:
    """Read a Parquet points file (:mod:`maizeviz.io.parquet`): its plain records as they
    are, any other table through the CSV reader, so that its messages are the CSV's.

    Raises
    ------
    PointsFileError
        Not a readable Parquet file, a required column missing, more than ``max_points``
        records (or ``max_lines``), no readable point; and whatever the CSV reader refuses.
    """
    from maizeviz.io.parquet import read_parquet_table

    got = read_parquet_table(path, max_points, max_lines)
    if isinstance(got, PointsTable):
        return got
    return parse_points(got, str(path), max_points, max_lines)


def parse_points(text: str, source: str = "<memory>", max_points: int = MAX_POINTS,
                 max_lines: int = MAX_LINES) -> PointsTable:
    """Parse the text of a points CSV file; see :func:`read_points`."""
    text = text.removeprefix("\ufeff")
    if "\x00" in text[:_BINARY_SNIFF]:
        raise PointsFileError(f"{source}: not a CSV text file (binary content)")
    return _parse_stream(_text_lines(text, source, MAX_LINE_BYTES), source, max_points,
                         max_lines)


def write_points(path: str | Path, grids, decimals: int = 3) -> None:
    """Write point grids in the points format (one line per point, tip rows written once),
    atomically: CSV, or Parquet where ``path`` ends in ``.parquet`` or ``.pq``
    (:func:`maizeviz.io.parquet.write_points_parquet`, the same numbers).

    Parameters
    ----------
    grids : iterable of leaf grids (``plant``, ``leaf``, ``points`` (m, n, 3) cm,
        ``tip_collapsed``), e.g. :class:`maizeviz.leaf.grid.LeafGrid`
    """
    if is_parquet_name(path):
        from maizeviz.io.parquet import write_points_parquet

        write_points_parquet(path, grids, decimals)
        return
    with atomic_open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(REQUIRED)
        for g in grids:
            for r in range(g.points.shape[0]):
                row = g.points[r]
                if r == g.points.shape[0] - 1 and g.tip_collapsed:
                    row = row[:1]
                for c, p in enumerate(row):
                    writer.writerow([g.plant, g.leaf, r, c, *(f"{v:.{decimals}f}" for v in p)])
