"""The desktop app as a person uses it: open, slide the complexity, compute light."""

import numpy as np
import pytest
from maizeviz_app.main_window import LEVELS

TIMEOUT = 120_000


def test_opens_example_and_slider_rebuilds(window, qtbot):
    w = window()
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT) as first:
        pass
    assert first.args == ["36 triangles"]
    assert "canopy" in w.viewport.actors and "stalks" in w.viewport.actors
    n36 = w.canopy.n_triangles
    assert w.table.rowCount() == 1 and w.table.item(0, 0).text() == "36 triangles"
    lai = float(w.table.item(0, 5).text())
    assert 4.5 < lai < 5.8
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT,
                          check_params_cb=lambda lv: lv == "4 triangles"):
        w.slider.setValue(LEVELS.index("4"))
    assert w.canopy.n_triangles < n36
    assert w.table.rowCount() == 2
    assert "at most 4 triangles" in w.level_label.text()


def test_fast_slider_moves_show_only_the_last_level(window, qtbot):
    w = window()
    qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    shown = []
    w.canopy_shown.connect(shown.append)
    # moves within the debounce interval coalesce into one rebuild
    for stop in ("standard", "16", "8", "K1", "4"):
        w.slider.setValue(LEVELS.index(stop))
    qtbot.waitUntil(lambda: bool(shown) and shown[-1] == "4 triangles", timeout=TIMEOUT)
    # rebuilds started back to back: the superseded one's result is dropped
    w.slider.blockSignals(True)
    w.slider.setValue(LEVELS.index("K2"))
    w.rebuild()
    w.slider.setValue(LEVELS.index("8"))
    w.rebuild()
    w.slider.blockSignals(False)
    qtbot.waitUntil(lambda: shown[-1] == "8 triangles", timeout=TIMEOUT)
    from PySide6.QtCore import QThreadPool
    QThreadPool.globalInstance().waitForDone(TIMEOUT)
    qtbot.wait(200)
    assert shown == ["4 triangles", "8 triangles"]


def test_compute_light(window, qtbot):
    w = window()
    qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    w.density.setValue(1.0)
    with qtbot.waitSignal(w.light_shown, timeout=TIMEOUT):
        w.light_button.click()
    t = [float(w.light_table.item(i, 1).text()) for i in range(w.light_table.rowCount())]
    assert len(t) == 6 and all(0 <= v <= 1 for v in t)
    assert np.all(np.diff(t) >= 0) and 0.02 < t[0] < 0.15
    assert not w.heatmap.pixmap().isNull()
    assert w.light_button.isEnabled()


def test_sun_from_place_and_bad_place(window, qtbot):
    w = window()
    w.place.setText("2005-08-01 12:00 39.9 116.4 Asia/Shanghai")
    w._sun_from_place()
    assert w.zenith.value() == pytest.approx(22.34, abs=0.02)
    w.place.setText("yesterday noon somewhere")
    w._sun_from_place()
    assert "error" in w.messages.toPlainText()


def test_bad_points_file_says_so(window, qtbot, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("this,is,not\n1,2,3\n")
    w = window(bad)
    with qtbot.waitSignal(w.failed, timeout=TIMEOUT) as err:
        pass
    assert "missing column" in err.args[0]
    assert "error" in w.messages.toPlainText()
    assert w.canopy is None
