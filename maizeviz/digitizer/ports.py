"""The serial ports of this computer, and which of them has a FASTRAK behind it (no Qt).

:func:`list_serial_ports` asks pyserial (``serial.tools.list_ports``) and puts the likely ports
first: a Polhemus USB device, then USB-serial adapters, then the built-in ports. Auto-detection
(:func:`detect`) opens each candidate in turn, asks for a status record with a short timeout
and closes it again; a port that answers with a FASTRAK status record is the one. Probing takes
up to ``timeout`` seconds a silent port, so callers run it off the GUI thread.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass

#: USB vendor id of Polhemus (its native USB trackers list with it).
POLHEMUS_VID = 0x0F44
#: Seconds a probe waits for a status record: a FASTRAK answers within milliseconds (55 bytes
#: take 5 ms at 115200 baud, 60 ms at 9600), a USB adapter adds its latency timer (16 ms).
PROBE_TIMEOUT_S = 0.5


@dataclass(frozen=True)
class PortInfo:
    """A serial port as the operating system lists it.

    Attributes
    ----------
    device : str, the path to open (``/dev/ttyUSB0``, ``COM3``)
    description : str, what the system calls it (``FT232R USB UART``), may be empty
    usb : bool, a USB device (an adapter or a native USB tracker)
    polhemus : bool, the USB vendor or maker is Polhemus
    """

    device: str
    description: str = ""
    usb: bool = False
    polhemus: bool = False

    @property
    def label(self) -> str:
        """``/dev/ttyUSB0 (FT232R USB UART)``, or the path alone."""
        return f"{self.device} ({self.description})" if self.description else self.device


def list_serial_ports() -> list[PortInfo]:
    """The serial ports present, likely FASTRAK ports first (then by name)."""
    from serial.tools import list_ports

    out = []
    for p in list_ports.comports():
        desc = p.description if p.description and p.description != "n/a" else ""
        if desc == p.device or desc == p.name:
            desc = ""
        maker = f"{p.manufacturer or ''} {p.product or ''} {desc}".lower()
        out.append(PortInfo(p.device, desc, p.vid is not None,
                            p.vid == POLHEMUS_VID or "polhemus" in maker))
    return sorted(out, key=lambda q: (not q.polhemus, not q.usb, q.device))


@dataclass(frozen=True)
class Probe:
    """What one port answered to a status request.

    Attributes
    ----------
    port : str
    found : bool, a FASTRAK answered
    kind : ``"fastrak"`` or a :data:`~maizeviz.digitizer.port_problems.KINDS` word
    message : one line for the technician
    """

    port: str
    found: bool
    kind: str
    message: str


def probe(port: str, baud: int = 115200, timeout: float = PROBE_TIMEOUT_S) -> Probe:
    """Open ``port``, ask once for a status record, close it: is a FASTRAK there?"""
    from maizeviz.digitizer.port import FastrakPort
    from maizeviz.digitizer.port_problems import DeviceError

    dev = FastrakPort(port, baud, answer_timeout=timeout, retries=1)
    try:
        dev.open()
        status = dev.identify()
    except DeviceError as exc:
        return Probe(port, False, exc.kind, str(exc))
    finally:
        dev.close()
    units = "cm" if status.centimetres else "inches"
    mode = "binary" if status.binary else "ASCII"
    return Probe(port, True, "fastrak",
                 f"a FASTRAK answers on {port} at {baud} baud (station {status.station}, "
                 f"{mode}, {units})")


def detect(ports: Iterable[str], baud: int = 115200, timeout: float = PROBE_TIMEOUT_S,
           cancel: threading.Event | None = None,
           progress: Callable[[Probe], None] | None = None) -> list[Probe]:
    """Probe each of ``ports`` in turn (duplicates once); ``progress(probe)`` after each.

    Every port is probed, so the caller can say why the others were not it. Stops early when
    ``cancel`` is set.
    """
    seen: set[str] = set()
    out = []
    for port in ports:
        port = port.strip()
        if not port or port in seen:
            continue
        if cancel is not None and cancel.is_set():
            break
        seen.add(port)
        result = probe(port, baud, timeout)
        out.append(result)
        if progress is not None:
            progress(result)
    return out
