"""Where a run writes: every output path, derived names included, checked before any work
against every input and every other output of the same run.

A command lists the files it reads and every file it will write: the per-level files a
``--levels`` comparison derives (``light_K_4.csv``), the files an output folder will hold
(``--heatmaps``, ``--plots``, a sweep's results). :func:`check_run_paths` then refuses, in one
line naming both paths,

- an output that is an input (by resolved path, and by device and inode when it exists:
  ``./a.csv``, ``../x/a.csv``, a symbolic link or a hard link to the input are all caught);
- two outputs that are the same file (``--leaf-light s.csv --plant-light s.csv``), which
  would otherwise silently keep only the second table;
- an output folder that is an existing file (an input or another output);
- a path that is a symbolic link loop, or that cannot be looked up at all.
"""

from __future__ import annotations

import errno
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from maizeviz.errors import MaizevizError
from maizeviz.io.atomic import check_output

#: (what, path): what a path is, in words ("the points file"), and the path (None: not asked).
Named = tuple[str, "str | Path | None"]


@dataclass(frozen=True)
class OutputFolder:
    """A folder a run creates if needed and fills.

    Attributes
    ----------
    what : words for it ("the heatmap folder"); path : the folder
    files : names of the files the run will write in it
    """

    what: str
    path: str | Path | None
    files: Sequence[str] = ()


@dataclass(frozen=True)
class _Place:
    what: str
    shown: str
    resolved: Path
    inode: tuple[int, int] | None
    is_dir: bool

    def same(self, other: _Place) -> bool:
        return self.resolved == other.resolved or \
            (self.inode is not None and self.inode == other.inode)


def place_of(path: str | Path, what: str) -> _Place:
    """Where ``path`` really is: its resolved path and, when it exists, its device and inode.

    Raises
    ------
    MaizevizError
        The path is a symbolic link loop, too long, or cannot be looked up.
    """
    p = Path(path)
    try:
        resolved = p.resolve()
        st = os.stat(p)
    except FileNotFoundError:
        return _Place(what, str(path), resolved, None, False)
    except RuntimeError:                       # Python < 3.13 reports a loop this way
        raise MaizevizError(f"{path}: {what} is a symbolic link loop") from None
    except (OSError, ValueError) as exc:
        code = getattr(exc, "errno", None)
        if code == errno.ELOOP:
            raise MaizevizError(f"{path}: {what} is a symbolic link loop") from None
        if code == errno.ENOTDIR:              # a file where a folder should be: found later
            return _Place(what, str(path), Path(os.path.abspath(p)), None, False)
        reason = getattr(exc, "strerror", None) or str(exc)
        raise MaizevizError(f"{path}: {what} cannot be looked up ({reason})") from None
    return _Place(what, str(path), resolved, (st.st_dev, st.st_ino),
                  os.path.isdir(p))


def check_run_paths(outputs: Iterable[Named], inputs: Iterable[Named] = (),
                    folders: Iterable[OutputFolder] = (), appended: Iterable[Named] = ()) -> None:
    """Refuse, before any work, a run whose outputs would overwrite an input or each other.

    Parameters
    ----------
    outputs : (what, path) of every file the run writes, derived names included; None paths
        are skipped. Each must be in an existing folder and not be a folder.
    inputs : (what, path) of every file the run reads; None skipped
    folders : output folders and the file names the run will write in each
    appended : (what, path) of files the run appends to (a recording): compared like outputs,
        their folder checked by their writer

    Raises
    ------
    MaizevizError
        One line naming the output and the input (or the other output) it would overwrite.
    """
    ins = [place_of(p, what) for what, p in inputs if p is not None]
    outs: list[_Place] = []
    for what, path in outputs:
        if path is None:
            continue
        place = place_of(path, what)
        check_output(path)
        outs.append(place)
    outs += [place_of(p, what) for what, p in appended if p is not None]
    for folder in folders:
        if folder.path is None:
            continue
        place = place_of(folder.path, folder.what)
        if place.inode is not None and not place.is_dir:
            raise MaizevizError(f"{folder.path}: {folder.what} is an existing file, not a "
                                "folder; choose another name")
        for other in ins + outs:
            if place.same(other):
                raise MaizevizError(f"{folder.path}: {folder.what} is {other.what} "
                                    f"{other.shown}; choose another name")
        for name in folder.files:
            outs.append(place_of(Path(folder.path) / name, f"{folder.what}'s {name}"))
    for k, out in enumerate(outs):
        for src in ins:
            if out.same(src):
                raise MaizevizError(f"{out.shown}: {out.what} would overwrite {src.what} "
                                    f"{src.shown}; choose another name")
        for other in outs[:k]:
            if out.same(other):
                raise MaizevizError(f"{out.shown}: {out.what} and {other.what} would be the "
                                    f"same file ({other.shown}), and one would be lost; give "
                                    "each its own name")
