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

from maizeviz.errors import MaizevizError

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISSOCK, "a socket"))


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def read_input(path: str | Path, what: str, max_bytes: int,
               error: type[MaizevizError] = MaizevizError) -> bytes:
    """The bytes of the input file ``path`` (``what`` names it in messages: "points file").

    Raises
    ------
    error
        Missing, not a regular file (saying what it is), unreadable, or larger than
        ``max_bytes`` (the message states the limit).
    """
    path = Path(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except FileNotFoundError:
        raise error(f"{path}: no such {what}") from None
    except IsADirectoryError:
        raise error(f"{path}: is a folder, not a {what}") from None
    except OSError as exc:
        raise error(f"{path}: cannot be read ({exc.strerror or exc})") from None
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        raise error(f"{path}: is {_kind(mode)}, not a {what}")
    os.set_blocking(fd, True)
    with os.fdopen(fd, "rb") as fh:
        try:
            data = fh.read(max_bytes + 1)
        except OSError as exc:
            raise error(f"{path}: cannot be read ({exc.strerror or exc})") from None
    if len(data) > max_bytes:
        raise error(f"{path}: more than the {max_bytes / 2**20:g} MiB limit for a {what}")
    return data
