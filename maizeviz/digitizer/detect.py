"""Which serial port has a FASTRAK behind it (no Qt).

Auto-detection (:func:`detect`) opens each candidate (:func:`maizeviz.digitizer.ports.
list_serial_ports` puts the likely ones first) in turn, asks for a status record with a short
timeout and closes it again; a port that answers with a FASTRAK status record is the one.
Probing takes up to ``timeout`` seconds a silent port, so callers run it off the GUI thread.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from maizeviz.digitizer.port import FastrakPort
from maizeviz.digitizer.port_problems import DeviceError

#: Seconds a probe waits for a status record: a FASTRAK answers within milliseconds (55 bytes
#: take 5 ms at 115200 baud, 60 ms at 9600), a USB adapter adds its latency timer (16 ms).
PROBE_TIMEOUT_S = 0.5


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
