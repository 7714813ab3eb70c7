"""Stalks in the light (issue 34 item 4): on by default, their share apart from the leaves,
the paper's leaves-only canopy one flag away and unchanged.

On the bundled block (36 triangles a leaf, tiled 3 x 3, periodic field), what holds exactly:

- a stalk only adds to the scene, so every sensor that sees the sun with the stalks sees it
  without them: transmission with stalks <= leaves-only at every height, per sensor;
- each ground ray's first hit is a leaf, a stalk or nothing: the leaves' and the stalks'
  intercepted fractions and T(0) add to 1;
- the energy balance closes with the stalks' absorption in it, which is 0 leaves-only;
- the leaf rows (and so every leaf area and LAI) are the leaves' only in both modes.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.cli import EXIT_OK, main
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.engine import LightEngine
from maizeviz.light.results.stalks import stalk_placements, stalk_rows
from maizeviz.light.sources.sun import Sun
from maizeviz.mesh.levels import Level
from maizeviz.resources import example_points

SUN = Sun(40.0, 150.0)
HEIGHTS = (0.0, 50.0, 100.0, 150.0)


@pytest.fixture(scope="module")
def canopy():
    leaves = read_leaves(example_points()).leaves
    return build_canopy(leaves, layout_for(leaves, (3, 3)), Level(triangles=36))


@pytest.fixture(scope="module")
def engines(canopy):
    return (LightEngine(canopy, periodic=True, density=1.0, heights_cm=HEIGHTS),
            LightEngine(canopy, periodic=True, density=1.0, heights_cm=HEIGHTS,
                        with_stalks=False))


def test_stalks_are_on_by_default_and_only_block_more(canopy, engines):
    stalks, leaves = engines
    assert stalks.with_stalks and not leaves.with_stalks
    a, b = stalks.sun(SUN), leaves.sun(SUN)
    assert np.all(a.transmission <= b.transmission)
    for k in range(len(HEIGHTS)):
        lit_a, lit_b = a.lit(k), b.lit(k)
        assert not np.any(lit_a & ~lit_b)              # lit with stalks: lit without
    assert a.transmission[0] < b.transmission[0]       # the stalks do cast shadows here
    # every ground ray's first hit: a leaf, a stalk or the ground
    total = a.sunlit_intercepted_fraction + a.stalk_intercepted_fraction + a.transmission[0]
    assert total == pytest.approx(1.0, abs=1e-12)
    assert a.stalk_intercepted_fraction > 0
    assert b.stalk_intercepted_fraction == 0.0
    assert b.sunlit_intercepted_fraction + b.transmission[0] == pytest.approx(1.0, abs=1e-12)
    # leaf rows hold the leaves only, with the same leaf areas in both modes
    ra = {(r["instance"], r["leaf"]): r["leaf_area_cm2"] for r in a.leaf_rows(canopy)}
    rb = {(r["instance"], r["leaf"]): r["leaf_area_cm2"] for r in b.leaf_rows(canopy)}
    assert all(leaf > 0 for _, leaf in ra) and all(ra[k] == rb[k] for k in ra.keys() & rb.keys())


def test_stalk_rows_sum_the_stalks_share_per_plant(canopy, engines):
    res = engines[0].sun(SUN)
    rows = stalk_rows(canopy, {"sunlit_intercepted_cm2": res.first_hits * res.ray_area_cm2})
    assert rows and all(r["leaf"] == 0 and r["stalk_area_cm2"] > 0 for r in rows)
    total = sum(r["sunlit_intercepted_cm2"] for r in rows) / res.rect_area_cm2
    assert total == pytest.approx(res.stalk_intercepted_fraction, rel=1e-12)
    inst = stalk_placements(canopy)
    assert len(inst) == len(canopy.stalk_faces) and inst.max() == canopy.n_plants - 1
    # light traced without stalks has no stalk part
    leaves = engines[1].sun(SUN)
    assert stalk_rows(canopy, {"x": leaves.first_hits.astype(float)}) == []


def test_absorbed_balance_holds_the_stalks_apart(engines):
    stalks, leaves = engines
    a = stalks.absorbed(SUN, diffuse_w_m2=100.0, directions=16, density=0.25)
    b = leaves.absorbed(SUN, diffuse_w_m2=100.0, directions=16, density=0.25)
    assert a.balance.absorbed_stalks > 0 and b.balance.absorbed_stalks == 0.0
    assert abs(a.balance.closure) < 0.02 and abs(b.balance.closure) < 0.02
    nf = stalks.canopy.n_triangles
    area = (a.rect[2] - a.rect[0]) * (a.rect[3] - a.rect[1]) * 1e-4
    assert a.balance.absorbed_leaves == pytest.approx(a.triangle_absorbed_w[:nf].sum() / area)
    assert a.balance.absorbed_stalks == pytest.approx(a.triangle_absorbed_w[nf:].sum() / area)
    assert a.fraction_absorbed == pytest.approx(a.balance.absorbed_leaves / a.balance.incident)


def test_the_command_line_reports_stalks_and_leaves_only_is_the_papers(capsys, tmp_path):
    base = ["light", str(example_points()), "--tile", "3x3", "--triangles", "36",
            "--periodic", "--sun-zenith", "40", "--sun-azimuth", "150", "--density", "1",
            "--heights", "0,100", "--json"]
    leaf_csv, plant_csv = tmp_path / "leaf.csv", tmp_path / "plant.csv"
    assert main([*base, "--leaf-light", str(leaf_csv), "--plant-light", str(plant_csv)]) \
        == EXIT_OK
    on = json.loads(capsys.readouterr().out)
    assert main([*base, "--leaves-only"]) == EXIT_OK
    off = json.loads(capsys.readouterr().out)
    assert on["stalks"]["traced"] and not off["stalks"]["traced"]
    assert on["stalks"]["sun_intercepted_fraction"] > 0
    assert on["transmission"][0] <= off["transmission"][0]
    assert on["sunlit_intercepted_fraction"] + on["stalks"]["sun_intercepted_fraction"] + \
        on["transmission"][0] == pytest.approx(1.0, abs=1e-12)
    leaf_lines = leaf_csv.read_text().splitlines()
    leaf_col = leaf_lines[0].split(",").index("leaf")
    assert all(r.split(",")[leaf_col] != "0" for r in leaf_lines[1:])   # leaves only
    plants = plant_csv.read_text().splitlines()
    col = plants[0].split(",").index("stalk_sunlit_intercepted_cm2")
    lit = [float(r.split(",")[col]) for r in plants[1:]]
    assert sum(v > 0 for v in lit) > 0
    assert sum(lit) / ((on["rect_cm"][2] - on["rect_cm"][0]) * (on["rect_cm"][3] -
                       on["rect_cm"][1])) == pytest.approx(
        on["stalks"]["sun_intercepted_fraction"], rel=1e-9)
    assert "stalk_sunlit_intercepted_cm2" in plant_csv.read_text().splitlines()[0]
    assert main([*base, "--leaves-only", "--with-stalks"]) != EXIT_OK
    assert "contradict" in capsys.readouterr().err


def test_a_stalk_is_no_leaf_area_in_the_canopy_measures(canopy):
    """--with-stalks lets the stalks shade the ground; leaf area and LAI stay the leaves'."""
    from maizeviz.canopy.measures import measure_canopy

    leaves = measure_canopy(canopy, 2.0)
    stalks = measure_canopy(canopy, 2.0, with_stalks=True)
    assert stalks.leaf_area_m2 == leaves.leaf_area_m2
    assert stalks.projected_area_m2 == leaves.projected_area_m2
    assert stalks.ground_cover_m2 >= leaves.ground_cover_m2
