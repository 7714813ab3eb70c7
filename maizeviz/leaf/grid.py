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


def grid_from_rows(plant: int, leaf: int, rows: dict[int, np.ndarray],
                   cols: dict[int, np.ndarray] | None = None) -> LeafGrid:
    """Build a :class:`LeafGrid` from the points of each cross-section.

    Parameters
    ----------
    rows : {row index: (k, 3) float64 cm}
        Points of each cross-section in column order.
    cols : {row index: (k,) int}, optional
        Column indices of those points, only used to name positions in messages.

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
        colids = cols[r] if cols is not None else np.arange(len(pts))
        bad = ~np.isfinite(pts)
        if bad.any():
            k = int(np.argwhere(bad.any(axis=1))[0, 0])
            fail(f"row {r}, col {colids[k]}: coordinate is {pts[k][bad[k]][0]} (not a number)")
        huge = np.abs(pts) > MAX_ABS_COORD_CM
        if huge.any():
            k = int(np.argwhere(huge.any(axis=1))[0, 0])
            fail(f"row {r}, col {colids[k]}: coordinate {pts[k][huge[k]][0]:g} cm is beyond "
                 f"{MAX_ABS_COORD_CM:g} cm; not a digitized point")
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
    single = [r for r, c in zip(kept_rows, counts) if c == 1]
    tip_collapsed = counts[-1] == 1 and len(kept) > 1
    for r in single:
        if r != kept_rows[-1] or len(kept) == 1:
            where = "at the collar" if r == kept_rows[0] else "in the middle of the leaf"
            fail(f"row {r}: a single point {where}; only the tip row may collapse to one point")
    regular = [c for c in counts if c > 1]
    if len(kept) < 2:
        fail(f"only {len(kept)} row; a leaf needs at least 2 cross-sections")
    if not regular:
        fail("every row is a single point; a leaf needs at least 2 points across")
    tally = Counter(regular)
    n = max(tally, key=lambda c: (tally[c], c))
    if n < 2:  # pragma: no cover - regular rows have > 1 point by construction
        fail("fewer than 2 columns")

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


def build_grids(table, strict: bool = False) -> tuple[list[LeafGrid], list[LeafError]]:
    """Gather a :class:`~maizeviz.io.points.PointsTable` into leaf grids.

    Returns
    -------
    grids : list of LeafGrid, sorted by (plant, leaf)
    errors : list of LeafError, one per refused leaf

    Raises
    ------
    LeafError
        With ``strict=True``, on the first refused leaf.
    """
    grids, errors = [], []
    keys = sorted(set(map(tuple, table.ids[:, :2].tolist())) | set(table.bad_leaves))
    order = np.lexsort((table.ids[:, 3], table.ids[:, 2], table.ids[:, 1], table.ids[:, 0]))
    ids, xyz, line = table.ids[order], table.xyz[order], table.line[order]
    starts = {}
    if len(ids):
        change = np.flatnonzero(np.any(np.diff(ids[:, :2], axis=0) != 0, axis=1)) + 1
        bounds = np.concatenate([[0], change, [len(ids)]])
        for a, b in zip(bounds[:-1], bounds[1:]):
            starts[(int(ids[a, 0]), int(ids[a, 1]))] = (a, b)
    for key in keys:
        plant, leaf = key
        try:
            if key in table.bad_leaves:
                raise LeafError(plant, leaf, "; ".join(table.bad_leaves[key]))
            a, b = starts[key]
            rc = ids[a:b, 2:]
            dup = np.flatnonzero(np.all(np.diff(rc, axis=0) == 0, axis=1))
            if len(dup):
                k = a + dup[0]
                raise LeafError(plant, leaf,
                                f"row {ids[k, 2]}, col {ids[k, 3]} appears twice "
                                f"(lines {line[k]} and {line[k + 1]})")
            rows, cols = {}, {}
            for r in np.unique(rc[:, 0]):
                sel = slice(a + np.searchsorted(rc[:, 0], r, "left"),
                            a + np.searchsorted(rc[:, 0], r, "right"))
                rows[int(r)] = xyz[sel]
                cols[int(r)] = ids[sel, 3]
            grids.append(grid_from_rows(plant, leaf, rows, cols))
        except LeafError as exc:
            if strict:
                raise
            errors.append(exc)
    return grids, errors
