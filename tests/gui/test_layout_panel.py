"""The canopy-layout editor as a widget over a two-plant layout: exact positions, dragging and
turning in the top view, undo/redo, tiling presets that ask before discarding edits; and once in
the window, the 3D view following an edit."""

import json

import numpy as np
import pytest
from PySide6.QtCore import QPoint, QPointF, Qt, QTimer
from PySide6.QtGui import QWheelEvent
from PySide6.QtWidgets import QApplication, QMessageBox

from maizeviz.canopy.layout import layout_to_dict, load_layout, tiled_layout

#: Stalk bases with every bit of their floats used: rounding anywhere would show.
BASES = {1: (30.023456789012345, 15.330000000000002), 2: (29.001, 44.69912345678901)}


@pytest.fixture
def panel(qtbot):
    from maizeviz_app.panels.layout import LayoutPanel

    p = LayoutPanel()
    qtbot.addWidget(p)
    p.resize(900, 500)
    p.show()
    qtbot.waitExposed(p)
    p.show_layout(tiled_layout(BASES, (1, 1)), set(BASES))
    return p


def _answer(button):
    """Click ``button`` of the next message box (run before the call that opens it)."""
    def click():
        box = QApplication.activeModalWidget()
        if isinstance(box, QMessageBox):
            box.button(button).click()
        else:
            QTimer.singleShot(20, click)
    QTimer.singleShot(0, click)


def test_apply_without_edits_changes_nothing(panel, qtbot):
    original = panel.layout_.placements
    # the table shows 0.1 cm, the editor gets every digit: opening and closing it is no edit
    idx = panel.rows.index(0, 0)
    assert panel.rows.data(idx) == "30.0"
    assert float(panel.rows.data(idx, Qt.EditRole)) == BASES[1][0]
    assert panel.rows.setData(idx, panel.rows.data(idx, Qt.EditRole))
    assert panel.undo_stack.count() == 0
    with qtbot.waitSignal(panel.applied) as applied:
        panel.apply_button.click()
    new = applied.args[0]
    assert new.placements == original                     # exactly, not to 0.1 cm
    assert layout_to_dict(new) == layout_to_dict(panel.layout_)
    assert new.ground_area == panel.layout_.ground_area


def test_labels_never_say_minus_zero(qtbot):
    from maizeviz_app.panels.layout import LayoutPanel

    p = LayoutPanel()
    qtbot.addWidget(p)
    bases = {1: (-0.04, 15.0), 2: (0.01, 45.0)}
    p.show_layout(tiled_layout(bases, (1, 1)), set(bases))
    assert "field x -30..30 cm" in p.info.text()
    assert p.rows.data(p.rows.index(0, 0)) == "0.0"                      # not "-0.0"
    assert p.rows.data(p.rows.index(0, 0), Qt.EditRole) == "-0.04"
    layout = tiled_layout({1: (29.6, 15.0), 2: (29.7, 45.0)}, (1, 1))
    p.show_layout(layout, {1, 2})
    assert layout.bounds[0] < 0 and "field x 0..60 cm" in p.info.text()   # was "-0..60"


def test_drag_moves_a_plant_in_the_document_and_undo_restores_it_exactly(panel, qtbot):
    view = panel.view
    item = view.items_[0]
    start = view.mapFromScene(item.scenePos())
    scale = abs(view.transform().m11())                   # pixels per cm
    qtbot.mousePress(view.viewport(), Qt.LeftButton, pos=start)
    for k in range(1, 6):
        qtbot.mouseMove(view.viewport(), start + QPoint(8 * k, 0))
    qtbot.mouseRelease(view.viewport(), Qt.LeftButton, pos=start + QPoint(40, 0))
    p = panel.draft.placements[0]
    assert p.x - BASES[1][0] == pytest.approx(40 / scale, abs=1.5 / scale)
    assert p.y == pytest.approx(BASES[1][1], abs=1.5 / scale)
    assert panel.draft.placements[1] == panel.layout_.placements[1]
    xs = [r["x"] for r in panel.document()["rows"]]
    assert p.x in xs and BASES[1][0] not in xs
    assert panel.undo_stack.count() == 1 and "1 plant edited" in panel.state.text()
    panel.undo_action.trigger()
    assert panel.draft.placements == list(panel.layout_.placements)
    assert view.items_[0].pos() == QPointF(*BASES[1])
    panel.redo_action.trigger()
    assert panel.draft.placements[0] == p


def test_wheel_turns_a_plant_and_its_steps_are_one_undo(panel, qtbot):
    view = panel.view
    at = QPointF(view.mapFromScene(view.items_[1].scenePos()))
    for _ in range(3):
        ev = QWheelEvent(at, QPointF(view.viewport().mapToGlobal(at.toPoint())), QPoint(0, 0),
                         QPoint(0, 120), Qt.NoButton, Qt.NoModifier, Qt.NoScrollPhase, False)
        QApplication.sendEvent(view.viewport(), ev)
    assert panel.draft.placements[1].azimuth_deg == 15.0
    assert view.items_[1].arrow.rotation() == 15.0
    assert panel.rows.data(panel.rows.index(1, 3)) == "15.0"
    assert panel.undo_stack.count() == 1
    panel.undo_action.trigger()
    assert panel.draft.placements[1].azimuth_deg == 0.0


def test_knob_turns_a_plant(panel, qtbot):
    view = panel.view
    item = view.items_[0]
    knob = view.mapFromScene(item.knob.scenePos())
    centre = view.mapFromScene(item.scenePos())
    up = centre + QPoint(0, -(knob.x() - centre.x()))      # north of the plant on screen
    qtbot.mousePress(view.viewport(), Qt.LeftButton, pos=knob)
    qtbot.mouseMove(view.viewport(), up)
    qtbot.mouseRelease(view.viewport(), Qt.LeftButton, pos=up)
    assert panel.draft.placements[0].azimuth_deg == 90.0  # counter-clockwise from east
    assert (panel.draft.placements[0].x, panel.draft.placements[0].y) == BASES[1]


def test_keys_undo_and_redo_table_edits(panel, qtbot):
    panel.rows.setData(panel.rows.index(0, 1), "20")
    panel.rows.setData(panel.rows.index(1, 2), "1")
    assert [p.plant for p in panel.draft.placements] == [1, 1]
    panel.activateWindow()
    panel.table.setFocus()
    qtbot.waitUntil(panel.table.hasFocus)
    qtbot.keyClick(panel.table, Qt.Key_Z, Qt.ControlModifier)
    assert [p.plant for p in panel.draft.placements] == [1, 2]
    qtbot.keyClick(panel.table, Qt.Key_Z, Qt.ControlModifier)
    assert panel.draft.placements[0].y == BASES[1][1]
    qtbot.keyClick(panel.table, Qt.Key_Z, Qt.ControlModifier | Qt.ShiftModifier)
    assert panel.draft.placements[0].y == 20.0
    assert panel.rows.data(panel.rows.index(0, 1)) == "20.0"


def test_bad_cells_are_refused_with_the_cell_named(panel, qtbot):
    said = []
    panel.problem.connect(said.append)
    assert not panel.rows.setData(panel.rows.index(1, 2), "x")
    assert not panel.rows.setData(panel.rows.index(1, 2), "77")
    assert not panel.rows.setData(panel.rows.index(0, 0), "nan")
    assert said[0] == "row 2, plant: 'x' is not a number"
    assert "plant 77 is not in the points file (it has 1, 2)" in said[1]
    assert "row 1, x cm" in said[2]
    assert panel.undo_stack.count() == 0


def test_tiling_change_asks_before_discarding_edits(panel, qtbot):
    assert panel.tiling.currentData() == 1 and panel.tiling.isEnabled()
    panel.rows.setData(panel.rows.index(0, 3), "45")
    edited = list(panel.draft.placements)
    _answer(QMessageBox.Cancel)
    assert not panel.set_tiling(3)                       # cancelled: nothing changed
    assert panel.draft.placements == edited and panel.tiling.currentData() == 1
    _answer(QMessageBox.Discard)
    assert panel.set_tiling(3)
    assert len(panel.draft.placements) == 18 and panel.tiling.currentData() == 3
    assert panel.draft.edits() == 0 and len(panel.view.items_) == 18
    panel.undo_action.trigger()                          # the edits come back, exactly
    assert panel.draft.placements == edited and panel.tiling.currentData() == 1
    # no edits, no question
    panel.undo_action.trigger()
    assert panel.set_tiling(5) and len(panel.draft.placements) == 50


def test_edits_follow_into_the_3d_view_and_save(panel, qtbot, tmp_path):
    with qtbot.waitSignal(panel.applied, timeout=5000) as applied:
        panel.rows.setData(panel.rows.index(1, 3), "90")
    assert [p.azimuth_deg for p in applied.args[0].placements] == [0.0, 90.0]
    assert "not applied" not in panel.state.text()
    path = tmp_path / "lay.json"
    assert panel.save(path)
    back = load_layout(path, {1, 2})
    assert sorted((p.plant, p.x, p.y, p.azimuth_deg) for p in back.placements) == \
        sorted((p.plant, p.x, p.y, p.azimuth_deg) for p in applied.args[0].placements)
    assert json.loads(path.read_text())["maizeviz_layout"] == 1
    # a layout file replaces the tiling, undoably
    other = tmp_path / "other.json"
    doc = layout_to_dict(panel.layout_)
    doc["rows"] = [{"x": 10.5, "plants": [{"y": 20.25, "plant": 2, "azimuth_deg": 30}]}]
    other.write_text(json.dumps(doc))
    _answer(QMessageBox.Discard)
    assert panel.load(other)
    assert [(p.plant, p.x, p.y) for p in panel.draft.placements] == [(2, 10.5, 20.25)]
    assert panel.tiling.currentData() is None
    panel.undo_action.trigger()
    assert len(panel.draft.placements) == 2


def test_layout_editor_in_the_window_turns_a_plant(window, two_plants, qtbot):
    w = window(two_plants, tile=1)
    qtbot.waitSignal(w.canopy_shown, timeout=120_000).wait()
    panel = w.layout_panel
    assert panel.rows.rowCount() == 2
    first = panel.draft.placements[0].plant
    before = w.model.canopy.vertices[w.model.canopy.faces[w.model.canopy.face_plant == first]].copy()
    with qtbot.waitSignal(w.canopy_shown, timeout=120_000):
        panel.rows.setData(panel.rows.index(0, 3), "90")      # the 3D view follows
    after = w.model.canopy.vertices[w.model.canopy.faces[w.model.canopy.face_plant == first]]
    assert not np.allclose(before, after)
    assert [p.azimuth_deg for p in w.model.loaded.layout.placements if p.plant == first] == [90]
    assert w.model.loaded.layout.ground_area_cm2 == pytest.approx(60 * 60)   # the tiling's ground


def test_the_tiling_has_one_place_and_the_window_follows_it(window, two_plants, qtbot, tmp_path):
    """Issue: the canopy panel had its own tiling combo, which went stale after a layout
    preset (a project then saved the old tiling and reopening the points undid the preset)."""
    import zipfile

    from PySide6.QtWidgets import QComboBox

    w = window(two_plants, tile=1)
    qtbot.waitSignal(w.canopy_shown, timeout=120_000).wait()
    tilings = [c for c in w.findChildren(QComboBox)
               if "repeat" in c.toolTip() or "repeated" in c.toolTip()]
    assert tilings == [w.layout_panel.tiling]                # one control, in the layout panel
    with qtbot.waitSignal(w.canopy_shown, timeout=120_000):
        assert w.layout_panel.set_tiling(3)                  # the preset; the view follows
    assert w.model.tile_n == 3 and len(w.model.canopy.layout.placements) == 18
    path = tmp_path / "tiled.maizeviz"
    with qtbot.waitSignal(w.saved, timeout=120_000):
        w.model.save_project(path)
    with zipfile.ZipFile(path) as zf:
        assert json.loads(zf.read("project.json"))["settings"]["canopy"]["tile"] == 3
    with qtbot.waitSignal(w.canopy_shown, timeout=120_000):
        w.open_points(two_plants)                            # reopened with the tiling shown
    assert len(w.model.loaded.layout.placements) == 18
    assert w.layout_panel.tiling.currentData() == 3


def test_rows_by_plants_at_spacings_is_one_undoable_edit(panel, qtbot):
    panel.rows_box.setValue(4)
    panel.per_row_box.setValue(3)
    panel.row_spacing_box.setValue(75.0)
    panel.plant_spacing_box.setValue(25.0)
    with qtbot.waitSignal(panel.applied) as applied:          # the 3D view follows
        panel.lay_out_button.click()
    layout = applied.args[0]
    assert len(layout.placements) == 12 and len(panel.view.items_) == 12
    assert panel.rows.rowCount() == 12 and layout.row_spacing == 75.0
    xs = sorted({p.x for p in layout.placements})
    assert np.allclose(np.diff(xs), 75.0) and len(xs) == 4
    assert panel.tiling.currentText() == "4 rows x 3 plants"
    assert panel.undo_stack.count() == 1
    panel.undo_action.trigger()
    assert panel.rows.rowCount() == 2 and panel.rows_box.value() == 1   # the fields follow
    assert panel.per_row_box.value() == 2 and panel.row_spacing_box.value() == 60.0


def test_a_plant_put_onto_another_is_red_and_listed_until_moved(panel, qtbot):
    from maizeviz_app.panels.field_view import OVERLAPPING, PLANT

    panel.select(0)
    panel.duplicate_button.click()          # the field is full: beside it, in the field
    assert panel.rows.rowCount() == 3 and panel.picked == 2
    x0, y0, x1, y1 = panel.draft.base.bounds
    copy = panel.draft.placements[2]
    assert x0 <= copy.x <= x1 and y0 <= copy.y <= y1
    qtbot.waitUntil(lambda: not panel.overlaps.isHidden(), timeout=2000)
    assert "ground cell overlaps" in panel.overlaps.item(0).text()
    a = panel.draft.placements[0]
    assert panel.rows.setData(panel.rows.index(2, 0), str(a.x + 2.0))
    assert panel.rows.setData(panel.rows.index(2, 1), str(a.y + 1.0))   # onto plant 1
    qtbot.waitUntil(lambda: panel.overlaps.count() == 1, timeout=2000)
    assert panel.overlaps.item(0).text().startswith("table lines 1 and 3: ")
    assert "2.2 cm apart" in panel.overlaps.item(0).text()
    assert panel.view.items_[0].brush().color() == OVERLAPPING
    assert panel.rows.data(panel.rows.index(0, 0), Qt.ForegroundRole) is not None
    assert panel.view.items_[1].brush().color() == PLANT
    panel.remove_button.click()                               # the picked one (row 3) goes
    qtbot.waitUntil(panel.overlaps.isHidden, timeout=2000)
    assert panel.rows.rowCount() == 2
    assert panel.view.items_[0].brush().color() == PLANT
    panel.undo_action.trigger()                               # back: red again
    qtbot.waitUntil(lambda: not panel.overlaps.isHidden(), timeout=2000)
    assert panel.rows.rowCount() == 3


def test_the_overlap_note_counts_its_pairs_in_words(panel, qtbot):
    """One pair is "1 overlapping pair", two are "2 overlapping pairs" (issue 25)."""
    said: list[str] = []
    panel.problem.connect(said.append)
    panel.follow.setChecked(False)                    # applied on Apply only
    a = panel.draft.placements[0]
    for k in (1, 2):                                  # a copy of plant 1 beside it, twice
        panel.select(0)
        panel.duplicate_button.click()
        row = panel.rows.rowCount() - 1
        assert panel.rows.setData(panel.rows.index(row, 0), str(a.x + k))
        assert panel.rows.setData(panel.rows.index(row, 1), str(a.y + 40.0 * (k - 1) + 1.0))
        said.clear()
        with qtbot.waitSignal(panel.applied):
            panel.apply_button.click()
        notes = [t for t in said if "overlapping" in t]
        assert len(notes) == 1, said
        want = "(1 overlapping pair," if k == 1 else "(2 overlapping pairs,"
        assert want in notes[0] and "1 overlapping pairs" not in notes[0], notes[0]


def test_one_plant_is_one_plant_in_the_summary(panel, qtbot):
    assert panel.info.text().startswith("2 plants on ")
    panel.select(1)
    panel.remove_button.click()
    qtbot.waitUntil(lambda: panel.rows.rowCount() == 1, timeout=2000)
    qtbot.waitUntil(lambda: panel.info.text().startswith("1 plant on "), timeout=2000)


def test_add_rotate_and_snap(panel, qtbot):
    panel.select(1)
    panel.add_button.click()                                  # beyond the end of the row
    new = panel.draft.placements[-1]
    assert (new.x, new.y) == (BASES[2][0], BASES[2][1] + 30.0) and panel.picked == 2
    panel.left_button.click()
    panel.left_button.click()
    panel.right_button.click()
    assert panel.draft.placements[2].azimuth_deg == 15.0
    panel.snap.setChecked(True)
    panel.snap_step.setValue(10.0)
    view = panel.view
    item = view.items_[0]
    start = view.mapFromScene(item.scenePos())
    qtbot.mousePress(view.viewport(), Qt.LeftButton, pos=start)
    qtbot.mouseMove(view.viewport(), start + QPoint(37, 0))
    qtbot.mouseRelease(view.viewport(), Qt.LeftButton, pos=start + QPoint(37, 0))
    p = panel.draft.placements[0]
    assert p.x % 10.0 == 0 and p.y % 10.0 == 0 and p.x != BASES[1][0]
    assert view.items_[0].pos() == QPointF(p.x, p.y)          # the disc sits where it snapped
    assert panel.undo_stack.count() == 5


def test_every_layout_control_has_a_name_and_a_tip(panel):
    from PySide6.QtWidgets import QAbstractButton, QAbstractSpinBox, QComboBox

    controls = [c for c in panel.findChildren(QAbstractButton)
                + panel.findChildren(QAbstractSpinBox) + panel.findChildren(QComboBox)
                if not c.objectName().startswith("qt_")]          # Qt's own parts
    assert len(controls) >= 15
    for c in controls:
        assert c.toolTip(), c
        assert c.accessibleName(), c


def test_delete_removes_a_plant_only_from_the_layout_editor(window, two_plants, qtbot):
    """Issue 37, item 5: with a plant picked in the Layout panel and the focus in the 3D view,
    Delete removed a plant (the Remove button's shortcut was the whole window's); now Delete
    acts where the focus is: in the layout editor it removes the picked plant."""
    w = window(two_plants, tile=1)
    qtbot.waitSignal(w.canopy_shown, timeout=120_000).wait()
    from PySide6.QtWidgets import QApplication

    w.show()
    qtbot.waitExposed(w)
    w.activateWindow()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is w, timeout=5000)
    panel = w.layout_panel
    panel.select(0)
    assert panel.rows.rowCount() == 2
    view = w.viewport
    view.setFocus()
    qtbot.waitUntil(view.hasFocus, timeout=2000)
    qtbot.keyClick(view, Qt.Key.Key_Delete)
    qtbot.wait(200)
    assert panel.rows.rowCount() == 2                    # nothing removed from the 3D view
    panel.view.setFocus()
    qtbot.waitUntil(panel.view.hasFocus, timeout=2000)
    qtbot.keyClick(panel.view, Qt.Key.Key_Delete)
    qtbot.waitUntil(lambda: panel.rows.rowCount() == 1, timeout=2000)
