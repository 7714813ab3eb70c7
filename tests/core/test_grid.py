"""Points files and leaf grids: what is repaired, what is refused, and how it is said."""

import numpy as np
import pytest

from maizeviz.errors import LeafError, PointsFileError
from maizeviz.io.points import parse_points, read_points, write_points
from maizeviz.leaf.grid import build_grids, grid_from_rows
from tests.conftest import grid_csv


def flat_grid(m=4, n=3):
    i, j = np.meshgrid(np.arange(m), np.arange(n), indexing="ij")
    return np.stack([i * 10.0, j * 2.0, np.zeros_like(i, dtype=float)], axis=-1)


def test_round_trip_rows_in_any_order(tmp_path, leaf_grid):
    text = grid_csv(leaf_grid)
    lines = text.splitlines()
    shuffled = [lines[0]] + lines[1:][::-1]
    table = parse_points("\n".join(shuffled))
    grids, errors = build_grids(table)
    assert not errors
    assert np.allclose(grids[0].points[:-1], leaf_grid[:-1], atol=1e-4)
    assert grids[0].tip_collapsed
    path = tmp_path / "out.csv"
    write_points(path, grids)
    again, _ = build_grids(read_points(path))
    assert np.allclose(again[0].points, grids[0].points, atol=1e-3)


def test_extra_columns_kept_and_case_insensitive_header():
    text = ("Plant,LEAF,row,col,x,y,z,time\n1,2,0,0,0,0,0,t0\n1,2,0,1,1,0,0,t1\n"
            "1,2,1,0,0,5,0,t2\n1,2,1,1,1,5,0,t3\n")
    table = parse_points(text)
    assert table.extra["time"] == ["t0", "t1", "t2", "t3"]
    grids, errors = build_grids(table)
    assert grids[0].key == (1, 2) and grids[0].shape == (2, 2)


@pytest.mark.parametrize("text, match", [
    ("", "empty"),
    ("   \n\n", "empty"),
    ("plant,leaf,row,col,x,y,z\n", "header only"),
    ("plant,leaf,row,col,x,y\n1,1,0,0,0,0\n", "missing column.*z"),
    ("hello world\nthis is not csv\n", "missing column"),
])
def test_unreadable_files(write_csv, text, match):
    with pytest.raises(PointsFileError, match=match):
        read_points(write_csv(text))


def test_binary_and_missing_files(tmp_path):
    p = tmp_path / "bin.csv"
    p.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00")
    with pytest.raises(PointsFileError, match="binary"):
        read_points(p)
    with pytest.raises(PointsFileError, match="no such points file"):
        read_points(tmp_path / "nope.csv")
    with pytest.raises(PointsFileError, match="folder"):
        read_points(tmp_path)


def test_non_integer_leaf_id_skips_line_but_not_leaf():
    good = grid_csv(flat_grid(), plant=1, leaf=1)
    table = parse_points(good + "1,abc,0,0,1,2,3\n")
    assert len(table.problems) == 1 and "line 14" in table.problems[0]
    grids, errors = build_grids(table)
    assert len(grids) == 1 and not errors


def test_non_numeric_coordinate_refuses_only_that_leaf():
    text = grid_csv(flat_grid(), plant=1, leaf=1) + grid_csv(flat_grid(), 1, 2, header=False)
    text = text.replace("1,2,2,1,20.0000", "1,2,2,1,twenty")
    grids, errors = build_grids(parse_points(text))
    assert [g.key for g in grids] == [(1, 1)]
    assert len(errors) == 1
    msg = str(errors[0])
    assert "plant 1, leaf 2" in msg and "row 2, col 1" in msg and "x is not a number" in msg
    with pytest.raises(LeafError):
        build_grids(parse_points(text), strict=True)


@pytest.mark.parametrize("value, match", [("nan", "not a number"), ("inf", "not a number"),
                                          ("1e30", "beyond")])
def test_nan_inf_and_absurd_coordinates(value, match):
    g = flat_grid()
    text = grid_csv(g).replace("1,1,2,1,20.0000,2.0000", f"1,1,2,1,20.0000,{value}")
    grids, errors = build_grids(parse_points(text))
    assert not grids
    assert "row 2, col 1" in str(errors[0]) and match in str(errors[0])


def test_missing_rows_named():
    rows = {0: flat_grid()[0], 1: flat_grid()[1], 3: flat_grid()[3]}
    with pytest.raises(LeafError, match=r"row\(s\) 2 missing"):
        grid_from_rows(1, 1, rows)
    with pytest.raises(LeafError, match="rows start at 1"):
        grid_from_rows(1, 1, {1: flat_grid()[1], 2: flat_grid()[2]})


def test_too_few_rows_or_cols():
    with pytest.raises(LeafError, match="at least 2 cross-sections"):
        grid_from_rows(1, 1, {0: flat_grid()[0]})
    with pytest.raises(LeafError, match="single point"):
        grid_from_rows(1, 1, {0: np.zeros((1, 3)), 1: np.ones((1, 3))})


def test_single_point_row_only_at_the_tip():
    g = flat_grid(4, 3)
    ok = grid_from_rows(1, 1, {0: g[0], 1: g[1], 2: g[2], 3: g[3][:1]})
    assert ok.tip_collapsed and np.all(ok.points[3] == g[3][0])
    with pytest.raises(LeafError, match="row 1: a single point in the middle"):
        grid_from_rows(1, 1, {0: g[0], 1: g[1][:1], 2: g[2], 3: g[3]})


def test_duplicate_points_and_rows_merged_and_said():
    g = flat_grid(4, 3)
    row1 = np.insert(g[1], 1, g[1][1], axis=0)           # a press recorded twice
    out = grid_from_rows(1, 1, {0: g[0], 1: row1, 2: g[2], 3: g[2].copy(), 4: g[3]})
    assert out.shape == (4, 3)
    assert np.allclose(out.points, g)
    assert any("merged 1 duplicate" in n for n in out.notes)
    assert any("row 3: same points as row 2" in n for n in out.notes)


def test_ragged_row_resampled_along_its_polyline():
    g = flat_grid(4, 5)
    short = g[2][[0, 2, 4]]                                 # 3 points, the others 5
    out = grid_from_rows(1, 1, {0: g[0], 1: g[1], 2: short, 3: g[3]})
    assert out.shape == (4, 5)
    assert np.allclose(out.points[2], g[2])                  # straight row: exact
    assert any("row 2: 3 points, the others 5; resampled" in n for n in out.notes)


def test_same_row_col_twice_is_refused_with_lines():
    text = grid_csv(flat_grid()) + "1,1,1,1,3,3,3\n"
    grids, errors = build_grids(parse_points(text))
    assert "row 1, col 1 appears twice" in str(errors[0]) and "lines" in str(errors[0])


def test_hostile_csv_field(write_csv):
    with pytest.raises(PointsFileError, match="not a readable CSV"):
        read_points(write_csv("plant,leaf,row,col,x,y,z\n1,1,0,0,\"" + "9" * 200000 + "\",0,0\n"))


def test_semicolon_and_bom():
    text = "\ufeffplant;leaf;row;col;x;y;z\n1;1;0;0;0;0;0\n1;1;0;1;1;0;0\n1;1;1;0;0;4;0\n1;1;1;1;1;4;0\n"
    grids, errors = build_grids(parse_points(text))
    assert grids[0].shape == (2, 2) and not errors
