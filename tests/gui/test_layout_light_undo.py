"""A layout drag sets the light aside and Undo brings it back, in the window (a new user's
report: the Light table emptied, the heatmaps and colours went, the notice sat in the Messages
tab behind another tab, and Ctrl+Z did not bring the light back). The status bar and the light
panel say the results belong to the previous layout; Undo shows the same results again
(table, heatmaps, the 3D view's colours) without tracing."""

from __future__ import annotations

from test_light_modes import TIMEOUT, compute, shown, small_light


def _cells(table):
    return [[table.item(r, c).text() if table.item(r, c) else ""
             for c in range(table.columnCount())] for r in range(table.rowCount())]


def test_a_drag_then_undo_brings_the_light_back(window, qtbot, small_points):
    w = shown(qtbot, window(small_points, tile=1))
    p = w.light_panel
    small_light(p, "sun")
    compute(qtbot, w)
    run = w.model.runs.last
    table = _cells(p.table)
    maps = w.model.figures.maps["sun"]
    assert w.viewport.colouring == "light" and maps
    added = []
    w.model.light_added.connect(added.append)
    # drag a plant 20 cm along its row (the layout editor follows: rebuilt at once)
    d = w.model.draft
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        assert d.move(0, d.placements[0].x, d.placements[0].y + 20.0, snap=False)
    assert p.table.rowCount() == 0 and not w.model.figures.maps
    assert "belong to the previous layout" in p.info.text()
    assert "belong to the previous layout" in w.statusBar().currentMessage()
    assert w.viewport.colouring == "leaf"
    # Undo: the same layout, its light back as it was, nothing traced
    with qtbot.waitSignal(w.model.light_shown, timeout=TIMEOUT):
        w.menu_actions["undo"].trigger()
    assert w.model.runs.last is run and not added
    assert _cells(p.table) == table and "are back" in p.info.text()
    assert "are back" in w.statusBar().currentMessage()
    assert w.viewport.colouring == "light"
    assert len(w.model.figures.maps["sun"]) == len(maps)
