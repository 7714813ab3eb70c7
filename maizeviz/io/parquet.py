"""Points files in Parquet: the digitized points format as columns, for field-scale studies.

A Parquet points file holds the columns ``plant, leaf, row, col, x, y, z`` (any order, any
case; ids as integers, coordinates as floats, cm), one record per point, and any other column
(kept as text, as a CSV's extra columns are). It is what a CSV points file is, read about 20
times faster and about a third of the size: the same points, checks and messages. A file is
taken for Parquet by its content (it begins and ends with ``PAR1``), whatever its name.

Reading: a table whose ids are whole numbers in range and whose coordinates are numbers is
taken at once, column by column; any other table (a missing value, an id out of range, a text
column where a number belongs, a ``status`` column) is read as the CSV the same records make
(written by pyarrow, header on line 1), so that every message is the CSV reader's: "line N"
then names record N - 1, counted from 1.

Writing (:func:`write_points_parquet`): the grids' points rounded as the CSV writer rounds
them (the same numbers a CSV of the same grids reads back), plant and leaf ids as int32, rows
and columns as int16, in row groups of whole plants (about :data:`ROW_GROUP_POINTS` points
each), written as the grids come: a field is written without being held, and read plant by
plant.

References
----------
Apache Parquet file format, https://parquet.apache.org/docs/file-format/ (the magic number
``PAR1`` at both ends); pyarrow.parquet (``read_table``, ``ParquetWriter``).
"""

from __future__ import annotations

import io
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from maizeviz.errors import PointsFileError
from maizeviz.io.points_table import (
    MAX_ID,
    MAX_INDEX,
    MAX_LINES,
    MAX_POINTS,
    REQUIRED,
    PointsTable,
    is_parquet_name,
    shown,
)

#: The bytes a Parquet file begins and ends with.
MAGIC = b"PAR1"
#: Points per row group written, rounded to whole plants.
ROW_GROUP_POINTS = 1 << 20
#: Most text, once decoded, the columns beside the points may hold (bytes): a CSV line holds
#: at most 10,000 bytes, but a compressed Parquet column of one value repeated decodes to any
#: size from a small file.
MAX_EXTRA_TEXT_BYTES = 256 * 2**20


def is_parquet(path: str | Path) -> bool:
    """Whether the file at ``path`` is a Parquet file (its first four bytes); False when it is
    not a regular file or cannot be read (the reader then says why; a named pipe is never
    opened here: that would wait for a writer)."""
    import os
    import stat

    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except (OSError, ValueError):
        return False
    try:
        return stat.S_ISREG(os.fstat(fd).st_mode) and os.read(fd, 4) == MAGIC
    except OSError:
        return False
    finally:
        os.close(fd)


def _pyarrow(source: str):
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise PointsFileError(f"{source}: a Parquet file; reading it needs pyarrow "
                              "(pip install pyarrow)") from None
    return pa, pq


def read_parquet_table(path: str | Path, max_points: int = MAX_POINTS,
                       max_lines: int = MAX_LINES) -> PointsTable | str:
    """Read a Parquet points file (see the module docstring): its records when they are
    plain (numbers in range, no status column), else the table as CSV text for the CSV reader
    (:func:`maizeviz.io.points.read_points_parquet` reads it, so its messages are the CSV's).

    Raises
    ------
    PointsFileError
        Not a readable Parquet file, a required column missing, more than ``max_points``
        records (or ``max_lines``), no readable point; and whatever the CSV reader refuses.
    """
    source = str(path)
    pa, pq = _pyarrow(source)
    try:
        pf = pq.ParquetFile(path)
    except (pa.ArrowException, OSError) as exc:
        raise PointsFileError(f"{source}: not a readable Parquet file ({exc})") from None
    names = [n.strip().lower() for n in pf.schema_arrow.names]
    missing = [c for c in REQUIRED if c not in names]
    if missing:
        found = shown(",".join(names), 80)
        raise PointsFileError(f"{source}: missing column(s) {', '.join(missing)}; a points file "
                              f"needs the columns plant,leaf,row,col,x,y,z (found '{found}')")
    rows = pf.metadata.num_rows
    if rows > min(max_points, max_lines):
        raise PointsFileError(f"{source}: more than {min(max_points, max_lines):,} points; that "
                              f"many would take over {min(max_points, max_lines) * 64 / 1e9:.1f} "
                              "GB of memory (split the file by plant)")
    if len(set(names)) != len(names):
        raise PointsFileError(f"{source}: columns named alike ('{shown(','.join(names), 80)}')")
    _check_flat(pf.schema_arrow, source, pa)
    texts = [f.name for f in pf.schema_arrow if f.name.strip().lower() not in REQUIRED
             and _is_text(f.type, pa)]
    try:
        if texts:          # read as dictionaries: a repeated value is held once until checked
            pf = pq.ParquetFile(path, read_dictionary=texts)
        table = pf.read()
    except (pa.ArrowException, OSError) as exc:
        raise PointsFileError(f"{source}: not a readable Parquet file ({exc})") from None
    _check_text_size(table, texts, source)
    # the points' columns (and status) by their lower-case names; the others keep theirs
    table = table.rename_columns([n if n in (*REQUIRED, "status") else f.strip()
                                  for n, f in zip(names, pf.schema_arrow.names)])
    got = _plain(table, pa)
    if got is not None:
        ids, xyz = got
        extra = {n: [_cell(v) for v in table.column(n).to_pylist()]
                 for n in table.column_names if n not in REQUIRED}
        if not len(ids):
            raise PointsFileError(f"{source}: header only, no points")
        return PointsTable(ids=ids, xyz=xyz, line=np.arange(2, len(ids) + 2, dtype=np.int64),
                           extra=extra, source=source)
    return _as_csv(table, pa, source)


def _cell(v) -> str:
    """An extra column's value as the text a CSV holds: text as it is (blanks, tabs and
    line ends kept), bytes as UTF-8, a missing value as empty."""
    if v is None:
        return ""
    if isinstance(v, bytes):
        return v.decode("utf-8", errors="replace")
    return str(v)


def _check_flat(schema, source: str, pa) -> None:
    """Refuse a column of lists, structs, maps or unions, naming it: a points file's cells
    are numbers or text (such a column ended in ArrowNotImplementedError when the table was
    cast to text for the CSV reader's checks)."""
    for f in schema:
        t = f.type.value_type if pa.types.is_dictionary(f.type) else f.type
        if pa.types.is_nested(t) or pa.types.is_union(t):
            raise PointsFileError(f"{source}: column '{shown(f.name, 40)}' holds {t} values, "
                                  "not numbers or text: a points file's columns hold one "
                                  "number or text per record (flatten or drop it)")


def _is_text(t, pa) -> bool:
    """Whether an arrow type holds text or bytes (plain or dictionary-encoded)."""
    if pa.types.is_dictionary(t):
        t = t.value_type
    return bool(pa.types.is_string(t) or pa.types.is_large_string(t) or pa.types.is_binary(t)
                or pa.types.is_large_binary(t))


def _check_text_size(table, texts: list[str], source: str) -> None:
    """Refuse extra text columns holding more than :data:`MAX_EXTRA_TEXT_BYTES` once decoded
    (counted on their dictionaries, before any is decoded). A compressed column of one long
    value repeated is a small file that decodes to any size: 586 KB holding 100,000 records
    of a 5,000-character note took 1.5 GB to read, a million would take 15."""
    import pyarrow as pa
    import pyarrow.compute as pc

    total = 0
    for name in texts:
        for chunk in table.column(name).chunks:
            if not pa.types.is_dictionary(chunk.type):
                total += int(pc.sum(pc.binary_length(chunk)).as_py() or 0)
                continue
            lengths = pc.binary_length(chunk.dictionary).to_numpy(zero_copy_only=False)
            index = chunk.indices.fill_null(0).to_numpy(zero_copy_only=False)
            total += int(np.nan_to_num(lengths)[index].sum()) if len(lengths) else 0
        if total > MAX_EXTRA_TEXT_BYTES:
            raise PointsFileError(
                f"{source}: the text columns beside the points ('{shown(name, 40)}'...) hold "
                f"over {MAX_EXTRA_TEXT_BYTES // 2**20} MiB once read (they are kept as text, "
                "as a CSV's are): drop them, or split the file by plant")


def _plain(table, pa) -> tuple[np.ndarray, np.ndarray] | None:
    """(ids (N, 4) int64, xyz (N, 3) float64) of a table whose required columns are numbers
    without a missing value, ids whole and in range, coordinates finite and no ``status``
    column; None otherwise (read as CSV)."""
    if "status" in table.column_names:
        return None
    cols = []
    for name in REQUIRED:
        col = table.column(name)
        if not (pa.types.is_integer(col.type) or pa.types.is_floating(col.type)) \
                or col.null_count:
            return None
        cols.append(col.to_numpy())
    n = table.num_rows
    ids = np.empty((n, 4), np.int64)
    for k, (col, limit, low) in enumerate(zip(cols[:4], (MAX_ID, MAX_ID, MAX_INDEX, MAX_INDEX),
                                              (-MAX_ID, -MAX_ID, 0, 0))):
        if col.dtype.kind == "f":
            if not (np.isfinite(col).all() and np.all(col == np.floor(col))):
                return None
        if n and not (col.min() >= low and col.max() <= limit):
            return None
        ids[:, k] = col
    xyz = np.empty((n, 3))
    for k, col in enumerate(cols[4:]):
        xyz[:, k] = col
    if not np.isfinite(xyz).all():
        return None
    return ids, xyz


def _as_csv(table, pa, source: str) -> str:
    """The table as CSV text, every column as text."""
    import pyarrow.csv as pacsv

    out = io.BytesIO()
    try:
        strings = table.cast(pa.schema([(n, pa.string()) for n in table.column_names]))
    except (pa.ArrowNotImplementedError, pa.ArrowInvalid) as exc:   # a type without text
        why = shown(str(exc), 80)
        raise PointsFileError(f"{source}: a column cannot be read as text ({why}): a points "
                              "file's columns hold numbers or text") from None
    pacsv.write_csv(strings, out, pacsv.WriteOptions(quoting_style="needed"))
    return out.getvalue().decode("utf-8", errors="replace")


def exact_rounding(values: np.ndarray, decimals: int) -> np.ndarray:
    """``values`` rounded to ``decimals`` as ``float(f"{v:.{decimals}f}")`` rounds each: the
    numbers a CSV written with that many decimals reads back, computed with numpy (the few
    values within rounding of a half-way point are formatted one by one)."""
    v = np.asarray(values, dtype=np.float64)
    scale = 10.0 ** decimals
    with np.errstate(invalid="ignore", over="ignore"):
        scaled = v * scale
        frac = np.abs(scaled - np.trunc(scaled))
    # rint(v 10^d) is the decimal rounding unless the product's own rounding may have moved
    # it across a half-way point (or the product is too large for its units to be exact);
    # k / 10^d is then the double nearest to the decimal, as float() of its text is
    out = np.rint(scaled) / scale
    size = np.abs(scaled)
    near_half = np.abs(frac - 0.5) <= 4 * np.spacing(size)
    flat, src = out.reshape(-1), v.reshape(-1)
    for i in np.flatnonzero((near_half | ~(size < 2.0**50)).reshape(-1)):
        flat[i] = float(f"{src[i]:.{decimals}f}")
    return out


def write_points_parquet(path: str | Path, grids: Iterable, decimals: int = 3) -> None:
    """Write point grids as a Parquet points file, atomically (one record per point, tip
    rows written once, as :func:`maizeviz.io.points.write_points` writes a CSV).

    Parameters
    ----------
    grids : iterable of leaf grids (``plant``, ``leaf``, ``points`` (m, n, 3) cm,
        ``tip_collapsed``), plants in order, e.g. :class:`maizeviz.leaf.grid.LeafGrid`
    decimals : coordinates rounded to this many decimals (as the CSV writer writes them)
    """
    from maizeviz.io.atomic import atomic_open

    pa, pq = _pyarrow(str(path))
    id_types = (pa.int32(), pa.int32(), pa.int16(), pa.int16())     # ids within MAX_ID, rows
    schema = pa.schema([(n, t) for n, t in zip(REQUIRED[:4], id_types)] +   # within MAX_INDEX
                       [(n, pa.float64()) for n in REQUIRED[4:]])
    parts: list[np.ndarray] = []
    ids: list[np.ndarray] = []
    held = 0
    last_plant = None

    def group(writer) -> None:
        xyz = exact_rounding(np.concatenate(parts), decimals)
        idv = np.concatenate(ids)
        columns = [pa.array(idv[:, k], type=id_types[k]) for k in range(4)] + \
            [pa.array(xyz[:, k]) for k in range(3)]
        writer.write_table(pa.Table.from_arrays(columns, schema=schema))
        parts.clear()
        ids.clear()

    with atomic_open(path, "wb") as fh:
        with pq.ParquetWriter(fh, schema, compression="zstd") as writer:
            for g in grids:
                if g.plant != last_plant and held >= ROW_GROUP_POINTS:
                    group(writer)                       # whole plants in each row group
                    held = 0
                last_plant = g.plant
                pts = np.asarray(g.points, dtype=np.float64)
                m, n = pts.shape[:2]
                keep = m * n - ((n - 1) if g.tip_collapsed else 0)
                r, c = np.divmod(np.arange(keep), n)
                parts.append(pts.reshape(-1, 3)[:keep])
                ids.append(np.column_stack([np.full(keep, g.plant), np.full(keep, g.leaf),
                                            r, c]))
                held += keep
            if parts or not held:
                if not parts:
                    parts.append(np.empty((0, 3)))
                    ids.append(np.empty((0, 4), np.int64))
                group(writer)


def _narrow(a: np.ndarray) -> np.ndarray:
    """``a`` (ints) in the narrowest signed integer type holding every value."""
    if not len(a):
        return a.astype(np.int32)
    lo, hi = int(a.min()), int(a.max())
    for t in (np.int8, np.int16, np.int32, np.int64):
        info = np.iinfo(t)
        if info.min <= lo and hi <= info.max:
            return a.astype(t)
    return a                                                    # pragma: no cover


def write_table(path: str | Path, table: PointsTable, decimals: int | None = None) -> None:
    """Write the records of a points table (as read: ids, coordinates, extra columns as text)
    to ``path``, atomically: Parquet where its name ends in ``.parquet`` or ``.pq``, else CSV.

    ``decimals``: coordinates rounded as the CSV writer rounds them; None keeps them exactly
    (a CSV then holds each number's shortest text that reads back to it).
    """
    from maizeviz.io.atomic import atomic_open

    xyz = table.xyz if decimals is None else exact_rounding(table.xyz, decimals)
    if is_parquet_name(path):
        pa, pq = _pyarrow(str(path))
        columns = {name: pa.array(_narrow(table.ids[:, k])) for k, name in
                   enumerate(REQUIRED[:4])}
        columns.update({name: pa.array(xyz[:, k]) for k, name in enumerate(REQUIRED[4:])})
        columns.update({name: pa.array(values, pa.string())
                        for name, values in table.extra.items()})
        with atomic_open(path, "wb") as fh:
            pq.write_table(pa.table(columns), fh, compression="zstd",
                           row_group_size=ROW_GROUP_POINTS)
        return
    import csv

    with atomic_open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow([*REQUIRED, *table.extra])
        extra = list(zip(*table.extra.values())) if table.extra else [()] * len(table)
        for ids, p, more in zip(table.ids.tolist(), xyz.tolist(), extra):
            writer.writerow([*ids, *(repr(v) if decimals is None else f"{v:.{decimals}f}"
                                     for v in p), *more])


class NotStreamable(Exception):
    """A Parquet points file that cannot be read plant chunk by plant chunk (records needing
    the CSV reader's checks, or a plant's records not together): read it whole instead."""


def parquet_rows(path: str | Path) -> int | None:
    """Records of a Parquet file from its footer (None when it is not a readable one)."""
    try:
        _, pq = _pyarrow(str(path))
        return int(pq.ParquetFile(path).metadata.num_rows)
    except Exception:                                    # noqa: BLE001 - the reader says why
        return None


def read_rows(path: str | Path, start: int, stop: int) -> PointsTable:
    """The records [start, stop) of a Parquet points file whose records are plain (as
    :func:`point_chunks` found them), line numbers as
    :func:`maizeviz.io.points.read_points_parquet` gives them.

    Raises
    ------
    NotStreamable
        They are not plain (the file changed since).
    """
    source = str(path)
    pa, pq = _pyarrow(source)
    pf = pq.ParquetFile(path)
    names = pf.schema_arrow.names
    lower = [n.strip().lower() for n in names]
    wanted = [names[lower.index(c)] for c in REQUIRED]
    sizes = [pf.metadata.row_group(k).num_rows for k in range(pf.metadata.num_row_groups)]
    ends = np.cumsum(sizes)
    first = int(np.searchsorted(ends, start, side="right"))
    last = int(np.searchsorted(ends, stop - 1, side="right")) if stop > start else first
    table = pf.read_row_groups(list(range(first, last + 1)), columns=wanted)
    begin = start - (int(ends[first - 1]) if first else 0)
    table = table.slice(begin, stop - start).rename_columns(list(REQUIRED))
    got = _plain(table, pa)
    if got is None:
        raise NotStreamable(source)
    ids, xyz = got
    return PointsTable(ids=ids, xyz=xyz, line=np.arange(start + 2, stop + 2, dtype=np.int64),
                       source=source)


def _streamable(path: str | Path):
    """(pyarrow, the ParquetFile, the required columns' names in it) of a points file whose
    records can be read in chunks.

    Raises
    ------
    PointsFileError
        Not a readable Parquet file, or a required column missing.
    NotStreamable
        A ``status`` column or a column named twice (the CSV reader's checks).
    """
    source = str(path)
    pa, pq = _pyarrow(source)
    try:
        pf = pq.ParquetFile(path)
    except (pa.ArrowException, OSError) as exc:
        raise PointsFileError(f"{source}: not a readable Parquet file ({exc})") from None
    names = pf.schema_arrow.names
    lower = [n.strip().lower() for n in names]
    missing = [c for c in REQUIRED if c not in lower]
    if missing:
        found = shown(",".join(lower), 80)
        raise PointsFileError(f"{source}: missing column(s) {', '.join(missing)}; a points file "
                              f"needs the columns plant,leaf,row,col,x,y,z (found '{found}')")
    if "status" in lower or len(set(lower)) != len(lower):
        raise NotStreamable(source)
    return pa, pf, [names[lower.index(c)] for c in REQUIRED]


def plant_chunk_bounds(path: str | Path, chunk_points: int = ROW_GROUP_POINTS
                       ) -> list[tuple[int, int]]:
    """Records [start, stop) of chunks of whole plants of a Parquet points file, each the
    plants starting before ``chunk_points`` records have gathered, read from its plant column
    alone (a hectare's 72 million records: about a second): what :func:`read_rows` of each
    gives, chunk by chunk, to workers side by side.

    Raises
    ------
    PointsFileError
        As :func:`point_chunks`.
    NotStreamable
        As :func:`point_chunks`, for the plant column (not whole numbers, a plant's records
        not together); the other columns are checked by :func:`read_rows`.
    """
    source = str(path)
    pa, pf, wanted = _streamable(path)
    starts: list[np.ndarray] = []
    firsts: list[np.ndarray] = []
    last = None
    n = 0
    try:
        for batch in pf.iter_batches(batch_size=1 << 22, columns=[wanted[0]]):
            col = batch.column(0)
            if not pa.types.is_integer(col.type) or col.null_count:
                raise NotStreamable(source)
            ids = col.to_numpy()
            if not len(ids):
                continue
            new = np.flatnonzero(np.r_[last is None or ids[:1] != last, ids[1:] != ids[:-1]])
            starts.append(new + n)
            firsts.append(ids[new])
            last = ids[-1:]
            n += len(ids)
    except (pa.ArrowException, OSError) as exc:
        raise PointsFileError(f"{source}: not a readable Parquet file ({exc})") from None
    at = np.concatenate(starts) if starts else np.zeros(0, np.int64)
    plants = np.concatenate(firsts) if firsts else np.zeros(0, np.int64)
    if len(np.unique(plants)) != len(plants):
        raise NotStreamable(f"{source}: the records of a plant are not together")
    bounds = []
    begin = 0
    for k in range(1, len(at)):
        if at[k] - begin >= chunk_points:
            bounds.append((begin, int(at[k])))
            begin = int(at[k])
    if n > begin:
        bounds.append((begin, n))
    return bounds


def point_chunks(path: str | Path, chunk_points: int = ROW_GROUP_POINTS):
    """The points of a Parquet file in tables of whole plants, about ``chunk_points`` points
    each, in the file's order (line numbers as
    :func:`maizeviz.io.points.read_points_parquet` gives them; extra columns left out).

    Yields
    ------
    PointsTable

    Raises
    ------
    PointsFileError
        As :func:`read_parquet_table`, for the file as a whole.
    NotStreamable
        A chunk holds records the CSV reader must check, or a plant's records are not
        together in the file.
    """
    source = str(path)
    pa, pf, wanted = _streamable(path)
    done: set[int] = set()
    carry: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    first = 0

    def emit(ids, xyz, line) -> PointsTable:
        plants = set(np.unique(ids[:, 0]).tolist())
        if plants & done:
            raise NotStreamable(f"{source}: the records of a plant are not together")
        done.update(plants)
        return PointsTable(ids=ids, xyz=xyz, line=line, source=source)

    try:
        for batch in pf.iter_batches(batch_size=max(1, chunk_points), columns=wanted):
            table = pa.Table.from_batches([batch]).rename_columns(list(REQUIRED))
            got = _plain(table, pa)
            if got is None:
                raise NotStreamable(source)
            ids, xyz = got
            line = np.arange(first + 2, first + 2 + len(ids), dtype=np.int64)
            first += len(ids)
            if carry is not None:
                ids, xyz, line = (np.concatenate([c, x]) for c, x in zip(carry, (ids, xyz, line)))
            # the last plant may go on in the next batch: hold it back
            tail = len(ids) - int(np.argmax(ids[::-1, 0] != ids[-1, 0])) \
                if np.any(ids[:, 0] != ids[-1, 0]) else 0
            carry = (ids[tail:], xyz[tail:], line[tail:])
            if tail:
                yield emit(ids[:tail], xyz[:tail], line[:tail])
    except (pa.ArrowException, OSError) as exc:
        raise PointsFileError(f"{source}: not a readable Parquet file ({exc})") from None
    if carry is not None and len(carry[0]):
        yield emit(*carry)
