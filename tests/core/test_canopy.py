"""Canopy layout, tiling arithmetic, canopy measures, layout files, synth and import."""

import json
from pathlib import Path

import numpy as np
import pytest

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import (
    LayoutError,
    layout_from_dict,
    load_layout,
    parse_shape,
    plant_bases,
    save_layout,
    tiled_layout,
    union_area,
)
from maizeviz.canopy.measures import ground_cover, measure_canopy
from maizeviz.cli import EXIT_FAIL, EXIT_OK, main
from maizeviz.errors import MaizevizError
from maizeviz.leaf.fit import fit_leaves
from maizeviz.leaf.grid import LeafGrid
from maizeviz.leaf.synth import PlantShape, block_grids, plant_grids
from maizeviz.mesh.levels import Level, measure, mesh_leaf

PHENO = str(Path(__file__).resolve().parents[2] / "maizeviz/resources/phenotrack3d/1649057232.json.gz")


def flat_leaf(plant, leaf, x0, y0, length, width, z, rows=4, cols=3, stalk=None):
    """A horizontal rectangle [x0, x0+length] x [y0, y0+width] at height z (cm)."""
    s = np.linspace(x0, x0 + length, rows)
    t = np.linspace(y0, y0 + width, cols)
    x, y = np.meshgrid(s, t, indexing="ij")
    pts = np.stack([x, y, np.full_like(x, z)], axis=-1)
    return LeafGrid(plant, leaf, pts, False)


def bases_3x3(rs=60.0, ps=30.0, jitter=0.0, seed=0):
    rng = np.random.default_rng(seed)
    return {1 + 3 * i + j: ((i + 0.5) * rs + rng.normal(0, jitter),
                            (j + 0.5) * ps + rng.normal(0, jitter))
            for i in range(3) for j in range(3)}


@pytest.mark.parametrize("jitter", [0.0, 1.5])
def test_tiling_arithmetic_is_exact(jitter):
    bases = bases_3x3(jitter=jitter, seed=3)
    one = tiled_layout(bases, (1, 1))
    nine = tiled_layout(bases, (3, 3))
    assert one.ground_area_cm2 == pytest.approx(180 * 90, abs=1e-9)
    assert nine.ground_area_cm2 == 9 * one.ground_area_cm2
    assert union_area(nine.cells) == pytest.approx(nine.ground_area_cm2, rel=1e-12)
    assert len(nine.placements) == 81
    assert nine.bounds == pytest.approx((-180, -90, 360, 180), abs=2 * jitter + 1e-9)
    assert "3 rows x 3 plants per row" in one.warnings[0]
    assert not any("overlap" in w for w in nine.warnings)
    # the central tile is the digitized block, unmoved
    centre = [p for p in nine.placements if p.tile == (0, 0)]
    assert {(p.plant, p.x, p.y) for p in centre} == {(k, *v) for k, v in bases.items()}


def test_tiles_are_translations_by_block_size():
    bases = bases_3x3()
    lay = tiled_layout(bases, (2, 3), row_spacing=75, plant_spacing=20)
    xs = sorted({round(p.x - bases[p.plant][0], 6) for p in lay.placements})
    ys = sorted({round(p.y - bases[p.plant][1], 6) for p in lay.placements})
    assert xs == [0.0, 225.0] and ys == [-60.0, 0.0, 60.0]


def test_union_area_with_overlap():
    rects = np.array([[0, 0, 10, 10], [5, 5, 15, 15], [20, 0, 21, 1]])
    assert union_area(rects) == pytest.approx(100 + 100 - 25 + 1)


@pytest.mark.parametrize("text", ["0x3", "3", "axb", "-1x2"])
def test_bad_tile(text):
    with pytest.raises(LayoutError):
        parse_shape(text, "--tile")


@pytest.mark.parametrize("rs, ps", [(-60, 30), (60, 0), (float("nan"), 30)])
def test_bad_spacing(rs, ps):
    with pytest.raises(LayoutError, match="spacing"):
        tiled_layout(bases_3x3(), (1, 1), rs, ps)


def test_ground_cover_of_separate_horizontal_leaves():
    grids = [flat_leaf(1, 1, 10, 10, 30, 8, 100), flat_leaf(1, 2, 50, 40, 20, 10, 80),
             flat_leaf(1, 3, 10, 60, 12.5, 12.5, 50)]
    leaves, _ = fit_leaves(grids)
    # the plant's stalk base is the median of its collar midribs: (10, 45); keep it there
    assert plant_bases(leaves)[1] == pytest.approx((10, 45))
    lay = layout_from_dict({"maizeviz_layout": 1, "row_spacing": 100, "plant_spacing": 100,
                            "field": {"x0": 0, "y0": 0, "x1": 100, "y1": 100},
                            "rows": [{"x": 10, "plants": [{"y": 45, "plant": 1}]}]})
    canopy = build_canopy(leaves, lay, Level(interp=0))
    m = measure_canopy(canopy, cover_resolution=0.25)
    assert m.leaf_area_m2 == pytest.approx((240 + 200 + 156.25) / 1e4, rel=1e-9)
    assert m.projected_area_m2 == pytest.approx(m.leaf_area_m2, rel=1e-9)
    assert m.ground_cover_m2 == pytest.approx(m.leaf_area_m2, rel=0.02)
    assert m.ground_area_m2 == pytest.approx(1.0)
    assert m.lai == pytest.approx(m.leaf_area_m2)


def test_ground_cover_counts_overlap_once_and_stays_inside_plot():
    grids = [flat_leaf(1, 1, 10, 10, 40, 40, 100), flat_leaf(1, 2, 10, 10, 40, 40, 50),
             flat_leaf(1, 3, 90, 90, 40, 40, 60)]                      # hangs out of the plot
    leaves, _ = fit_leaves(grids)
    bx, by = plant_bases(leaves)[1]
    lay = layout_from_dict({"maizeviz_layout": 1, "row_spacing": 100, "plant_spacing": 100,
                            "field": {"x0": 0, "y0": 0, "x1": 100, "y1": 100},
                            "rows": [{"x": bx, "plants": [{"y": by, "plant": 1}]}]})
    canopy = build_canopy(leaves, lay, Level(interp=0))
    cover = ground_cover(canopy, 0.5)
    assert cover == pytest.approx(1600 + 100, rel=0.03)


def test_layout_file_round_trip(tmp_path):
    lay = tiled_layout(bases_3x3(), (3, 1))
    path = tmp_path / "field.json"
    save_layout(path, lay)
    back = load_layout(path, plants=set(range(1, 10)))
    assert sorted((p.plant, round(p.x, 6), round(p.y, 6)) for p in back.placements) == \
        sorted((p.plant, round(p.x, 6), round(p.y, 6)) for p in lay.placements)
    assert back.ground_area_cm2 == pytest.approx(lay.ground_area_cm2)
    assert (back.row_spacing, back.plant_spacing) == (60.0, 30.0)


def _doc(**over):
    d = {"maizeviz_layout": 1, "row_spacing": 60, "plant_spacing": 30,
         "field": {"x0": 0, "y0": 0, "x1": 120, "y1": 60},
         "rows": [{"x": 30, "plants": [{"y": 15, "plant": 1}, {"y": 45, "plant": 2}]},
                  {"x": 90, "plants": [{"y": 15, "plant": 1, "azimuth_deg": 90,
                                        "jitter_cm": 2}]}]}
    d.update(over)
    return d


@pytest.mark.parametrize("change, match", [
    ({"maizeviz_layout": 2}, "reads schema 1"),
    ({"maizeviz_layout": None}, "maizeviz_layout"),
    ({"row_spacing": -60}, "'row_spacing' must be positive"),
    ({"plant_spacing": "30"}, "'plant_spacing' must be a number"),
    ({"field": {"x0": 0, "y0": 0, "x1": -5, "y1": 60}}, "x1 > x0"),
    ({"rows": []}, "non-empty"),
    ({"rows": [{"x": 30, "plants": [{"y": 15, "plant": 7}]}]}, r"rows\[0\].plants\[0\]: plant 7"),
    ({"rows": [{"x": 30, "plants": [{"y": 15, "plant": "1"}]}]}, "integer plant id"),
    ({"rows": [{"x": 30, "plants": [{"y": 1e999, "plant": 1}]}]}, "'y' must be a number"),
    ({"rows": [{"x": 30, "plants": [{"y": 15, "plant": 1, "jitter_cm": -1}]}]}, "jitter"),
])
def test_bad_layout_documents(change, match):
    with pytest.raises(LayoutError, match=match):
        layout_from_dict(_doc(**change), plants={1, 2})


def test_layout_warnings_overlap_and_outside():
    doc = _doc(rows=[{"x": 30, "plants": [{"y": 15, "plant": 1}, {"y": 20, "plant": 2}]},
                     {"x": 500, "plants": [{"y": 15, "plant": 1}]}])
    lay = layout_from_dict(doc, plants={1, 2})
    text = " ".join(lay.warnings)
    assert "outside the field" in text and "closer than the spacing" in text


@pytest.mark.parametrize("ys, words", [((15, 20), "(1 overlapping pair, about"),
                                        ((15, 20, 25), "(3 overlapping pairs, about")])
def test_the_overlap_warning_counts_pairs_in_words(ys, words):
    doc = _doc(rows=[{"x": 30, "plants": [{"y": y, "plant": 1} for y in ys]}])
    text = " ".join(layout_from_dict(doc, plants={1, 2}).warnings)
    assert words in text, text


@pytest.mark.parametrize("content, match", [
    ("not json", "not valid JSON"),
    ("[" * 100000 + "]" * 100000, "not valid JSON"),
    ('"a string"', "JSON object"),
])
def test_hostile_layout_files(tmp_path, content, match):
    p = tmp_path / "evil.json"
    p.write_text(content)
    with pytest.raises(LayoutError, match=match):
        load_layout(p)


def test_layout_rotation_and_jitter_applied():
    grids = plant_grids(1, PlantShape(leaves=4), base=(0, 0, 0), rng=np.random.default_rng(0))
    grids += plant_grids(2, PlantShape(leaves=4), base=(0, 50, 0), rng=np.random.default_rng(1))
    leaves, _ = fit_leaves(grids)
    lay = layout_from_dict(_doc(), plants={1, 2})
    canopy = build_canopy(leaves, lay, Level(interp=0))
    assert canopy.n_plants == 3 and canopy.n_leaves == 12
    inst2 = canopy.vertices[np.unique(canopy.faces[canopy.face_instance == 2])]
    inst0 = canopy.vertices[np.unique(canopy.faces[canopy.face_instance == 0])]
    # the same plant, turned 90 degrees: same area footprint size, swapped extents
    ext0 = np.ptp(inst0[:, :2], axis=0)
    ext2 = np.ptp(inst2[:, :2], axis=0)
    assert ext0 == pytest.approx(ext2[::-1], rel=1e-6)


def test_build_progress_and_cancel():
    leaves, _ = fit_leaves(block_grids(1, 2, seed=1))
    lay = tiled_layout(plant_bases(leaves), (2, 2))
    calls = []
    build_canopy(leaves, lay, Level(triangles=36), progress=lambda d, t: calls.append((d, t)))
    assert calls[-1][0] == calls[-1][1] and len(calls) > 3
    assert all(b[0] >= a[0] for a, b in zip(calls, calls[1:]))
    with pytest.raises(InterruptedError):
        build_canopy(leaves, lay, Level(interp=1), progress=lambda d, t: d < 5)


def test_layout_naming_missing_plant_is_refused():
    leaves, _ = fit_leaves(block_grids(1, 1, seed=1))
    lay = layout_from_dict(_doc())
    with pytest.raises(MaizevizError, match="plant.*2"):
        build_canopy(leaves, lay, Level(interp=0))


def test_synthetic_plant_matches_the_paper():
    """Default synthetic plant: ~245 cm, ~16 leaves, ~0.94 m2 of leaf (docs/method.md, synthetic plant)."""
    areas, heights, counts = [], [], []
    for seed in range(4):
        grids = block_grids(1, 1, seed=seed)
        leaves, _ = fit_leaves(grids)
        areas.append(sum(measure(lf, mesh_leaf(lf, Level(interp=4))).area_cm2 for lf in leaves))
        heights.append(max(g.points[..., 2].max() for g in grids))
        counts.append(len(grids))
    assert np.mean(areas) == pytest.approx(9400, rel=0.10)
    assert 15 <= np.mean(counts) <= 17
    assert np.mean(heights) == pytest.approx(245, rel=0.08)


def test_cli_synth_then_canopy_reproduces_table2_shape(tmp_path, capsys):
    block = tmp_path / "block.csv"
    assert main(["synth", "--plants", "3x3", "--seed", "7", "--out", str(block)]) == EXIT_OK
    code = main(["canopy", str(block), "--tile", "3x3", "--levels", "K4,standard,36,4",
                 "--json", "--cover-resolution", "2"])
    out = capsys.readouterr().out
    assert code == EXIT_OK
    runs = {r["level"]: r for r in json.loads(out)["levels"]}
    ref = runs["K=4"]
    for key in ("plants", "leaves", "triangles", "leaf_area_m2", "projected_area_m2",
                "ground_cover_m2", "ground_area_m2", "lai"):
        assert key in ref
    assert ref["plants"] == 81 and ref["ground_area_m2"] == pytest.approx(14.58)
    assert 4.5 < ref["lai"] < 5.8
    assert ref["ground_cover_m2"] < ref["ground_area_m2"]
    for lv in ("standard", "36 triangles"):
        assert runs[lv]["leaf_area_m2"] == pytest.approx(ref["leaf_area_m2"], rel=0.03)
    assert runs["4 triangles, widths unscaled"]["leaf_area_m2"] < 0.9 * ref["leaf_area_m2"]
    assert runs["4 triangles"]["leaf_area_m2"] == pytest.approx(ref["leaf_area_m2"], rel=1e-6)


def test_cli_canopy_bad_input(tmp_path, capsys):
    block = tmp_path / "block.csv"
    main(["synth", "--plants", "1x2", "--out", str(block)])
    capsys.readouterr()
    for argv, says in [(["--tile", "0x3"], "--tile"), (["--row-spacing", "-5"], "spacing"),
                       (["--layout", str(tmp_path / "none.json")], "no such layout"),
                       (["--cover-resolution", "0"], "cover-resolution")]:
        assert main(["canopy", str(block), *argv]) == EXIT_FAIL
        err = capsys.readouterr().err
        assert says in err and "Traceback" not in err


def test_cli_canopy_export_and_layout(tmp_path, capsys):
    block = tmp_path / "block.csv"
    main(["synth", "--plants", "1x2", "--out", str(block)])
    lay = tmp_path / "lay.json"
    out = tmp_path / "c.vtp"
    assert main(["canopy", str(block), "--tile", "2x1", "--triangles", "8", "--export", str(out),
                 "--save-layout", str(lay)]) == EXIT_OK
    import pyvista
    mesh = pyvista.read(out)
    assert set(np.unique(mesh.cell_data["plant"])) == {1, 2, 3, 4}
    capsys.readouterr()
    assert main(["canopy", str(block), "--layout", str(lay), "--json"]) == EXIT_OK
    data = json.loads(capsys.readouterr().out)
    assert data["plants"] == 4


def test_import_phenomenal_real_plant(tmp_path, capsys):
    out = tmp_path / "real.csv"
    assert main(["import-phenomenal", PHENO, "--out", str(out), "--plant", "5"]) == EXIT_OK
    assert main(["leaf", str(out), "--json"]) == EXIT_OK
    leaves = json.loads(capsys.readouterr().out)["leaves"]
    from maizeviz.io.phenomenal import leaf_traits, load_phenomenal
    traits = {t.rank: t for t in leaf_traits(load_phenomenal(PHENO))}
    assert {lf["plant"] for lf in leaves} == {5} and len(leaves) == 16
    mature = [lf for lf in leaves if traits[lf["leaf"]].label == "mature_leaf"]
    ratio = [lf["area_cm2"] / traits[lf["leaf"]].area_cm2 for lf in mature]
    assert 0.85 < np.median(ratio) < 1.15


def test_import_phenomenal_bad_files(tmp_path, capsys):
    bad = tmp_path / "x.json.gz"
    bad.write_bytes(b"\x1f\x8bnot really gzip")
    assert main(["import-phenomenal", str(bad), "--out", str(tmp_path / "o.csv")]) == EXIT_FAIL
    assert "not a Phenomenal JSON" in capsys.readouterr().err
    empty = tmp_path / "e.json"
    empty.write_text('{"voxel_organs": []}')
    assert main(["import-phenomenal", str(empty), "--out", str(tmp_path / "o.csv")]) == EXIT_FAIL
    assert "no leaf could be imported" in capsys.readouterr().err


def test_huge_layout_refused_and_large_one_fast():
    rows = [{"x": 30.0 * i, "plants": [{"y": 30.0 * j, "plant": 1} for j in range(1001)]}
            for i in range(100)]
    with pytest.raises(LayoutError, match="at most 100000"):
        layout_from_dict(_doc(rows=rows), plants={1})
    big = layout_from_dict(_doc(rows=[{"x": 60.0 * i, "plants": [{"y": 30.0 * j, "plant": 1}
                                                                  for j in range(200)]}
                                      for i in range(100)]), plants={1})
    assert len(big.placements) == 20000 and not any("closer" in w for w in big.warnings)
    assert len(big.warnings) == 1 and "and 19990 more" in big.warnings[0]
