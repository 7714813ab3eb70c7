"""The desktop app as a person uses it: open, slide the complexity, compute light."""

import numpy as np
from maizeviz_app.main_window import LEVELS

TIMEOUT = 120_000


def test_opens_example_and_slider_rebuilds(window, qtbot):
    w = window()
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT) as first:
        pass
    assert first.args == ["36 triangles"]
    assert "canopy" in w.viewport.actors
    assert np.any(w.viewport.canopy_mesh.cell_data["light"] == -2)      # stalks, same mesh
    n36 = w.model.canopy.n_triangles
    assert w.canopy_panel.table.rowCount() == 1 and w.canopy_panel.table.item(0, 0).text() == "36 triangles"
    lai = float(w.canopy_panel.table.item(0, 5).text())
    assert 4.5 < lai < 5.8
    shown = "at most 36 triangles" in w.canopy_panel.level_label.text()
    # the label as it reads while the new level builds (a timed wait raced the build, which
    # now takes under 300 ms at 4 triangles on a quiet machine)
    while_building: list[str] = []
    w.runner.changed.connect(lambda: while_building.append(w.canopy_panel.level_label.text())
                             if w.runner.current("build") is not None else None)
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT,
                          check_params_cb=lambda lv: lv == "4 triangles"):
        w.canopy_panel.slider.setValue(LEVELS.index("4"))
    assert shown and while_building
    assert all("at most 36 triangles" in text for text in while_building), while_building
    # label, table and view changed together
    assert w.model.canopy.n_triangles < n36
    assert w.canopy_panel.table.rowCount() == 2
    assert "at most 4 triangles" in w.canopy_panel.level_label.text()


def test_fast_slider_moves_show_only_the_last_level(window, qtbot):
    w = window()
    qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    shown = []
    w.canopy_shown.connect(shown.append)
    # moves within the debounce interval coalesce into one rebuild
    for stop in ("standard", "16", "8", "K1", "4"):
        w.canopy_panel.slider.setValue(LEVELS.index(stop))
    qtbot.waitUntil(lambda: bool(shown) and shown[-1] == "4 triangles", timeout=TIMEOUT)
    # rebuilds started back to back (levels set by a script): the superseded one's result
    # is dropped, and the slider follows the level set
    w.model.settings.canopy.level = "K2"
    w.model.settings.canopy.level = "8"
    assert w.canopy_panel.level == "8"
    qtbot.waitUntil(lambda: shown[-1] == "8 triangles", timeout=TIMEOUT)
    from PySide6.QtCore import QThreadPool
    QThreadPool.globalInstance().waitForDone(TIMEOUT)
    qtbot.wait(200)
    assert shown == ["4 triangles", "8 triangles"]


def test_compute_light_colours_the_leaves(window, qtbot):
    w = window()
    qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    panel = w.light_panel
    panel.density.setValue(1.0)
    with qtbot.waitSignal(w.light_shown, timeout=TIMEOUT):
        panel.compute_button.click()
    t = [float(panel.table.item(i, 1).text()) for i in range(panel.table.rowCount())]
    assert len(t) == 6 and all(0 <= v <= 1 for v in t)
    assert np.all(np.diff(t) >= 0) and 0.02 < t[0] < 0.15
    assert panel.compute_button.isEnabled() and not panel.cancel_button.isEnabled()
    # the leaves are coloured by the light they received, with a legend
    assert w.viewport.colouring == "light"
    assert w.viewport.actors["canopy"].mapper.GetArrayName() == "light"
    light = w.viewport.canopy_mesh.cell_data["light"][:w.model.canopy.n_triangles]
    assert set(np.unique(light)) == {0, 1, 2}
    assert w.menu_actions["colour_light"].isChecked()
    # a heatmap per height and the transmission plot
    assert w.plots.height_box.count() == 6 and w.plots.heatmap.image() is not None
    assert w.plots.transmission.image() is not None
    w.plots.height_box.setCurrentIndex(3)
    assert w.plots.shown_height == 150.0


def test_sun_from_place_and_bad_place(window, qtbot):
    w = window()
    panel = w.light_panel
    panel.place.setText("2005-08-01 12:00 39.9 116.4 Asia/Shanghai")
    panel.zenith.setValue(10)
    w.model.sun_from_place()
    qtbot.waitUntil(lambda: abs(panel.zenith.value() - 22.34) < 0.02, timeout=TIMEOUT)
    panel.place.setText("yesterday noon somewhere")
    with qtbot.waitSignal(w.failed, timeout=TIMEOUT) as err:
        w.model.sun_from_place()
    assert "YYYY-MM-DD" in err.args[0]
    assert "error" in w.messages.toPlainText()
    assert "d0342c" in panel.place.styleSheet()            # the field is marked


def test_bad_points_file_says_so_and_keeps_the_canopy(window, qtbot, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("this,is,not\n1,2,3\n")
    w = window(bad, wait_ready=False)           # the event loop has not run: nothing said yet
    failed: list[str] = []
    w.failed.connect(failed.append)
    qtbot.waitUntil(lambda: bool(failed), timeout=TIMEOUT)
    assert "missing column" in failed[0] and "Choose a points CSV" in failed[0]
    assert "Error" not in failed[0] and "maizeviz.errors" not in failed[0]
    assert "error" in w.messages.toPlainText()
    assert w.model.canopy is None
    # a good file, then a bad one: the good one stays, named in the label
    from maizeviz.resources import example_points
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.open_points(example_points())
    canopy, label = w.model.canopy, w.canopy_panel.file_label.text()
    assert label.endswith("block3x3.csv")
    notnum = tmp_path / "notnum.csv"
    notnum.write_text("plant,leaf,row,col,x,y,z\nA,1,0,0,x,y,z\n")
    with qtbot.waitSignal(w.failed, timeout=TIMEOUT) as err:
        w.open_points(notnum)
    assert "could not convert" not in err.args[0]
    assert w.model.canopy is canopy and w.canopy_panel.file_label.text() == label
