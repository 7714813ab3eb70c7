"""Content hashes of files, read in pieces, and copies that are checked before every use.

A points file may be hundreds of MiB: its hash is computed by streaming it in 1 MiB pieces,
never by reading it whole. A copy kept in a cache folder (a project's points, unpacked so the
loaders can read them as a file) is named after its hash, written atomically and hashed again
each time it is about to be used: a copy cut short by a full disk or a crash is rewritten,
never used.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import BinaryIO

from maizeviz.errors import MaizevizError
from maizeviz.io.atomic import atomic_open, cannot_write
from maizeviz.io.inputs import open_input

#: Bytes read at a time while hashing.
CHUNK = 1 << 20


def sha256_stream(fh: BinaryIO) -> str:
    """Hex SHA-256 of what is left to read in ``fh``, read in :data:`CHUNK` pieces; OSError
    when it cannot be read."""
    digest = hashlib.sha256()
    while chunk := fh.read(CHUNK):
        digest.update(chunk)
    return digest.hexdigest()


def sha256_file(path: str | Path, what: str = "file",
                error: type[MaizevizError] = MaizevizError) -> str:
    """Hex SHA-256 of the file ``path``, read in :data:`CHUNK` pieces (memory stays flat).

    Raises
    ------
    error
        The file is missing, not a regular file or cannot be read (see
        :func:`maizeviz.io.inputs.open_input`).
    """
    fh, _ = open_input(path, what, error)
    with fh:
        try:
            return sha256_stream(fh)
        except OSError as exc:
            raise error(f"{path}: cannot be read ({exc.strerror or exc})") from None


def same_content(path: str | Path, sha256: str) -> bool:
    """Whether ``path`` is a readable regular file whose SHA-256 is ``sha256`` (hex)."""
    try:
        return sha256_file(path) == sha256.lower()
    except MaizevizError:
        return False


def checked_copy(folder: str | Path, name: str, data: bytes, sha256: str,
                 error: type[MaizevizError] = MaizevizError) -> Path:
    """A file holding ``data`` (whose SHA-256 is ``sha256``) in ``folder``, named
    ``<first 16 hex digits>-<name>``: reused when its content still hashes to ``sha256``,
    else (missing, cut short, altered) written again atomically and checked.

    Raises
    ------
    error
        ``data`` does not match ``sha256``, or the copy cannot be written or read back.
    """
    if hashlib.sha256(data).hexdigest() != sha256.lower():
        raise error(f"the data to copy to {folder} do not match their checksum")
    folder = Path(folder)
    safe = Path(name).name or "data"
    copy = folder / f"{sha256[:16].lower()}-{safe}"
    if same_content(copy, sha256):
        return copy
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise error(f"{folder}: cannot create the folder ({exc.strerror or exc})") from None
    try:
        with atomic_open(copy, "wb") as fh:
            fh.write(data)
    except MaizevizError as exc:
        raise error(str(exc)) from None
    except OSError as exc:
        raise error(str(cannot_write(copy, exc))) from None
    if not same_content(copy, sha256):
        raise error(f"{copy}: the copy written does not read back with its checksum (a full "
                    "disk?); nothing was opened")
    return copy
