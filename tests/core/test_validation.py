"""Every value a user can type that reaches the layout and points readers: checked by range,
with a one-line message naming the file, line and field, never an internal error."""

import json
import time
import tracemalloc

import numpy as np
import pytest

from maizeviz.canopy.layout import LayoutError, layout_from_dict, load_layout, tiled_layout
from maizeviz.cli import EXIT_FAIL, main
from maizeviz.errors import MaizevizError, PointsFileError
from maizeviz.io.points import MAX_LINE_BYTES, parse_points, read_points
from maizeviz.leaf.grid import build_grids
from maizeviz.leaf.synth import block_grids
from tests.conftest import grid_csv


def doc(**over):
    d = {"maizeviz_layout": 1, "row_spacing": 60, "plant_spacing": 30,
         "field": {"x0": 0, "y0": 0, "x1": 120, "y1": 60},
         "rows": [{"x": 30, "plants": [{"y": 15, "plant": 1}]},
                  {"x": 90, "plants": [{"y": 15, "plant": 2, "jitter_cm": 2}]}]}
    d.update(over)
    return d


def with_plant(**fields):
    rows = doc()["rows"]
    rows[1]["plants"][0].update(fields)
    return doc(rows=rows)


# ----------------------------------------------------------------------------- layouts
@pytest.mark.parametrize("d, says", [
    (doc(seed=-1), "'seed' must be a whole number from 0 to 4294967295, got -1"),
    (doc(seed=1e300), "'seed' must be a whole number"),
    (doc(seed=2.5), "'seed' must be a whole number"),
    (doc(seed=True), "'seed' must be a whole number"),
    (doc(seed=10**400), "got 10000000000"),
    (doc(seed=10**5000), "got a number too long to show"),
    (doc(rows=[{"x": 1e308, "plants": [{"y": 15, "plant": 1}]}]),
     "rows[0]: 'x' is 1e+308 cm; it must be from -100000 to 100000 cm"),
    (doc(rows=[{"x": 10, "plants": [{"y": -1e308, "plant": 1}]}]), "rows[0].plants[0]: 'y' is"),
    (doc(field={"x0": 0, "y0": 0, "x1": 1e308, "y1": 60}), "field: 'x1' is 1e+308 cm"),
    (doc(row_spacing=1e-300), "'row_spacing' is 1e-300 cm; it must be from 1 to 100000 cm"),
    (doc(plant_spacing=1e300), "'plant_spacing' is 1e+300 cm"),
    (doc(row_spacing=10**400), "'row_spacing' must be a number"),
    (with_plant(jitter_cm=1e300), "rows[1].plants[0]: 'jitter_cm' is 1e+300 cm; it must be "
                                  "from 0 to 100 cm"),
    (with_plant(azimuth_deg=1e300), "rows[1].plants[0]: 'azimuth_deg' is 1e+300 degrees"),
    (with_plant(plant=10**12), "rows[1].plants[0]: 'plant' must be an integer plant id"),
    (with_plant(plant=1e300), "'plant' must be an integer plant id"),
    (doc(north_deg=-1e300), "'north_deg' is -1e+300 degrees"),
    (doc(rows=[{"x": 30, "plants": []}, {"x": 90, "plants": []}]), "no plant stands in the layout"),
    (doc(field={"x0": 0, "y0": 0, "x1": 1e-9, "y1": 1e-9}), "field is 1e-09 x 1e-09 cm; each "
                                                            "side must be at least 1 cm"),
    (doc(maizeviz_layout=10**5000), "'maizeviz_layout' is a number too long to show"),
    (doc(maizeviz_layout=True), "'maizeviz_layout' is true"),
])
def test_layout_values_out_of_range(d, says):
    with pytest.raises(LayoutError) as exc:
        layout_from_dict(d, plants={1, 2}, source="f.json")
    msg = str(exc.value)
    assert says in msg and msg.startswith("f.json: ") and "\n" not in msg and "--" not in msg


def test_tiny_field_no_longer_gives_an_absurd_lai(tmp_path, capsys):
    block = tmp_path / "block.csv"
    main(["synth", "--plants", "1x1", "--out", str(block)])
    lay = tmp_path / "lay.json"
    lay.write_text(json.dumps({"maizeviz_layout": 1, "row_spacing": 60, "plant_spacing": 30,
                               "field": {"x0": 0, "y0": 0, "x1": 1e-9, "y1": 1e-9},
                               "rows": [{"x": 0, "plants": [{"y": 0, "plant": 1}]}]}))
    capsys.readouterr()
    assert main(["canopy", str(block), "--layout", str(lay)]) == EXIT_FAIL
    err = capsys.readouterr().err
    assert "each side must be at least 1 cm" in err and "internal error" not in err


@pytest.mark.parametrize("seed", [-1, 1e300])
def test_layout_seed_through_the_cli(tmp_path, capsys, seed):
    block = tmp_path / "block.csv"
    main(["synth", "--plants", "1x1", "--out", str(block)])
    lay = tmp_path / "lay.json"
    lay.write_text(json.dumps(doc(seed=seed, rows=[{"x": 30, "plants": [{"y": 15,
                                                                          "plant": 1}]}])))
    capsys.readouterr()
    assert main(["canopy", str(block), "--layout", str(lay)]) == EXIT_FAIL
    err = capsys.readouterr().err
    assert "'seed' must be a whole number" in err and "internal error" not in err


def test_layout_file_that_is_not_a_regular_file_or_too_long(tmp_path):
    import os
    fifo = tmp_path / "lay.json"
    os.mkfifo(fifo)
    with pytest.raises(LayoutError, match="is a FIFO"):
        load_layout(fifo)
    with pytest.raises(LayoutError, match="is a character device"):
        load_layout("/dev/zero")
    big = tmp_path / "big.json"
    big.write_text('{"a": "' + "x" * 20_000_001 + '"}')
    with pytest.raises(LayoutError, match="limit for a layout file"):
        load_layout(big)
    digits = tmp_path / "digits.json"
    digits.write_text('{"maizeviz_layout": ' + "9" * 5000 + "}")
    with pytest.raises(LayoutError, match="not valid JSON"):
        load_layout(digits)
    latin = tmp_path / "latin.json"
    latin.write_bytes(b'{"a": "\xe9"}')
    with pytest.raises(LayoutError, match="not UTF-8"):
        load_layout(latin)


def bases():
    return {k + 1: (60.0 * (k // 3), 30.0 * (k % 3)) for k in range(9)}


@pytest.mark.parametrize("kw, says", [
    ({"tile": (1000, 1000)}, "1000 x 1000 tiles of a block of 9 plants make 9,000,000 plants"),
    ({"tile": (0, 3)}, "the tile count must be a whole number from 1"),
    ({"tile": (1.5, 3)}, "the tile count must be a whole number"),
    ({"row_spacing": 1e-300}, "row spacing is 1e-300 cm; it must be from 1 to 100000 cm"),
    ({"plant_spacing": float("nan")}, "plant spacing must be a positive number of cm"),
    ({"block": (0, 3)}, "the block shape must be a whole number"),
    ({"north_deg": 1e300}, "north must be an angle"),
])
def test_tiling_arguments(kw, says):
    args = {"tile": (1, 1), **kw}
    t0 = time.monotonic()
    with pytest.raises(LayoutError) as exc:
        tiled_layout(bases(), **args)
    assert time.monotonic() - t0 < 1.0
    assert says in str(exc.value) and "--" not in str(exc.value)


# ------------------------------------------------------------------------------ points
def flat(m=4, n=3):
    i, j = np.meshgrid(np.arange(m), np.arange(n), indexing="ij")
    return np.stack([i * 10.0, j * 2.0, np.zeros_like(i, dtype=float)], axis=-1)


@pytest.mark.parametrize("line, says", [
    ("1e300,1,0,0,1,2,3", "line 14: plant id 1e300 is beyond the range "
                          "-2,147,483,647..2,147,483,647; line skipped"),
    ("1,-1e300,0,0,1,2,3", "line 14: leaf id -1e300 is beyond the range"),
    ("1," + "9" * 400 + ",0,0,1,2,3", "leaf id 999999999999999999999999999999... is beyond"),
    ("inf,1,0,0,1,2,3", "plant/leaf id is not an integer ('inf', '1')"),
])
def test_absurd_ids_skip_the_line(line, says):
    table = parse_points(grid_csv(flat()) + line + "\n")
    assert len(table) == 12 and table.problems == [table.problems[0]] and says in table.problems[0]
    grids, errors = build_grids(table)
    assert len(grids) == 1 and not errors


def test_absurd_row_refuses_only_its_leaf():
    text = grid_csv(flat()) + grid_csv(flat(), 1, 2, header=False) + "1,2,1e9,0,1,2,3\n"
    grids, errors = build_grids(parse_points(text))
    assert [g.key for g in grids] == [(1, 1)]
    assert "row 1e9, col 0: beyond 10,000" in str(errors[0])


def test_plant_id_1e300_through_leaf(write_csv, capsys):
    path = write_csv(grid_csv(flat()) + "1e300,1,0,0,1,2,3\n")
    code = main(["leaf", str(path)])
    err = capsys.readouterr().err
    assert code != EXIT_FAIL and "internal error" not in err and "plant id 1e300" in err


def test_limits_say_what_and_why(write_csv):
    path = write_csv(grid_csv(flat()))
    with pytest.raises(PointsFileError, match=r"more than 5 points; that many would take"):
        read_points(path, max_points=5)
    with pytest.raises(PointsFileError, match=r"more than 3 lines; reading more would take"):
        read_points(path, max_lines=3)
    long = write_csv("plant,leaf,row,col,x,y,z\n1,1,0,0,1,2," + "3" * MAX_LINE_BYTES + "\n")
    with pytest.raises(PointsFileError, match=r"line 2 is longer than 10,000 bytes"):
        read_points(long)
    late_nul = write_csv(grid_csv(flat()) * 200 + "1,1,0,0,1,2,\x003\n")
    with pytest.raises(PointsFileError, match=r"line 2601: binary content"):
        read_points(late_nul)
    with pytest.raises(PointsFileError, match="binary"):
        read_points(write_csv("\x01\x02\x03\x04\x05\x06\x07\x08abc\n" * 10))


def test_reading_streams_memory_follows_points_kept(tmp_path):
    """200,000 points: the old reader held the text, a list of lists and Python floats (about
    60x the bytes of the arrays); the streaming one holds the arrays and little more."""
    rows = grid_csv(block_grids(1, 1)[0].points).splitlines()[1:]
    path = tmp_path / "big.csv"
    with path.open("w") as fh:
        fh.write("plant,leaf,row,col,x,y,z\n")
        for k in range(200_000 // len(rows) + 1):
            fh.writelines(f"{k + 1}," + r.split(",", 1)[1] + "\n" for r in rows)
    n = sum(1 for _ in path.open()) - 1
    read_points(path)           # once first: what a file this large imports (pyarrow) is not data
    tracemalloc.start()
    table = read_points(path)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert len(table) == n
    arrays = table.ids.nbytes + table.xyz.nbytes + table.line.nbytes
    assert peak < 1.6 * arrays + 4e6, (peak, arrays)


def test_every_layout_and_points_error_is_a_maizeviz_error():
    assert issubclass(LayoutError, MaizevizError) and issubclass(PointsFileError, MaizevizError)


def test_tile_count_checked_before_any_point_is_read():
    from maizeviz.canopy.layout import check_tile
    t0 = time.monotonic()
    with pytest.raises(LayoutError, match="1000 x 1000 tiles of one plant make 1,000,000 plants"):
        check_tile((1000, 1000))
    assert time.monotonic() - t0 < 0.1
    assert check_tile((3, 3), 9) == (3, 3)
    for bad in ((3,), None, ("3", 3), (True, 3)):
        with pytest.raises(LayoutError, match="tile count"):
            check_tile(bad)


@pytest.mark.parametrize("kw", [{"north_deg": 10**400}, {"row_spacing": 10**400},
                                {"plant_spacing": np.float64("nan")}, {"tile": (np.int64(0), 1)}])
def test_tiling_arguments_of_any_type(kw):
    with pytest.raises(LayoutError) as exc:
        tiled_layout(bases(), **{"tile": (1, 1), **kw})
    assert len(str(exc.value).splitlines()) == 1 and len(str(exc.value)) < 300
