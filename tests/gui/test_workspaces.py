"""Workspaces in a real window: Analyse (the light docks) and Digitize (the view large, the
digitizer beside it), switched from View > Workspace, remembered, and following the work:
recording goes to Digitize, a light result back to Analyse."""

from maizeviz.digitizer.protocol import Record
from maizeviz.digitizer.recorder import Recorder
from maizeviz.digitizer.session import Session

TIMEOUT = 120_000
ANALYSE = {"canopy", "light", "layout", "colour", "instruments", "results", "messages",
           "history"}


def _open(w):
    """The docks that are open (shown, or a tab behind another)."""
    return {name for name, dock in w.docks.items() if dock.toggleViewAction().isChecked()}


def _menu_action(w, text):
    for top in w.menuBar().actions():
        if top.text() == "&View":
            for sub in top.menu().actions():
                if sub.menu() is not None and sub.text() == "&Workspace":
                    return {a.text(): a for a in sub.menu().actions()}[text]
    raise AssertionError("no View > Workspace menu")


def test_switching_from_the_view_menu(qtbot, window, two_plants):
    w = window(two_plants, tile=1)
    qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    qtbot.wait(100)
    assert w.workspaces.current == "analyse" and _open(w) == ANALYSE
    view_h = w.viewport.height()
    digitize = _menu_action(w, "&Digitize")
    assert digitize.shortcut().toString() == "Ctrl+Alt+2" and not digitize.isChecked()
    digitize.trigger()
    qtbot.wait(100)
    assert w.workspaces.current == "digitize" and digitize.isChecked()
    assert _open(w) == {"digitizer"}
    # the light results no longer take the window's lower part: the view is taller and wider
    assert w.viewport.height() > view_h + 150
    assert w.viewport.width() > 0.6 * w.width()
    assert w.docks["digitizer"].width() >= 400            # the big buttons, two to a row
    _menu_action(w, "&Analyse").trigger()
    qtbot.wait(100)
    assert _open(w) == ANALYSE and w.viewport.height() == view_h


def test_each_workspace_keeps_its_arrangement_and_the_window_starts_in_the_last(
        qtbot, window, two_plants):
    w = window(two_plants, tile=1)
    w.docks["messages"].close()                           # the user's arrangement of Analyse
    w.workspaces.show("digitize")
    w.workspaces.show("analyse")
    assert _open(w) == ANALYSE - {"messages"}
    w.workspaces.show("digitize")
    w.close()
    w2 = window(two_plants, tile=1)
    qtbot.wait(200)
    assert w2.workspaces.current == "digitize" and _open(w2) == {"digitizer"}
    assert w2.menu_actions["workspace_digitize"].isChecked()
    w2.workspaces.show("analyse")
    assert _open(w2) == ANALYSE - {"messages"}
    # View > Reset window layout: the workspace as on a first start
    w2.reset_layout()
    assert _open(w2) == ANALYSE


def test_recording_goes_to_digitize_and_a_light_result_back(qtbot, window, two_plants,
                                                             tmp_path):
    w = window(two_plants, tile=1)
    qtbot.waitSignal(w.canopy_shown, timeout=TIMEOUT).wait()
    rec = Recorder(Session(tmp_path / "s.csv", 3), None)
    w.digitizer.begin(rec)
    assert w.workspaces.current == "digitize" and "results" not in _open(w)
    rec.events.put(Record(1, " ", (1.0, 2.0, 3.0), (0.0, 0.0, 0.0), 1))
    w.digitizer._drain()
    with qtbot.waitSignal(w.digitizer.stopped, timeout=TIMEOUT):
        w.digitizer.stop()
    assert w.workspaces.current == "digitize"              # stays for the next plant
    assert "digitized" in w.viewport.actors and "canopy" not in w.viewport.actors
    with qtbot.waitSignal(w.light_shown, timeout=TIMEOUT):
        w.model.compute_light()
    assert w.workspaces.current == "analyse" and "results" in _open(w)
    assert "canopy" in w.viewport.actors and "digitized" not in w.viewport.actors
