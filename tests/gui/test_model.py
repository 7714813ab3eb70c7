"""The app's study model without a window (Qt-free), and the window's unsaved-changes marker
and prompt built on it."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from maizeviz_app.jobs import load_points
from maizeviz_app.model import StudyModel
from maizeviz_app.runs import Run
from test_light_modes import TIMEOUT, compute, shown, small_light


class _Result:
    def __init__(self, heights=(0.0, 100.0), t=(0.4, 0.8)):
        self.heights_cm, self.transmission = heights, t


@pytest.fixture(scope="module")
def loaded(small_points):
    return load_points(str(small_points), (1, 1))


def _record(model):
    seen = []
    for name in ("points_changed", "layout_changed", "canopy_changed", "runs_changed",
                 "project_changed", "modified_changed"):
        getattr(model, name).connect(lambda *a, name=name: seen.append((name, a)))
    return seen


def test_the_model_imports_without_qt():
    code = ("import sys, maizeviz_app.model, maizeviz_app.runs; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('PySide6', 'pyvista', 'vtk')]; "
            "print(bad); sys.exit(1 if bad else 0)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_opening_points_starts_a_clean_study(loaded, small_points):
    model = StudyModel(tile=3)
    seen = _record(model)
    assert model.title == "maizeviz" and not model.modified
    model.set_points(loaded, b"abc", str(small_points))
    assert model.loaded is loaded and model.points_bytes == b"abc" and model.serial == 1
    assert [n for n, _ in seen] == ["runs_changed", "points_changed", "project_changed"]
    assert not model.modified and model.title == f"maizeviz — {small_points.name}[*]"
    assert model.tile_n == 1                        # the layout's own tiling, not the start's


def test_light_results_are_unsaved_work_until_saved(loaded, small_points, tmp_path):
    model = StudyModel()
    model.set_points(loaded, b"", str(small_points))
    seen = _record(model)
    run = Run("36 triangles", model.signature("36 triangles"), _Result())
    assert not model.add_run(run, ("sun",), ("h",), "traced")
    assert model.modified and ("modified_changed", (True,)) in seen
    assert ("runs_changed", (model.runs, "traced")) in seen
    assert list(model.runs.runs) == ["36 triangles"]
    # a result for older points is not kept
    stale = Run("K=4", (model.serial - 1, "K=4"), _Result())
    assert not model.add_run(stale, ("sun",), ("h",))
    assert list(model.runs.runs) == ["36 triangles"]
    target = str(tmp_path / "s.maizeviz")
    model.mark_saved(target)
    assert not model.modified and model.project_path == target
    assert model.title == "maizeviz — s.maizeviz[*]"
    # results read back from a project are not new work
    model.add_run(Run("4 triangles", model.signature("4 triangles"), _Result()), ("sun",),
                  ("h",), saved=True)
    assert not model.modified and len(model.runs.runs) == 2


def test_a_layout_edit_drops_results_and_stales_canopies(loaded, small_points):
    from dataclasses import replace

    model = StudyModel()
    model.set_points(loaded, b"", str(small_points))
    old_serial = model.serial
    model.add_run(Run("36 triangles", model.signature("36 triangles"), _Result()), (), ())
    seen = _record(model)
    first = loaded.layout.placements[0]
    moved = replace(loaded.layout, placements=(replace(first, x=first.x + 7.5),)
                    + loaded.layout.placements[1:])     # other stands: the results set aside
    assert model.edit_layout(moved) is True
    assert model.loaded.layout is moved and model.layout_edited and model.modified
    assert model.serial == old_serial + 1 and not model.runs.runs
    assert ("layout_changed", (moved,)) in seen

    class Built:
        serial, label, row, level = old_serial, "36 triangles", {"a": "1"}, "36"
        canopy = None
    assert not model.show_built(Built())            # built for the layout before the edit
    assert model.built is None
    Built.serial = model.serial
    assert model.show_built(Built()) and model.measures_rows == {"36 triangles": {"a": "1"}}


def test_window_marks_unsaved_work_and_asks_before_closing(window, qtbot, small_points,
                                                           tmp_path):
    from PySide6.QtCore import QTimer
    from PySide6.QtWidgets import QApplication, QMessageBox

    w = shown(qtbot, window(small_points, tile=1))
    assert not w.isWindowModified() and w.windowTitle().endswith("[*]")
    small_light(w.light_panel, "sun")
    compute(qtbot, w)
    assert w.isWindowModified() and w.model.modified
    w.confirm_unsaved = True
    answers = []

    def answer(button):
        def click():
            box = QApplication.activeModalWidget()
            if isinstance(box, QMessageBox):
                answers.append(box.text())
                box.button(button).click()
            else:
                QTimer.singleShot(50, click)
        QTimer.singleShot(50, click)

    answer(QMessageBox.StandardButton.Cancel)
    assert not w.close()                            # Cancel: the window stays, results kept
    assert w.isVisible() and w.model.runs.runs and "not in a project" in answers[0]
    # Save with a project already named: saved, then closed
    w.model.project_path = str(tmp_path / "kept.maizeviz")
    answer(QMessageBox.StandardButton.Save)
    with qtbot.waitSignal(w.saved, timeout=TIMEOUT):
        assert not w.close()                        # closes once the project is written
    qtbot.waitUntil(lambda: not w.isVisible(), timeout=TIMEOUT)
    assert (tmp_path / "kept.maizeviz").stat().st_size > 0 and len(answers) == 2


def test_discarding_lets_another_file_open(window, qtbot, small_points):
    from PySide6.QtCore import QTimer
    from PySide6.QtWidgets import QApplication, QMessageBox

    w = shown(qtbot, window(small_points, tile=1))
    small_light(w.light_panel, "sun")
    compute(qtbot, w)
    w.confirm_unsaved = True
    serial = w.model.serial

    def discard():
        box = QApplication.activeModalWidget()
        if isinstance(box, QMessageBox):
            box.button(QMessageBox.StandardButton.Discard).click()
        else:
            QTimer.singleShot(50, discard)
    QTimer.singleShot(50, discard)
    with qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT):
        w.open_points(small_points)
    assert w.model.serial == serial + 1 and not w.model.runs.runs and not w.isWindowModified()


def test_the_digitizer_connection_is_a_setting_of_the_study(window, qtbot):
    w = window(wait_ready=True)
    d, settings = w.digitizer, w.model.settings.digitizer
    assert settings.port == d.port and settings.baud == d.baud.value()
    settings.port, settings.baud = "/dev/ttyS7", 9600          # set by a script: shown
    assert d.port == "/dev/ttyS7" and d.baud.value() == 9600
    assert d.ports.baud == 9600                                 # Find FASTRAK probes at it
    d.ports.box.setEditText("/dev/ttyUSB3")                     # typed: the study's
    d.baud.setValue(38400)
    assert (settings.port, settings.baud) == ("/dev/ttyUSB3", 38400)
    assert w.undo.stack.count() == 0                            # not an edit of the study


def test_the_view_renders_the_studys_view_state(window, qtbot, small_points):
    """The colouring and the camera are the study's (view_state.py): the View menu sets them,
    the viewport renders them; a script setting them moves the view, a drag of the view
    moves the study's pose."""
    from PySide6.QtCore import QPoint, Qt

    w = shown(qtbot, window(small_points, tile=1))
    view, state = w.viewport, w.model.view
    w.menu_actions["colour_plant"].trigger()                    # the menu sets the state
    assert state.colouring == "plant" and view.colouring == "plant"
    state.colouring = "leaf"                                    # a script: the view follows
    assert view.colouring == "leaf" and w.menu_actions["colour_leaf"].isChecked()
    w.view_link.camera("top")
    assert state.camera == "top" and state.pose == view.camera_pose()
    top = state.pose
    position, focal, _up = top
    moved = ((position[0] + 50.0, position[1], position[2]), focal, (0.0, 1.0, 0.0))
    state.pose = moved                                          # a script moves the camera
    np.testing.assert_allclose(view.camera_pose()[0], moved[0])
    centre = QPoint(view.width() // 2, view.height() // 2)      # a drag turns it: the study's
    qtbot.mousePress(view, Qt.LeftButton, pos=centre)
    qtbot.mouseMove(view, centre + QPoint(60, 20))
    qtbot.mouseRelease(view, Qt.LeftButton, pos=centre + QPoint(60, 20))
    assert state.pose == view.camera_pose() and state.pose != moved
