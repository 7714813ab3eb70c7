"""Why a serial port cannot be used, said plainly with the likely fix (no Qt).

pyserial reports every failure as text such as ``[Errno 2] could not open port ...`` or
``(25, 'Inappropriate ioctl for device')``. A technician needs to know what to do instead: plug
the adapter in, join the group that owns the port, close the other program that holds it,
switch the unit on or match its baud rate. Each failure becomes a :class:`DeviceError` whose
``kind`` names the case, so the command line (``maizeviz record``) and the app's digitizer
panel show the same line, and a test can tell the cases apart.

=============  ===================================================================
kind           meaning
=============  ===================================================================
missing        nothing at that path (adapter unplugged, a mistyped name)
not_serial     something is there but it is not a serial port (a file, a folder)
denied         the operating system refuses: the user lacks the port's group
busy           another program (or another recording) has the port open
no_device      the port exists but no hardware answers to it (EIO, ENXIO, ENODEV)
silent         the port opened but nothing answered the status request
not_fastrak    something answered, but not as a FASTRAK does (wrong device, or baud)
lost           the port went away during a session (the cable pulled)
cancelled      the connection was given up on purpose (Stop while connecting)
failed         anything else, with the system's own words
=============  ===================================================================
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from maizeviz.errors import MaizevizError

#: Failures the messages below explain.
KINDS = ("missing", "not_serial", "denied", "busy", "no_device", "silent", "not_fastrak",
         "lost", "cancelled", "failed")
#: How many bytes of an unexpected answer a message shows.
SAMPLE_BYTES = 24


class DeviceError(MaizevizError):
    """The device cannot be reached or configured; ``kind`` is one of :data:`KINDS`."""

    def __init__(self, message: str = "", kind: str = "failed", quantity: str | None = None):
        super().__init__(message, quantity=quantity)
        self.kind = kind


def _is_url(port: str) -> bool:
    """pyserial's URL ports (``socket://``, ``rfc2217://``, ``loop://``) have no path."""
    return "://" in port


def open_problem(port: str, exc: BaseException) -> DeviceError:
    """The plain error for ``exc``, raised by pyserial when opening ``port``.

    Parameters
    ----------
    port : str
        The port as the user gave it (``/dev/ttyUSB0``).
    exc : BaseException
        What ``serial.Serial(port, ...)`` raised (a ``SerialException``, an ``OSError``...).
    """
    code = getattr(exc, "errno", None)
    text = str(exc)
    if _is_url(port):
        return DeviceError(f"cannot open {port}: {text}", "failed")
    path = Path(port)
    exists = os.path.lexists(port)
    if code == errno.ENOENT or not exists:
        return DeviceError(f"no serial port {port}: nothing is plugged in there; is the "
                           f"FASTRAK's cable (or its USB-serial adapter) plugged in? "
                           f"{_present_ports(port)}", "missing")
    if code in (errno.EACCES, errno.EPERM):
        return DeviceError(_denied(path), "denied")
    if code in (errno.EAGAIN, errno.EWOULDBLOCK, errno.EBUSY) or "exclusively lock" in text:
        return DeviceError(_busy(port), "busy")
    what = _not_a_terminal(path)
    if code in (errno.EISDIR, errno.ENOTTY) or what or "Inappropriate ioctl" in text:
        return DeviceError(f"{port} is not a serial port ({what or 'not a terminal device'}); "
                           f"choose the port the FASTRAK is plugged into. "
                           f"{_present_ports(port)}", "not_serial")
    if code in (errno.EIO, errno.ENXIO, errno.ENODEV):
        return DeviceError(f"{port} is there but no device answers to it "
                           f"({os.strerror(code)}): the adapter may have just been unplugged, "
                           f"or the port has no hardware behind it. {_present_ports(port)}",
                           "no_device")
    detail = os.strerror(code) if isinstance(code, int) else text
    return DeviceError(f"cannot open {port}: {detail}", "failed")


def _present_ports(not_this: str) -> str:
    """``Serial ports present: /dev/ttyUSB1 (FT232R USB UART).`` or that there are none."""
    from maizeviz.digitizer.ports import list_serial_ports

    try:
        ports = [p for p in list_serial_ports() if p.device != not_this]
    except Exception:  # noqa: BLE001 - a hint only: listing must never hide the real error
        return ""
    if not ports:
        return "No serial port is present on this computer."
    return "Serial ports present: " + ", ".join(p.label for p in ports[:6]) + \
        (f" and {len(ports) - 6} more." if len(ports) > 6 else ".")


def _not_a_terminal(path: Path) -> str:
    """What ``path`` is when it is not a character device: 'a folder', 'a regular file'."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return ""
    if stat.S_ISCHR(mode):
        return ""
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISREG(mode):
        return "a regular file"
    return "not a character device"


def _denied(path: Path) -> str:
    """Permission denied: name the group that owns the port and how to join it."""
    port = str(path)
    try:
        st = os.stat(path)
    except OSError:
        return f"permission denied on {port}; check its permissions with 'ls -l {port}'"
    mode = stat.filemode(st.st_mode)
    try:
        import grp
        import pwd

        group = grp.getgrgid(st.st_gid).gr_name
        user = pwd.getpwuid(os.geteuid()).pw_name
        members = set(grp.getgrgid(st.st_gid).gr_mem)
    except (ImportError, KeyError):
        return f"permission denied on {port} ({mode}); check its permissions with 'ls -l {port}'"
    if st.st_gid in os.getgroups() or os.getegid() == st.st_gid:
        return (f"permission denied on {port} ({mode}, group '{group}'): your user {user} is in "
                f"that group but the port does not let the group read and write; ask the "
                f"administrator to fix its permissions (udev rule)")
    if user in members:
        return (f"permission denied on {port}: it belongs to the group '{group}', which your "
                f"user {user} was added to after this session began; log out and back in "
                f"(or run 'newgrp {group}') and connect again")
    return (f"permission denied on {port}: it belongs to the group '{group}', which your user "
            f"{user} is not in; add yourself with 'sudo usermod -aG {group} {user}', then log "
            f"out and back in")


def _busy(port: str) -> str:
    """The port is held: say by whom when the system tells."""
    held = holders(port)
    if held and all(pid == os.getpid() for pid, _ in held):
        return (f"{port} is busy: this program already has it open (a recording or a port "
                f"search under way); stop that first, then connect again")
    held = [(pid, name) for pid, name in held if pid != os.getpid()]
    if held:
        who = ", ".join(f"{name} (pid {pid})" for pid, name in held[:3])
        return (f"{port} is busy: {who} has it open; close that program (or stop that "
                f"recording), then connect again")
    return (f"{port} is busy: another program has it open (another recording, a terminal "
            f"program such as minicom or screen, or ModemManager probing new ports); close it, "
            f"then connect again")


def holders(port: str) -> list[tuple[int, str]]:
    """Processes that have ``port`` open, as (pid, command name), read from ``/proc``.

    Only processes this user may inspect are seen; an empty list means none was found (or
    there is no ``/proc``), not that none exists.
    """
    try:
        target = os.path.realpath(port)
        pids = [d for d in os.listdir("/proc") if d.isdigit()]
    except OSError:
        return []
    out = []
    for pid in pids:
        fd_dir = f"/proc/{pid}/fd"
        try:
            fds = os.listdir(fd_dir)
        except OSError:
            continue
        for fd in fds:
            try:
                if os.readlink(f"{fd_dir}/{fd}") == target:
                    break
            except OSError:
                continue
        else:
            continue
        try:
            with open(f"/proc/{pid}/comm", encoding="utf-8", errors="replace") as fh:
                name = fh.read().strip()
        except OSError:
            name = "?"
        out.append((int(pid), name))
    return sorted(out)


def silent_problem(port: str, baud: int, requests: int) -> DeviceError:
    """Nothing at all came back to ``requests`` status requests."""
    return DeviceError(
        f"no answer from a FASTRAK on {port} at {baud} baud after {requests} status "
        f"request{'s' if requests != 1 else ''}: is the unit switched on and its cable on this "
        "port? A unit just switched on or re-initialised stays silent about 10 s; the baud rate "
        "must match its rear DIP switches", "silent", quantity="baud")


def not_fastrak_problem(port: str, baud: int, sample: bytes, total: int) -> DeviceError:
    """Bytes came back, but no FASTRAK status record among them."""
    shown = sample[:SAMPLE_BYTES].decode("latin-1")
    more = "…" if total > SAMPLE_BYTES else ""
    return DeviceError(
        f"something answers on {port}, but not as a FASTRAK does ({total} bytes such as "
        f"'{shown}{more}' and no status record): either the baud rate ({baud}) differs from the "
        "unit's rear DIP switches (unreadable characters are the usual sign), or another "
        "device is on this port", "not_fastrak", quantity="baud")


def lost_message(port: str, exc: BaseException | None = None) -> str:
    """The port went away mid-session (one line; the recorder adds what is safe)."""
    why = ""
    if exc is not None:
        code = getattr(exc, "errno", None)
        if isinstance(code, int):
            why = f" ({os.strerror(code)})"
        elif "returned no data" in str(exc) or "disconnected" in str(exc):
            why = " (the device disconnected)"    # pyserial's words for a hung-up port
        else:
            why = f" ({str(exc)[:60]})"
    return (f"the connection to {port} was lost{why}: is the cable or the USB-serial adapter "
            "still plugged in?")
