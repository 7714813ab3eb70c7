"""Reading input files safely: only regular files, never more than a stated size.

A named pipe, a device such as /dev/zero, a socket or a folder given where a file is expected
is refused at once with one line saying what it is (reading a pipe would wait forever; reading
/dev/zero would never end). The file is opened without blocking and checked on the open
descriptor, so nothing can swap it for a pipe in between.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import BinaryIO

from maizeviz.errors import MaizevizError

_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))



def _a(what: str) -> str:
    """``what`` with its indefinite article ("a points file", "an optics table")."""
    return f"{'an' if what[:1].lower() in 'aeiou' else 'a'} {what}"

def file_kind(mode: int) -> str | None:
    """What a file that is neither regular nor a folder is, in words (else None)."""
    return next((name for test, name in _KINDS if test(mode)), None)


def open_input(path: str | Path, what: str, error: type[MaizevizError] = MaizevizError,
               buffering: int = 1 << 20) -> tuple[BinaryIO, int]:
    """Open the input file ``path`` for reading in binary (``what`` names it in messages:
    "points file"); returns (file, size in bytes).

    Raises
    ------
    error
        Missing, a folder, not a regular file (saying what it is), or unreadable.
    """
    path = Path(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise error(f"{path}: no such {what}") from None
    except IsADirectoryError:
        raise error(f"{path}: is a folder, not {_a(what)}") from None
    except (OSError, ValueError) as exc:
        try:                                       # a socket cannot even be opened
            kind = file_kind(os.stat(path).st_mode)
        except (OSError, ValueError):
            kind = None
        if kind:
            raise error(f"{path}: is {kind}, not a regular file; {_a(what)} must be a regular "
                        "file") from None
        raise error(f"{path}: cannot be read ({getattr(exc, 'strerror', None) or exc})") from None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):
        os.close(fd)
        if stat.S_ISDIR(st.st_mode):
            raise error(f"{path}: is a folder, not {_a(what)}")
        raise error(f"{path}: is {file_kind(st.st_mode) or 'not a file'}, not a regular file; "
                    f"{_a(what)} must be a regular file")
    os.set_blocking(fd, True)
    return os.fdopen(fd, "rb", buffering=buffering), st.st_size


def _size(n: int) -> str:
    if n % 2**20 == 0:
        return f"{n // 2**20} MiB"
    return f"{n / 1e6:g} MB" if n >= 10**6 else f"{n:,} bytes"


def read_input(path: str | Path, what: str, max_bytes: int,
               error: type[MaizevizError] = MaizevizError) -> bytes:
    """The bytes of the input file ``path``, refused beyond ``max_bytes`` (the message states
    the limit); see :func:`open_input`."""
    fh, size = open_input(path, what, error)
    with fh:
        if size > max_bytes:
            raise error(f"{path}: more than the {_size(max_bytes)} limit for {_a(what)}")
        try:
            data = fh.read(max_bytes + 1)
        except OSError as exc:
            raise error(f"{path}: cannot be read ({exc.strerror or exc})") from None
    if len(data) > max_bytes:
        raise error(f"{path}: more than the {_size(max_bytes)} limit for {_a(what)}")
    return data


def refuse_zero_tail(raw: bytes, path: str | Path, what: str,
                     error: type[MaizevizError] = MaizevizError) -> bytes:
    """``raw`` unless it ends in zero bytes, as a power cut leaves a file being written (its
    new length on disk, not its data). Settings files (a layout, a sweep, an optics table) are
    refused then, naming the zeros: what followed them was lost, and a run of the part before
    them would run something else than was written. Data files are read up to the zeros with
    a note instead (points, journals, weather, meshes)."""
    kept = raw.rstrip(b"\x00")
    if len(kept) < len(raw):
        raise error(f"{path}: ends in {len(raw) - len(kept):,} zero bytes after "
                    f"{len(kept):,} bytes of text, as a power cut leaves a file being "
                    f"written: part of {_a(what)} may be lost; cut the zeros (or restore the "
                    "file) and check it")
    return raw

