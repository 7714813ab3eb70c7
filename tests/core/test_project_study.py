"""Projects read by the core (maizeviz.project.study): results stay on their plants across
save and open, stale results are dropped with a note, the points copy is checked before use,
and what a project may hold is bounded before anything is built."""

import hashlib
import io
import json
import os
import random
import zipfile
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import CanopyLayout, Placement, layout_for, layout_to_dict
from maizeviz.io.archive import Project, ProjectError, load_project, save_project
from maizeviz.io.hashing import sha256_file
from maizeviz.io.points import write_points
from maizeviz.leaf.fit import read_leaves
from maizeviz.leaf.synth import block_grids
from maizeviz.light.scene.request import Sampling
from maizeviz.light.sources.sky import make_sky
from maizeviz.light.trace.directions import trace_sky
from maizeviz.mesh.levels import parse_level
from maizeviz.project import study

LEVEL = parse_level("16")
SAMPLING = Sampling((0.0, 100.0), 0.2, None, True, 1)


@pytest.fixture(scope="module")
def points(tmp_path_factory):
    path = tmp_path_factory.mktemp("study") / "four.csv"
    write_points(path, block_grids(2, 2, seed=5))
    return path


@pytest.fixture(scope="module")
def leaves(points):
    return read_leaves(points).leaves


def stand_key(p: Placement) -> tuple:
    return p.plant, round(p.x, 6), round(p.y, 6), round(p.azimuth_deg, 6), p.tile


def per_stand(canopy, per_triangle: np.ndarray) -> dict:
    """Stand identity -> the values of its triangles, in the canopy's order (the oracle)."""
    return {stand_key(p): per_triangle[canopy.face_instance == i]
            for i, p in enumerate(canopy.layout.placements)}


def edited(leaves, tile: tuple[int, int], seed: int, drop: int, turn: int) -> CanopyLayout:
    """A tiling edited as in the layout panel: stands dropped, turned and reordered."""
    layout = layout_for(leaves, tile)
    rng = random.Random(seed)
    stands = list(layout.placements)
    rng.shuffle(stands)
    stands = stands[:max(1, len(stands) - drop)]
    stands = [replace(p, azimuth_deg=float(rng.randrange(-180, 180))) if i < turn else p
              for i, p in enumerate(stands)]
    return replace(layout, placements=tuple(stands))


def reopen(path, plants, cache):
    opened = study.open_project(path, cache)
    layout = study.restore_layout(opened, plants)
    return opened, layout


@settings(max_examples=12, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(tile=st.tuples(st.integers(1, 3), st.integers(1, 3)), seed=st.integers(0, 10**6),
       drop=st.integers(0, 5), turn=st.integers(0, 4))
def test_per_plant_light_is_on_the_same_plant_after_save_and_open(points, leaves, tmp_path,
                                                                   tile, seed, drop, turn):
    layout = edited(leaves, tile, seed, drop, turn)
    canopy = build_canopy(leaves, layout, LEVEL)
    sky = trace_sky(canopy, make_sky("soc", 16), SAMPLING)
    path = tmp_path / "edited.maizeviz"
    save_project(path, study.make_project(str(points), points.read_bytes(), layout, layout,
                                          {"tile": 3}, {}, [(LEVEL.label, sky)]))
    opened, back = reopen(path, {lf.plant for lf in leaves}, tmp_path / "cache")
    assert back is not None
    assert [stand_key(p) for p in back.placements] == [stand_key(p) for p in layout.placements]
    results, dropped = study.results_on(opened, back)
    assert dropped == [] and len(results) == 1
    canopy_back = build_canopy(leaves, back, LEVEL)
    want = per_stand(canopy, sky.triangle_share)
    got = per_stand(canopy_back, results[0].result.triangle_share)
    assert got.keys() == want.keys()
    for stand, values in want.items():
        np.testing.assert_array_equal(got[stand], values)


def test_results_traced_on_other_stands_are_dropped_with_a_note(points, leaves, tmp_path):
    shown = layout_for(leaves, (2, 2))
    other = layout_for(leaves, (3, 3))
    sky = trace_sky(build_canopy(leaves, other, LEVEL), make_sky("soc", 16), SAMPLING)
    path = tmp_path / "stale.maizeviz"
    # a result of the 3 x 3 tiling saved with a project laid out 2 x 2
    save_project(path, study.make_project(str(points), points.read_bytes(), shown, other,
                                          {}, {}, [(LEVEL.label, sky)]))
    opened, back = reopen(path, {lf.plant for lf in leaves}, tmp_path)
    results, notes = study.results_on(opened, back)
    assert results == []
    assert notes == [f"the sky result on {LEVEL.label} was traced on other stands (36 plants) "
                     "than the project's layout (16); left out (compute it again)"]


def test_an_older_project_with_an_edited_layout_drops_its_per_plant_results(points, leaves,
                                                                           tmp_path):
    layout = edited(leaves, (3, 3), 7, 1, 1)
    sky = trace_sky(build_canopy(leaves, layout, LEVEL), make_sky("soc", 16), SAMPLING)
    proj = study.make_project(str(points), points.read_bytes(), layout, layout, {}, {},
                              [(LEVEL.label, sky)])
    # as maizeviz 0.1 wrote it: no stands in order, no identity on the result
    arrays = {k: v for k, v in proj.arrays.items() if k != "layout_placements"}
    rec = proj.results[0]
    old = replace(proj, arrays=arrays,
                  results=(replace(rec, meta={k: v for k, v in rec.meta.items()
                                              if k != "stands"}),))
    path = tmp_path / "old.maizeviz"
    save_project(path, old)
    opened, back = reopen(path, {lf.plant for lf in leaves}, tmp_path)
    results, notes = study.results_on(opened, back)
    assert results == [] and "older maizeviz" in notes[0] and len(notes) == 1
    # the same older project on its settings' tiling keeps its results (same order as then)
    tiled = layout_for(leaves, (3, 3))
    sky = trace_sky(build_canopy(leaves, tiled, LEVEL), make_sky("soc", 16), SAMPLING)
    proj = study.make_project(str(points), points.read_bytes(), None, tiled, {}, {},
                              [(LEVEL.label, sky)])
    rec = proj.results[0]
    save_project(path, replace(proj, results=(replace(rec, meta={
        k: v for k, v in rec.meta.items() if k != "stands"}),)))
    opened, _ = reopen(path, {lf.plant for lf in leaves}, tmp_path)
    results, notes = study.results_on(opened, tiled)
    assert len(results) == 1 and notes == []


# ------------------------------------------------------------------------ the points copy
def test_a_truncated_points_copy_is_never_used(points, leaves, tmp_path):
    data = points.read_bytes()
    moved = tmp_path / "gone" / "four.csv"                 # the original is not there
    path = tmp_path / "p.maizeviz"
    save_project(path, Project(data, str(moved)))
    cache = tmp_path / "cache"
    sha = hashlib.sha256(data).hexdigest()
    cache.mkdir()
    copy = cache / f"{sha[:16]}-four.csv"
    copy.write_bytes(data[:len(data) // 2])               # what a full disk left
    opened = study.open_project(path, cache)
    assert opened.points_path == str(copy)
    assert copy.read_bytes() == data and sha256_file(copy) == sha
    assert len(read_leaves(opened.points_path).leaves) == len(leaves)
    assert "is not there; using the copy saved in the project" in opened.notes[0]
    assert [p for p in cache.iterdir() if ".part" in p.name] == []
    copy.write_bytes(data.replace(b"1", b"2", 1))         # altered since: rewritten again
    study.open_project(path, cache)
    assert copy.read_bytes() == data


def test_the_points_file_is_hashed_in_pieces(tmp_path):
    import tracemalloc

    from maizeviz.io import hashing

    big = tmp_path / "big.csv"
    with open(big, "wb") as fh:
        for _ in range(32):
            fh.write(b"1,2,3\n" * (2**20 // 6))
    want = hashlib.sha256(big.read_bytes()).hexdigest()
    tracemalloc.start()
    try:
        got = sha256_file(big)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert got == want
    assert peak < 4 * hashing.CHUNK            # a few pieces, not the 32 MiB file


# ------------------------------------------------------------------- what a project holds
def _with_json(path, change):
    with zipfile.ZipFile(path) as zf:
        parts = {i.filename: zf.read(i) for i in zf.infolist()}
    parts["project.json"] = change(parts["project.json"].decode())
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in parts.items():
            zf.writestr(name, data)


@pytest.mark.parametrize("change, field", [
    (lambda t: t.replace('"path": "', '"path": "\\u0000', 1), "'points.path'"),
    (lambda t: t.replace('"tile": 3', '"tile": ' + "9" * 5000), "'tile'"),
    (lambda t: t.replace('"tile": 3', '"tile": -' + "9" * 5000), "'tile'"),
])
def test_a_nul_or_a_5000_digit_number_is_one_line_naming_the_field(points, tmp_path, change,
                                                                   field):
    path = tmp_path / "bad.maizeviz"
    save_project(path, Project(points.read_bytes(), str(points), None,
                               {"canopy": {"tile": 3}}))
    _with_json(path, change)
    with pytest.raises(ProjectError) as err:
        opened = study.open_project(path, tmp_path)
        from maizeviz.io.archive import get
        get(opened.canopy, "tile", int, where=opened.path)   # as the window reads it
    text = str(err.value)
    assert field in text and "\n" not in text and text.startswith(str(path))


OPEN_HUGE = """
import resource, sys
resource.setrlimit(resource.RLIMIT_AS, (2 * 2**30, 2 * 2**30))   # listing the pairs needs more
from maizeviz.io.archive import ProjectError
from maizeviz.leaf.fit import read_leaves
from maizeviz.mesh.levels import parse_level
from maizeviz.project import study
opened = study.open_project(sys.argv[1], sys.argv[2])
leaves = read_leaves(opened.points_path).leaves
layout = study.project_layout(opened, leaves)
print(len(layout.placements), layout.warnings[-1])
try:
    study.check_canopy_fits(leaves, layout, parse_level("K1"), opened.path)
except ProjectError as exc:
    print(exc.quantity, exc)
"""


def test_a_100000_plant_layout_1_cm_apart_is_refused_before_building(points, leaves,
                                                                     tmp_path):
    import subprocess
    import sys

    side = 316                      # 99,856 plants 1 cm apart, on cells of 60 x 30 cm
    stands = tuple(Placement(leaves[0].plant, float(i % side), float(i // side))
                   for i in range(side * side))
    layout = CanopyLayout(stands, np.array([[0.0, 0.0, side, side]]), 60.0, 30.0)
    path = tmp_path / "huge.maizeviz"
    save_project(path, Project(points.read_bytes(), str(points), layout_to_dict(layout)))
    out = subprocess.run([sys.executable, "-c", OPEN_HUGE, str(path), str(tmp_path)],
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    lines = out.stdout.splitlines()
    assert lines[0].startswith("99856 ") and "overlapping pairs" in lines[0]
    assert lines[1].startswith(f"layout {path}: the canopy of 99,856 plants")
    assert "memory" in lines[1]


def test_an_array_claiming_a_huge_shape_is_refused_unread(points, tmp_path):
    path = tmp_path / "p.maizeviz"
    save_project(path, Project(points.read_bytes(), str(points), None, {},
                               {"cells": np.zeros((2, 4))}))
    with zipfile.ZipFile(path) as zf:
        parts = {i.filename: zf.read(i) for i in zf.infolist()}
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False,
                                                  "shape": (2**40,)})
    # a member whose zip header agrees with the npy header: nothing catches it but the size
    claimed = header.getvalue()
    inner = io.BytesIO()
    with zipfile.ZipFile(inner, "w") as zf:
        info = zipfile.ZipInfo("project.cells.npy")
        zf.writestr(info, claimed + b"\0" * 64)
    raw = bytearray(inner.getvalue())
    parts["arrays.npz"] = bytes(raw)
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in parts.items():
            zf.writestr(name, data)
    with pytest.raises(ProjectError, match="project.cells"):
        load_project(path)
    doc = json.loads(parts["project.json"])
    assert doc["arrays"] == ["cells"]


def test_project_layout_is_the_stored_one_or_the_settings_tiling(points, leaves, tmp_path):
    path = tmp_path / "tiled.maizeviz"
    save_project(path, Project(points.read_bytes(), str(points), None,
                               {"canopy": {"tile": 2}}))
    opened = study.open_project(path, tmp_path)
    assert study.project_layout(opened, leaves).placements == \
        layout_for(leaves, (2, 2)).placements
    layout = edited(leaves, (2, 3), 11, 2, 2)
    save_project(path, study.make_project(str(points), points.read_bytes(), layout, layout,
                                          {"tile": 2}, {}, []))
    back = study.project_layout(study.open_project(path, tmp_path), leaves)
    assert [stand_key(p) for p in back.placements] == [stand_key(p) for p in layout.placements]
    save_project(path, Project(points.read_bytes(), str(points), None,
                               {"canopy": {"tile": 200}}))
    with pytest.raises(ProjectError, match="tiles of a block of 4 plants"):
        study.project_layout(study.open_project(path, tmp_path), leaves)


def test_opening_a_project_removes_the_part_files_of_killed_saves(points, tmp_path):
    import subprocess
    import sys

    path = tmp_path / "p.maizeviz"
    save_project(path, Project(points.read_bytes(), str(points)))
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    dead = tmp_path / f".p.maizeviz.{int(gone.stdout)}.k3j9.part.maizeviz"   # its writer died
    dead.write_bytes(b"PK" * 1000)
    mine = tmp_path / f".p.maizeviz.{os.getpid()}.a8b2.part.maizeviz"       # a live writer's
    mine.write_bytes(b"PK")
    study.open_project(path, tmp_path)
    assert not dead.exists() and mine.exists()


# ------------------------------------------------- arrays sized against the canopy first
def _sky_project(points, leaves, tmp_path, share=None):
    """A 2 x 2 project with one sky result; ``share`` replaces its per-triangle array."""
    layout = layout_for(leaves, (2, 2))
    canopy = build_canopy(leaves, layout, LEVEL)
    sky = trace_sky(canopy, make_sky("soc", 16), SAMPLING)
    proj = study.make_project(str(points), points.read_bytes(), None, layout, {"tile": 2}, {},
                              [(LEVEL.label, sky)])
    if share is not None:
        rec = proj.results[0]
        proj = replace(proj, results=(replace(rec, arrays={**rec.arrays,
                                                           "triangle_share": share}),))
    path = tmp_path / "sized.maizeviz"
    save_project(path, proj)
    return path, layout, canopy, sky


def test_per_triangle_light_larger_than_the_canopy_is_left_out_unread(points, leaves,
                                                                      tmp_path):
    import tracemalloc

    big = np.zeros(25_000_000)                      # 200 MB declared, a few hundred kB packed
    path, layout, canopy, _ = _sky_project(points, leaves, tmp_path, big)
    del big
    assert path.stat().st_size < 5_000_000
    tracemalloc.start()
    try:
        opened = study.open_project(path, tmp_path / "cache")
        results, notes = study.results_on(opened, layout, leaves)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    most = study.scene_triangles(leaves, layout, LEVEL.label)
    # the estimate bounds the scene (leaves and stalks) from above
    assert canopy.n_triangles + 16 * len(layout.placements) <= most < 2 * canopy.n_triangles
    assert results == []
    assert notes == [f"the sky result on {LEVEL.label} holds light for 25,000,000 triangles, "
                     f"but its canopy has at most {most:,}; left out (compute it again)"]
    assert peak < 20 * 2**20, f"{peak / 2**20:.0f} MiB allocated: the array was read"


def test_stored_arrays_are_read_when_used_and_equal_what_was_saved(points, leaves, tmp_path):
    path, layout, canopy, sky = _sky_project(points, leaves, tmp_path)
    opened = study.open_project(path, tmp_path / "cache")
    share = opened.records[0].arrays["triangle_share"]
    assert share.shape == sky.triangle_share.shape and share._data is None   # header only
    results, notes = study.results_on(opened, layout, leaves)
    assert notes == [] and len(results) == 1
    np.testing.assert_array_equal(results[0].result.triangle_share, sky.triangle_share)
    np.testing.assert_array_equal(results[0].result.maps, sky.maps)


def test_a_project_changed_after_it_was_opened_is_refused_when_its_arrays_are_read(
        points, leaves, tmp_path):
    path, layout, _, _ = _sky_project(points, leaves, tmp_path)
    opened = study.open_project(path, tmp_path / "cache")
    (tmp_path / "other").mkdir()
    other, *_ = _sky_project(points, leaves, tmp_path / "other")
    os.replace(other, path)                          # saved again by another window
    with pytest.raises(ProjectError) as err:
        study.results_on(opened, layout)
    assert str(err.value) == (f"{path}: the project file changed after it was opened; open "
                              "it again")


def test_a_project_whose_arrays_are_packed_by_another_writer_opens(points, leaves, tmp_path):
    path, layout, _, sky = _sky_project(points, leaves, tmp_path)
    repacked = tmp_path / "repacked.maizeviz"
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(repacked, "w",
                                                       zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            dst.writestr(info.filename, src.read(info))   # arrays.npz deflated too
    with zipfile.ZipFile(repacked) as zf:
        assert zf.getinfo("arrays.npz").compress_type == zipfile.ZIP_DEFLATED
    opened = study.open_project(repacked, tmp_path / "cache")
    results, notes = study.results_on(opened, layout)
    assert notes == []
    np.testing.assert_array_equal(results[0].result.triangle_share, sky.triangle_share)


def test_results_at_other_levels_are_sized_against_their_own_level(points, leaves, tmp_path):
    layout = layout_for(leaves, (2, 2))
    fine, coarse = parse_level("36"), LEVEL
    runs = [(lv.label, trace_sky(build_canopy(leaves, layout, lv), make_sky("soc", 16),
                                 SAMPLING)) for lv in (fine, coarse)]
    path = tmp_path / "levels.maizeviz"
    save_project(path, study.make_project(str(points), points.read_bytes(), None, layout,
                                          {"tile": 2, "level": coarse.label}, {}, runs))
    results, notes = study.results_on(study.open_project(path, tmp_path), layout, leaves)
    assert notes == [] and [r.label for r in results] == [fine.label, coarse.label]
    assert len(results[0].result.triangle_share) > study.scene_triangles(leaves, layout,
                                                                         coarse.label)
    # a level this maizeviz does not know is left out, unread
    proj = load_project(path)
    rec = proj.results[0]
    odd = replace(rec, meta={**rec.meta, "level": "K=999999"},
                  arrays={k: np.asarray(v) for k, v in rec.arrays.items()})
    save_project(path, replace(proj, results=(odd,)))
    results, notes = study.results_on(study.open_project(path, tmp_path), layout, leaves)
    assert results == [] and "its mesh level 'K=999999' is not one this maizeviz knows" in notes[0]


# ------------------------------------------------------------------ results and their stands
def test_save_study_refuses_a_result_traced_on_other_stands(points, leaves, tmp_path):
    """Issue 25 case 4: ``save_study`` stored a result traced on another layout and
    ``read_study`` gave it back on the wrong stands, with no note. Every traced result now
    carries the identity of its stands, and saving it with other stands is one line, nothing
    written."""
    from maizeviz.canopy.layout import stands_identity
    from maizeviz.errors import MaizevizError
    from maizeviz.light.scene.request import LightRequest
    from maizeviz.light.sources.sun import Sun
    from maizeviz.light.trace.beam import trace_light

    shown = layout_for(leaves, (2, 2))
    other = edited(leaves, (2, 2), 3, 0, 2)              # the same 16 plants, two turned
    canopy = build_canopy(leaves, other, LEVEL)
    sun = trace_light(canopy, LightRequest(Sun(30, 180), SAMPLING))
    sky = trace_sky(canopy, make_sky("soc", 16), SAMPLING)
    assert sun.stands == sky.stands == stands_identity(other) != stands_identity(shown)
    path = tmp_path / "wrong.maizeviz"
    for result in (sun, sky):
        with pytest.raises(MaizevizError, match="result 1 .* was traced on other stands"):
            study.save_study(path, points, shown, [result], level=LEVEL.label)
        assert not path.exists()
    # on its own stands it is saved, read back with them, and saved again unchanged
    study.save_study(path, points, other, [sun, sky], level=LEVEL.label)
    back = study.read_study(path, tmp_path / "cache")
    assert [r.result.stands for r in back.results] == [stands_identity(other)] * 2
    study.save_study(tmp_path / "again.maizeviz", points, back.layout,
                     [r.result for r in back.results], level=LEVEL.label)
    assert len(study.read_study(tmp_path / "again.maizeviz", tmp_path / "cache").results) == 2


def test_a_day_refuses_a_sky_traced_on_other_stands(points, leaves):
    """A day reuses a sky traced with the same sampling; traced on other stands, its shares
    per triangle belong to other plants."""
    from maizeviz.errors import MaizevizError
    from maizeviz.light.sources.irradiance import clear_sky_period
    from maizeviz.light.trace.directions import trace_period

    sky = trace_sky(build_canopy(leaves, edited(leaves, (2, 2), 3, 0, 2), LEVEL),
                    make_sky("soc", 16), SAMPLING)
    period = clear_sky_period("2024-07-01", 43.6, 1.4, "Europe/Paris", step_min=180)
    with pytest.raises(MaizevizError, match="traced on other stands"):
        trace_period(build_canopy(leaves, layout_for(leaves, (2, 2)), LEVEL), period, SAMPLING,
                     sky=sky)


def test_per_triangle_arrays_of_the_wrong_length_are_one_line(points, leaves, tmp_path):
    """Issue 25: a project's per-triangle arrays of the wrong length for sun and sky results
    were accepted and failed later with a broadcast error (a day's were checked). A sun's two
    hit arrays must match each other when read; any result's light per triangle must match
    the canopy it is tabled on."""
    from maizeviz.errors import MaizevizError
    from maizeviz.light.scene.request import LightRequest
    from maizeviz.light.sources.sun import Sun
    from maizeviz.light.trace.beam import trace_light

    layout = layout_for(leaves, (2, 2))
    canopy = build_canopy(leaves, layout, LEVEL)
    sun = trace_light(canopy, LightRequest(Sun(30, 180), SAMPLING))
    sky = trace_sky(canopy, make_sky("soc", 16), SAMPLING)
    path = tmp_path / "ok.maizeviz"
    study.save_study(path, points, layout, [sun, sky], level=LEVEL.label)
    project = load_project(path)
    short = canopy.n_triangles - 7
    for name, kind in (("second_hits", 0), ("triangle_share", 1)):
        rec = project.results[kind]
        arrays = {**rec.arrays, name: np.asarray(rec.arrays[name])[:short]}
        results = list(project.results)
        results[kind] = replace(rec, arrays=arrays)
        bad = tmp_path / f"short_{name}.maizeviz"
        save_project(bad, replace(project, results=tuple(results)))
        if kind == 0:
            with pytest.raises(ProjectError, match=f"array 'second_hits' holds {short:,} "
                                                   "values, expected") as exc:
                study.read_study(bad, tmp_path / "cache")
            assert "\n" not in str(exc.value)
        else:                  # refused at read (issue 35): the array and its length named
            with pytest.raises(ProjectError, match=f"array 'triangle_share' holds {short:,} "
                                                   f"values, expected {canopy.n_triangles:,}"):
                study.read_study(bad, tmp_path / "cache")
            opened = study.open_project(bad, tmp_path / "cache")
            with pytest.raises(ProjectError, match="array 'triangle_share' holds"):
                study.results_on(opened, layout, leaves)     # the app's path: the same check
            stored = [r for r in study.results_on(opened, layout, leaves, exact=False)[0]
                      if r.kind == "sky"][0].result
            for by in ("leaf", "plant"):       # the bound alone lets it through: tables refuse
                with pytest.raises(MaizevizError, match=f"holds light for {short:,} triangles, "
                                                        "but the canopy has"):
                    stored.table(by, canopy)
    # the same tables on the undamaged project add up (leaves = plants)
    back = study.read_study(path, tmp_path / "cache")
    for r in back.results:
        leaf, plant = r.result.table("leaf", canopy), r.result.table("plant", canopy)
        col = "sunlit_intercepted_cm2" if r.kind == "sun" else "diffuse_intercepted_cm2"
        assert leaf[col].sum() == pytest.approx(plant[col].sum(), rel=1e-12)
        assert leaf[col].sum() > 0
