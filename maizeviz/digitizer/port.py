"""The FASTRAK on a serial port (pyserial, no Qt): start-up, configuration, a reader thread.

Start-up follows docs/fastrak.md: stop streaming, flush, ask for status (with retries, since a unit
just re-initialised stays silent for about 10 s), then centimetres, ASCII, the output list of
each station (with the stylus switch on station 1) and the stylus in point mode, and read the
status back. A unit that keeps answering in inches or binary is not fought: the parser follows
what the status says and inches are converted, with a warning.

The reader thread parses bytes into events and hands each to a callback (or a queue); a port
that vanishes (an unplugged USB adapter) ends the thread with a :class:`PortLost` event.
"""

from __future__ import annotations

import queue
import threading
import time
from dataclasses import dataclass, replace

import serial

from maizeviz.digitizer import protocol as fp
from maizeviz.errors import MaizevizError

CM_PER_INCH = 2.54


class DeviceError(MaizevizError):
    """The device cannot be reached or configured."""


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
        self.stations = (1,)

    # --------------------------------------------------------------------------- open
    def open(self) -> None:
        try:
            self.serial = serial.Serial(self.port_name, self.baud, bytesize=serial.EIGHTBITS,
                                        parity=serial.PARITY_NONE, stopbits=serial.STOPBITS_ONE,
                                        timeout=0.05, xonxoff=False, rtscts=False)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise DeviceError(f"cannot open {self.port_name}: {exc}") from None

    @property
    def _port(self) -> serial.Serial:
        """The open serial port (:class:`DeviceError` when it is not open)."""
        if self.serial is None:
            raise DeviceError(f"{self.port_name} is not open")
        return self.serial

    def _send(self, data: bytes) -> None:
        port = self._port
        try:
            port.write(data)
            port.flush()
        except (serial.SerialException, OSError) as exc:
            raise DeviceError(f"{self.port_name}: write failed ({exc})") from None

    def _read_reply(self, want, timeout: float):
        """Read type-2 replies until one of type ``want`` (or an ErrorReply) arrives."""
        parser = fp.RecordParser()
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                chunk = self._port.read(256)
            except (serial.SerialException, OSError) as exc:
                raise DeviceError(f"{self.port_name}: read failed ({exc})") from None
            for ev in parser.feed(chunk):
                if isinstance(ev, (want, fp.ErrorReply)):
                    return ev
        return None

    def status(self) -> fp.Status:
        """Ask for a status record, retrying; :class:`DeviceError` when nothing answers."""
        for _ in range(self.retries):
            self._send(fp.STATUS)
            ev = self._read_reply(fp.Status, self.answer_timeout)
            if isinstance(ev, fp.Status):
                return ev
        raise DeviceError(
            f"no answer from a FASTRAK on {self.port_name} at {self.baud} baud after "
            f"{self.retries} status requests: check that the unit is on (a unit just "
            "re-initialised stays silent about 10 s), the cable, and that the baud rate matches "
            "its rear DIP switches", quantity="baud")

    def configure(self, stations=(1,)) -> DeviceConfig:
        """The start-up sequence; returns what the device ended up reporting."""
        if self.serial is None:
            self.open()
        self.stations = tuple(stations)
        self._send(fp.STOP_CONTINUOUS)
        time.sleep(0.05)
        self._port.reset_input_buffer()
        self.status()
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
    def start_reader(self, callback=None) -> queue.Queue | None:
        """Start the reader thread; events go to ``callback(event)`` or to a returned queue.

        Events: :class:`~maizeviz.digitizer.protocol.Record` (position in cm),
        ``Garbled``, ``ErrorReply``, ``Reply`` and, last, :class:`PortLost`.
        """
        if self.parser is None:
            raise DeviceError("configure the device before reading")
        q: queue.Queue | None = None
        if callback is None:
            q = queue.Queue()
            callback = q.put
        self._stop.clear()
        self._thread = threading.Thread(target=self._read_loop, args=(callback,),
                                        name="fastrak-reader", daemon=True)
        self._thread.start()
        return q

    def _read_loop(self, callback):
        ser, parser = self._port, self.parser
        assert parser is not None                  # start_reader checked it
        while not self._stop.is_set():
            try:
                data = ser.read(max(1, min(ser.in_waiting, 65536)))
            except (serial.SerialException, OSError, TypeError, AttributeError) as exc:
                if not self._stop.is_set():
                    callback(PortLost(f"{self.port_name} vanished ({exc})"))
                return
            if not data:
                continue
            for ev in parser.feed(data):
                callback(self.to_cm(ev) if isinstance(ev, fp.Record) else ev)

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2)
            self._thread = None

    def close(self) -> None:
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
        raise DeviceError(f"could not reconnect to {self.port_name}: {last}")
