"""Messages for people: what went wrong and what to do, never a Python class name.

The core's errors (:class:`~maizeviz.errors.MaizevizError`) are already one line naming the
file, the leaf or the quantity; here they get what the user can do about it. Anything else is
an internal error: one line in the window (with what the user was doing), the traceback on
stderr for a bug report.
"""

from __future__ import annotations

import re

from maizeviz.errors import MaizevizError, PointsFileError

#: What to do after an error, by what the user was doing.
ADVICE = {
    "open points": "choose a points CSV with the columns plant, leaf, row, col, x, y, z "
                   "(centimetres); the previous canopy stays open",
    "open project": "choose a project saved by maizeviz (.maizeviz); the previous canopy "
                    "stays open",
    "save project": "choose another folder or name",
    "export": "choose another folder or name",
    "light": "change the light settings and compute again",
    "build": "choose another mesh level",
    "sun": "write the place as: YYYY-MM-DD HH:MM latitude longitude time zone, e.g. "
           "2005-08-01 12:00 39.9 116.4 Asia/Shanghai",
}

_AT_LINE = re.compile(r"\bline \d")
_CLASS_PREFIX = re.compile(r"^(?:[A-Za-z_][\w.]*\.)?[A-Z]\w*(?:Error|Exception|Warning): ")


def user_message(exc: BaseException, doing: str = "") -> str:
    """One line for the status bar and the Messages panel (no traceback, no class name)."""
    advice = ADVICE.get(doing, "")
    if isinstance(exc, MaizevizError):
        text = _CLASS_PREFIX.sub("", str(exc)).strip() or "the input cannot be used"
        if isinstance(exc, PointsFileError) or doing in ("open points", "open project"):
            if doing == "open points" and _AT_LINE.search(text):
                # the file has the columns: a value on a line is wrong, not the layout
                advice = ("correct that line and open the file again; the previous canopy "
                          "stays open")
            return _join(text, advice)
        return _join(text, advice if doing in ("save project", "export") else "")
    if isinstance(exc, MemoryError):
        return _join(f"not enough memory to {doing or 'finish'}",
                     "choose a coarser mesh level or a lower ray density")
    if isinstance(exc, PermissionError):
        return _join(f"{exc.filename or 'the file'}: permission denied", advice)
    if isinstance(exc, FileNotFoundError):
        return _join(f"{exc.filename or 'the file'}: no such file", advice)
    if isinstance(exc, OSError):
        where = f"{exc.filename}: " if exc.filename else ""
        return _join(f"{where}{exc.strerror or 'cannot read or write the file'}", advice)
    what = doing or "the last action"
    detail = _CLASS_PREFIX.sub("", str(exc)).strip()
    return (f"{what} failed because of an internal error in maizeviz"
            + (f" ({detail[:120]})" if detail else "")
            + "; please report it with the details printed in the terminal")


def _join(text: str, advice: str) -> str:
    text = text.rstrip(". ")
    return f"{text}. {advice[0].upper() + advice[1:]}." if advice else f"{text}."
