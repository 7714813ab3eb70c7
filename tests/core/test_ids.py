"""Identifiers as wide as the data: no plant and leaf id packed into one number, anywhere.

Issue 25 case 5: leaf tables keyed leaves by ``instance * 10_000 + leaf``, so a plant with
10,000 leaves or more (or leaf ids from 10,000, as segmenters write them) lent its leaves to
the next plant. The ids now group by their columns (:mod:`maizeviz.ids`); these tests use
10,003 leaves on one plant and ids next to 2^31 - 1, the largest the canopy holds.
"""

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.cli import main
from maizeviz.ids import group_rows, groups

ROOT = Path(__file__).resolve().parents[2]
BIG = 2**31 - 1


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.integers(-2**63, 2**63 - 1), st.integers(-2**63, 2**63 - 1),
                          st.integers(-3, 3)), max_size=60))
def test_groups_are_those_of_the_rows_themselves(rows):
    """The oracle is Python's own tuples: sorted distinct rows, each row's position among
    them, over the whole int64 range (where any packing overflows)."""
    cols = [np.array([r[k] for r in rows], np.int64) for k in range(3)]
    keys, inverse = groups(*cols)
    want = sorted(set(rows))
    assert [tuple(int(v) for v in k) for k in keys] == want
    assert [want[i] for i in inverse] == rows
    order, starts = group_rows(inverse, len(keys))
    for k, row in enumerate(want):
        idx = order[starts[k]:starts[k + 1]]
        assert list(idx) == [i for i, r in enumerate(rows) if r == row]


def _leaf_lines(plant, leaf, x0, y0, z):
    return [f"{plant},{leaf},{r},{c},{x0 + 0.5 * c:.3f},{y0 + r:.3f},{z + 0.2 * r:.3f}"
            for r in range(3) for c in range(3)]


def _two_plants(tmp_path, plant_ids, leaf_ids_1, leaf_id_2):
    """A points file of two plants (plant 1 with ``leaf_ids_1``, small leaves at random places
    around x = 0; plant 2 with one leaf at x = 60) and a layout standing them 60 cm apart."""
    rng = np.random.default_rng(0)
    lines = ["plant,leaf,row,col,x,y,z"]
    for leaf in leaf_ids_1:
        lines += _leaf_lines(plant_ids[0], leaf, rng.uniform(-10, 10), rng.uniform(-10, 10),
                             rng.uniform(10, 150))
    lines += _leaf_lines(plant_ids[1], leaf_id_2, 50.0, -1.0, 100.0)
    points = tmp_path / "points.csv"
    points.write_text("\n".join(lines) + "\n")
    layout = tmp_path / "layout.json"
    layout.write_text(json.dumps({
        "maizeviz_layout": 1, "row_spacing": 60, "plant_spacing": 30,
        "field": {"x0": -30, "y0": -30, "x1": 90, "y1": 30},
        "rows": [{"x": 0, "plants": [{"y": 0, "plant": plant_ids[0]}]},
                 {"x": 60, "plants": [{"y": 0, "plant": plant_ids[1]}]}]}))
    return points, layout


def _light_tables(tmp_path, capsys, points, layout):
    leaves, plants = tmp_path / "leaves.csv", tmp_path / "plants.csv"
    capsys.readouterr()
    code = main(["light", str(points), "--layout", str(layout), "--interp", "0",
                 "--sun-zenith", "0", "--sun-azimuth", "0", "--density", "1", "--heights", "0",
                 "--leaf-light", str(leaves), "--plant-light", str(plants), "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    with open(leaves, newline="") as fh:
        leaf_rows = list(csv.DictReader(fh))
    with open(plants, newline="") as fh:
        plant_rows = list(csv.DictReader(fh))
    return json.loads(out), leaf_rows, plant_rows


@pytest.mark.parametrize("plant_ids, leaf_ids_1, leaf_id_2", [
    ((1, 2), range(1, 10_004), 1),                         # 10,003 leaves on plant 1
    ((BIG, -BIG), [BIG, BIG - 1, 1, 10_000, 20_001], BIG),  # ids next to 2^31
])
@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_leaves_keep_their_plant_whatever_their_ids(tmp_path, capsys, plant_ids, leaf_ids_1,
                                                    leaf_id_2, fmt):
    """The same in a Parquet points file (ids stored as int32, read column by column)."""
    points, layout = _two_plants(tmp_path, plant_ids, leaf_ids_1, leaf_id_2)
    if fmt == "parquet":
        assert main(["convert", str(points), "--out", str(points.with_suffix(".parquet"))]) == 0
        points = points.with_suffix(".parquet")
    doc, leaf_rows, plant_rows = _light_tables(tmp_path, capsys, points, layout)
    # each leaf row names its own plant and leaf
    by_instance = {int(r["instance"]): int(r["plant"]) for r in plant_rows}
    assert by_instance == {1: plant_ids[0], 2: plant_ids[1]}
    for r in leaf_rows:
        assert int(r["plant"]) == plant_ids[int(r["instance"]) - 1]
        if int(r["instance"]) == 1:
            assert int(r["leaf"]) in set(leaf_ids_1)
        else:
            assert int(r["leaf"]) == leaf_id_2
    assert len({(r["instance"], r["leaf"]) for r in leaf_rows}) == len(leaf_rows)
    # plant 2's one leaf stands alone under a vertical sun: its sunlit area is its own
    second = [r for r in leaf_rows if int(r["instance"]) == 2]
    assert len(second) == 1
    # conservation: leaf rows sum to the plant rows, and these to the canopy's interception
    for p in plant_rows:
        mine = [r for r in leaf_rows if r["instance"] == p["instance"]]
        assert int(p["leaves_lit"]) == len(mine)
        for col in ("sunlit_intercepted_cm2", "second_class_intercepted_cm2"):
            assert float(p[col]) == pytest.approx(sum(float(r[col]) for r in mine), rel=1e-12)
    rect = doc["rect_cm"]
    area = (rect[2] - rect[0]) * (rect[3] - rect[1])
    assert sum(float(p["sunlit_intercepted_cm2"]) for p in plant_rows) == pytest.approx(
        doc["sunlit_intercepted_fraction"] * area, rel=1e-12)


def test_an_id_beyond_32_bits_is_one_line_naming_the_line(tmp_path, capsys):
    points, _ = _two_plants(tmp_path, (1, 2), [1], 2**31)
    capsys.readouterr()
    assert main(["leaf", str(points), "--interp", "0", "--strict"]) == 1
    err = capsys.readouterr().err
    assert "leaf id 2147483648 is beyond the range" in err and err.count("\n") == 1


def test_mesh_leaf_ids_beyond_9999_read_export_and_come_back(tmp_path):
    """Mesh files took leaf ids up to 9999 only (the light tables' packing); now any 32-bit
    id, through reading, the leaf table and an export read back."""
    from maizeviz.canopy.export import export_canopy
    from maizeviz.canopy.from_mesh import read_mesh_canopy
    from maizeviz.light.scene.request import LightRequest, Sampling
    from maizeviz.light.sources.sun import Sun
    from maizeviz.light.trace.beam import trace_light
    from tests.core.test_mesh_canopy import write_ply

    leaves = [1, 9_999, 10_000, 10_003, BIG]
    v, f, plant, leaf = [], [], [], []
    for k, lid in enumerate(leaves):
        x = 10.0 * k
        v += [[x, 0, 50], [x + 8, 0, 50], [x + 8, 8, 55], [x, 8, 55]]
        f += [[4 * k, 4 * k + 1, 4 * k + 2], [4 * k, 4 * k + 2, 4 * k + 3]]
        plant += [BIG if k % 2 else 7] * 2
        leaf += [lid] * 2
    path = write_ply(tmp_path / "m.ply", np.array(v, float), f,
                     {"plant": plant, "leaf": leaf})
    canopy, _, _ = read_mesh_canopy(path, unit="cm")
    assert sorted(set(canopy.face_leaf.tolist())) == leaves
    r = trace_light(canopy, LightRequest(Sun(0, 0), Sampling((0,), 4.0)))
    got = {(int(x.plant), int(x.leaf)): float(x.sunlit_area_cm2)
           for x in r.table("leaf", canopy).itertuples()}
    # each leaf is an 8 x 8 cm square seen from above, rising 5 cm across, alone under a
    # vertical sun: all of its 8 x sqrt(8^2 + 5^2) cm2 is sunlit
    assert got == pytest.approx({(BIG if k % 2 else 7, lid): 8 * 89**0.5
                                 for k, lid in enumerate(leaves)}, rel=0.05)
    again, _, _ = read_mesh_canopy(export_canopy(tmp_path / "back.ply", canopy), unit="cm")
    assert np.array_equal(again.face_leaf, canopy.face_leaf)


#: An id column multiplied by a wide constant, a shift or a radix taken from the data: the
#: packing this file's tests found (``rep[face_instance] * 10_000 + face_leaf``).
PACKING = re.compile(r"(plant|leaf|inst|instance)\w*(\[[^\]]*\])?(\.astype\([^)]*\))?\s*\*\s*"
                     r"(\(?[0-9][0-9_]{3,}|\(?1\s*<<|\(?2\s*\*\*|\(?MAX_\w+|\(?\w+\.max\(\))")


def test_no_id_is_packed_with_another_anywhere():
    """Grep the core and the app for ids packed into one number."""
    found = []
    for path in sorted((ROOT / "maizeviz").rglob("*.py")) + sorted((ROOT / "app").rglob("*.py")):
        for no, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#", 1)[0]
            if PACKING.search(code):
                found.append(f"{path.relative_to(ROOT)}:{no}: {line.strip()}")
    assert not found, "\n".join(found)
