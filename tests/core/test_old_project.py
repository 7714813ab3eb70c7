"""A project saved before maizeviz/light/ was split into layers still opens whole.

``data/light-0.1.maizeviz`` was written by maizeviz 0.1.0 at commit e6c25db (``light/`` as 26
flat modules, the results in ``transmission``, ``daylight`` and ``scatter``): a sun, a sky, a
Perez day and absorbed PAR traced on a synthetic block of 2 x 2 plants at 16 triangles a leaf,
with their settings, saved as the app saves them (``data/README.md`` says how). The oracle is
the file itself: every number it stores comes back, in today's result types, and the tables
built from them add up.
"""

import json
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest

import maizeviz as mv
from maizeviz.light.specs import DaySpec, OpticsSpec, SkySpec
from maizeviz.project import study

OLD = Path(__file__).parent / "data" / "light-0.1.maizeviz"


@pytest.fixture(scope="module")
def old(tmp_path_factory):
    folder = tmp_path_factory.mktemp("old")
    path = folder / OLD.name
    shutil.copyfile(OLD, path)
    return path, mv.read_study(path, cache=folder / "cache")


@pytest.fixture(scope="module")
def stored():
    """The file's own JSON records and arrays, read without maizeviz."""
    with zipfile.ZipFile(OLD) as zf:
        doc = json.loads(zf.read("project.json"))
        with zf.open("arrays.npz") as fh, np.load(fh, allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in npz.files}
    return doc, arrays


def test_every_result_of_the_old_project_opens_as_todays_type(old):
    _, s = old
    assert [r.kind for r in s.results] == ["sun", "sky", "day", "absorbed"]
    types = (mv.LightResult, mv.SkyLight, mv.PeriodLight, mv.AbsorbedLight)
    assert all(isinstance(r.result, t) for r, t in zip(s.results, types))
    assert {r.label for r in s.results} == {"16"} and s.level == "16 triangles"
    assert sorted(p.plant for p in s.layout.placements) == [1, 2, 3, 4]
    # the points file it names is gone: its own copy is used, and said so
    assert any("using the copy saved in the project" in n for n in s.notes)


def test_the_stored_numbers_come_back_bit_for_bit(old, stored):
    doc, arrays = stored
    sun, sky, day, absorbed = (r.result for r in old[1].results)
    meta = [r["meta"] for r in doc["results"]]
    np.testing.assert_array_equal(sun.transmission, meta[0]["transmission"])
    for name in ("first_z", "sensor_lit", "first_hits", "second_hits"):
        np.testing.assert_array_equal(getattr(sun, name), arrays[f"r0.{name}"])
    np.testing.assert_array_equal(sky.transmission, meta[1]["transmission"])
    for name in ("per_direction", "triangle_share", "maps", "map_rays"):
        np.testing.assert_array_equal(getattr(sky, name), arrays[f"r1.{name}"])
    for name in ("step_transmission", "triangle_direct_mol", "triangle_diffuse_mol", "maps"):
        np.testing.assert_array_equal(getattr(day, name), arrays[f"r2.{name}"])
    np.testing.assert_array_equal(day.diffuse.f1, arrays["r2.perez_f1"])
    np.testing.assert_array_equal(day.sky.triangle_share, arrays["r2.diffuse_triangle_share"])
    np.testing.assert_array_equal(absorbed.triangle_absorbed_w, arrays["r3.triangle_absorbed_w"])
    assert absorbed.balance.as_dict() | meta[3]["balance"] == absorbed.balance.as_dict()


def test_the_old_results_table_per_leaf_and_per_plant_alike(old):
    s = old[1]
    canopy = mv.build_canopy(s.plants, s.layout, level=s.level)
    columns = {"sun": "sunlit_intercepted_cm2", "sky": "diffuse_intercepted_cm2",
               "day": "par_intercepted_mol", "absorbed": "absorbed_w"}
    for r in s.results:
        leaves = r.result.table("leaf", canopy)
        plants = r.result.table("plant", canopy)
        col = columns[r.kind]
        assert len(leaves) and leaves[col].sum() > 0, r.kind
        assert plants[col].sum() == pytest.approx(leaves[col].sum(), rel=1e-12), r.kind
    sun = s.results[0].result
    heights = sun.table()
    np.testing.assert_array_equal(heights["transmission"], sun.transmission)


def test_the_old_settings_read_as_todays_specs(old, stored):
    doc, _ = stored
    sky, day, absorbed = (r.specs() for r in old[1].results[1:])
    assert sky == SkySpec(**doc["results"][1]["meta"]["settings"]["sky"])
    assert day == (DaySpec(**doc["results"][2]["meta"]["settings"]["day"]),
                   SkySpec(**doc["results"][2]["meta"]["settings"]["sky"]))
    # saved before the C4 temperature response was a choice: read as CLM 4.5's, what it
    # computed then
    assert absorbed == OpticsSpec(**{**doc["results"][3]["meta"]["settings"]["optics"],
                                     "ranks": (), "c4_temperature": "clm45"})


def test_the_old_project_saved_again_holds_the_same_records(old, stored, tmp_path):
    path, s = old
    again = tmp_path / "again.maizeviz"
    opened = study.open_project(path, tmp_path / "cache")
    project = study.make_project(opened.project.points_path, opened.project.points_csv,
                                 s.layout, s.layout, opened.canopy, opened.light,
                                 [(r.label, r.result, r.settings) for r in s.results])
    from maizeviz.io.archive import save_project

    save_project(again, project)
    with zipfile.ZipFile(again) as zf:
        doc = json.loads(zf.read("project.json"))
        with zf.open("arrays.npz") as fh, np.load(fh, allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in npz.files}
    old_doc, old_arrays = stored
    assert doc["results"] == old_doc["results"]
    assert sorted(arrays) == sorted(old_arrays)
    for k, v in old_arrays.items():
        np.testing.assert_array_equal(arrays[k], v, err_msg=k)
