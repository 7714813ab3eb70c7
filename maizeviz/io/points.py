"""Read and write the digitized points format.

CSV with a header; required columns ``plant,leaf,row,col,x,y,z`` (any order, any case), other
columns are kept as text in :attr:`PointsTable.extra`. A ``status`` column (written by
``maizeviz record``) is honoured: ``undone`` lines take back the latest recording of that
point, and control lines (``next_leaf``, ``next_plant``, ``end_row``) carry no point. ``x, y, z`` are centimetres, z up.
A row whose ids cannot be read is reported and skipped; a row whose coordinates cannot be read
marks its leaf as bad (the leaf is refused later with the line number), so one bad press never
takes the other leaves down with it.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from maizeviz.errors import PointsFileError
from maizeviz.io.atomic import atomic_open

REQUIRED = ("plant", "leaf", "row", "col", "x", "y", "z")
ID_COLUMNS = ("plant", "leaf", "row", "col")


@dataclass(frozen=True)
class PointsTable:
    """All readable points of a file, one entry per CSV line.

    Attributes
    ----------
    ids : (N, 4) int64
        plant, leaf, row, col.
    xyz : (N, 3) float64, cm
        Coordinates as written (may hold NaN: the grid builder refuses those by position).
    line : (N,) int64
        1-based line number in the file, for messages.
    extra : dict[str, list[str]]
        Other columns, as text, aligned with ``ids``.
    problems : list[str]
        Lines that were skipped, with the reason.
    bad_leaves : dict[(plant, leaf), list[str]]
        Leaves with an unreadable coordinate; they are refused by the grid builder.
    source : str
        Where the table came from (file name), for messages.
    """

    ids: np.ndarray
    xyz: np.ndarray
    line: np.ndarray
    extra: dict = field(default_factory=dict)
    problems: list = field(default_factory=list)
    bad_leaves: dict = field(default_factory=dict)
    source: str = "<memory>"

    def __len__(self) -> int:
        return len(self.line)


def _parse_int(text: str) -> int:
    value = float(text)  # accepts "3", "3.0", " 3 "
    if not math.isfinite(value) or value != int(value):
        raise ValueError
    return int(value)


def read_points(path: str | Path) -> PointsTable:
    """Read a points CSV file.

    Raises
    ------
    PointsFileError
        The file is missing, empty, binary, has no header or lacks a required column, or
        not one line could be read.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise PointsFileError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise PointsFileError(f"{path}: is a folder, not a points file") from None
    except OSError as exc:
        raise PointsFileError(f"{path}: cannot be read ({exc.strerror})") from None
    if b"\x00" in raw[:4096]:
        raise PointsFileError(f"{path}: not a CSV text file (binary content)")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        try:
            text = raw.decode("latin-1")
        except UnicodeDecodeError:  # pragma: no cover - latin-1 decodes every byte
            raise PointsFileError(f"{path}: not a text file") from None
    return parse_points(text, source=str(path))


def parse_points(text: str, source: str = "<memory>") -> PointsTable:
    """Parse the text of a points CSV file; see :func:`read_points`."""
    try:
        return _parse(text, source)
    except csv.Error as exc:                       # a field over csv's size limit, a NUL...
        raise PointsFileError(f"{source}: not a readable CSV file ({exc})") from None


def _parse(text: str, source: str) -> PointsTable:
    text = text.lstrip("\ufeff")
    if not text.strip():
        raise PointsFileError(f"{source}: the file is empty")
    first = text.lstrip().splitlines()[0]
    delimiter = ","
    if "," not in first:
        delimiter = ";" if ";" in first else ("\t" if "\t" in first else ",")
    reader = csv.reader(io.StringIO(text), delimiter=delimiter)
    header = None
    header_line = 0
    for header_line, fields in enumerate(reader, start=1):
        if any(f.strip() for f in fields):
            header = [f.strip().lower() for f in fields]
            break
    missing = [c for c in REQUIRED if c not in (header or [])]
    if missing:
        shown = ",".join(header or [])[:80]
        raise PointsFileError(
            f"{source}: line {header_line}: missing column(s) {', '.join(missing)}; "
            f"a points file needs the header plant,leaf,row,col,x,y,z (found '{shown}')")
    index = {name: header.index(name) for name in REQUIRED}
    extra_names = [h for h in header if h and h not in REQUIRED]
    extra_index = {h: header.index(h) for h in extra_names}

    ids, xyz, lines, problems = [], [], [], []
    extra = {h: [] for h in extra_names}
    bad_leaves: dict = {}
    status_col = header.index("status") if "status" in header else None
    undone = []                                   # (ids, line) taken back by the technician
    for lineno, fields in enumerate(reader, start=header_line + 1):
        if not any(f.strip() for f in fields):
            continue
        if len(fields) < len(header):
            fields = fields + [""] * (len(header) - len(fields))
        if status_col is not None:
            status = fields[status_col].strip().lower()
            if status == "undone":
                try:
                    undone.append((tuple(_parse_int(fields[index[c]]) for c in ID_COLUMNS),
                                   len(ids)))
                except ValueError:
                    problems.append(f"line {lineno}: unreadable undo line; skipped")
                continue
            if status not in ("", "recorded", "ok"):
                continue                          # session controls carry no point
        try:
            plant = _parse_int(fields[index["plant"]])
            leaf = _parse_int(fields[index["leaf"]])
        except ValueError:
            problems.append(
                f"line {lineno}: plant/leaf id is not an integer "
                f"('{fields[index['plant']].strip()}', '{fields[index['leaf']].strip()}'); line skipped")
            continue
        try:
            row = _parse_int(fields[index["row"]])
            col = _parse_int(fields[index["col"]])
        except ValueError:
            bad_leaves.setdefault((plant, leaf), []).append(
                f"line {lineno}: row/col is not a whole number "
                f"('{fields[index['row']].strip()}', '{fields[index['col']].strip()}')")
            continue
        if row < 0 or col < 0:
            bad_leaves.setdefault((plant, leaf), []).append(
                f"line {lineno}: row {row}, col {col}: negative index")
            continue
        coords = []
        for axis in "xyz":
            value = fields[index[axis]].strip()
            try:
                coords.append(float(value))
            except ValueError:
                bad_leaves.setdefault((plant, leaf), []).append(
                    f"row {row}, col {col} (line {lineno}): {axis} is not a number ('{value}')")
                break
        else:
            ids.append((plant, leaf, row, col))
            xyz.append(coords)
            lines.append(lineno)
            for h, i in extra_index.items():
                extra[h].append(fields[i].strip())
    if undone:                                    # drop each undone point (its latest recording)
        keep = np.ones(len(ids), dtype=bool)
        for key, before in undone:
            for k in range(before - 1, -1, -1):
                if keep[k] and ids[k] == key:
                    keep[k] = False
                    break
        ids = [v for v, k in zip(ids, keep) if k]
        xyz = [v for v, k in zip(xyz, keep) if k]
        lines = [v for v, k in zip(lines, keep) if k]
        extra = {h: [v for v, k in zip(vals, keep) if k] for h, vals in extra.items()}
    if not ids and not bad_leaves:
        if problems:
            raise PointsFileError(f"{source}: no readable point; first problem: {problems[0]}")
        raise PointsFileError(f"{source}: header only, no points")
    return PointsTable(
        ids=np.asarray(ids, dtype=np.int64).reshape(-1, 4),
        xyz=np.asarray(xyz, dtype=np.float64).reshape(-1, 3),
        line=np.asarray(lines, dtype=np.int64),
        extra=extra,
        problems=problems,
        bad_leaves=bad_leaves,
        source=source,
    )


def write_points(path: str | Path, grids, decimals: int = 3) -> None:
    """Write point grids in the points format (one line per point, tip rows written once),
    atomically.

    Parameters
    ----------
    grids : iterable of leaf grids (``plant``, ``leaf``, ``points`` (m, n, 3) cm,
        ``tip_collapsed``), e.g. :class:`maizeviz.leaf.grid.LeafGrid`
    """
    with atomic_open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(REQUIRED)
        for g in grids:
            for r in range(g.points.shape[0]):
                row = g.points[r]
                if r == g.points.shape[0] - 1 and g.tip_collapsed:
                    row = row[:1]
                for c, p in enumerate(row):
                    writer.writerow([g.plant, g.leaf, r, c, *(f"{v:.{decimals}f}" for v in p)])
