"""The digitizer panel as a technician with gloves uses it: a real (simulated) FASTRAK on a pty,
the panel's reader and timer, the journal on disk, the 3D view of the growing plant."""

import gc

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QLineEdit

from maizeviz.digitizer.protocol import Record
from maizeviz.digitizer.recorder import Recorder
from maizeviz.digitizer.session import Session
from maizeviz.digitizer.simulator import FastrakSimulator
from maizeviz.io.points import read_points

TIMEOUT = 20_000


@pytest.fixture
def viewport(qtbot):
    from maizeviz_app.viewport import Viewport

    vp = Viewport()
    vp.resize(500, 400)
    vp.show()
    qtbot.waitExposed(vp)
    yield vp
    vp.close()
    # collected here, on the GUI thread: a view left to the cyclic collector was finalized
    # (its OpenGL context destroyed) in whatever thread ran the next collection, such as a
    # later window's warm-up thread, and the process aborted
    del vp
    gc.collect()


@pytest.fixture
def sim():
    from maizeviz.digitizer.simulator import FastrakSimulator

    s = FastrakSimulator(press_gap_s=0.0, noise_cm=0.0)
    yield s
    s.close()


def _press(x, y=0.0, z=0.0):
    return Record(1, " ", (float(x), float(y), float(z)), (0.0, 0.0, 0.0), 1)


def _connect(qtbot, panel, sim, out, cols=3):
    panel.ports.set_port(sim.path)
    panel.out_edit.setText(str(out))
    panel.cols.setValue(cols)
    with qtbot.waitSignal(panel.started, timeout=TIMEOUT):
        panel.connect_button.click()


def _press_and_wait(qtbot, panel, sim, points):
    for p in points:
        n = panel.session.count.points
        assert sim.press(p)
        qtbot.waitUntil(lambda n=n: panel.session is not None and panel.session.count.points > n,
                        timeout=TIMEOUT)


def test_buttons_are_big_and_the_panel_scrolls_on_a_laptop(make_panel):
    panel = make_panel()
    for b in panel.control_buttons + [panel.connect_button, panel.demo_button,
                                      panel.stop_button]:
        assert b.height() >= 48 and b.font().pointSize() >= 14
    # every control fits in a small dock: the rest scrolls
    assert panel.minimumSizeHint().height() < 300
    panel.resize(380, 320)
    assert panel.scroll_area.verticalScrollBar().maximum() > 0


def test_shortcuts_act_wherever_the_focus_is(qtbot, make_panel, tmp_path):
    panel = make_panel()
    out = tmp_path / "s.csv"
    panel.out_edit.setText(str(out))
    path = panel.out_edit.text()
    panel.begin(Recorder(Session(out, 3), None))
    panel.activateWindow()
    panel.out_edit.setFocus()
    qtbot.waitUntil(panel.out_edit.hasFocus, timeout=TIMEOUT)
    qtbot.keyClick(panel.out_edit, Qt.Key_N)
    assert panel.out_edit.text() == path                 # not "...csvn"
    assert panel.session.pos.leaf == 2
    # an editable text field elsewhere in the application does not swallow the keys either
    other = QLineEdit()
    qtbot.addWidget(other)
    other.show()
    qtbot.waitExposed(other)
    other.activateWindow()
    other.setFocus()
    qtbot.waitUntil(other.hasFocus, timeout=TIMEOUT)
    qtbot.keyClick(other, Qt.Key_P)
    assert other.text() == "" and panel.session.pos.plant == 2
    qtbot.keyClick(other, Qt.Key_U)                       # nothing to undo: said, no harm
    assert "nothing to undo" in panel.band.message.text()
    panel.stop()
    # after the session the keys are letters again and the fields editable
    qtbot.keyClick(other, Qt.Key_N)
    assert other.text() == "n"
    assert not panel.out_edit.isReadOnly() and panel.cols.isEnabled()


def test_q_in_the_same_tick_as_a_point(qtbot, make_panel, sim, tmp_path):
    """The demo types q right after its last press: the point on disk and the recorder's end
    can reach the window in one timer tick; the window shows the point, then the end."""
    panel = make_panel()
    out = tmp_path / "s.csv"
    _connect(qtbot, panel, sim, out)
    panel.timer.stop()                                    # hold the tick
    assert sim.press((1.0, 2.0, 3.0))
    # the recorder journals the press with the window asleep
    qtbot.waitUntil(lambda: b"recorded" in out.read_bytes(), timeout=TIMEOUT)
    panel.digitizing.control("q")
    proc = panel.digitizing._proc
    qtbot.waitUntil(lambda: proc.poll() is not None, timeout=TIMEOUT)
    with qtbot.waitSignal(panel.stopped, timeout=TIMEOUT) as stopped:
        panel.timer.start()                               # one tick sees the point and the q
    assert stopped.args == ["finished"]
    pts = read_points(out)
    assert len(pts) == 1 and np.allclose(pts.xyz[0], (1.0, 2.0, 3.0))
    assert "1 point, 1 leaf" in panel.counts.text()     # the session summary says 1 point
    assert panel.press_beeps == 1 and panel.press_count.text() == "1 point"


def test_refused_point_and_garbled_record_are_loud(qtbot, make_panel, sim, tmp_path):
    panel = make_panel()
    alerts = []
    panel.alert.connect(alerts.append)
    _connect(qtbot, panel, sim, tmp_path / "s.csv")
    _press_and_wait(qtbot, panel, sim, [(1.0, 0.0, 0.0)])
    assert panel.band.state == "ok" and not alerts
    sim.set_error("x")
    assert sim.press((2.0, 0.0, 0.0))
    qtbot.waitUntil(lambda: panel.band.state == "error", timeout=TIMEOUT)
    assert "refused" in panel.band.message.text() and "refused" in alerts[-1]
    assert panel.beeps == 1
    sim.set_error(" ")
    _press_and_wait(qtbot, panel, sim, [(2.0, 0.0, 0.0)])
    assert panel.band.state == "ok"                       # back to green with a good point
    sim.inject(b"\x00\xff#noise#\r\n")
    qtbot.waitUntil(lambda: panel.band.state == "warn", timeout=TIMEOUT)
    assert "garbled" in alerts[-1] and panel.beeps == 2
    assert panel.session.count.points == 2


def test_lost_port_is_loud_and_every_point_is_on_disk(qtbot, make_panel, sim, tmp_path):
    panel = make_panel()
    alerts = []
    panel.alert.connect(alerts.append)
    out = tmp_path / "s.csv"
    _connect(qtbot, panel, sim, out)
    _press_and_wait(qtbot, panel, sim, [(k, 0.0, 0.0) for k in range(4)])
    with qtbot.waitSignal(panel.stopped, timeout=TIMEOUT) as stopped:
        sim.vanish()
    assert stopped.args == ["port lost"]
    assert panel.band.state == "error" and "on disk" in panel.band.message.text()
    assert "not recording (port lost)" in panel.band.where.text()
    assert any("on disk" in a for a in alerts) and panel.beeps >= 1
    assert len(read_points(out)) == 4
    assert panel.connect_button.isEnabled() and not panel.out_edit.isReadOnly()
    # plugged back in, Connect continues the same file where it stopped
    assert panel.resume.isChecked()
    with FastrakSimulator(press_gap_s=0.0, noise_cm=0.0) as again:
        _connect(qtbot, panel, again, out)
        assert panel.session.count.points == 4
        _press_and_wait(qtbot, panel, again, [(9.0, 0.0, 0.0)])
        panel.stop(wait=True)
    assert read_points(out).xyz[:, 0].tolist() == [0, 1, 2, 3, 9]


def test_unwritable_output_and_missing_port_are_said(qtbot, make_panel, tmp_path):
    panel = make_panel()
    panel.out_edit.setText(str(tmp_path / "missing" / "x.csv"))
    panel.connect_button.click()
    assert "no such folder" in panel.log.item(panel.log.count() - 1).text()
    assert panel.band.state == "error" and panel.connect_button.isEnabled()
    panel.out_edit.setText(str(tmp_path / "ok.csv"))
    panel.ports.set_port("/dev/does-not-exist")
    with qtbot.waitSignal(panel.stopped, timeout=TIMEOUT) as stopped:
        panel.connect_button.click()
    assert stopped.args == ["could not connect"]
    texts = [panel.log.item(i).text() for i in range(panel.log.count())]
    assert any("no serial port /dev/does-not-exist: nothing is plugged in" in t for t in texts)
    assert panel.connect_button.isEnabled() and panel.session is None


def _leaf_rows(leaf, rows=3, cols=3, x0=0.0):
    """Points of a small flat leaf rising along z, one row per list (cm)."""
    return [[(x0 + 2.0 * c, 0.5 * r, 10.0 * leaf + 8.0 * r) for c in range(cols)]
            for r in range(rows)]


def test_the_plant_grows_one_leaf_at_a_time_off_the_gui_thread(qtbot, make_panel, viewport,
                                                               tmp_path):
    panel = make_panel(viewport)
    viewport.add_mesh(__import__("pyvista").Sphere(), name="canopy")
    rec = Recorder(Session(tmp_path / "s.csv", 3), None)
    panel.begin(rec)
    assert "canopy" not in viewport.actors                # made room for the plant
    meshed = []
    panel.plant.leaf_meshed.connect(lambda p, lf: meshed.append((p, lf)))
    leaf1 = _leaf_rows(1)
    for p in leaf1[0] + leaf1[1]:
        rec.events.put(_press(*p))
    panel._drain()
    # the surface is fitted in a worker: the press returned before it exists
    assert "leafsurf-p1-l1" not in viewport.actors and meshed == []
    qtbot.waitUntil(lambda: meshed == [(1, 1)], timeout=TIMEOUT)
    assert "leafsurf-p1-l1" in viewport.actors
    dots = viewport.actors["digitized"].prop
    assert dots.opacity < 1 and dots.point_size <= 6     # small, the surface shows through
    rec.events.put(_press(*leaf1[2][0]))                  # a row begun: nothing to re-fit
    panel._drain()
    panel.control("n")                                    # ... ended as a one-point tip
    leaf2 = _leaf_rows(2)
    for p in leaf2[0] + leaf2[1]:
        rec.events.put(_press(*p))
    panel._drain()
    qtbot.waitUntil(lambda: len(meshed) == 3, timeout=TIMEOUT)
    panel.plant.wait()
    qtbot.wait(100)
    assert sorted(meshed) == [(1, 1), (1, 1), (1, 2)]     # leaf 1 never re-fitted for leaf 2
    # undo the last point: leaf 2 loses a row, its surface goes
    panel.control("u")
    qtbot.waitUntil(lambda: "leafsurf-p1-l2" not in viewport.actors, timeout=TIMEOUT)
    assert "leafsurf-p1-l1" in viewport.actors


def test_camera_follows_the_current_plant_and_the_canopy_comes_back(qtbot, make_panel,
                                                                    viewport, tmp_path):
    panel = make_panel(viewport)
    rec = Recorder(Session(tmp_path / "s.csv", 3), None)
    panel.begin(rec)
    for row in _leaf_rows(1):
        for p in row:
            rec.events.put(_press(*p))
    panel._drain()
    focal = np.array(viewport.camera.focal_point)
    assert np.linalg.norm(focal - [2.0, 0.5, 18.0]) < 5
    panel.control("p")
    for row in _leaf_rows(1, x0=300.0):
        for p in row:
            rec.events.put(_press(*p))
    panel._drain()
    focal = np.array(viewport.camera.focal_point)
    assert np.linalg.norm(focal - [302.0, 0.5, 18.0]) < 5
    panel.plant.wait()
    with qtbot.waitSignal(panel.stopped, timeout=TIMEOUT):
        panel.stop()
    # the plant just digitized stays in view until the canopy comes back
    assert [n for n in viewport.actors if str(n).startswith(("leafsurf", "digitized"))]
    panel.release_view()
    assert not [n for n in viewport.actors if str(n).startswith(("leafsurf", "digitized"))]


def test_demo_records_through_the_simulator(qtbot, make_panel, viewport, tmp_path):
    """Demo mode: a simulated FASTRAK on a real pty replays a file and types n and q itself."""
    from maizeviz.io.points import write_points
    from maizeviz.leaf.grid import LeafGrid
    from maizeviz.leaf.synth import LeafShape, leaf_points

    rng = np.random.default_rng(1)
    src = tmp_path / "two_leaves.csv"
    write_points(src, [LeafGrid(1, k + 1, leaf_points(LeafShape(length=40, base=(0, 0, 30 * k)),
                                                      3, 2, rng=rng), True) for k in range(2)])
    n_points = len(read_points(src))
    panel = make_panel(viewport)
    panel.demo_file, panel.demo_pace = src, 0.0
    panel.cols.setValue(2)
    out = tmp_path / "session.csv"
    panel.out_edit.setText(str(out))
    recorded, stopped = [], []
    panel.recorded.connect(recorded.append)
    panel.stopped.connect(stopped.append)
    panel.demo_button.click()
    qtbot.waitUntil(lambda: bool(stopped), timeout=60_000)
    assert stopped == ["finished"] and recorded[-1] == n_points
    pts = read_points(out)
    assert len(pts) == n_points and set(map(tuple, pts.ids[:, :2].tolist())) == {(1, 1), (1, 2)}
    assert f"{n_points} points, 2 leaves" in panel.counts.text()


def test_canopy_returns_in_the_window_after_a_session(window, two_plants, qtbot, tmp_path):
    w = window(two_plants, tile=1)
    qtbot.waitSignal(w.canopy_shown, timeout=120_000).wait()
    alerts = []
    w.statusBar().messageChanged.connect(alerts.append)
    rec = Recorder(Session(tmp_path / "s.csv", 3), None)
    w.digitizer.begin(rec)
    assert "canopy" not in w.viewport.actors
    rec.events.put(Record(1, "x", (1.0, 2.0, 3.0), (0.0, 0.0, 0.0), 1))
    w.digitizer._drain()
    assert any("refused" in a for a in alerts)            # the status bar says it too
    with qtbot.waitSignal(w.digitizer.stopped, timeout=TIMEOUT):
        w.digitizer.stop()
    assert "canopy" not in w.viewport.actors              # Digitize: the plant keeps the view
    w.workspaces.show("analyse")
    assert "canopy" in w.viewport.actors


def test_stop_while_connecting_lets_go_of_the_file(qtbot, make_panel, tmp_path):
    """A unit that does not answer: the window stays live, Stop ends the attempt at once and
    the journal (and its lock) is free for the next try."""
    from maizeviz.digitizer.simulator import FastrakSimulator

    with FastrakSimulator(silent=True) as silent:
        panel = make_panel()
        out = tmp_path / "s.csv"
        panel.ports.set_port(silent.path)
        panel.out_edit.setText(str(out))
        panel.connect_button.click()
        assert panel.band.state == "busy" and panel.stop_button.isEnabled()
        assert panel.out_edit.isReadOnly()
        qtbot.wait(200)                                   # the GUI thread is not blocked
        with qtbot.waitSignal(panel.stopped, timeout=TIMEOUT) as stopped:
            panel.stop_button.click()
        assert stopped.args == ["stopped"] and panel.connect_button.isEnabled()
    Session(out, 3, resume=True).close()                  # nobody holds the file any more


def test_a_canopy_built_while_digitizing_waits_for_the_session(window, two_plants, qtbot,
                                                               tmp_path):
    """Issue: a canopy arriving while the digitizer records was shown at once, wiping the
    growing plant from the view; it now waits and shows when the session stops."""
    w = window(two_plants, tile=1)
    qtbot.waitSignal(w.canopy_shown, timeout=120_000).wait()
    rec = Recorder(Session(tmp_path / "s.csv", 3), None)
    w.digitizer.begin(rec)
    for x in (0.0, 1.0, 2.0):                                # one cross-section
        rec.events.put(_press(x, 0.0, 50.0))
    w.digitizer._drain()
    qtbot.waitUntil(lambda: "digitized" in w.viewport.actors, timeout=TIMEOUT)
    with qtbot.waitSignal(w.canopy_shown, timeout=120_000):
        w.canopy_panel.slider.setValue(w.canopy_panel.slider.value() + 1)             # a rebuild finishes meanwhile
    assert w.model.built.label == "16 triangles"
    assert "canopy" not in w.viewport.actors                 # the plant keeps the view
    assert "digitized" in w.viewport.actors
    with qtbot.waitSignal(w.digitizer.stopped, timeout=TIMEOUT):
        w.digitizer.stop()
    assert "digitized" in w.viewport.actors                  # still, until Analyse
    w.workspaces.show("analyse")
    assert "canopy" in w.viewport.actors and "digitized" not in w.viewport.actors
    n_stalk = len(w.model.canopy.stalk_faces)
    assert w.viewport.canopy_mesh.n_cells == w.model.canopy.n_triangles + n_stalk   # the new one
