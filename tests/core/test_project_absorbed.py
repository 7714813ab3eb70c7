"""Absorbed light (leaf optics, scattering) in projects: a sun's absorbed light is stored
beside it and read back bit for bit, with the optics it was traced with; what is damaged is
refused in one line, and what declares more triangles than its canopy has is left out unread."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.io.archive import ProjectError, Record, load_project, save_project
from maizeviz.io.points import write_points
from maizeviz.leaf.fit import read_leaves
from maizeviz.leaf.synth import block_grids
from maizeviz.light.engine import LightEngine
from maizeviz.light.specs import OpticsSpec
from maizeviz.mesh.levels import parse_level
from maizeviz.project import study
from maizeviz.project.records import absorbed_from_record, run_from_record, run_record
from maizeviz.project.settings import settings_doc

SPEC = OpticsSpec("nir", 0.4, 0.35, 0.2, 500.0, 50.0, 2, 7)


@pytest.fixture(scope="module")
def traced(tmp_path_factory):
    path = tmp_path_factory.mktemp("absorbed") / "four.csv"
    write_points(path, block_grids(2, 2, seed=5))
    leaves = read_leaves(path).leaves
    layout = layout_for(leaves, (1, 1))
    canopy = build_canopy(leaves, layout, parse_level("16"))
    engine = LightEngine(canopy, density=0.3, heights_cm=(0.0, 100.0), periodic=True,
                         threads=1)
    light = SPEC.absorbed(engine, engine.sun(zenith=30, azimuth=180).sun)
    return path, leaves, layout, canopy, light


def test_absorbed_light_round_trips_with_its_optics(traced, tmp_path):
    path, leaves, layout, canopy, light = traced
    proj = study.make_project(str(path), path.read_bytes(), None, layout,
                              {"tile": 1, "level": "16"}, {},
                              [("16 triangles", light, settings_doc("absorbed", SPEC))])
    target = tmp_path / "a.maizeviz"
    save_project(target, proj)
    opened = study.open_project(target)
    results, notes = study.results_on(opened, layout, leaves)
    assert not notes and len(results) == 1
    got = results[0]
    assert got.kind == "absorbed" and got.label == "16 triangles"
    assert got.specs() == SPEC
    back = got.result
    assert back.balance == light.balance and back.optics == light.optics
    assert back.band == "nir" and back.irradiance_w_m2 == light.irradiance_w_m2
    np.testing.assert_array_equal(back.triangle_absorbed_w, light.triangle_absorbed_w)
    np.testing.assert_array_equal(back.triangle_sunlit_cm2, light.triangle_sunlit_cm2)
    assert (back.rect, back.rays, back.depth, back.seed, back.periodic) == \
        (light.rect, light.rays, light.depth, light.seed, light.periodic)
    # tables from the record equal the traced result's
    assert back.table("plant", canopy).equals(light.table("plant", canopy))
    # what photosynthesis needs comes back too: its figures and errors bit for bit
    np.testing.assert_array_equal(back.triangle_direct_w, light.triangle_direct_w)
    assert back.sun_direction == light.sun_direction
    for name in ("absorbed", "direct", "sunlit_cm2"):
        assert (getattr(back.batches, name) != getattr(light.batches, name)).nnz == 0


def test_a_par_records_photosynthesis_comes_back_the_same(traced, tmp_path):
    from maizeviz.light.results.assimilation import assimilate
    from maizeviz.photosynthesis.split import leaf_model

    path, leaves, layout, canopy, _ = traced
    engine = LightEngine(canopy, density=0.3, heights_cm=(0.0,), periodic=True, threads=1)
    par = OpticsSpec("par", 0.1, 0.05, 0.1, 480.0, 60.0, 20, 3, photosynthesis="c4",
                     temperature_c=30.0, photosynthesis_params=(("vmax", 45.0),))
    light = par.absorbed(engine, engine.sun(zenith=30, azimuth=180).sun)
    proj = study.make_project(str(path), path.read_bytes(), None, layout,
                              {"tile": 1, "level": "16"}, {},
                              [("16 triangles", light, settings_doc("absorbed", par))])
    target = tmp_path / "p.maizeviz"
    save_project(target, proj)
    got = study.results_on(study.open_project(target), layout, leaves)[0][0]
    back = got.result
    assert got.specs() == par                   # the leaf model chosen is kept with the result
    model = leaf_model("c4", vmax=45.0)
    a, b = assimilate(canopy, light, model, 30.0), assimilate(canopy, back, model, 30.0)
    assert a.as_dict() == b.as_dict() and a.canopy_gross_umol_m2_s > 0
    assert a.table("leaf", canopy).equals(b.table("leaf", canopy))
    assert got.specs().assimilation(canopy, back).as_dict() == a.as_dict()
    # a stored leaf model that is not one is refused in one line naming the project
    import json

    from maizeviz.project.settings import run_settings

    doc = json.loads(json.dumps(settings_doc("absorbed", par)))     # as a project stores it
    doc["optics"]["photosynthesis"] = "c3"
    with pytest.raises(ProjectError, match="unknown photosynthesis model 'c3'") as err:
        run_settings("absorbed", back, doc, "p.maizeviz")
    assert "p.maizeviz" in str(err.value) and "\n" not in str(err.value)
    # the C4 temperature response is stored; a project saved before it was a choice computed
    # with CLM 4.5's and reads as that
    doc = json.loads(json.dumps(settings_doc("absorbed", par)))
    assert doc["optics"]["c4_temperature"] == "collatz"
    assert run_settings("absorbed", back, doc, "p").leaf_model().temperature_response == \
        "collatz"
    del doc["optics"]["c4_temperature"]
    old = run_settings("absorbed", back, doc, "p")
    assert old.c4_temperature == "clm45" and old.leaf_model().temperature_response == "clm45"


def _damaged(rec: Record, **change) -> Record:
    meta = dict(rec.meta)
    arrays = dict(rec.arrays)
    for k, v in change.items():
        if k in arrays or k.startswith("triangle_"):
            if v is None:
                arrays.pop(k, None)
            else:
                arrays[k] = v
        else:
            meta[k] = v
    return replace(rec, meta=meta, arrays=arrays)


@pytest.mark.parametrize("change, says", [
    ({"triangle_absorbed_w": None}, "has no array 'triangle_absorbed_w'"),
    ({"triangle_absorbed_w": -np.ones(5)}, "outside"),
    ({"triangle_sunlit_cm2": np.zeros(3)}, "expected"),
    ({"optics": {"reflectance": 0.7, "transmittance": 0.6, "ground_reflectance": 0.1}},
     "cannot be used"),
    ({"optics": {"reflectance": 2, "transmittance": 0.1, "ground_reflectance": 0.1}},
     "out of range"),
    ({"band": 7}, "band"),
    ({"balance": {"incident": "x"}}, "incident"),
    ({"rect": [0, 1]}, "inconsistent sizes"),
])
def test_a_damaged_absorbed_record_is_one_line(traced, change, says):
    light = traced[4]
    rec = run_record("16 triangles", light, settings_doc("absorbed", SPEC))
    assert absorbed_from_record(rec, "p.maizeviz")[1].balance == light.balance
    with pytest.raises(ProjectError, match=says) as info:
        run_from_record(_damaged(rec, **change), "p.maizeviz")
    assert "\n" not in str(info.value) and str(info.value).startswith("p.maizeviz")


def test_absorbed_light_declaring_more_triangles_than_its_canopy_is_left_out(traced, tmp_path):
    path, leaves, layout, canopy, light = traced
    big = replace(light, triangle_absorbed_w=np.zeros(canopy.n_triangles * 50),
                  triangle_sunlit_cm2=np.zeros(canopy.n_triangles * 50))
    proj = study.make_project(str(path), path.read_bytes(), None, layout,
                              {"tile": 1, "level": "16"}, {}, [("16 triangles", big)])
    target = tmp_path / "big.maizeviz"
    save_project(target, proj)
    results, notes = study.results_on(study.open_project(target), layout, leaves)
    assert not results and len(notes) == 1 and "absorbed result" in notes[0]
    assert load_project(target).results[0].kind == "light_absorbed"


def test_optics_per_rank_travel_with_the_absorbed_light(traced, tmp_path):
    path, leaves, layout, canopy, _ = traced
    spec = OpticsSpec("par", ranks=((1, 0.2, 0.1), (2, 0.18, 0.08)))
    engine = LightEngine(canopy, density=0.3, heights_cm=(0.0,), periodic=True, threads=1)
    light = spec.absorbed(engine, engine.sun(zenith=40, azimuth=120).sun)
    assert light.optics.ranks == ((1, 0.2, 0.1), (2, 0.18, 0.08))
    proj = study.make_project(str(path), path.read_bytes(), None, layout,
                              {"tile": 1, "level": "16"}, {},
                              [("16 triangles", light, settings_doc("absorbed", spec))])
    target = tmp_path / "r.maizeviz"
    save_project(target, proj)
    got = study.results_on(study.open_project(target), layout, leaves)[0][0]
    assert got.result.optics == light.optics and got.specs().optics() == light.optics
    rec = run_record("16 triangles", light)
    rec.meta["optics"] = dict(rec.meta["optics"], ranks=[[1, 0.2]])
    with pytest.raises(ProjectError, match="cannot be used"):
        run_from_record(rec, "p.maizeviz")
