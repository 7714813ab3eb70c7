"""The FASTRAK on a serial port (pyserial, no Qt): start-up, configuration, a reader thread.

Start-up follows docs/fastrak.md: stop streaming, flush, ask for status (with retries, since a unit
just re-initialised stays silent for about 10 s), then centimetres, ASCII, the output list of
each station (with the stylus switch on station 1) and the stylus in point mode, and read the
status back. A unit that keeps answering in inches or binary is not fought: the parser follows
what the status says and inches are converted, with a warning.

The port is opened for this program alone (``exclusive``: a second recorder on the same port is
told the port is busy instead of sharing its bytes), and every failure becomes a
:class:`~maizeviz.digitizer.port_problems.DeviceError` in plain words with its likely fix.

The reader thread parses bytes into events and hands each to a callback (or a queue); a port
that vanishes (an unplugged USB adapter) ends the thread with a :class:`PortLost` event. Asked
to (``live_every``), it also polls the unit for the stylus's position between presses and sorts
the replies from the presses (:class:`~maizeviz.digitizer.live.PollSorter`).
"""

from __future__ import annotations

import queue
import threading
import time
from dataclasses import dataclass, replace

import serial

from maizeviz.digitizer import protocol as fp
from maizeviz.digitizer.live import POLL_WITH_FENCE, PollSorter
from maizeviz.digitizer.port_problems import (
    DeviceError,
    lost_message,
    not_fastrak_problem,
    open_problem,
    silent_problem,
)

__all__ = ["CM_PER_INCH", "DeviceConfig", "DeviceError", "FastrakPort", "PortLost"]

CM_PER_INCH = 2.54
#: Seconds one read waits for bytes: how soon the reader sees Stop, and how finely it polls.
READ_TIMEOUT_S = 0.02


@dataclass(frozen=True)
class PortLost:
    """The serial port vanished or failed; ``message`` says how."""

    message: str


@dataclass(frozen=True)
class DeviceConfig:
    """What the device reported after configuration."""

    centimetres: bool
    binary: bool
    items: dict[int, tuple[int, ...]]
    warnings: tuple[str, ...] = ()


class FastrakPort:
    """A FASTRAK on ``port`` (a path such as /dev/ttyUSB0, or a simulator's pty).

    Parameters
    ----------
    baud : int, 115200 by default (the factory DIP setting); always 8N1, no flow control
    answer_timeout : seconds to wait for each reply
    """

    def __init__(self, port: str, baud: int = 115200, answer_timeout: float = 1.0,
                 retries: int = 3):
        self.port_name = port
        self.baud = baud
        self.answer_timeout = answer_timeout
        self.retries = retries
        self.serial: serial.Serial | None = None
        self.config: DeviceConfig | None = None
        self.parser: fp.RecordParser | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._cancel = threading.Event()
        self.stations = (1,)
        #: Polls the reader sent and replies it sorted out (live positions), for tests.
        self.polls = 0

    # --------------------------------------------------------------------------- open
    def open(self) -> None:
        """Open the port for this program alone; a plain :class:`DeviceError` if it cannot."""
        self._check()
        try:
            self.serial = serial.Serial(self.port_name, self.baud, bytesize=serial.EIGHTBITS,
                                        parity=serial.PARITY_NONE, stopbits=serial.STOPBITS_ONE,
                                        timeout=READ_TIMEOUT_S, xonxoff=False, rtscts=False,
                                        exclusive=True)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise open_problem(self.port_name, exc) from None

    def cancel(self) -> None:
        """Give up a :meth:`configure` under way in another thread (it raises a "cancelled"
        DeviceError within a read timeout, and the caller closes the port). Thread-safe."""
        self._cancel.set()

    def _check(self) -> None:
        if self._cancel.is_set():
            raise DeviceError(f"connecting to {self.port_name} was given up", "cancelled")

    @property
    def _port(self) -> serial.Serial:
        """The open serial port (:class:`DeviceError` when it is not open)."""
        self._check()
        if self.serial is None:
            raise DeviceError(f"{self.port_name} is not open")
        return self.serial

    def _send(self, data: bytes) -> None:
        port = self._port
        try:
            port.write(data)
            port.flush()
        except (serial.SerialException, OSError) as exc:
            raise DeviceError(lost_message(self.port_name, exc), "lost") from None

    def _read_reply(self, want, timeout: float, heard: bytearray | None = None):
        """Read type-2 replies until one of type ``want`` (or an ErrorReply) arrives; the
        bytes read are appended to ``heard``."""
        parser = fp.RecordParser()
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                chunk = self._port.read(256)
            except (serial.SerialException, OSError) as exc:
                raise DeviceError(lost_message(self.port_name, exc), "lost") from None
            if heard is not None:
                heard += chunk
            for ev in parser.feed(chunk):
                if isinstance(ev, (want, fp.ErrorReply)):
                    return ev
        return None

    def status(self) -> fp.Status:
        """Ask for a status record, retrying.

        Raises
        ------
        DeviceError
            ``silent`` when nothing came back at all, ``not_fastrak`` when bytes came back but
            no status record among them (another device, or a baud rate that differs from the
            unit's).
        """
        heard = bytearray()
        for _ in range(self.retries):
            self._send(fp.STATUS)
            ev = self._read_reply(fp.Status, self.answer_timeout, heard)
            if isinstance(ev, fp.Status):
                return ev
        if heard.strip(b"\r\n\x00"):
            raise not_fastrak_problem(self.port_name, self.baud, bytes(heard.strip()), len(heard))
        raise silent_problem(self.port_name, self.baud, self.retries)

    def identify(self) -> fp.Status:
        """Stop any stream, drop what was waiting and ask for the status record."""
        self._send(fp.STOP_CONTINUOUS)
        time.sleep(0.05)
        self._port.reset_input_buffer()
        return self.status()

    def configure(self, stations=(1,)) -> DeviceConfig:
        """The start-up sequence; returns what the device ended up reporting."""
        if self.serial is None:
            self.open()
        self.stations = tuple(stations)
        self.identify()
        for station in range(1, 5):
            self._send(fp.station_enable(station, station in self.stations))
        self._send(fp.CENTIMETRES)
        self._send(fp.ASCII)
        items: dict[int, tuple[int, ...]] = {}
        for station in self.stations:
            items[station] = fp.STYLUS_ITEMS if station == 1 else fp.DEFAULT_ITEMS
            self._send(fp.output_list(station, items[station]))
        self._send(fp.stylus_mode(1, True))
        time.sleep(0.05)
        st = self.status()
        warnings = []
        if not st.centimetres:
            warnings.append("the unit keeps answering in inches; positions are converted to cm")
        if st.binary:
            warnings.append("the unit keeps answering in binary; records are read as binary")
        self.config = DeviceConfig(st.centimetres, st.binary, items, tuple(warnings))
        self.parser = fp.RecordParser(items, binary=st.binary)
        self._port.reset_input_buffer()
        return self.config

    def to_cm(self, rec: fp.Record) -> fp.Record:
        """A record with its position in centimetres, whatever the unit was set to."""
        if self.config is None or self.config.centimetres or rec.position is None:
            return rec
        x, y, z = rec.position
        return replace(rec, position=(x * CM_PER_INCH, y * CM_PER_INCH, z * CM_PER_INCH))

    # ------------------------------------------------------------------------- reader
    def start_reader(self, callback=None, live_every: float | None = None) -> queue.Queue | None:
        """Start the reader thread; events go to ``callback(event)`` or to a returned queue.

        Events: :class:`~maizeviz.digitizer.protocol.Record` (position in cm) for each press,
        ``Garbled``, ``ErrorReply``, ``Reply`` and, last, :class:`PortLost`. With
        ``live_every`` (seconds) the reader also asks the unit where the stylus is that often
        and hands the answers on as :class:`~maizeviz.digitizer.live.Live`, never as presses
        (each poll fenced by a status request, whose reply is not handed on).
        """
        if self.parser is None:
            raise DeviceError("configure the device before reading")
        q: queue.Queue | None = None
        if callback is None:
            q = queue.Queue()
            callback = q.put
        self._stop.clear()
        sorter = None
        if live_every is not None:
            sorter = PollSorter(self.stations, live_every, self.baud, self._frame_bytes())
        self._thread = threading.Thread(target=self._read_loop, args=(callback, sorter),
                                        name="fastrak-reader", daemon=True)
        self._thread.start()
        return q

    def _frame_bytes(self) -> int:
        """Bytes of one record of every active station (how long a poll's answer takes)."""
        items = self.config.items if self.config is not None else {}
        size = fp.binary_length if self.config is not None and self.config.binary else \
            fp.ascii_length
        return sum(size(items.get(s, fp.DEFAULT_ITEMS)) for s in self.stations)

    def _read_loop(self, callback, sorter: PollSorter | None) -> None:
        ser, parser = self._port, self.parser
        assert parser is not None                  # start_reader checked it
        while not self._stop.is_set():
            try:
                if sorter is not None and sorter.due(time.monotonic()):
                    ser.write(POLL_WITH_FENCE)
                    sorter.polled(time.monotonic())
                    self.polls += 1
                data = ser.read(max(1, min(ser.in_waiting, 65536)))
            except (serial.SerialException, OSError, TypeError, AttributeError) as exc:
                self._flush(callback, sorter)
                if not self._stop.is_set():
                    callback(PortLost(lost_message(self.port_name, exc)))
                return
            events = [self.to_cm(ev) if isinstance(ev, fp.Record) else ev
                      for ev in parser.feed(data)] if data else []
            if sorter is not None:
                now = time.monotonic()
                events = [out for ev in events for out in sorter.feed(ev, now)]
                events += sorter.tick(now)
            for ev in events:
                callback(ev)
        self._flush(callback, sorter)

    @staticmethod
    def _flush(callback, sorter: PollSorter | None) -> None:
        """Presses the sorter still holds (waiting for a poll's answer) are handed on."""
        if sorter is not None:
            for ev in sorter.flush(time.monotonic()):
                callback(ev)

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2)
            self._thread = None

    def close(self) -> None:
        """Stop the reader and close the port (from the thread that configured it, or after
        :meth:`cancel` made that thread give up)."""
        self.stop()
        if self.serial is not None:
            try:
                self.serial.close()
            except (serial.SerialException, OSError):
                pass
            self.serial = None

    def reconnect(self, attempts: int = 5, wait: float = 1.0) -> DeviceConfig:
        """Close, reopen and reconfigure (after the adapter was plugged back in)."""
        self.close()
        last = None
        for _ in range(attempts):
            try:
                self.open()
                return self.configure(self.stations)
            except DeviceError as exc:
                last = exc
                self.close()
                time.sleep(wait)
        raise DeviceError(f"could not reconnect to {self.port_name}: {last}",
                          last.kind if last is not None else "failed")
