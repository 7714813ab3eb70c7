"""build_grids assembles regular leaves with numpy: the same grids, notes and errors as
grid_from_rows leaf by leaf, whatever the table holds."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import maizeviz.leaf.grid as grid_module
from maizeviz.errors import LeafError
from maizeviz.io.points import PointsTable, parse_points
from maizeviz.leaf.grid import build_grids, grid_from_rows
from maizeviz.leaf.synth import block_grids


def reference_grids(table):
    """Leaf by leaf through grid_from_rows, as build_grids did before its fast path."""
    grids, errors = [], []
    keys = sorted(set(map(tuple, table.ids[:, :2].tolist())) | set(table.bad_leaves))
    order = np.lexsort((table.ids[:, 3], table.ids[:, 2], table.ids[:, 1], table.ids[:, 0]))
    ids, xyz, line = table.ids[order], table.xyz[order], table.line[order]
    for plant, leaf in keys:
        try:
            if (plant, leaf) in table.bad_leaves:
                raise LeafError(plant, leaf, "; ".join(table.bad_leaves[(plant, leaf)]))
            sel = np.flatnonzero((ids[:, 0] == plant) & (ids[:, 1] == leaf))
            rc = ids[sel, 2:]
            dup = np.flatnonzero(np.all(np.diff(rc, axis=0) == 0, axis=1))
            if len(dup):
                k = sel[dup[0]]
                raise LeafError(plant, leaf, f"row {ids[k, 2]}, col {ids[k, 3]} appears twice "
                                             f"(lines {line[k]} and {line[k + 1]})")
            rows = {int(r): xyz[sel[rc[:, 0] == r]] for r in np.unique(rc[:, 0])}
            cols = {int(r): ids[sel[rc[:, 0] == r], 3] for r in np.unique(rc[:, 0])}
            lines = {int(r): line[sel[rc[:, 0] == r]] for r in np.unique(rc[:, 0])}
            grids.append(grid_from_rows(plant, leaf, rows, cols, lines))
        except LeafError as exc:
            errors.append(exc)
    return grids, errors


def assert_same_grids(table):
    got, got_errors = build_grids(table)
    want, want_errors = reference_grids(table)
    assert [str(e) for e in got_errors] == [str(e) for e in want_errors]
    assert len(got) == len(want)
    for g, w in zip(got, want):
        assert (g.plant, g.leaf, g.tip_collapsed, g.rows, g.notes) == \
            (w.plant, w.leaf, w.tip_collapsed, w.rows, w.notes)
        assert g.points.dtype == np.float64 and np.array_equal(g.points, w.points)
    return got, got_errors


def table_of(leaves, bad_leaves=None, shuffle=None):
    """A PointsTable of [(plant, leaf, {row: (k, 3) points})] (cols 0..k-1)."""
    ids, xyz = [], []
    for plant, leaf, rows in leaves:
        for r, pts in rows.items():
            for c, p in enumerate(pts):
                ids.append((plant, leaf, r, c))
                xyz.append(p)
    ids = np.array(ids, dtype=np.int64).reshape(-1, 4)
    xyz = np.array(xyz, dtype=np.float64).reshape(-1, 3)
    line = np.arange(2, len(ids) + 2, dtype=np.int64)
    if shuffle is not None:
        perm = shuffle.permutation(len(ids))
        ids, xyz, line = ids[perm], xyz[perm], line[perm]
    return PointsTable(ids, xyz, line, bad_leaves=bad_leaves or {})


def regular_rows(rng, m, n, tip):
    base = rng.uniform(-80, 80, 3)
    pts = base + np.cumsum(rng.uniform(0.5, 4.0, (m, n, 3)), axis=0) \
        + np.arange(n)[None, :, None] * rng.uniform(0.5, 2.0, 3)
    rows = {r: pts[r] for r in range(m)}
    if tip:
        rows[m - 1] = pts[m - 1][:1]
    return rows


DAMAGE = ["none", "dup_point", "dup_row", "nan", "huge", "gap", "start1", "ragged", "dup_id",
          "single_middle", "one_row", "tip_all_same", "one_col"]


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1), st.lists(st.tuples(st.integers(2, 14), st.integers(2, 7),
                                                     st.booleans(), st.sampled_from(DAMAGE)),
                                           min_size=1, max_size=8),
       st.booleans())
def test_fast_path_equals_grid_from_rows(seed, specs, shuffled):
    rng = np.random.default_rng(seed)
    leaves = []
    for k, (m, n, tip, damage) in enumerate(specs):
        rows = regular_rows(rng, m, n, tip)
        r = int(rng.integers(0, m - 1)) if m > 1 else 0      # a row that is not the tip
        if damage == "dup_point":
            rows[r] = np.insert(rows[r], 1, rows[r][0] + 0.001, axis=0)
        elif damage == "dup_row" and m > 2:
            rows = {i: rows[i] if i <= r else rows[i - 1] for i in range(m + 1)}
            rows[r + 1] = rows[r] + 0.002
        elif damage in ("nan", "huge"):
            rows[r] = rows[r].copy()
            rows[r][-1, int(rng.integers(3))] = np.nan if damage == "nan" else 1e7
        elif damage == "gap" and m > 2:
            del rows[1 + r % (m - 2)]
        elif damage == "start1":
            rows = {i + 1: p for i, p in rows.items()}
        elif damage == "ragged" and n > 2:
            rows[r] = rows[r][:-1]
        elif damage == "single_middle" and m > 2:
            rows[1] = rows[1][:1]
        elif damage == "one_row":
            rows = {0: rows[0]}
        elif damage == "tip_all_same":
            rows[m - 1] = np.repeat(rows[m - 1][:1], n, axis=0)
        elif damage == "one_col":
            rows = {i: p[:1] for i, p in rows.items()}
        leaves.append((1 + k // 3, 1 + k % 3 * 2, rows))
        if damage == "dup_id":
            extra = {r: rows[r][:1] + 5.0}
            leaves.append((1 + k // 3, 1 + k % 3 * 2, extra))
    table = table_of(leaves, shuffle=rng if shuffled else None)
    assert_same_grids(table)


def test_regular_leaves_never_reach_grid_from_rows(monkeypatch):
    grids = block_grids(2, 2)
    text = "plant,leaf,row,col,x,y,z\n" + "".join(
        f"{g.plant},{g.leaf},{r},{c},{p[0]:.3f},{p[1]:.3f},{p[2]:.3f}\n"
        for g in grids for r in range(g.shape[0])
        for c, p in enumerate(g.points[r][:1] if r == g.shape[0] - 1 else g.points[r]))
    table = parse_points(text)
    want = assert_same_grids(table)[0]

    def refuse(*args, **kwargs):
        raise AssertionError("a regular leaf went through grid_from_rows")

    monkeypatch.setattr(grid_module, "grid_from_rows", refuse)
    got, errors = build_grids(table)
    assert not errors and len(got) == len(want) == len(grids)


def test_unsorted_and_bad_leaves_kept_in_key_order():
    rng = np.random.default_rng(5)
    leaves = [(p, q, regular_rows(rng, 5, 3, True)) for p in (3, 1, 2) for q in (2, 1)]
    table = table_of(leaves, bad_leaves={(1, 2): ["row 1, col 1: x is not a number"],
                                         (0, 9): ["row 0, col 0: y is not a number"]},
                     shuffle=rng)
    got, errors = assert_same_grids(table)
    assert [g.key for g in got] == [(1, 1), (2, 1), (2, 2), (3, 1), (3, 2)]
    assert [(e.plant, e.leaf) for e in errors] == [(0, 9), (1, 2)]
    with pytest.raises(LeafError, match="plant 0, leaf 9"):
        build_grids(table, strict=True)


def test_empty_table_and_progress():
    empty = PointsTable(np.zeros((0, 4), np.int64), np.zeros((0, 3)), np.zeros(0, np.int64))
    assert build_grids(empty) == ([], [])
    rng = np.random.default_rng(1)
    table = table_of([(1, q, regular_rows(rng, 4, 3, False)) for q in range(1, 6)])
    seen = []
    build_grids(table, progress=lambda d, t: seen.append((d, t)))
    assert seen[-1] == (5, 5)
    with pytest.raises(InterruptedError):
        build_grids(table, progress=lambda d, t: False)
