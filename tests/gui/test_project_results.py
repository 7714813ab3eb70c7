"""A project keeps the sky and day results: computed in the window on two plants, saved,
reopened in a fresh window, they are listed, plotted, mapped and colour the canopy as after a
fresh run."""

import json
import zipfile

import numpy as np
import pytest
from maizeviz_app.exports import export_job
from test_light_modes import compute, headers, shown, small_light

TIMEOUT = 120_000


def test_sky_and_day_results_come_back_with_a_project(window, qtbot, small_points, tmp_path):
    w = shown(qtbot, window(small_points, tile=1))
    panel = w.light_panel
    small_light(panel, "sun")
    compute(qtbot, w)
    small_light(panel, "sky")
    compute(qtbot, w)
    small_light(panel, "day", step=180.0)
    panel.day_from.setText("06:00")
    panel.day_to.setText("18:00")
    compute(qtbot, w)
    table = [[panel.table.item(r, c).text() for c in range(panel.table.columnCount())]
             for r in range(panel.table.rowCount())]
    names = headers(panel.table)
    assert names == ["height cm", "36 triangles", "36 triangles, overcast sky",
                     "36 triangles, day: PAR transmitted"]
    summary = panel.summary.text()
    plants = [[panel.plants.item(r, c).text() for c in range(panel.plants.columnCount())]
              for r in range(panel.plants.rowCount())]
    day = w.model.runs.of_kind("day")
    values = w.viewport.canopy_mesh.cell_data["light_value"][:w.model.canopy.n_triangles].copy()
    path = tmp_path / "diffuse.maizeviz"
    with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
        w.model.save_project(path)
    with zipfile.ZipFile(path) as zf:
        kinds = [r["kind"] for r in json.loads(zf.read("project.json"))["results"]]
    assert kinds == ["light", "light_sky", "light_day"]

    w2 = window(path)
    with qtbot.waitSignal(w2.light_shown, timeout=TIMEOUT):
        pass
    p2 = w2.light_panel
    assert headers(p2.table) == names
    assert [[p2.table.item(r, c).text() for c in range(p2.table.columnCount())]
            for r in range(p2.table.rowCount())] == table
    assert "3 light result(s) from the project" in p2.info.text()
    # the day: its summary, its plants, its numbers, its map and the canopy's colours
    assert p2.summary.text() == summary and summary.startswith("2005-08-01 06:00 to 18:00")
    assert [[p2.plants.item(r, c).text() for c in range(p2.plants.columnCount())]
            for r in range(p2.plants.rowCount())] == plants and len(plants) == 2
    day2 = w2.model.runs.of_kind("day")
    assert day2.extra is not None and day2.signature == w2.model.signature(w2.model.built.label)
    np.testing.assert_array_equal(day2.result.step_transmitted_mol_m2,
                                  day.result.step_transmitted_mol_m2)
    assert day2.result.par_intercepted_mol_m2 == day.result.par_intercepted_mol_m2
    sources = [w2.plots.source.itemText(i) for i in range(w2.plots.source.count())]
    assert len(sources) == 3 and w2.plots.kind == "day"
    assert w2.plots.heatmap.image() is not None and w2.plots.transmission.image() is not None
    assert w2.viewport.colouring == "light" and w2.viewport.light_variant == "values"
    np.testing.assert_array_equal(
        w2.viewport.canopy_mesh.cell_data["light_value"][:w2.model.canopy.n_triangles], values)
    # the sky's map on demand, and the exports of a day
    w2.plots.source.setCurrentIndex(sources.index("diffuse sky"))
    assert w2.plots.kind == "sky" and w2.plots.height_box.count() == 3
    for what in ("steps", "leaves", "plants"):
        with qtbot.waitSignal(w2.saved, timeout=TIMEOUT):
            w2.model.export(what, tmp_path / f"{what}.csv")
        assert (tmp_path / f"{what}.csv").stat().st_size > 0
    # the comparison goes on: the same day again replaces nothing but its own column
    compute(qtbot, w2)
    assert headers(p2.table) == names and "starts again" not in w2.messages.toPlainText()


@pytest.mark.parametrize("mode", ["sky"])
def test_a_sky_at_another_level_gets_its_plants_when_that_level_is_shown(
        window, qtbot, small_points, tmp_path, mode):
    w = shown(qtbot, window(small_points, tile=1))
    small_light(w.light_panel, mode)
    compute(qtbot, w)
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.canopy_panel.slider.setValue(w.canopy_panel.slider.value() + 1)            # 16 triangles, saved as the level
    path = tmp_path / "sky.maizeviz"
    with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
        w.model.save_project(path)
    w2 = window(path)
    with qtbot.waitSignal(w2.light_shown, timeout=TIMEOUT):
        pass
    run = w2.model.runs.of_kind("sky")
    assert run.label == "36 triangles" and run.extra is None and w2.model.settings.canopy.level == "16"
    with pytest.raises(Exception, match="show level 36 triangles first"):
        export_job("leaves", str(tmp_path / "x.csv"), w2.model)
    with qtbot.waitSignal(w2.canopy_shown, timeout=TIMEOUT):
        w2.canopy_panel.slider.setValue(w2.canopy_panel.slider.value() - 1)          # back to 36: computed against it
    qtbot.waitUntil(lambda: run.extra is not None, timeout=TIMEOUT)    # in a worker
    assert w2.light_panel.plants.rowCount() == 2
