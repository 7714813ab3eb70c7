"""A whole study driven through the app's model, with no window and no QApplication: open
points, build at a level, a sun, a day, leaf optics, an edited layout, save, reopen. The oracle
is the core itself (the same light traced by :class:`maizeviz.light.engine.LightEngine`),
conservation (the energy balance closes) and round trips (the project reopens to the same
settings, layout and results)."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from maizeviz.io.points import write_points
from maizeviz.leaf.synth import block_grids

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


@pytest.fixture(scope="module")
def points(tmp_path_factory):
    path = tmp_path_factory.mktemp("study") / "two_plants.csv"
    write_points(path, block_grids(1, 2, seed=3))
    return path


@pytest.fixture
def study():
    from maizeviz_app.model import StudyModel
    from maizeviz_app.runner import InlineRunner

    runner = InlineRunner()
    model = StudyModel(tile=1, runner=runner)
    said: list[str] = []
    model.said.connect(lambda text, error, status_only: said.append(text))
    model.said_lines = said                               # type: ignore[attr-defined]
    yield model
    runner.shutdown()


def _errors(model) -> list[str]:
    return [t for t in model.said_lines if t.startswith("error")]


def test_a_script_draws_no_figure(points):
    """compute_light in a script draws no heatmap or plot: matplotlib is not even imported
    (the window sets draw_figures, since it shows them)."""
    code = ("import sys\n"
            "from maizeviz_app.model import StudyModel\n"
            "from maizeviz_app.runner import InlineRunner\n"
            "if __name__ == '__main__':\n"
            "    r = InlineRunner(); m = StudyModel(tile=1, runner=r)\n"
            f"    m.open_points({str(points)!r})\n"
            "    m.settings.sampling.heights = '0, 100'\n"
            "    ok = m.compute_light() and m.runs.of_kind('sun') is not None\n"
            "    r.shutdown()\n"
            "    bad = sorted(n for n in sys.modules if n.split('.')[0] == 'matplotlib')\n"
            "    print(ok, bad[:3]); sys.exit(0 if ok and not bad else 1)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr[-3000:]


def test_the_model_and_its_actions_run_without_qt():
    code = ("import sys, maizeviz_app.model, maizeviz_app.runner, maizeviz_app.settings; "
            "m = maizeviz_app.model.StudyModel(runner=maizeviz_app.runner.InlineRunner()); "
            "m.settings.light.mode = 'day'; m.compute_light(); "
            "bad = [n for n in sys.modules if n.split('.')[0] in ('PySide6', 'pyvista', 'vtk')]; "
            "print(bad); sys.exit(1 if bad else 0)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_a_whole_study_through_the_model(study, points, tmp_path):
    from maizeviz_app.model import StudyModel
    from maizeviz_app.runner import InlineRunner

    from maizeviz.light.engine import LightEngine

    m = study
    built = []
    m.canopy_changed.connect(built.append)
    # ---- open points: read, laid out, built at the level set
    m.open_points(points)
    assert m.loaded is not None and len(m.loaded.plants) == 2
    assert [b.label for b in built] == ["36 triangles"] and not _errors(m)
    n36 = m.canopy.n_triangles
    # ---- another level: setting it rebuilds; Table 2 keeps a row per level
    m.settings.canopy.level = "8"
    assert m.built.label == "8 triangles" and m.canopy.n_triangles < n36
    assert set(m.measures_rows) == {"36 triangles", "8 triangles"}
    # ---- the sun: what the core traces on the same canopy, to the last bit
    s = m.settings
    s.sampling.heights, s.sampling.density = "0, 100, 200", 1.0
    s.sun.zenith_deg, s.sun.azimuth_deg = 30.0, 120.0
    assert m.compute_light() and not _errors(m)
    run = m.runs.of_kind("sun")
    own = LightEngine(m.canopy).sun(zenith=30.0, azimuth=120.0,
                                    sampling=s.sampling_spec())
    np.testing.assert_array_equal(run.transmission, own.transmission)
    assert run.classes is not None and len(run.classes) == m.canopy.n_triangles
    assert m.modified and m.figures.plot is None and not m.figures.maps   # none drawn
    m.draw_figures = True                                      # as the window draws them
    shown = []
    m.light_shown.connect(lambda: shown.append(m.figures.plot))
    assert m.compute_light() and not _errors(m)
    assert shown and shown[-1] is not None and len(m.figures.maps["sun"]) == 3
    assert m.figures.maps["sun"][0][1] is not None             # the height shown drawn
    np.testing.assert_array_equal(m.runs.of_kind("sun").transmission, run.transmission)
    run = m.runs.of_kind("sun")
    # ---- a day: PAR transmitted between 0 and 1, never less light higher up
    s.light.mode = "day"
    s.day.step_min, s.day.start, s.day.end = 120.0, "10:00", "14:00"
    s.sky.split, s.sky.directions = "auto", 16
    assert m.compute_light() and not _errors(m)
    day = m.runs.of_kind("day")
    t = day.transmission
    assert np.all((0 <= t) & (t <= 1)) and np.all(np.diff(t) >= -1e-12)
    assert "PAR incident" in m.summary and m.plants_run is day
    assert m.runs.of_kind("sun") is run                        # both compared
    # ---- leaf optics: the energy balance closes
    s.light.mode = "sun"
    s.optics.enabled = True
    s.optics.band = "nir"                                      # the band's optics follow
    assert s.optics.reflectance > 0.3
    assert m.compute_light() and not _errors(m)
    balance = m.runs.of_kind("sun").balance
    assert balance is not None and abs(balance.closure) < 0.02
    assert m.runs.of_kind("day") is day                        # the sun's settings only
    # ---- edit the layout: results of the old layout go, the canopy is rebuilt on the new
    old = m.loaded.layout
    moved = replace(old.placements[0], x=old.placements[0].x + 7.5, azimuth_deg=90.0)
    layout = replace(old, placements=(moved,) + old.placements[1:])
    serial = m.serial
    assert m.apply_layout(layout) is True
    assert m.serial == serial + 1 and not m.runs.runs and m.layout_edited
    assert m.built.serial == m.serial and m.canopy.layout.placements[0] == moved
    s.optics.enabled = False
    s.light.mode = "sun"
    assert m.compute_light()
    sun_after = m.runs.of_kind("sun").transmission
    # ---- save, then reopen in a new model: settings, layout and results come back
    path = tmp_path / "study.maizeviz"
    assert m.save_project(path) and m.project_path == str(path) and not m.modified
    runner2 = InlineRunner()
    try:
        m2 = StudyModel(tile=3, runner=runner2)
        m2.open_project(path)
        assert m2.settings.light_doc() == s.light_doc()
        assert m2.settings.canopy.level == "8" and m2.loaded.layout.placements[0] == moved
        assert m2.built.label == "8 triangles" and not m2.modified
        reread = m2.runs.of_kind("sun")
        np.testing.assert_array_equal(reread.transmission, sun_after)
        assert reread.classes is not None                      # completed on its canopy
    finally:
        runner2.shutdown()


def test_a_setting_out_of_range_is_named(study):
    from maizeviz_app.settings import InputProblem

    with pytest.raises(InputProblem, match="density.*from 0.01 to 100") as err:
        study.settings.set("sampling", {"density": 500.0})
    assert err.value.quantity == "density"
    with pytest.raises(InputProblem, match="'mode' is 'moon'"):
        study.settings.set("light", {"mode": "moon"})
    assert study.settings.sampling.density == 2.0          # nothing set


def test_bad_heights_fail_the_light_naming_the_field(study, points):
    failed = []
    study.failed.connect(lambda *a: failed.append(a))
    study.open_points(points)
    study.settings.sampling.heights = "0, fifty"
    assert not study.compute_light()
    text, doing, quantity, mode = failed[-1]
    assert "fifty" in text and doing == "light" and quantity == "heights" and mode == "sun"


def test_the_settings_defaults_are_the_cores():
    from maizeviz_app.settings import StudySettings, band_defaults

    from maizeviz.light.sources.irradiance import DEFAULT_PAR_UMOL_PER_J
    from maizeviz.light.trace.scatter import DEFAULT_DEPTH

    s = StudySettings()
    assert s.day.par_factor == DEFAULT_PAR_UMOL_PER_J and s.optics.depth == DEFAULT_DEPTH
    o = s.optics
    assert (o.reflectance, o.transmittance, o.ground_reflectance, o.direct_w_m2) == \
        band_defaults("par")


def test_the_scripting_example_of_docs_app_runs(tmp_path):
    """docs/app.md's script, run as written in a folder holding a block.csv."""
    import re
    from pathlib import Path

    doc = (Path(__file__).parents[2] / "docs" / "app.md").read_text()
    code = re.search(r"```python\n(.*?)```", doc, re.S).group(1)
    write_points(tmp_path / "block.csv", block_grids(1, 2, seed=3))
    (tmp_path / "script.py").write_text(code)
    proc = subprocess.run([sys.executable, "script.py"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "8 triangles: transmission" in proc.stdout and "PAR incident" in proc.stdout
    assert "saved the project study.maizeviz" in proc.stdout
    assert (tmp_path / "study.maizeviz").stat().st_size > 0


WEATHER = __import__("pathlib").Path(__file__).parents[1] / "data" / "weather"


@pytest.mark.parametrize("name, lat, lon, tz", [
    ("pvgis_tmy_45N_8E_july.epw", 45.0, 8.0, "Etc/GMT-1"),
    ("tmy3_703165_july.csv", 55.317, -160.517, "Etc/GMT+9"),
    ("psm3_401182_july.csv", 40.53, -108.54, "Etc/GMT+7")])
def test_a_weather_file_chosen_brings_its_place_and_zone(study, name, lat, lon, tz):
    """Choosing an EPW, TMY3 or PSM file sets the day's place to its header's (the app's
    default place is Beijing: a sun traced there would not match the file's irradiance), and
    its time zone to the header's (issue 37 item 2: it kept Beijing's, and the day then warned
    about a zone the user never typed); one undo step puts all back."""
    day = study.settings.day
    before = (day.latitude, day.longitude, day.tz)
    assert (day.latitude, day.longitude) != (lat, lon)
    study.choose_weather(str(WEATHER / name))
    assert day.source == "weather" and day.weather.endswith(name)
    assert (day.latitude, day.longitude, day.tz) == (lat, lon, tz)
    assert any(t.startswith(f"place: latitude {lat:g}, longitude {lon:g}")
               and f"time zone {tz}" in t for t in study.said_lines)
    study.history.undo()
    assert (day.latitude, day.longitude, day.tz) == before


def test_a_weather_csv_keeps_the_place_set(study, tmp_path):
    path = tmp_path / "station.csv"
    path.write_text("time,ghi\n2005-08-01T12:00+08:00,800\n2005-08-01T13:00+08:00,700\n")
    before = (study.settings.day.latitude, study.settings.day.longitude)
    study.choose_weather(str(path))
    assert study.settings.day.weather == str(path)
    assert (study.settings.day.latitude, study.settings.day.longitude) == before
    assert not _errors(study)


def _numbers(run) -> dict:
    """What a sun run with absorbed light and C4 shows, as numbers: transmission by height,
    each plant's absorbed light and gross assimilation, the canopy's."""
    a = run.extra
    return {"transmission": np.asarray(run.transmission),
            "heights": np.asarray(run.result.heights_cm),
            "plants": [(r["plant"], r["absorbed_w"], r["gross_umol_s"]) for r in a.plant_rows],
            "canopy": a.assimilation.canopy_gross_umol_m2_s}


def test_a_whole_study_with_c4_edits_and_named_undo_steps(study, points, tmp_path):
    """Open, build, a sun with C4 photosynthesis, a layout edit, undo and redo by named
    steps, save, reopen: every setting, the layout and every number come back."""
    from maizeviz_app.model import UNDOABLE, StudyModel
    from maizeviz_app.runner import InlineRunner

    m, s = study, study.settings
    m.open_points(points)
    assert m.history.steps == [] and not _errors(m)
    with m.history.step("sampling"):
        s.sampling.heights, s.sampling.density, s.sampling.periodic = "0, 100, 200", 1.0, True
    with m.history.step("noon sun, C4 at 30 °C"):
        s.sun.zenith_deg, s.sun.azimuth_deg = 30.0, 120.0
        s.optics.enabled = True
        s.photosynthesis.model = "c4"
        s.photosynthesis.temperature_c = 30.0
    s.canopy.level = "16"                                    # no block: a step of its own
    assert m.history.texts == ["sampling", "noon sun, C4 at 30 °C", "mesh level 16"]
    assert m.built.label == "16 triangles"
    assert m.compute_light() and not _errors(m)
    first = _numbers(m.runs.of_kind("sun"))
    assert first["canopy"] > 0 and len(first["plants"]) == len(m.loaded.layout.placements)
    # ---- the view's state: coloured by the new light, then by its CO2 when asked
    assert m.view.colouring == "light"
    assert m.colour_view_by("assimilation") and m.view.colouring == "assimilation"
    cameras = []
    m.view.events.camera.connect(lambda name, *_: cameras.append(name))
    m.view.ask_camera("top")
    m.view.ask_camera("top")                                  # asked again: framed again
    assert cameras == ["top", "top"] and m.view.camera == "top"
    assert sum(p[2] for p in first["plants"]) > 0
    # ---- the layout edited as the panel edits it: the model applies it and rebuilds
    placements = m.loaded.layout.placements
    with m.history.step("turn the first plant"):
        assert m.draft.turn(0, 90.0)
    assert m.loaded.layout.placements[0].azimuth_deg == 90.0 and not m.runs.runs
    assert m.view.colouring == "leaf"                         # no light on this canopy
    assert not m.colour_view_by("light") and "no light result" in m.said_lines[-1]
    assert m.built.serial == m.serial and m.canopy.layout.placements[0].azimuth_deg == 90.0
    # ---- undo the edit and the level, by their names; redo them
    assert m.history.undo_text == "turn the first plant"
    m.history.undo()
    assert m.loaded.layout.placements == placements and m.built.serial == m.serial
    assert m.history.undo_text == "mesh level 16"
    m.history.undo()
    assert s.canopy.level == "36" and m.built.label == "36 triangles"
    assert m.history.redo_text == "mesh level 16"
    m.history.redo()
    m.history.redo()
    assert s.canopy.level == "16" and m.built.label == "16 triangles"
    assert m.loaded.layout.placements[0].azimuth_deg == 90.0
    assert m.history.index == len(m.history.steps) == 4
    # ---- the layout no longer follows: an edit waits for apply_draft
    m.layout_options.follow = False
    serial = m.serial
    assert m.draft.turn(1, 45.0) and m.serial == serial
    assert m.apply_draft() and m.loaded.layout.placements[1].azimuth_deg == 45.0
    assert m.compute_light() and not _errors(m)
    edited = _numbers(m.runs.of_kind("sun"))
    # ---- save, reopen in a new model: every setting, the layout and every number
    path = tmp_path / "c4.maizeviz"
    assert m.save_project(path) and not m.modified
    runner2 = InlineRunner()
    try:
        m2 = StudyModel(tile=3, runner=runner2)
        said: list[str] = []
        m2.said.connect(lambda text, error, status_only: said.append(text))
        m2.open_project(path)
        assert not [t for t in said if t.startswith(("error", "warning"))], said
        for group in UNDOABLE:
            assert m2.settings.snapshot(group) == s.snapshot(group), group
        assert m2.colour.to_doc() == m.colour.to_doc()
        assert m2.loaded.layout.placements == m.loaded.layout.placements
        assert m2.built.label == "16 triangles" and not m2.modified
        assert m2.history.steps == []                          # a new study, a new history
        back = _numbers(m2.runs.of_kind("sun"))
        for key in ("transmission", "heights"):
            np.testing.assert_array_equal(back[key], edited[key])
        assert [p[0] for p in back["plants"]] == [p[0] for p in edited["plants"]]
        np.testing.assert_allclose([p[1:] for p in back["plants"]],
                                   [p[1:] for p in edited["plants"]], rtol=1e-12)
        assert back["canopy"] == pytest.approx(edited["canopy"], rel=1e-12)
    finally:
        runner2.shutdown()


def test_a_removed_plant_then_sun_and_c4_warns_as_the_command_line_does(points):
    """Issue 37, item 3: on a tiled field edited so that its sample rectangle (the central
    tile) is no longer a tile of a periodic field, the command line warns that the
    assimilation of leaves outside the rays' reach is understated; the study says it too,
    and the light panel's text carries it."""
    from maizeviz_app.model import StudyModel
    from maizeviz_app.runner import InlineRunner
    from maizeviz_app.runs import run_info

    runner = InlineRunner()
    m = StudyModel(tile=3, runner=runner)
    said: list[str] = []
    m.said.connect(lambda text, error, status_only: said.append(text))
    m.said_lines = said                                   # type: ignore[attr-defined]
    s = m.settings
    s.canopy.level = "8"
    m.open_points(points)
    s.sampling.heights, s.sampling.density, s.sampling.periodic = "0, 100", 1.0, True
    s.optics.enabled = True
    s.photosynthesis.model = "c4"
    assert m.compute_light() and not _errors(m)
    run = m.runs.of_kind("sun")
    assert not run.extra.assimilation.warnings
    with m.history.step("remove a plant"):
        assert m.draft.remove(0)
    assert m.compute_light()
    run = m.runs.of_kind("sun")
    expected = run.extra.assimilation.warnings
    assert expected and "understated" in expected[0]       # the core's own warning
    said_now = [t for t in said if t.startswith("warning: CO₂ assimilation:")]
    assert said_now and expected[0] in said_now[-1]
    assert expected[0] in run_info(run)
    runner.shutdown()


def test_a_points_file_with_a_bad_value_is_named_by_its_line(study, tmp_path):
    """Issue 37, item 4: a points CSV whose x is 'abc' was refused by asking for the columns
    the file has; the study names line 2 and the value, as the command line does, and asks
    for that line to be corrected."""
    path = tmp_path / "abc.csv"
    path.write_text("plant,leaf,row,col,x,y,z\n1,1,0,0,abc,2,3\n1,1,0,1,1,2,3\n")
    study.open_points(path)
    errors = _errors(study)
    assert errors and "line 2" in errors[-1] and "x is not a number ('abc')" in errors[-1]
    assert "columns" not in errors[-1] and "correct that line" in errors[-1].lower()


def test_a_reopened_c4_project_has_its_co2_row_and_colouring(study, points, tmp_path):
    """Issue 37, item 6: a project saved after a sun with C4, coloured by CO2, reopened
    without its canopy's gross CO2 row in the results table and coloured by absorbed PAR;
    both come back now."""
    from maizeviz_app.model import StudyModel
    from maizeviz_app.runner import InlineRunner
    from maizeviz_app.runs import ASSIMILATION_ROW

    m, s = study, study.settings
    m.open_points(points)
    s.sampling.heights, s.sampling.density, s.sampling.periodic = "0, 100", 1.0, True
    s.optics.enabled = True
    s.photosynthesis.model = "c4"
    assert m.compute_light() and not _errors(m)
    m.view.colouring = "assimilation"
    _, rows = m.runs.table()
    assert any(r[0] == ASSIMILATION_ROW for r in rows)
    path = tmp_path / "c4.maizeviz"
    assert m.save_project(path)
    runner2 = InlineRunner()
    try:
        m2 = StudyModel(tile=1, runner=runner2)
        tables: list = []
        m2.runs_changed.connect(lambda runs, info: tables.append(runs.table()[1]))
        m2.open_project(path)
        assert m2.runs.of_kind("sun").extra.assimilation is not None
        assert any(r[0] == ASSIMILATION_ROW for r in tables[-1])
        assert m2.view.colouring == "assimilation"
    finally:
        runner2.shutdown()


def test_a_duplicate_is_named_as_a_duplicate_in_the_history(study, points):
    """Issue 37, item 8: the history named a Duplicate "add plant 1"."""
    study.open_points(points)
    assert study.draft.duplicate(0)
    plant = study.loaded.layout.placements[0].plant
    assert study.history.undo_text == f"duplicate plant {plant} (row 1)"
    assert study.draft.add(500.0, 500.0)
    assert study.history.undo_text.startswith("add plant")


def test_leaves_only_is_a_light_setting_of_the_model(study, points, tmp_path):
    """Whether the stalks take light is the study's light setting: traced as the core traces
    ``LightEngine(with_stalks=False)`` on the same canopy, a named undo step, a new
    comparison, each result tagged, kept in the project."""
    from maizeviz_app.model import StudyModel
    from maizeviz_app.runner import InlineRunner

    from maizeviz.light.engine import LightEngine

    m, s = study, study.settings
    m.open_points(points)
    s.sampling.heights, s.sampling.density = "0, 100, 200", 1.0
    s.sun.zenith_deg, s.sun.azimuth_deg = 30.0, 120.0
    assert s.light.stalks is True                            # the command line's default
    assert m.compute_light() and not _errors(m)
    assert m.runs.of_kind("sun").stalks
    with m.history.step("leaves only"):
        s.light.stalks = False
    assert m.history.undo_text == "leaves only"
    assert m.compute_light() and not _errors(m)
    run = m.runs.of_kind("sun")
    assert not run.stalks and len(m.runs.runs) == 1          # a new comparison
    own = LightEngine(m.canopy, with_stalks=False).sun(zenith=30.0, azimuth=120.0,
                                                       heights_cm=(0, 100, 200),
                                                       density=1.0, periodic=True)
    np.testing.assert_allclose(run.result.transmission, own.transmission, rtol=0, atol=1e-12)
    assert len(run.result.first_hits) == m.canopy.n_triangles      # no stalk triangle
    path = tmp_path / "leaves.maizeviz"
    assert m.save_project(path)
    m.history.undo()
    assert s.light.stalks is True
    runner2 = InlineRunner()
    try:
        m2 = StudyModel(tile=3, runner=runner2)
        m2.open_project(path)
        assert m2.settings.light.stalks is False and m2.runs.of_kind("sun").stalks is False
    finally:
        runner2.shutdown()
