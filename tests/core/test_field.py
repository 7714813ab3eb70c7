"""A field read plant chunk by plant chunk (maizeviz.canopy.field) gives the canopy, the light
and the messages of the same points read whole."""

import json

import numpy as np
import pytest

import maizeviz.canopy.field as field
from maizeviz.canopy.field import FieldLeaves, canopy_of, field_input
from maizeviz.canopy.layout import layout_for
from maizeviz.cli import EXIT_OK, EXIT_PARTIAL, main
from maizeviz.cost import layout_cost
from maizeviz.io.parquet import write_table
from maizeviz.io.points import PointsTable, read_points, write_points
from maizeviz.leaf.fit import read_leaves
from maizeviz.leaf.grid import LeafGrid
from maizeviz.leaf.synth import block_grids
from maizeviz.mesh.levels import parse_level

pytest.importorskip("pyarrow")


@pytest.fixture(scope="module")
def points(tmp_path_factory):
    """A 4 x 5 synthetic block as Parquet: one leaf has a row like the one before (merged, a
    note), one a row missing (refused by the grids)."""
    grids = block_grids(4, 5, seed=11)
    bad = grids[7].points.copy()
    bad[3] = bad[2]
    grids[7] = LeafGrid(grids[7].plant, grids[7].leaf, bad, grids[7].tip_collapsed)
    folder = tmp_path_factory.mktemp("field")
    write_points(folder / "all.parquet", grids)
    table = read_points(folder / "all.parquet")
    gap = (table.ids[:, 0] == 9) & (table.ids[:, 1] == 4) & (table.ids[:, 2] == 2)
    write_table(folder / "field.parquet", PointsTable(table.ids[~gap], table.xyz[~gap],
                                                      table.line[~gap]))
    return folder / "field.parquet"


@pytest.fixture
def small_chunks(monkeypatch):
    """Every file is a field, read a few hundred points at a time (plants cut across chunks
    of the file: the reader must hold them back)."""
    monkeypatch.setattr(field, "FIELD_POINTS", 0)
    monkeypatch.setattr(field, "CHUNK_POINTS", 333)
    monkeypatch.setattr(field, "WORKERS", 1)


def same_canopy(a, b):
    for name in ("vertices", "faces", "face_instance", "face_plant", "face_leaf",
                 "stalk_vertices", "stalk_faces", "leaves_per_instance"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and np.array_equal(x, y), name


@pytest.mark.parametrize("level", ["K2", "standard", "36", "8"])
@pytest.mark.parametrize("tile", [(1, 1), (2, 3)])
def test_a_field_builds_the_canopy_of_its_leaves_read_whole(points, small_chunks, level, tile):
    whole = read_leaves(points)
    surveyed = FieldLeaves(points)
    assert whole.skipped and whole.notes
    assert field_input(points)
    assert len(surveyed) == len(whole.leaves)
    assert [str(e) for e in surveyed.skipped] == [str(e) for e in whole.skipped]
    layout = layout_for(whole.leaves, tile)
    other = layout_for(surveyed, tile)
    assert layout.placements == other.placements and np.array_equal(layout.cells, other.cells)
    lv = parse_level(level)
    same_canopy(canopy_of(surveyed, layout, lv), canopy_of(whole.leaves, layout, lv))
    assert layout_cost(surveyed, layout, lv) == layout_cost(whole.leaves, layout, lv)


def test_the_light_command_reads_a_field_as_the_whole_file(points, small_chunks, capsys,
                                                           monkeypatch):
    monkeypatch.setattr(field, "WORKERS", 2)           # chunks built in 2 processes
    argv = ["light", str(points), "--triangles", "36", "--sun-zenith", "35", "--sun-azimuth",
            "120", "--density", "1", "--json"]
    assert main(argv) == EXIT_PARTIAL                       # the spoiled leaf
    out = capsys.readouterr()
    as_field = json.loads(out.out)
    assert "read plant by plant" in out.err
    monkeypatch.setattr(field, "FIELD_POINTS", 10**9)
    assert main(argv) == EXIT_PARTIAL
    whole = json.loads(capsys.readouterr().out)
    assert _timeless(as_field) == _timeless(whole)


def _timeless(doc):
    if isinstance(doc, dict):
        return {k: _timeless(v) for k, v in doc.items() if k != "seconds"}
    if isinstance(doc, list):
        return [_timeless(v) for v in doc]
    return doc


def test_a_field_whose_plants_are_scattered_is_read_whole(tmp_path, small_chunks, capsys):
    grids = block_grids(2, 2, seed=2)
    path = tmp_path / "mixed.parquet"
    write_points(path, grids[::2] + grids[1::2])            # plant 1's leaves in two places
    assert field.read_field(path) is None
    assert main(["canopy", str(path), "--json", "--interp", "0"]) == EXIT_OK


def test_a_survey_in_workers_is_the_survey_in_one_process(points, small_chunks):
    """The chunks' bounds read from the plant column alone, each chunk surveyed in a worker
    process: the same leaves, shapes, bases, extents, notes and refusals as one process
    reading the chunks in turn, chunks of whole plants covering every record once, and the
    same canopy built from them."""
    one = FieldLeaves(points)
    two = FieldLeaves(points, workers=2)
    assert len(two.chunks) > 2
    assert two.chunks[0][0] == 0 and two.chunks[-1][1] == two.rows
    assert all(a[1] == b[0] for a, b in zip(two.chunks, two.chunks[1:]))
    for name in ("plant", "rows", "cols", "tip"):
        assert np.array_equal(getattr(one.shapes, name), getattr(two.shapes, name)), name
    assert one.bases == two.bases and one.extents == two.extents
    assert one.notes == two.notes and one.highest == two.highest
    assert [str(e) for e in one.skipped] == [str(e) for e in two.skipped]
    layout = layout_for(one, (1, 1))
    same_canopy(canopy_of(two, layout, parse_level("8")), canopy_of(one, layout,
                                                                   parse_level("8")))


def test_scattered_plants_are_found_from_the_plant_column(tmp_path, small_chunks):
    from maizeviz.io.parquet import NotStreamable, plant_chunk_bounds

    grids = block_grids(2, 2, seed=2)
    path = tmp_path / "mixed.parquet"
    write_points(path, grids[::2] + grids[1::2])
    with pytest.raises(NotStreamable, match="not together"):
        plant_chunk_bounds(path, 100)
    assert field.read_field(path, workers=2) is None


def test_long_work_is_estimated_before_it_starts(points, small_chunks, capsys, monkeypatch):
    """Work estimated past SAY_SECONDS is told on stderr before the canopy is built: its
    time and memory, and its largest part."""
    import maizeviz.cost as cost

    argv = ["light", str(points), "--triangles", "36", "--sun-zenith", "35", "--sun-azimuth",
            "120", "--density", "1"]
    assert main(argv) == EXIT_PARTIAL                       # the spoiled leaf
    assert "estimate:" not in capsys.readouterr().err       # seconds of work: not told
    monkeypatch.setattr(cost, "SAY_SECONDS", 0.0)
    assert main(argv) == EXIT_PARTIAL                       # the spoiled leaf
    err = capsys.readouterr().err
    line = next(x for x in err.splitlines() if x.startswith("estimate:"))
    assert "of work and" in line and "of memory (the largest part: " in line
    assert "36 triangles" in line or "rays" in line
    assert err.index("read plant by plant") < err.index("estimate:")   # after the survey
