"""The light panel's three lights in the window: a sun, an overcast sky, a day (clear sky or a
weather file), on a small canopy (two synthetic plants, few directions and steps)."""

import csv
import re
import time

import numpy as np
import pytest

TIMEOUT = 120_000


def shown(qtbot, w):
    if w.model.canopy is None:
        qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    return w


def small_light(panel, mode, directions=16, step=60.0, density=0.5):
    """A quick setting of ``mode``: 16 sky directions, hourly steps, 0.5 rays/cm2."""
    panel.set_mode(mode)
    panel.heights.setText("0, 100, 200")
    panel.density.setValue(density)
    panel.sky_split.setCurrentIndex(panel.sky_split.findData(directions))
    panel.step.setValue(step)


def compute(qtbot, w):
    with qtbot.waitSignal(w.light_shown, timeout=TIMEOUT):
        w.light_panel.compute_button.click()
    return w


def headers(table):
    return [table.horizontalHeaderItem(c).text().replace("\n", " ")
            for c in range(table.columnCount())]


def column(table, name):
    c = headers(table).index(name)
    return [float(table.item(r, c).text()) for r in range(table.rowCount())]


def test_sky_mode_adds_a_diffuse_curve_maps_and_colours(window, qtbot, small_points):
    w = shown(qtbot, window(small_points, tile=1))
    panel = w.light_panel
    small_light(panel, "sun")
    compute(qtbot, w)                                        # the sun first: a comparison
    small_light(panel, "sky")
    assert panel.compute_button.text() == "Compute diffuse light"
    compute(qtbot, w)
    assert headers(panel.table) == ["height cm", "36 triangles", "36 triangles, overcast sky"]
    assert "Embree scene kept from the last run" in panel.info.text()   # the sun's scene
    diffuse = column(panel.table, "36 triangles, overcast sky")
    assert all(0 <= t <= 1 for t in diffuse) and diffuse == sorted(diffuse)
    assert diffuse[0] < 0.3 and diffuse[-1] > 0.5
    # the heatmap selector offers both lights' maps; the diffuse one is shown
    sources = [w.plots.source.itemText(i) for i in range(w.plots.source.count())]
    assert sources == ["direct sun", "diffuse sky"] and w.plots.kind == "sky"
    assert w.plots.height_box.count() == 3 and w.plots.heatmap.image() is not None
    w.plots.height_box.setCurrentIndex(2)                       # another height: drawn on demand
    qtbot.waitUntil(lambda: w.plots.heatmap.image() is not None, timeout=TIMEOUT)
    assert w.plots.transmission.image() is not None
    # the leaves coloured by the diffuse light they take, with a colour bar
    assert w.viewport.colouring == "light" and w.viewport.light_variant == "values"
    assert w.viewport.actors["canopy"].mapper.GetArrayName() == "light_rgb"
    assert "diffuse light per leaf" in w.viewport.key.text()
    values = w.viewport.canopy_mesh.cell_data["light_value"][:w.model.canopy.n_triangles]
    assert np.all(np.isfinite(values)) and values.max() > 0.2
    # what each plant takes: two plants, shares of the sky's light summing to the canopy's
    assert panel.plants.isVisible() and panel.plants.rowCount() == 2
    shares = [float(panel.plants.item(r, 3).text().rstrip("%")) / 100 for r in range(2)]
    assert sum(shares) == pytest.approx(w.model.runs.of_kind("sky").result.intercepted_fraction,
                                        abs=0.002)
    # back to the sun's colours and map
    w.plots.source.setCurrentIndex(0)
    assert w.plots.kind == "sun" and w.plots.height_box.count() == 3


def test_day_mode_summary_plants_and_exports(window, qtbot, small_points, tmp_path):
    w = shown(qtbot, window(small_points, tile=1))
    panel = w.light_panel
    small_light(panel, "day")                                # Beijing 2005-08-01, clear sky
    progress = []
    w.runner.progressed.connect(lambda _id, kind, text, *_: progress.append(text))
    compute(qtbot, w)
    assert any(re.fullmatch(r"sky direction \d+ of 16", t) for t in progress)
    assert any(re.fullmatch(r"time step \d+ of 14", t) for t in progress)
    summary = panel.summary.text()
    assert panel.summary.isVisible() and "Ineichen" in summary and "Linke turbidity 3" in summary
    incident = float(re.search(r"PAR incident ([\d.]+) mol/m²", summary).group(1))
    intercepted = float(re.search(r"intercepted [\d.]+ mol/m² \(([\d.]+)%\)", summary).group(1))
    ground = float(re.search(r"transmitted to the ground ([\d.]+) mol/m²", summary).group(1))
    assert 58 < incident < 65                        # pvlib's clear Beijing day: ~61.7
    assert 50 < intercepted < 99 and 0 < ground < 0.5 * incident
    assert "PAR incident" in w.statusBar().currentMessage()
    assert "36 triangles, day: PAR transmitted" in headers(panel.table)
    assert w.plots.kind == "day"
    plants = [float(panel.plants.item(r, 3).text()) for r in range(panel.plants.rowCount())]
    assert len(plants) == 2 and all(3 < p < 25 for p in plants)      # mol per plant
    assert w.viewport.light_variant == "values" and "mol/m² leaf" in w.viewport.key.text()
    # exports: steps, leaves, plants (CSV) and the day figure (PNG)
    outs = {"steps": tmp_path / "steps.csv", "leaves": tmp_path / "leaves.csv",
            "plants": tmp_path / "plants.csv", "day": tmp_path / "day.png",
            "table": tmp_path / "table.csv", "canopy": tmp_path / "canopy.vtu"}
    for what, path in outs.items():
        with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
            w.model.export(what, path)
    steps = list(csv.DictReader(outs["steps"].open()))
    assert len(steps) == 14 and {"time", "par_intercepted_mol_m2"} <= set(steps[0])
    assert sum(float(r["par_direct_mol_m2"]) + float(r["par_diffuse_mol_m2"])
               for r in steps) == pytest.approx(incident, abs=0.06)
    by_plant = list(csv.DictReader(outs["plants"].open()))
    assert [round(float(r["par_intercepted_mol"]), 2) for r in by_plant] == plants
    leaves = list(csv.DictReader(outs["leaves"].open()))
    assert len(leaves) > 10 and leaves[0]["level"] == "36 triangles"
    assert outs["day"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "transmission 36 triangles, day: PAR transmitted" in \
        outs["table"].read_text().splitlines()[0]
    import meshio

    mesh = meshio.read(outs["canopy"])
    par = np.concatenate(mesh.cell_data["par_mol_per_m2_leaf"])[:w.model.canopy.n_triangles]
    assert np.nanmax(par) > 5


def test_cancel_during_a_day_run_stops_within_half_a_second(window, qtbot, small_points):
    w = shown(qtbot, window(small_points, tile=1))
    panel = w.light_panel
    small_light(panel, "sun")
    compute(qtbot, w)
    before = headers(panel.table)
    small_light(panel, "day", directions=145, step=5.0, density=20.0)   # a long day
    progress = []
    w.runner.progressed.connect(lambda _id, kind, text, *_: progress.append(text))
    panel.compute_button.click()
    qtbot.waitUntil(lambda: bool(progress), timeout=TIMEOUT)      # the child is tracing
    assert "sky direction" in progress[-1] and panel.cancel_button.isEnabled()
    t0 = time.perf_counter()
    panel.cancel_button.click()
    qtbot.waitUntil(lambda: w.runner.current("light") is None, timeout=5000)
    stopped = time.perf_counter() - t0
    assert stopped < 0.5, f"Cancel took {stopped:.2f} s"
    assert w.runner.light_process.pid is None                # the child was killed
    assert panel.compute_button.isEnabled() and not panel.cancel_button.isEnabled()
    assert "cancelled" in w.messages.toPlainText()
    assert headers(panel.table) == before                    # nothing shown was lost


def test_bad_light_inputs_are_refused_in_one_line_with_the_field_marked(window, qtbot,
                                                                         small_points, tmp_path):
    w = shown(qtbot, window(small_points, tile=1))
    panel = w.light_panel
    small_light(panel, "sun")
    compute(qtbot, w)
    table = [[panel.table.item(r, c).text() for c in range(panel.table.columnCount())]
             for r in range(panel.table.rowCount())]
    bad = tmp_path / "station.csv"
    bad.write_text("time,ghi\n2005-08-01T12:00+08:00,500\n2005-08-01T12:30+08:00,-3\n")

    def refused(setup, field, words):
        panel.clear_problem()
        setup()
        with qtbot.waitSignal(w.failed, timeout=TIMEOUT) as err:
            panel.compute_button.click()
        text = err.args[0]
        assert "\n" not in text and "Error" not in text and words in text, text
        assert panel.problem.isVisible() and panel.problem.text() == text
        bar = w.statusBar()                    # a line too long is cut there, whole in its tip
        assert words in bar.currentMessage() or \
            ("…" in bar.currentMessage() and bar.toolTip().endswith(text)), bar.currentMessage()
        assert "d0342c" in field.styleSheet(), f"{words}: field not marked"
        assert [[panel.table.item(r, c).text() for c in range(panel.table.columnCount())]
                for r in range(panel.table.rowCount())] == table       # nothing lost
        assert panel.compute_button.isEnabled()

    def weather():
        small_light(panel, "day")
        panel.source_weather.setChecked(True)
        panel.weather.setText(str(bad))

    refused(weather, panel.weather, "line 3 (2005-08-01T12:30+08:00), column ghi: negative "
                                    "irradiance -3 W/m2")
    panel.weather.setText("")
    refused(lambda: None, panel.weather, "choose a weather file")

    def step_zero():
        panel.source_clear.setChecked(True)
        panel.step.setValue(0)

    refused(step_zero, panel.step, "the time step must be > 0 min")

    def polar_night():
        panel.step.setValue(60)
        panel.day_date.setDate(panel.day_date.date().fromString("2005-12-21", "yyyy-MM-dd"))
        panel.lat.setValue(85.0)

    refused(polar_night, panel.day_date, "the sun stays below the horizon")

    def no_directions():
        small_light(panel, "sky")
        panel.sky_split.setCurrentIndex(panel.sky_split.findData(None))
        panel.sky_n.setValue(0)

    refused(no_directions, panel.sky_n, "sky directions must be at least 1")
    panel.sky_n.setValue(3)                                  # editing clears the mark
    assert panel.sky_n.styleSheet() == "" and not panel.problem.isVisible()


def test_project_keeps_the_light_mode_and_its_settings(window, qtbot, small_points, tmp_path):
    import json
    import zipfile

    w = shown(qtbot, window(small_points, tile=1))
    panel = w.light_panel
    panel.set_mode("day")
    panel.sky_kind.setCurrentIndex(panel.sky_kind.findData("uoc"))
    panel.sky_split.setCurrentIndex(panel.sky_split.findData(None))
    panel.sky_n.setValue(30)
    panel.day_date.setDate(panel.day_date.date().fromString("2006-06-21", "yyyy-MM-dd"))
    panel.lat.setValue(48.8)
    panel.lon.setValue(2.35)
    panel.tz.setText("Europe/Paris")
    panel.step.setValue(20)
    panel.day_from.setText("06:00")
    panel.day_to.setText("20:00")
    panel.par_factor.setValue(2.0)
    panel.source_weather.setChecked(True)
    panel.weather.setText("/data/paris.csv")
    settings = panel.settings.light_doc()
    path = tmp_path / "day.maizeviz"
    with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
        w.model.save_project(path)
    with zipfile.ZipFile(path) as zf:
        light = json.loads(zf.read("project.json"))["settings"]["light"]
    assert light["mode"] == "day" and light["sky_directions"] == 30
    w2 = shown(qtbot, window(path))
    p2 = w2.light_panel
    assert p2.mode == "day" and p2.settings.light_doc() == settings
    assert p2.pages.isVisible() and p2.sky_box.isVisible() and not p2.day_date.isEnabled()
    assert p2.settings.sky_spec().split == "equal" and p2.settings.day_spec().weather == "/data/paris.csv"


def test_a_project_without_light_modes_opens_in_sun_mode(window, qtbot, small_points,
                                                         tmp_path):
    from maizeviz.io.archive import Project, save_project

    path = tmp_path / "old.maizeviz"
    save_project(path, Project(small_points.read_bytes(), str(small_points), None,
                               {"canopy": {"tile": 1, "level": "36"},
                                "light": {"heights": "0, 100", "density": 1.0}}))
    w = shown(qtbot, window(path))
    panel = w.light_panel
    assert panel.mode == "sun" and panel.heights.text() == "0, 100"
    assert panel.settings.sky_spec().directions == 46 and panel.settings.day_spec().date == "2005-08-01"
