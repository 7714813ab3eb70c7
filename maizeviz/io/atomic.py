"""Atomic output files: a kill or a full disk leaves the old file or the new one, never a part.

Every file maizeviz writes goes to a temporary file in the same folder, is flushed to disk
(fsync) and renamed over the target (``os.replace`` is atomic within a file system); the folder
is fsynced so the rename itself survives a power cut. A failure removes the temporary file and
raises :class:`~maizeviz.errors.MaizevizError` naming the path.

A process killed outright (kill -9, power cut) cannot remove its temporary file, so its name
carries the writer's process id, ``.<name>.<pid>.<random>.part<suffix>``: the next write of the
same target removes the leftovers of writers that are no longer running (a live writer's file
is never touched, so two processes may write the same target at once).
"""

from __future__ import annotations

import contextlib
import csv
import os
import tempfile
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import IO, Any

from maizeviz.errors import MaizevizError


def read_umask() -> int:
    """The process's umask, without a moment where it is 0.

    Linux tells it in /proc/self/status; elsewhere ``os.umask`` can only read it by setting
    it, so it is set to 0o077 for that instant: a file another thread creates meanwhile is
    private, never world-writable (setting 0, as before, gave such a file mode 0o666).
    """
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o077)
    os.umask(mask)
    return mask


#: The umask, read once when maizeviz.io.atomic is imported (before any thread of maizeviz
#: writes): never set again while files are written.
UMASK = read_umask()
#: Mode of the files written here: what ``open`` would give a new file under :data:`UMASK`
#: (0o644 under the usual 0o022; mkstemp's temporary file is 0o600).
FILE_MODE = 0o666 & ~UMASK


def _fsync_folder(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:                              # some file systems cannot open folders
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def cannot_write(path: str | Path, exc: OSError) -> MaizevizError:
    """The one-line error for an output that could not be written."""
    return MaizevizError(f"{path}: cannot write ({exc.strerror or exc}); nothing was written "
                         "there")


def file_tag(text: str) -> str:
    """``"K=4"`` -> ``"K_4"``: a label made fit for a file name (other than letters and digits,
    characters become ``_``; leading and trailing ones are dropped)."""
    return "".join(c if c.isalnum() else "_" for c in text).strip("_")


def make_folder(path: str | Path) -> Path:
    """The output folder ``path``, created (with its parents) if needed."""
    folder = Path(path)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise MaizevizError(f"{folder}: cannot create the folder ({exc.strerror})") from None
    return folder


def check_output(path: str | Path) -> Path:
    """Refuse, before any work, an output whose folder is missing or that is a folder."""
    path = Path(path)
    try:
        is_dir, folder_there = path.is_dir(), path.parent.is_dir()
    except (OSError, ValueError) as exc:       # a name too long, a NUL: not a lookup failure
        why = getattr(exc, "strerror", None) or str(exc)
        raise MaizevizError(f"{path}: cannot be looked up ({why})") from None
    if is_dir:
        raise MaizevizError(f"{path} is a folder; give a file name")
    if not folder_there:
        raise MaizevizError(f"{path}: the folder {path.parent} does not exist")
    return path


def _temp_prefix(path: Path) -> str:
    return f".{path.name}."


def temp_leftovers(path: str | Path) -> list[Path]:
    """Temporary files of ``path`` left by writers that are no longer running."""
    path = Path(path)
    prefix = _temp_prefix(path)
    out = []
    try:
        entries = list(os.scandir(path.parent))
    except OSError:
        return []
    for entry in entries:
        name = entry.name
        if not name.startswith(prefix) or not name.endswith(f".part{path.suffix}"):
            continue
        pid_text = name[len(prefix):].split(".", 1)[0]
        if not pid_text.isdigit() or _running(int(pid_text)):
            continue
        out.append(Path(entry.path))
    return out


def _running(pid: int) -> bool:
    """Whether process ``pid`` exists (ours always does)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, OSError):
        return True          # another user's process, or a number we cannot check: keep it
    return True


def remove_leftovers(path: str | Path) -> int:
    """Remove the temporary files of ``path`` left by killed writers; returns how many."""
    n = 0
    for tmp in temp_leftovers(path):
        try:
            tmp.unlink()
            n += 1
        except OSError:        # gone meanwhile, or not ours to remove: harmless
            pass
    return n


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary path beside ``path`` (same suffix, for writers that pick a format by it);
    renamed over ``path`` when the block ends without an exception.

    Raises
    ------
    MaizevizError
        The folder is missing or the file cannot be written (the target is left untouched).
    """
    path = check_output(path)
    folder = path.parent
    remove_leftovers(path)
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f"{_temp_prefix(path)}{os.getpid()}.",
                                        suffix=f".part{path.suffix}", dir=folder)
    except OSError as exc:
        raise cannot_write(path, exc) from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        os.chmod(tmp, FILE_MODE)
        yield tmp
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise cannot_write(path, exc) from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    _fsync_folder(folder)


@contextlib.contextmanager
def atomic_open(path: str | Path, mode: str = "w", **kwargs: Any) -> Iterator[IO[Any]]:
    """``open(path, mode)`` for writing, atomically (see the module docstring).

    ``mode`` is ``"w"`` or ``"wb"``; ``kwargs`` go to :func:`open` (``newline``,
    ``encoding``). Text defaults to UTF-8.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_open writes whole files: mode 'w' or 'wb', not '{mode}'")
    if mode == "w":
        kwargs.setdefault("encoding", "utf-8")
    with atomic_path(path) as tmp:
        try:
            with open(tmp, mode, **kwargs) as fh:
                yield fh
        except OSError as exc:
            raise cannot_write(path, exc) from None


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_open(path, "w") as fh:
        fh.write(text)


def write_rows(path: str | Path, rows: Sequence[Mapping[str, Any]]) -> None:
    """Rows of dicts as a CSV file with a header, atomically; the columns are the first
    row's keys (an empty list writes an empty file)."""
    fields = list(rows[0].keys()) if rows else []
    with atomic_open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)
