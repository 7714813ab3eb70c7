"""A pretend FASTRAK on a pseudo-terminal: the device behind tests, demos and training.

The simulator owns the master side of a pty pair; a driver opens the slave path with pyserial
exactly as it would open ``/dev/ttyUSB0``, so the real POSIX serial code path (termios,
timeouts, ``read_until``) is exercised. It speaks the commands of docs/fastrak.md (``P c C F f U u
S O l e H N B b o ^Y W``), ASCII and binary records, inches (the default) and centimetres,
stations on and off, stylus presses in point and track modes (a press within 333 ms of the
previous one is ignored, as the unit does), status and error replies, and continuous output at
120 Hz divided among the active stations. Faults can be injected: garbled bytes, truncated
records, BIT error letters, a unit that stays silent, one that ignores the unit or format
commands, and a port that vanishes mid-session.
"""

from __future__ import annotations

import os
import select
import struct
import threading
import time
import tty
from dataclasses import dataclass

import numpy as np

from maizeviz.digitizer.geometry import euler_matrix
from maizeviz.digitizer.protocol import DEFAULT_ITEMS, ITEMS

CM_PER_INCH = 2.54
PRESS_GAP_S = 0.333
SINGLE = set("PCcFfUuSWBb\x19")
WITH_PARAMS = set("OleHNAoRQIVGx")


@dataclass
class Pose:
    """Position (cm) and Euler angles (deg) of a receiver."""

    position: np.ndarray
    angles: np.ndarray


class FastrakSimulator:
    """Simulated FASTRAK; ``path`` is the serial port to open.

    Parameters
    ----------
    stations : active stations at power-up (station 1 carries the stylus)
    noise_cm : RMS position noise added to every record (the unit's 0.08 cm)
    silent : never answer (a unit switched off, or the wrong port)
    ignore_units, ignore_format : keep inches / ASCII whatever the driver asks
    start_binary : power up in binary output
    garbage : answer every command with unreadable bytes (another device on the port, or a
        baud rate that differs from the unit's)
    answer_delay_s : seconds the unit takes to answer a poll (``P``), the commands after it
        waiting their turn as on the unit (a unit's side starved of CPU); presses are sent
        meanwhile
    """

    def __init__(self, stations=(1,), noise_cm: float = 0.08, seed: int = 0,
                 silent: bool = False, ignore_units: bool = False, ignore_format: bool = False,
                 start_binary: bool = False, press_gap_s: float = PRESS_GAP_S,
                 garbage: bool = False, answer_delay_s: float = 0.0):
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)
        self.rng = np.random.default_rng(seed)
        self.noise = noise_cm
        self.answer_delay = answer_delay_s
        self.silent = silent
        self.garbage = garbage
        self.ignore_units = ignore_units
        self.ignore_format = ignore_format
        self.binary = start_binary
        self.centimetres = False
        self.continuous = False
        self.active = set(stations)
        self.items = {s: tuple(DEFAULT_ITEMS) for s in range(1, 5)}
        self.point_mode = True
        self.stylus = np.zeros(3)               # stylus tip, world frame, cm
        self.reference = Pose(np.array([0.0, 0.0, 0.0]), np.zeros(3))
        self.error_letter = " "
        self.last_press = -1e9
        self.press_gap = press_gap_s
        self.streaming = True                   # continuous output not paused by the stylus
        self.stylus_down_until = -1.0
        self.records_sent = 0
        self.presses = 0
        self.commands: list[str] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="fastrak-sim", daemon=True)
        self._thread.start()

    # ---------------------------------------------------------------- the outside world
    def move_reference(self, position_cm, angles_deg) -> None:
        """Move the reference receiver (station 2, fixed to the stalk)."""
        self.reference = Pose(np.asarray(position_cm, float), np.asarray(angles_deg, float))

    def press(self, point_cm=None, plant_frame: bool = False, hold_s: float = 0.0) -> bool:
        """Press the stylus button (optionally at ``point_cm``) and hold it ``hold_s`` seconds
        (records asked for meanwhile, by ``P`` or the stream, show the switch down).

        With ``plant_frame`` the point is given in the reference receiver's frame and placed in
        the world through the reference's current pose. Returns False when the unit ignores
        the press (within 333 ms of the previous one, or mouse mode without streaming).
        """
        if point_cm is not None:
            p = np.asarray(point_cm, float)
            if plant_frame:
                p = self.reference.position + euler_matrix(*self.reference.angles) @ p
            self.stylus = p
        now = time.monotonic()
        if now - self.last_press < self.press_gap:
            return False
        self.last_press = now
        self.presses += 1
        if self.point_mode:
            self.stylus_down_until = now + hold_s
            if self.continuous:
                self.streaming = not self.streaming     # a press toggles the stream
            else:
                self._emit_all(stylus=1)                # a press acts like P
        else:
            self.stylus_down_until = now + 0.1          # mouse mode: only item 16 shows it
        return True

    # ---------------------------------------------------------------------- faults
    def inject(self, data: bytes) -> None:
        """Write raw bytes (garbage, a truncated record) to the driver."""
        self._write(data)

    def set_error(self, letter: str) -> None:
        """BIT error letter of the following records (' ' for none)."""
        self.error_letter = letter

    @property
    def closed(self) -> bool:
        """True once the port has vanished or the simulator was closed."""
        return self._stop.is_set()

    def vanish(self) -> None:
        """The port disappears (USB adapter pulled): the master side closes."""
        self._stop.set()
        with self._lock:
            if self.master >= 0:
                os.close(self.master)
                self.master = -1

    def close(self) -> None:
        self.vanish()
        self._thread.join(timeout=2)
        try:
            os.close(self.slave)
        except OSError:
            pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ---------------------------------------------------------------------- device
    def _write(self, data: bytes) -> None:
        with self._lock:
            if self.master < 0:
                return
            try:
                os.write(self.master, data)
            except OSError:
                pass

    def _record(self, station: int, stylus: int = 0) -> bytes:
        if station == 1:
            pos, ang = self.stylus, np.zeros(3)
        elif station == 2:
            pos, ang = self.reference.position, self.reference.angles
        else:
            pos, ang = np.zeros(3), np.zeros(3)
        pos = pos + self.rng.normal(0.0, self.noise, 3)
        if not self.centimetres:
            pos = pos / CM_PER_INCH
        head = f"0{station}{self.error_letter}".encode("ascii")
        out = [head]
        for item in self.items[station]:
            if item == 1:
                out.append(b"\r\n")
            elif item == 0:
                out.append(b" ")
            elif item == 16:
                out.append(f" {stylus}".encode())
            else:
                vals = {2: pos, 52: pos, 4: ang, 54: ang}.get(item, np.zeros(ITEMS[item][2]))
                if self.binary:
                    out.append(struct.pack(f"<{len(vals)}f", *vals))
                elif item in (52, 54):
                    out.append("".join(f"{v:+.4E} " for v in vals).encode())
                elif item in (5, 6, 7, 11):
                    out.append("".join(f"{np.clip(v, -9.9999, 9.9999):7.4f}" for v in vals).encode())
                else:
                    out.append("".join(f"{np.clip(v, -999.99, 999.99):7.2f}" for v in vals).encode())
        return b"".join(out)

    def _emit_all(self, stylus: int | None = None) -> None:
        if stylus is None:
            stylus = int(time.monotonic() < self.stylus_down_until)
        self._write(b"".join(self._record(s, stylus) for s in sorted(self.active)))
        self.records_sent += len(self.active)

    def flood(self, seconds: float) -> int:
        """Write records as fast as the pty takes them for ``seconds`` (no pacing); returns
        how many were written."""
        rec = self._record(1)
        batch = rec * 64
        end = time.monotonic() + seconds
        sent = 0
        while time.monotonic() < end:
            with self._lock:
                if self.master < 0:
                    break
                try:
                    n = os.write(self.master, batch)
                except BlockingIOError:
                    n = 0
                except OSError:
                    break
            if n < len(batch):
                # a partial write leaves a partial record: finish it so framing stays intact
                rest = batch[n:]
                while rest:
                    with self._lock:
                        try:
                            m = os.write(self.master, rest)
                        except OSError:
                            m = 0
                    rest = rest[m:]
                    if m == 0:
                        time.sleep(0.0005)
            sent += 64
        self.records_sent += sent
        return sent

    def _status(self, station: int) -> bytes:
        flags = int(self.binary) | (int(self.centimetres) << 1) | (int(self.continuous) << 3)
        body = f"2{station}S{flags:03X}  0  3.00 VERSION SIMULATED-FASTRAK MAIZEVIZ"
        return body.ljust(53).encode("ascii") + b"\r\n"

    def _error(self, cmd: str, code: int, field: int = 1) -> bytes:
        return f"2 E*ERROR*{cmd}*ERROR* EC{code}*PS1*FL{field}*ST0\r\n".encode("ascii")

    def _handle(self, cmd: str) -> None:
        self.commands.append(cmd)
        if self.silent:
            return
        if self.garbage:
            self._write(bytes(self.rng.integers(0x80, 0x100, 40, dtype=np.uint8)) + b"\r\n")
            return
        c, args = cmd[0], cmd[1:].rstrip("\r")
        if self._switch(c):
            return
        if c == "S":
            self._write(self._status(min(self.active) if self.active else 1))
        elif c == "W":
            self._reset()
        elif c == "\x19":
            self._reset()
            time.sleep(0.05)
        elif c in "Bb":
            pass
        elif c == "O":
            self._output_list(cmd, args)
        elif c == "l":
            self._station(cmd, args)
        elif c == "e":
            parts = args.split(",")
            if len(parts) > 1 and parts[1] in ("0", "1"):
                self.point_mode = parts[1] == "1"
            else:
                self._write(self._error(cmd.strip(), -1))
        elif c in WITH_PARAMS:
            pass
        else:
            self._write(self._error(repr(cmd), -99))

    def _switch(self, c: str) -> bool:
        """The one-letter commands that switch a mode (or ask for a point); whether ``c``
        was one of them (a format or unit command the unit ignores is not)."""
        if c == "P":
            if self.answer_delay > 0:
                time.sleep(self.answer_delay)
            self._emit_all()
        elif c == "C":
            self.continuous = True
            self.streaming = True
        elif c == "c":
            self.continuous = False
        elif c == "F" and not self.ignore_format:
            self.binary = False
        elif c == "f":
            self.binary = True
        elif c == "U":
            self.centimetres = False
        elif c == "u" and not self.ignore_units:
            self.centimetres = True
        else:
            return False
        return True

    def _output_list(self, cmd: str, args: str) -> None:
        """``O station,items``: the items a station reports (errors -2 and -3 as the unit)."""
        parts = args.split(",")
        try:
            st = int(parts[0])
            items = tuple(int(p) for p in parts[1:] if p != "")
        except ValueError:
            self._write(self._error(cmd.strip(), -2))
            return
        if not 1 <= st <= 4 or any(i not in ITEMS for i in items):
            self._write(self._error(cmd.strip(), -3))
            return
        self.items[st] = items

    def _station(self, cmd: str, args: str) -> None:
        """``l station[,state]``: turn a station on or off, or report its state."""
        parts = args.split(",")
        try:
            st = int(parts[0])
        except ValueError:
            self._write(self._error(cmd.strip(), -2))
            return
        if len(parts) > 1 and parts[1] != "":
            (self.active.add if parts[1] == "1" else self.active.discard)(st)
        else:
            self._write(f"2{st}l{int(st in self.active)}\r\n".encode())

    def _reset(self):
        self.binary = False
        self.centimetres = False
        self.continuous = False
        self.items = {s: tuple(DEFAULT_ITEMS) for s in range(1, 5)}

    def _serve(self) -> None:
        pending = ""
        next_tick = time.monotonic()
        while not self._stop.is_set():
            with self._lock:
                fd = self.master
            if fd < 0:
                return
            try:
                ready, _, _ = select.select([fd], [], [], 0.002)
            except (OSError, ValueError):
                return
            if ready:
                try:
                    data = os.read(fd, 1024).decode("latin-1")
                except OSError:
                    return
                for ch in data:
                    if pending:
                        pending += ch
                        if ch == "\r":
                            self._handle(pending)
                            pending = ""
                    elif ch in SINGLE:
                        self._handle(ch)
                    elif ch in WITH_PARAMS:
                        pending = ch
                    elif ch in "\r\n ":
                        continue
                    else:
                        self._handle(ch)
            if self.continuous and self.streaming and not self.silent and self.active:
                now = time.monotonic()
                if now >= next_tick:
                    # 120 Hz shared among the active stations: one frame per 1/120 s per station
                    self._emit_all()
                    next_tick = now + len(self.active) / 120.0
