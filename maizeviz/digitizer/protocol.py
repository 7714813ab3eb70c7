"""Polhemus FASTRAK serial protocol, pure: commands to bytes, bytes to records (docs/fastrak.md).

Nothing here touches a port. :class:`RecordParser` is fed raw bytes as they arrive and
returns events: :class:`Record` (type-0 data), :class:`Status`, :class:`ErrorReply`,
:class:`Reply` (other type-2 replies) and :class:`Garbled` (bytes that make no record, counted
and reported, never raised).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

# ------------------------------------------------------------------------------- commands
STOP_CONTINUOUS = b"c"
START_CONTINUOUS = b"C"
POLL = b"P"
ASCII = b"F"
BINARY = b"f"
INCHES = b"U"
CENTIMETRES = b"u"
STATUS = b"S"
REINIT = b"\x19"

#: Output-list items the parser knows: item -> (ASCII characters, binary bytes, values).
ITEMS = {
    0: (1, 1, 0),      # space
    1: (2, 2, 0),      # CR LF
    2: (21, 12, 3),    # x, y, z: three Sxxx.xx
    4: (21, 12, 3),    # azimuth, elevation, roll: three Sxxx.xx
    5: (21, 12, 3),    # x direction cosines: three Sx.xxxx
    6: (21, 12, 3),
    7: (21, 12, 3),
    11: (28, 16, 4),   # quaternion: four Sx.xxxx
    16: (2, 2, 0),     # stylus switch: blank + '0'/'1'
    52: (36, 12, 3),   # extended-precision x, y, z: three Sx.xxxxxESxxb
    54: (36, 12, 3),   # extended-precision Euler angles
}
DEFAULT_ITEMS = (2, 4, 1)
STYLUS_ITEMS = (2, 4, 16, 1)
TRUST_ERRORS = {"x": "receiver out of the motion box", "y": "angles outside the angular envelope"}


def output_list(station: int, items) -> bytes:
    """``O<st>,i1,i2,...<CR>``."""
    return f"O{station},{','.join(str(i) for i in items)}\r".encode("ascii")


def station_enable(station: int, on: bool = True) -> bytes:
    return f"l{station},{int(on)}\r".encode("ascii")


def stylus_mode(station: int = 1, point_mode: bool = True) -> bytes:
    """``e<st>,1`` makes a press act like P (point mode); ``e<st>,0`` mouse mode."""
    return f"e{station},{int(point_mode)}\r".encode("ascii")


def set_baud(baud: int) -> bytes:
    return f"o{baud // 100},N,8,0\r".encode("ascii")


# ---------------------------------------------------------------------------------- events
@dataclass(frozen=True)
class Record:
    """One data record.

    Attributes
    ----------
    station : int (1..4)
    error : str, a space when all is well, else the built-in-test letter
    position : (3,) tuple of float or None, in the unit the device is set to
    angles : (3,) tuple of float or None, degrees (azimuth, elevation, roll)
    stylus : int or None (0 up, 1 pressed)
    values : dict item -> tuple of float, every item read
    """

    station: int
    error: str
    position: tuple[float, float, float] | None
    angles: tuple[float, float, float] | None
    stylus: int | None
    values: dict = field(default_factory=dict)

    @property
    def trustworthy(self) -> bool:
        return self.error not in TRUST_ERRORS


@dataclass(frozen=True)
class Status:
    """A status record (reply to ``S``)."""

    station: int
    flags: int
    binary: bool
    centimetres: bool
    continuous: bool
    raw: bytes


@dataclass(frozen=True)
class ErrorReply:
    """The device refused a command: code -1 missing field, -2 non-numeric, -3 out of range,
    -4 frequency not configured, -5 buffer overflow, -99 unknown."""

    command: str
    code: int
    raw: bytes


@dataclass(frozen=True)
class Reply:
    """Any other type-2 reply (output list, station state, ...)."""

    station: int
    command: str
    text: str


@dataclass(frozen=True)
class Garbled:
    """Bytes that make no record; ``reason`` says why."""

    data: bytes
    reason: str


def _field(text: str) -> float:
    """A fixed-width numeric field; the sign may sit anywhere before the digits."""
    t = text.replace(" ", "")
    if t.endswith("b"):
        t = t[:-1]
    return float(t)


def ascii_length(items) -> int:
    return 3 + sum(ITEMS[i][0] for i in items)


def binary_length(items) -> int:
    return 3 + sum(ITEMS[i][1] for i in items)


def _parse_record(data: bytes, items, binary: bool) -> Record:
    """Walk the output list over one record; only how a value is decoded differs by format."""
    expected = binary_length(items) if binary else ascii_length(items)
    if len(data) != expected:
        raise ValueError(f"{len(data)} bytes, expected {expected}")
    if not binary:
        data.decode("ascii")                              # text records are ASCII throughout
    pos = 3
    values, stylus = {}, None
    for item in items:
        ascii_width, binary_size, count = ITEMS[item]
        size = binary_size if binary else ascii_width
        chunk = data[pos:pos + size]
        pos += size
        if item == 16:
            c = chunk.strip()[-1:]
            if c not in (b"0", b"1"):
                raise ValueError(f"stylus field {chunk!r}")
            stylus = int(c)
        elif item == 1:
            if chunk != b"\r\n":
                raise ValueError("no CR LF where item 1 ends the record")
        elif count and binary:
            values[item] = struct.unpack(f"<{count}f", chunk)
        elif count:
            step = size // count
            values[item] = tuple(_field(chunk[k * step:(k + 1) * step].decode("ascii"))
                                 for k in range(count))
    return Record(data[1] - 0x30, chr(data[2]), values.get(2) or values.get(52),
                  values.get(4) or values.get(54), stylus, values)


def parse_ascii_record(line: bytes, items) -> Record:
    """A type-0 ASCII record (with its CR LF) under output list ``items``.

    Raises
    ------
    ValueError
        When the length or a field does not fit.
    """
    return _parse_record(line, items, binary=False)


def parse_binary_record(data: bytes, items) -> Record:
    """A type-0 binary record: header, little-endian float32 per value, raw CR LF / stylus."""
    return _parse_record(data, items, binary=True)


def parse_reply(line: bytes):
    """A type-2 line (with CR LF) -> Status, ErrorReply or Reply."""
    text = line.decode("ascii", errors="replace").rstrip("\r\n")
    if "*ERROR*" in text:
        code = -99
        if "EC" in text:
            try:
                code = int(text.split("EC", 1)[1].split("*", 1)[0])
            except ValueError:
                pass
        cmd = text.split("*ERROR*")[1] if text.count("*ERROR*") >= 2 else ""
        return ErrorReply(cmd, code, line)
    station = int(text[1]) if len(text) > 1 and text[1].isdigit() else 0
    cmd = text[2] if len(text) > 2 else ""
    if cmd == "S" and len(text) >= 6:
        flags = int(text[3:6], 16)
        return Status(station, flags, bool(flags & 1), bool(flags & 2), bool(flags & 8), line)
    return Reply(station, cmd, text[3:])


class RecordParser:
    """Incremental parser of the device's output stream.

    Parameters
    ----------
    items : {station: output list}; stations not listed use :data:`DEFAULT_ITEMS`.
    binary : bool, the device sends binary data records.

    ``feed(bytes)`` returns the events completed by those bytes; a partial record waits for
    the next call. Garbled input is skipped up to the next line end and reported once.
    """

    def __init__(self, items: dict | None = None, binary: bool = False):
        self.items = dict(items or {})
        self.binary = binary
        self.buffer = bytearray()
        self.garbled = 0

    def items_for(self, station: int):
        return self.items.get(station, DEFAULT_ITEMS)

    def feed(self, data: bytes) -> list:
        self.buffer += data
        out = []
        while self.buffer:
            event, used = self._next()
            if used == 0:
                break
            del self.buffer[:used]
            if event is not None:
                if isinstance(event, Garbled):
                    self.garbled += 1
                out.append(event)
        return out

    def _skip_to_line_end(self, reason):
        end = self.buffer.find(b"\r\n")
        if end < 0:
            if len(self.buffer) > 4096:                  # noise with no line end at all
                return Garbled(bytes(self.buffer), reason), len(self.buffer)
            return None, 0
        return Garbled(bytes(self.buffer[:end + 2]), reason), end + 2

    def _next(self):
        buf = self.buffer
        start = buf[:1]
        if start == b"0":
            if len(buf) < 3:
                return None, 0
            if not (0x31 <= buf[1] <= 0x34):
                return self._skip_to_line_end("bad station byte")
            items = self.items_for(buf[1] - 0x30)
            n = binary_length(items) if self.binary else ascii_length(items)
            if len(buf) < n:
                # a truncated record shows as a line end before the expected length (ASCII)
                if not self.binary:
                    end = buf.find(b"\r\n")
                    if 0 <= end < n - 2:
                        return Garbled(bytes(buf[:end + 2]), "truncated record"), end + 2
                return None, 0
            chunk = bytes(buf[:n])
            try:
                rec = (parse_binary_record if self.binary else parse_ascii_record)(chunk, items)
            except (ValueError, UnicodeDecodeError, struct.error) as exc:
                event, used = self._skip_to_line_end(f"unreadable record ({exc})")
                return (event, used) if used else (Garbled(chunk, str(exc)), n)
            return rec, n
        if start == b"2":
            end = buf.find(b"\r\n")
            if end < 0:
                return (None, 0) if len(buf) < 4096 else (Garbled(bytes(buf), "reply too long"), len(buf))
            try:
                return parse_reply(bytes(buf[:end + 2])), end + 2
            except (ValueError, IndexError) as exc:
                return Garbled(bytes(buf[:end + 2]), f"unreadable reply ({exc})"), end + 2
        if start in (b"\r", b"\n"):
            return None, 1                                   # stray line ends between records
        # anything else: garbage up to the next plausible record start or line end
        nxt = [i for i in (buf.find(b"\r\n"), buf.find(b"\r\n0", 0)) if i >= 0]
        if not nxt:
            if len(buf) > 4096:
                return Garbled(bytes(buf), "noise"), len(buf)
            return None, 0
        cut = min(nxt) + 2
        return Garbled(bytes(buf[:cut]), "noise"), cut
