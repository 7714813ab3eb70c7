"""maizeviz.fspm.mtg: digitized plants out to OpenAlea's MTG (FORM-A) and back.

OpenAlea's own reader (``openalea.mtg.io.read_mtg_file``) is not on PyPI; it was run on these
files while this module was written (docs/fspm.md). Here the files are held to the format's
grammar as that reader applies it: the header's sections, features in the columns the
``ENTITY-CODE`` line sets, entity codes indented by tabs, and no character its code parser
splits on inside a value."""

from __future__ import annotations

import re

import numpy as np
import pytest

import maizeviz as mv
from maizeviz.fspm.mtg import MTGFileError, mtg_text, parse_mtg, read_mtg, write_mtg


@pytest.fixture(scope="module")
def leaves():
    return mv.read_points(mv.example_points()).leaves


def test_the_digitized_points_come_back_from_the_mtg(tmp_path, leaves):
    path = write_mtg(tmp_path / "plants.mtg", leaves)
    grids = read_mtg(path)
    assert len(grids) == len(leaves)
    original = {lf.key: lf.grid.points for lf in leaves}
    for g in grids:
        np.testing.assert_allclose(g.points, original[g.key], atol=0.5e-4)


def test_the_topology_is_plant_then_stalk_bearing_its_leaves(tmp_path, leaves):
    verts = parse_mtg(write_mtg(tmp_path / "plants.mtg", leaves))
    plants = [v for v in verts if v.symbol == "P"]
    assert sorted(v.index for v in plants) == sorted({lf.plant for lf in leaves})
    for v in verts:
        if v.symbol == "S":
            assert verts[v.complex].symbol == "P" and v.edge == "/"
        if v.symbol == "L":
            assert v.edge == "+" and verts[v.parent].symbol == "S"
            assert verts[v.complex].symbol == "P"
            assert v.features["rows"] * v.features["cols"] == \
                len(v.features["points"].split(";"))


def test_each_leaf_carries_its_mesh_with_the_canopys_area(tmp_path, leaves):
    from maizeviz.mesh.levels import measure_leaves, mesh_leaves, parse_level

    verts = parse_mtg(write_mtg(tmp_path / "plants.mtg", leaves[:6]))
    level = parse_level("standard")
    meshes = list(mesh_leaves(leaves[:6], level))
    areas = {lf.key: m.area_cm2 for lf, m in zip(leaves[:6], measure_leaves(leaves[:6], meshes))}
    got = [v for v in verts if v.symbol == "L"]
    assert len(got) == 6
    for v in got:
        plant = verts[v.complex].index
        pts = np.array([[float(c) for c in p.split()] for p in v.features["vertices"].split(";")])
        faces = np.array([[int(c) for c in f.split()] for f in v.features["faces"].split(";")])
        tri = pts[faces]
        area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]),
                                    axis=1).sum()
        assert area == pytest.approx(v.features["area"], abs=1e-3)
        assert area == pytest.approx(areas[(plant, v.features["rank"])], rel=1e-4)


def test_the_text_follows_the_grammar_openaleas_reader_applies(leaves):
    text = mtg_text(leaves[:20], level=False)
    lines = text.splitlines()
    heads = [ln.split(":")[0].strip() for ln in lines if ln.rstrip().endswith(":")
             or ln.startswith("CODE")]
    assert heads[:5] == ["CODE", "CLASSES", "DESCRIPTION", "FEATURES", "MTG"]
    head = next(ln for ln in lines if ln.startswith("ENTITY-CODE"))
    first = head.split("\t")[1:].index("x") + 1        # the column the reader slices from
    code = lines[lines.index(head) + 1:]
    for ln in code:
        cells = ln.split("\t")
        entity = ln.strip().split("\t")[0]
        assert re.fullmatch(r"\^?(/|\+|<)[A-Z]\d+(/[A-Z]\d+)*", entity)
        assert all(not c for c in cells[1:first] if c != entity)
        for value in cells[first:]:
            assert not set(value) & set("/+<[](),=\t"), value
            assert "e" not in value.lower() or value.isalpha()


@pytest.mark.parametrize("edit, words", [
    (lambda t: t.replace("MTG:", "XTG:"), "no MTG: section"),
    (lambda t: t.replace("+L1\t", "+Q1\t", 1), "symbol Q is not in CLASSES"),
    (lambda t: t.replace("rank\tINT", "rank\tINTEGER"), "a feature is NAME TYPE"),
    (lambda t: t.replace("\t1\t5\t", "\tone\t5\t", 1), "feature rank 'one' is not a whole"),
    (lambda t: t.replace("\t5\t5\t", "\t4\t5\t", 1), "points for a grid of 4 x 5"),
    (lambda t: re.sub(r"(\t\+L)2(\t+)2\t", r"\g<1>1\g<2>1\t", t, count=1),
     "two leaves of rank 1"),
    (lambda t: t.replace("\t+L1\t", "\t+P9\t", 1), "joins scale 2 to scale 1"),
])
def test_a_malformed_mtg_is_refused_naming_the_line(tmp_path, leaves, edit, words):
    text = mtg_text(leaves[:3], level=False)
    path = tmp_path / "bad.mtg"
    path.write_text(edit(text))
    with pytest.raises(MTGFileError) as err:
        read_mtg(path)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_an_mtg_as_openalea_writes_it_is_read(tmp_path):
    """Spaced section names, padding tabs and two plants at the top level, as
    ``openalea.mtg.io.write_mtg`` writes them."""
    row = "0.0000 0.0000 0.0000;1.0000 0.0000 0.0000;0.0000 1.0000 1.0000;1.0000 1.0000 1.0000"
    text = ("CODE :  \tFORM-A\n\nCLASSES :\nSYMBOL\tSCALE\tDECOMPOSITION\tINDEXATION\t"
            "DEFINITION\n$\t0\tFREE\tFREE\tIMPLICIT\nP\t1\tFREE\tFREE\tEXPLICIT\n"
            "S\t2\tFREE\tFREE\tEXPLICIT\nL\t2\tFREE\tFREE\tEXPLICIT\n\nDESCRIPTION :\n"
            "LEFT\tRIGHT\tRELTYPE\tMAX\nS\tS,L\t+\t?\n\nFEATURES :\nNAME\tTYPE\nrank\tINT\n"
            "rows\tINT\ncols\tINT\npoints\tSTRING\n\nMTG :\n"
            "ENTITY-CODE\t\t\t\t\t\trank\trows\tcols\tpoints\n"
            "/P3\t\t\t\t\t\t\t\t\t\n^/S1\t\t\t\t\t\t\t\t\t\n"
            f"\t+L1\t\t\t\t\t1\t2\t2\t{row}\n\t+L2\t\t\t\t\t2\t2\t2\t{row}\n"
            "/P7\t\t\t\t\t\t\t\t\t\n^/S1\t\t\t\t\t\t\t\t\t\n"
            f"\t+L4\t\t\t\t\t4\t2\t2\t{row}\n")
    path = tmp_path / "oa.mtg"
    path.write_text(text)
    grids = read_mtg(path)
    assert [g.key for g in grids] == [(3, 1), (3, 2), (7, 4)]
    assert grids[0].points.shape == (2, 2, 3)


def test_convert_to_an_mtg_and_back_gives_the_same_leaves(tmp_path, capsys):
    """``maizeviz convert points.csv --out plants.mtg`` and back: ``maizeviz leaf --json`` of
    the round trip equals the original's, every number."""
    from maizeviz.cli import main

    assert main(["convert", str(mv.example_points()), "--out", str(tmp_path / "p.mtg")]) == 0
    assert main(["convert", str(tmp_path / "p.mtg"), "--out", str(tmp_path / "back.csv")]) == 0
    capsys.readouterr()
    assert main(["leaf", str(mv.example_points()), "--json"]) == 0
    before = capsys.readouterr().out
    assert main(["leaf", str(tmp_path / "back.csv"), "--json"]) == 0
    assert capsys.readouterr().out == before


def test_a_leaf_left_out_of_the_mtg_exits_3_as_the_other_commands(tmp_path, capsys):
    """A NaN in one leaf: the MTG holds the others, the leaf is named as skipped and the exit
    is 3 (some skipped), as ``maizeviz canopy`` gives for the same file; it was a warning
    and exit 0."""
    from maizeviz.cli import EXIT_PARTIAL, main

    lines = mv.example_points().read_text().splitlines()
    lines[5] = ",".join(lines[5].split(",")[:4] + ["nan"] + lines[5].split(",")[5:])
    src = tmp_path / "nan.csv"
    src.write_text("\n".join(lines) + "\n")
    out = tmp_path / "p.mtg"
    assert main(["convert", str(src), "--out", str(out)]) == EXIT_PARTIAL
    err = capsys.readouterr().err
    assert "skipped: plant" in err and "1 skipped" in err
    assert len(read_mtg(out)) == len(mv.read_points(mv.example_points()).leaves) - 1
    assert main(["canopy", str(src)]) == EXIT_PARTIAL
