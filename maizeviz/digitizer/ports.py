"""The serial ports of this computer (no Qt).

:func:`list_serial_ports` asks pyserial (``serial.tools.list_ports``) and puts the likely ports
first: a Polhemus USB device, then USB-serial adapters, then the built-in ports. Which of them
has a FASTRAK behind it is :mod:`maizeviz.digitizer.detect`'s question.
"""

from __future__ import annotations

from dataclasses import dataclass

#: USB vendor id of Polhemus (its native USB trackers list with it).
POLHEMUS_VID = 0x0F44



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
