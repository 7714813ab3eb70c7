"""Points files in Parquet: the same points, checks and messages as the CSV, read by every
command that takes points, written by the commands that write them."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.cli import EXIT_FAIL, EXIT_OK, main
from maizeviz.errors import PointsFileError
from maizeviz.io.parquet import exact_rounding, write_table
from maizeviz.io.points import parse_points, read_points, read_points_parquet, write_points
from maizeviz.leaf.grid import build_grids
from maizeviz.leaf.synth import block_grids
from maizeviz.resources import example_points

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")


def same_table(a, b, lines=True):
    assert np.array_equal(a.ids, b.ids)
    assert np.array_equal(a.xyz, b.xyz, equal_nan=True)
    assert not lines or np.array_equal(a.line, b.line)
    assert a.problems == b.problems and a.bad_leaves == b.bad_leaves and a.extra == b.extra


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 3), st.integers(1, 3), st.integers(0, 2**32 - 1), st.integers(0, 5),
       st.integers(3, 14), st.integers(2, 6))
def test_grids_written_as_csv_and_parquet_read_back_alike(tmp_path_factory, rows, per_row, seed,
                                                          decimals, sections, across):
    tmp = tmp_path_factory.mktemp("pq")
    grids = block_grids(rows, per_row, seed=seed, grid_rows=sections, grid_cols=across)
    write_points(tmp / "p.csv", grids, decimals)
    write_points(tmp / "p.parquet", grids, decimals)
    csv, par = read_points(tmp / "p.csv"), read_points(tmp / "p.parquet")
    same_table(csv, par)
    # and the same grids, fitted leaves built from them alike
    a, b = build_grids(csv)[0], build_grids(par)[0]
    assert all(np.array_equal(g.points, h.points) and g.key == h.key for g, h in zip(a, b))


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(allow_nan=False, width=64, min_value=-1e7, max_value=1e7) |
                st.sampled_from([0.0005, -0.0005, 1.0005, 2.5e-4, -0.0, 1234.5675]),
                min_size=1, max_size=50), st.integers(0, 6))
def test_exact_rounding_is_the_csv_writers(values, decimals):
    got = exact_rounding(np.array(values), decimals)
    expected = [float(f"{v:.{decimals}f}") for v in values]
    assert got.tolist() == expected
    assert [np.signbit(v) for v in got] == [np.signbit(v) for v in expected]


def test_parquet_is_taken_by_its_content_and_ids_stored_narrow(tmp_path, monkeypatch):
    import maizeviz.io.parquet as parquet

    grids = block_grids(2, 2)
    monkeypatch.setattr(parquet, "ROW_GROUP_POINTS", 500)     # row groups of whole plants
    write_points(tmp_path / "p.parquet", grids)
    meta = pq.ParquetFile(tmp_path / "p.parquet").metadata
    assert meta.num_row_groups == 4
    firsts = pq.read_table(tmp_path / "p.parquet")["plant"].to_numpy()
    sizes = [meta.row_group(k).num_rows for k in range(4)]
    assert [len(set(firsts[a:a + n])) for a, n in zip(np.cumsum([0] + sizes), sizes)] == \
        [1, 1, 1, 1]
    named_csv = tmp_path / "really-parquet.csv"
    named_csv.write_bytes((tmp_path / "p.parquet").read_bytes())
    same_table(read_points(named_csv), read_points(tmp_path / "p.parquet"))
    schema = pq.read_schema(tmp_path / "p.parquet")
    assert [str(schema.field(c).type) for c in ("plant", "leaf", "row", "col", "x")] == \
        ["int32", "int32", "int16", "int16", "double"]
    monkeypatch.undo()                                 # row groups of a million points
    write_points(tmp_path / "big_groups.parquet", grids)
    assert (tmp_path / "big_groups.parquet").stat().st_size < 0.6 * _csv_size(tmp_path, grids)


def _csv_size(tmp_path, grids):
    write_points(tmp_path / "size.csv", grids)
    return (tmp_path / "size.csv").stat().st_size


def _table(tmp_path, columns, name="t.parquet"):
    path = tmp_path / name
    pq.write_table(pa.table(columns), path)
    return path


def test_a_missing_column_is_one_line(tmp_path):
    path = _table(tmp_path, {"plant": [1], "leaf": [1], "row": [0], "col": [0], "x": [1.0],
                             "y": [2.0]})
    with pytest.raises(PointsFileError, match=r"missing column\(s\) z; a points file needs the "
                                              r"columns plant,leaf,row,col,x,y,z"):
        read_points(path)


def test_odd_records_get_the_csv_readers_messages(tmp_path):
    """A missing coordinate, an id out of range, a row index that is not whole, text in a
    number's column: each record as the CSV line of the same record reads."""
    cols = {"plant": [1, 1, 1, 1, 2, 3000000000], "leaf": [1, 1, 1, 1, 1, 1],
            "row": [0.0, 0.0, 1.0, 1.5, 0.0, 0.0], "col": [0, 1, 0, 0, 0, 0],
            "x": [0.0, 1.0, None, 0.5, 1.0, 1.0], "y": [0.0, 0.0, 9.0, 9.0, 0.0, 0.0],
            "z": ["0", "0", "0", "0", "zero", "0"], "note": ["a", "b", None, "d", "e", "f"]}
    path = _table(tmp_path, cols)
    got = read_points(path)
    csv = ["plant,leaf,row,col,x,y,z,note", "1,1,0.0,0,0.0,0.0,0,a", "1,1,0.0,1,1.0,0.0,0,b",
           "1,1,1.0,0,,9.0,0,", "1,1,1.5,0,0.5,9.0,0,d", "2,1,0.0,0,1.0,0.0,zero,e",
           "3000000000,1,0.0,0,1.0,0.0,0,f"]
    expected = parse_points("\n".join(csv) + "\n", str(path))
    same_table(got, expected)
    assert got.bad_leaves and got.problems            # the messages are there to compare


def test_plain_tables_are_read_column_by_column(tmp_path):
    """Integer or float ids, float32 coordinates, an extra column: the points as the CSV
    holding the same numbers reads them."""
    path = _table(tmp_path, {"Plant": np.array([1, 1, 1, 1], np.int16),
                             "LEAF": [1.0, 1.0, 1.0, 1.0], "row": [0, 0, 1, 1],
                             "col": [0, 1, 0, 1], "x": np.array([0, 1, 0, 1], np.float32),
                             "y": [0.0, 0.0, 5.0, 5.0], "z": [1.0, 1.0, 1.5, 1.5],
                             "tag": ["p", "q", "r", "s"]})
    got = read_points_parquet(path)
    expected = parse_points("plant,leaf,row,col,x,y,z,tag\n1,1,0,0,0,0,1,p\n1,1,0,1,1,0,1,q\n"
                            "1,1,1,0,0,5,1.5,r\n1,1,1,1,1,5,1.5,s\n", str(path))
    same_table(got, expected)


def test_not_parquet_inside(tmp_path):
    path = tmp_path / "broken.parquet"
    path.write_bytes(b"PAR1" + b"\x00" * 50)
    with pytest.raises(PointsFileError, match="not a readable Parquet file"):
        read_points(path)


def test_convert_round_trip_keeps_every_record(tmp_path, capsys):
    src = example_points()
    assert main(["convert", str(src), "--out", str(tmp_path / "b.parquet")]) == EXIT_OK
    assert main(["convert", str(tmp_path / "b.parquet"), "--out", str(tmp_path / "b.csv")]) \
        == EXIT_OK
    same_table(read_points(src), read_points(tmp_path / "b.parquet"))
    same_table(read_points(src), read_points(tmp_path / "b.csv"))
    capsys.readouterr()
    assert main(["convert", str(src), "--out", str(src)]) == EXIT_FAIL      # overwriting it


def _json(capsys, argv):
    capsys.readouterr()
    assert main(argv) == EXIT_OK
    return json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def both(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("both")
    grids = block_grids(2, 3, seed=5)
    write_points(tmp / "p.csv", grids)
    assert main(["synth", "--plants", "2x3", "--seed", "5", "--out", str(tmp / "p.parquet")]) \
        == EXIT_OK
    return tmp / "p.csv", tmp / "p.parquet"


@pytest.mark.parametrize("argv", [
    ["leaf", "P", "--levels", "standard,8", "--json"],
    ["canopy", "P", "--json"],
    ["light", "P", "--sun-zenith", "30", "--sun-azimuth", "150", "--density", "1", "--json"],
])
def test_every_command_reads_parquet_as_its_csv(capsys, both, argv):
    csv, par = both
    a = _json(capsys, [str(csv) if x == "P" else x for x in argv])
    b = _json(capsys, [str(par) if x == "P" else x for x in argv])
    assert _without_seconds(a) == _without_seconds(b)


def _without_seconds(doc):
    if isinstance(doc, dict):
        return {k: _without_seconds(v) for k, v in doc.items()
                if not k.endswith("_s") and "second" not in k and k not in ("points", "source")}
    if isinstance(doc, list):
        return [_without_seconds(v) for v in doc]
    return doc


def test_the_recorder_refuses_a_parquet_journal(capsys, tmp_path):
    assert main(["record", "--port", "/dev/null", "--out", str(tmp_path / "r.parquet")]) \
        == EXIT_FAIL
    assert "a recording is a CSV journal" in capsys.readouterr().err
    assert not (tmp_path / "r.parquet").exists()


def test_write_table_keeps_extra_columns(tmp_path):
    table = parse_points("plant,leaf,row,col,x,y,z,who\n1,1,0,0,0.1,0.2,0.3,ann\n"
                         "1,1,0,1,1.1,1.2,1.3,bob\n")
    write_table(tmp_path / "t.pq", table)
    same_table(read_points(tmp_path / "t.pq"), table)
