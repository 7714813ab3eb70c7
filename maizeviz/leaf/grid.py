"""Gather digitized points into one rows x cols grid per leaf, repairing what is safe.

Convention (docs/method.md, section 1): ``row`` i runs along the midrib from the collar (0) to the
tip, ``col`` j across the blade from one margin (0) over the midrib to the other margin.

Repairs, each reported in :attr:`LeafGrid.notes`:
- consecutive duplicate points in a cross-section (a press recorded twice) are merged;
- a cross-section identical to the previous one is merged;
- a tip row collapsed to a single point is legal and is repeated across the columns;
- a cross-section with a different number of points is resampled to the common count along
  its own polyline, at the mean normalised arc-length positions of the regular rows.

Everything else is refused with a :class:`~maizeviz.errors.LeafError` naming plant, leaf, row
and col.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from maizeviz.errors import LeafError
from maizeviz.progress import ProgressCallback, report

#: Points closer than this (cm) are the same press: the FASTRAK prints 0.01 cm steps.
DUPLICATE_TOL_CM = 0.005
#: No digitized coordinate is farther than this from the transmitter (cm).
MAX_ABS_COORD_CM = 1.0e5


@dataclass(frozen=True)
class LeafGrid:
    """The point grid of one leaf.

    Attributes
    ----------
    plant, leaf : int
    points : (m, n, 3) float64, cm
        ``points[i, j]``: cross-section i (collar to tip), position j (margin to margin).
    tip_collapsed : bool
        The last row is one point repeated n times.
    rows : (m,) int
        Row index in the points file of each grid row (after merging duplicate rows).
    notes : tuple[str, ...]
        Repairs made, in words.
    """

    plant: int
    leaf: int
    points: np.ndarray
    tip_collapsed: bool = False
    rows: tuple[int, ...] = ()
    notes: tuple[str, ...] = ()

    @property
    def shape(self) -> tuple[int, int]:
        return self.points.shape[0], self.points.shape[1]

    @property
    def key(self) -> tuple[int, int]:
        return self.plant, self.leaf

    @property
    def collar(self) -> np.ndarray:
        """(3,) cm: the midrib point of the collar cross-section, where the leaf is inserted
        on the stalk."""
        return self.points[0, self.points.shape[1] // 2]


def stalk_base(grids) -> tuple[float, float]:
    """(x, y) cm of a plant's stalk base: the median of its leaves' collar points seen from
    above (``grids``: the plant's LeafGrids, at least one)."""
    return base_of_collars(np.array([g.collar[:2] for g in grids]))


def base_of_collars(collars: np.ndarray) -> tuple[float, float]:
    """(x, y) cm: the median of collar points (k, 2) cm seen from above (:func:`stalk_base`)."""
    return float(np.median(collars[:, 0])), float(np.median(collars[:, 1]))


def _polyline_resample(points: np.ndarray, fractions: np.ndarray) -> np.ndarray:
    """Resample a polyline (k, 3) at normalised arc-length ``fractions`` (n,) -> (n, 3)."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    s /= s[-1]
    return np.column_stack([np.interp(fractions, s, points[:, a]) for a in range(3)])


def _merge_duplicates(points: np.ndarray) -> np.ndarray:
    """Drop points that repeat the previous one within :data:`DUPLICATE_TOL_CM`."""
    if len(points) < 2:
        return points
    step = np.linalg.norm(np.diff(points, axis=0), axis=1)
    keep = np.concatenate([[True], step > DUPLICATE_TOL_CM])
    return points[keep]


def _check_coordinates(pts: np.ndarray, r: int, colids, fail, lines=None) -> None:
    """Refuse (through ``fail``) a row's first coordinate that is not a number or lies beyond
    :data:`MAX_ABS_COORD_CM` [cm], naming its row and col, and its line in the file when
    ``lines`` ((k,) int) are known; the axis too, as the reader names a value it cannot read."""
    def at(k: int, axis: int) -> str:
        where = f" (line {lines[k]})" if lines is not None else ""
        return f"row {r}, col {colids[k]}{where}: {'xyz'[axis]}"

    bad = ~np.isfinite(pts)
    if bad.any():
        k = int(np.argwhere(bad.any(axis=1))[0, 0])
        axis = int(np.argmax(bad[k]))
        fail(f"{at(k, axis)} is {pts[k, axis]} (not a number)")
    huge = np.abs(pts) > MAX_ABS_COORD_CM
    if huge.any():
        k = int(np.argwhere(huge.any(axis=1))[0, 0])
        axis = int(np.argmax(huge[k]))
        fail(f"{at(k, axis)} = {pts[k, axis]:g} cm is beyond "
             f"{MAX_ABS_COORD_CM:g} cm; not a digitized point")


def _columns(kept_rows: list[int], counts: list[int], fail) -> int:
    """The columns of the leaf's grid: the most common point count of its rows of more than
    one point (the larger on a tie); refused (through ``fail``) where a row other than the
    tip is a single point, or there are fewer than 2 rows or 2 columns."""
    for r, c in zip(kept_rows, counts):
        if c == 1 and (r != kept_rows[-1] or len(counts) == 1):
            where = "at the collar" if r == kept_rows[0] else "in the middle of the leaf"
            fail(f"row {r}: a single point {where}; only the tip row may collapse to one point")
    regular = [c for c in counts if c > 1]
    if len(counts) < 2:
        fail(f"only {len(counts)} row; a leaf needs at least 2 cross-sections")
    if not regular:
        fail("every row is a single point; a leaf needs at least 2 points across")
    tally = Counter(regular)
    n = max(tally, key=lambda c: (tally[c], c))
    if n < 2:  # pragma: no cover - regular rows have > 1 point by construction
        fail("fewer than 2 columns")
    return n


def grid_from_rows(plant: int, leaf: int, rows: dict[int, np.ndarray],
                   cols: dict[int, np.ndarray] | None = None,
                   lines: dict[int, np.ndarray] | None = None) -> LeafGrid:
    """Build a :class:`LeafGrid` from the points of each cross-section.

    Parameters
    ----------
    rows : {row index: (k, 3) float64 cm}
        Points of each cross-section in column order.
    cols : {row index: (k,) int}, optional
        Column indices of those points, only used to name positions in messages.
    lines : {row index: (k,) int}, optional
        Line numbers of those points in their file, only used in messages.

    Raises
    ------
    LeafError
        Naming row and col of the first problem.
    """
    def fail(msg: str):
        raise LeafError(plant, leaf, msg)

    if not rows:
        fail("no points")
    indices = sorted(rows)
    expected = list(range(indices[0], indices[0] + len(indices)))
    if indices[0] != 0:
        fail(f"rows start at {indices[0]}: row(s) 0..{indices[0] - 1} missing "
             "(row 0 is the cross-section at the collar)")
    if indices != expected:
        gaps = sorted(set(range(indices[-1] + 1)) - set(indices))
        fail(f"row(s) {', '.join(map(str, gaps))} missing between rows 0 and {indices[-1]}")

    notes = []
    cleaned = []
    for r in indices:
        pts = np.asarray(rows[r], dtype=np.float64).reshape(-1, 3)
        _check_coordinates(pts, r, cols[r] if cols is not None else np.arange(len(pts)), fail,
                           lines[r] if lines is not None else None)
        merged = _merge_duplicates(pts)
        if len(merged) < len(pts):
            notes.append(f"row {r}: merged {len(pts) - len(merged)} duplicate point(s)")
        cleaned.append(merged)

    # merge cross-sections identical to the previous one (a repeated section)
    kept_rows, kept = [indices[0]], [cleaned[0]]
    for r, pts in zip(indices[1:], cleaned[1:]):
        prev = kept[-1]
        if len(prev) == len(pts) and np.all(np.linalg.norm(prev - pts, axis=1) <= DUPLICATE_TOL_CM):
            notes.append(f"row {r}: same points as row {kept_rows[-1]}, merged")
            continue
        kept_rows.append(r)
        kept.append(pts)

    counts = [len(p) for p in kept]
    tip_collapsed = counts[-1] == 1 and len(kept) > 1
    n = _columns(kept_rows, counts, fail)

    # resample ragged rows at the mean arc-length fractions of the regular ones
    reg = [p for p in kept if len(p) == n]
    fr = []
    for p in reg:
        seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
        fr.append(np.concatenate([[0.0], np.cumsum(seg)]) / seg.sum())
    fractions = np.mean(fr, axis=0)
    grid = np.empty((len(kept), n, 3))
    for i, (r, p) in enumerate(zip(kept_rows, kept)):
        if len(p) == n:
            grid[i] = p
        elif len(p) == 1:
            grid[i] = p[0]
        else:
            notes.append(f"row {r}: {len(p)} points, the others {n}; resampled along its polyline")
            grid[i] = _polyline_resample(p, fractions)
    return LeafGrid(plant, leaf, grid, tip_collapsed, tuple(kept_rows), tuple(notes))


def build_grids(table, strict: bool = False, progress: ProgressCallback | None = None
                ) -> tuple[list[LeafGrid], list[LeafError]]:
    """Gather a :class:`~maizeviz.io.points.PointsTable` into leaf grids.

    Leaves that need nothing repaired (rows 0 .. m-1, every row with the same number n >= 2 of
    points, or the last with one point, a collapsed tip; no point or row repeated, every
    coordinate a number within :data:`MAX_ABS_COORD_CM`), the common case, are assembled with
    a few numpy calls per grid shape; the others go through :func:`grid_from_rows`, which
    repairs or refuses them. Both give the same grids, notes and errors.

    Parameters
    ----------
    table : PointsTable (ids (N, 4) plant, leaf, row, col; xyz (N, 3) cm; line (N,))
    strict : raise on the first refused leaf instead of listing it
    progress : ``progress(done, total)`` in leaves; returning ``False`` stops with
        :class:`InterruptedError`

    Returns
    -------
    grids : list of LeafGrid, sorted by (plant, leaf)
    errors : list of LeafError, one per refused leaf

    Raises
    ------
    LeafError
        With ``strict=True``, on the first refused leaf.
    """
    ids, xyz, line = table.ids, table.xyz, table.line
    if len(ids) and not _lexsorted(ids):
        order = np.lexsort((ids[:, 3], ids[:, 2], ids[:, 1], ids[:, 0]))
        ids, xyz, line = ids[order], xyz[order], line[order]
    seg = _Segments(ids, xyz)
    found = {key: k for k, key in enumerate(seg.keys)}
    keys = sorted(set(found) | set(table.bad_leaves))
    total = len(keys)
    fast = _regular_grids(seg, xyz)
    grids, errors = [], []
    for done, key in enumerate(keys, start=1):
        plant, leaf = key
        k = found.get(key, -1)
        try:
            if key in table.bad_leaves:
                raise LeafError(plant, leaf, "; ".join(table.bad_leaves[key]))
            grid = fast.get(k)
            if grid is None:
                grid = _grid_of_leaf(plant, leaf, ids, xyz, line, seg.start[k], seg.start[k + 1])
            grids.append(grid)
        except LeafError as exc:
            if strict:
                raise
            errors.append(exc)
        if done % 4096 == 0 or done == total:
            report(progress, done, total, "gathering leaf grids")
    return grids, errors


def _lexsorted(ids: np.ndarray, block: int = 1 << 20) -> bool:
    """Whether rows of ``ids`` (N, c) int are in lexicographic order (ties allowed), checked
    ``block`` rows at a time."""
    for s in range(0, len(ids) - 1, block):
        part = ids[s:s + block + 1]
        less = np.zeros(len(part) - 1, dtype=bool)
        same = np.ones(len(part) - 1, dtype=bool)
        for c in range(ids.shape[1]):
            d = part[1:, c] - part[:-1, c]
            less |= same & (d < 0)
            same &= d == 0
        if less.any():
            return False
    return True


class _Segments:
    """Leaves and rows of points sorted by (plant, leaf, row, col).

    Attributes
    ----------
    keys : list of (plant, leaf), one per leaf, sorted
    start : (K + 1,) int: leaf k holds points start[k] .. start[k + 1] - 1
    row_start : (R + 1,) int: the same for the rows of all leaves, in order
    row_leaf : (R,) int: the leaf of each row
    first_row : (K + 1,) int: leaf k holds rows first_row[k] .. first_row[k + 1] - 1
    """

    def __init__(self, ids: np.ndarray, xyz: np.ndarray):
        n = len(ids)
        leaf_change = (ids[1:, 0] != ids[:-1, 0]) | (ids[1:, 1] != ids[:-1, 1])
        row_change = leaf_change | (ids[1:, 2] != ids[:-1, 2])
        self.start = np.concatenate([[0], np.flatnonzero(leaf_change) + 1, [n]]) if n else \
            np.zeros(1, dtype=np.int64)
        self.keys = [(int(p), int(q)) for p, q in ids[self.start[:-1], :2]]
        self.row_start = np.concatenate([[0], np.flatnonzero(row_change) + 1, [n]]) if n else \
            np.zeros(1, dtype=np.int64)
        self.row_leaf = np.searchsorted(self.start, self.row_start[:-1], side="right") - 1
        self.first_row = np.searchsorted(self.row_leaf, np.arange(len(self.keys) + 1))
        self.row_index = ids[self.row_start[:-1], 2]
        #: (N - 1,) bool: point i + 1 starts a row; (N - 1,) bool: it repeats the (row, col)
        self.row_change = row_change
        self.same_col = ~row_change & (ids[1:, 3] == ids[:-1, 3])


def _regular_grids(seg: _Segments, xyz: np.ndarray) -> dict[int, LeafGrid]:
    """The grids of the leaves that need no repair, by leaf number, built per grid shape."""
    nleaves = len(seg.keys)
    if nleaves == 0:
        return {}
    row_len = np.diff(seg.row_start)
    nrows = np.diff(seg.first_row)
    # a point that rules its leaf out: not a number or absurd, the same place as the previous
    # point of its row (a press recorded twice), or the same row and col as it
    bad_point = ~np.isfinite(xyz).all(axis=1) | (np.abs(xyz) > MAX_ABS_COORD_CM).any(axis=1)
    step = np.linalg.norm(np.diff(xyz, axis=0), axis=1)
    repeat = (~seg.row_change & ~(step > DUPLICATE_TOL_CM)) | seg.same_col
    bad_leaf = np.zeros(nleaves, dtype=bool)
    leaf_of_point = np.repeat(np.arange(nleaves), np.diff(seg.start))
    bad_leaf[leaf_of_point[bad_point]] = True
    bad_leaf[leaf_of_point[1:][repeat]] = True
    # rows numbered 0 .. m-1 in each leaf
    rank = np.arange(len(seg.row_index)) - seg.first_row[seg.row_leaf]
    bad_leaf[seg.row_leaf[seg.row_index != rank]] = True
    # every row with n >= 2 points, the last one with n or 1
    first = seg.first_row[:-1]
    last = seg.first_row[1:] - 1
    n = row_len[first]
    tip = row_len[last] == 1
    bad_leaf |= (nrows < 2) | (n < 2)
    wrong = row_len != n[seg.row_leaf]
    wrong[last[tip]] = False
    bad_leaf[seg.row_leaf[wrong]] = True
    out: dict[int, LeafGrid] = {}
    ok = np.flatnonzero(~bad_leaf)
    shapes = np.stack([nrows[ok], n[ok], tip[ok]], axis=1)
    for m, cols, is_tip in np.unique(shapes, axis=0).tolist():
        which = ok[np.all(shapes == (m, cols, is_tip), axis=1)]
        full = m - is_tip
        take = seg.start[which][:, None] + np.arange(full * cols)
        grid = np.empty((len(which), m, cols, 3))
        grid[:, :full] = xyz[take].reshape(len(which), full, cols, 3)
        if is_tip:
            grid[:, -1] = xyz[seg.start[which] + full * cols][:, None, :]
        # a row with the same points as the one before is merged by grid_from_rows
        same = np.all(np.linalg.norm(grid[:, :full - 1] - grid[:, 1:full], axis=-1)
                      <= DUPLICATE_TOL_CM, axis=-1).any(axis=-1)
        rows = tuple(range(m))
        for k, g in zip(which[~same].tolist(), grid[~same]):
            plant, leaf = seg.keys[k]
            out[k] = LeafGrid(plant, leaf, g, bool(is_tip), rows, ())
    return out


def _grid_of_leaf(plant: int, leaf: int, ids: np.ndarray, xyz: np.ndarray, line: np.ndarray,
                  a: int, b: int) -> LeafGrid:
    """:func:`grid_from_rows` of the points ``a .. b - 1`` of sorted arrays (one leaf)."""
    rc = ids[a:b, 2:]
    dup = np.flatnonzero(np.all(np.diff(rc, axis=0) == 0, axis=1))
    if len(dup):
        k = a + dup[0]
        raise LeafError(plant, leaf, f"row {ids[k, 2]}, col {ids[k, 3]} appears twice "
                                     f"(lines {line[k]} and {line[k + 1]})")
    rows, cols, lines = {}, {}, {}
    for r in np.unique(rc[:, 0]):
        sel = slice(a + np.searchsorted(rc[:, 0], r, "left"),
                    a + np.searchsorted(rc[:, 0], r, "right"))
        rows[int(r)] = xyz[sel]
        cols[int(r)] = ids[sel, 3]
        lines[int(r)] = line[sel]
    return grid_from_rows(plant, leaf, rows, cols, lines)
