"""The digitizer as a vendor's program is used: the port picked from the system's list or found
by asking each port, plain errors with their fix, Pause, the tip's live position, a Stop that
lets the window go on at once, and a question before closing while recording. A simulated
FASTRAK on a real pty and pyserial behind it, the panel a real widget under Xvfb."""

import numpy as np
import pytest
from PySide6.QtCore import QTimer
from PySide6.QtWidgets import QApplication, QComboBox, QMessageBox

from maizeviz.digitizer.port import FastrakPort
from maizeviz.digitizer.ports import list_serial_ports
from maizeviz.digitizer.recorder import Recorder
from maizeviz.digitizer.session import Session
from maizeviz.digitizer.simulator import FastrakSimulator
from maizeviz.io.points import read_points

TIMEOUT = 20_000


@pytest.fixture
def sim():
    s = FastrakSimulator(press_gap_s=0.0, noise_cm=0.0)
    yield s
    s.close()


def _connect(qtbot, panel, port, out, cols=3):
    panel.ports.set_port(port)
    panel.out_edit.setText(str(out))
    panel.cols.setValue(cols)
    with qtbot.waitSignal(panel.started, timeout=TIMEOUT):
        panel.connect_button.click()


def _press(qtbot, panel, sim, point, **kw):
    n = panel.session.count.points
    assert sim.press(point, **kw)
    qtbot.waitUntil(lambda: panel.session.count.points > n, timeout=TIMEOUT)


def _log(panel):
    return [panel.log.item(i).text() for i in range(panel.log.count())]


def _failed_connect(qtbot, panel, port, out):
    panel.ports.set_port(port)
    panel.out_edit.setText(str(out))
    with qtbot.waitSignal(panel.stopped, timeout=TIMEOUT) as stopped:
        panel.connect_button.click()
    assert stopped.args == ["could not connect"]
    assert panel.band.state == "error" and panel.connect_button.isEnabled()
    assert not out.exists() and not out.with_name(f".{out.name}.lock").exists()   # no junk
    Session(out, 3).close()                   # the journal is free, and still holds no point
    out.unlink()
    return panel.band.message.text()


def test_the_port_list_is_the_systems(qtbot, make_panel):
    panel = make_panel()
    box = panel.findChild(QComboBox)
    assert box is panel.ports.box and box.accessibleName() == "serial port"
    listed = [box.itemText(i) for i in range(box.count())]
    assert listed == [p.device for p in list_serial_ports()]
    # what is typed stays through a refresh
    panel.ports.set_port("/dev/ttyUSB5")
    with qtbot.waitSignal(panel.ports.listed, timeout=TIMEOUT):
        panel.ports.refresh_button.click()
    assert panel.port == "/dev/ttyUSB5"
    assert panel.ports.candidates()[0] == "/dev/ttyUSB5"


def test_find_fastrak_asks_each_port_off_the_gui_thread(qtbot, make_panel, tmp_path):
    panel = make_panel()
    with FastrakSimulator(silent=True) as silent, FastrakSimulator(garbage=True) as other, \
            FastrakSimulator(noise_cm=0.0) as good:
        for path in (other.path, good.path):
            panel.ports.box.addItem(path)
        panel.ports.set_port(silent.path)             # typed: tried first
        with qtbot.waitSignal(panel.ports.searched, timeout=30_000) as searched:
            panel.ports.find_button.click()
            # the search runs in a worker: the window answers meanwhile
            assert panel.ports.busy and not panel.connect_button.isEnabled()
            assert panel.band.state == "busy" and "searching" in panel.band.message.text()
        results = searched.args[0]
        by_port = {r.port: r for r in results}
        assert by_port[silent.path].kind == "silent" and by_port[other.path].kind == \
            "not_fastrak" and by_port[good.path].found
        assert panel.port == good.path
        assert panel.band.state == "ok" and f"FASTRAK found on {good.path}" in \
            panel.band.message.text()
        log = _log(panel)
        assert any(t.startswith(f"no answer from a FASTRAK on {silent.path}") for t in log)
        assert any(t.startswith(f"something answers on {other.path}") for t in log)
        assert any(t.startswith(f"found: a FASTRAK answers on {good.path}") for t in log)
        assert panel.connect_button.isEnabled() and panel.ports.find_button.isEnabled()
        # the port found records
        _connect(qtbot, panel, panel.port, tmp_path / "s.csv")
        _press(qtbot, panel, good, (1.0, 2.0, 3.0))
        panel.stop(wait=True)
    assert read_points(tmp_path / "s.csv").xyz.tolist() == [[1.0, 2.0, 3.0]]


def test_nothing_found_is_said(qtbot, make_panel, tmp_path):
    panel = make_panel()
    with FastrakSimulator(silent=True) as silent:
        panel.ports.box.clear()
        panel.ports.set_port(silent.path)
        with qtbot.waitSignal(panel.ports.searched, timeout=30_000):
            panel.ports.find_button.click()
    assert panel.band.state == "warn" and "no FASTRAK answered on 1 port" in \
        panel.band.message.text() and panel.beeps == 1
    assert panel.port == silent.path                       # left as typed


def test_each_connection_error_is_said_with_its_fix(qtbot, make_panel, tmp_path):
    panel = make_panel()
    out = tmp_path / "s.csv"
    text = _failed_connect(qtbot, panel, str(tmp_path / "ttyUSB9"), out)
    assert f"no serial port {tmp_path / 'ttyUSB9'}: nothing is plugged in" in text
    with FastrakSimulator(silent=True) as silent:
        text = _failed_connect(qtbot, panel, silent.path, out)
    assert "no answer from a FASTRAK" in text and "DIP switches" in text
    with FastrakSimulator(garbage=True) as other:
        text = _failed_connect(qtbot, panel, other.path, out)
    assert "not as a FASTRAK does" in text
    with FastrakSimulator() as held:
        holder = FastrakPort(held.path, answer_timeout=0.3)
        holder.configure()
        try:
            text = _failed_connect(qtbot, panel, held.path, out)
        finally:
            holder.close()
    assert f"{held.path} is busy" in text
    assert "Errno" not in " ".join(_log(panel)) and "ioctl" not in " ".join(_log(panel))


def test_pause_does_not_record_and_says_so(qtbot, make_panel, sim, tmp_path):
    panel = make_panel()
    out = tmp_path / "s.csv"
    alerts = []
    panel.alert.connect(alerts.append)
    _connect(qtbot, panel, sim.path, out)
    _press(qtbot, panel, sim, (1.0, 0.0, 0.0))
    panel.pause_button.click()
    qtbot.waitUntil(lambda: panel.band.state == "warn", timeout=TIMEOUT)
    assert panel.paused and panel.pause_button.accessibleName() == "Resume"
    assert panel.band.where.text().startswith("PAUSED")
    beeps = panel.beeps
    assert sim.press((2.0, 0.0, 0.0))
    qtbot.waitUntil(lambda: "NOT recorded" in panel.band.message.text(), timeout=TIMEOUT)
    assert panel.beeps == beeps + 1 and "NOT recorded" in alerts[-1]
    assert panel.session.count.points == 1
    panel.activateWindow()
    panel.log.setFocus()
    qtbot.waitUntil(panel.log.hasFocus, timeout=TIMEOUT)
    qtbot.keyClick(panel.log, "s")                        # the key resumes, wherever the focus
    qtbot.waitUntil(lambda: not panel.paused, timeout=TIMEOUT)
    assert "resumed" in panel.band.message.text() and panel.band.state == "ok"
    _press(qtbot, panel, sim, (3.0, 0.0, 0.0))
    with qtbot.waitSignal(panel.stopped, timeout=TIMEOUT):
        panel.stop_button.click()
    assert read_points(out).xyz[:, 0].tolist() == [1.0, 3.0]


def test_the_tip_is_shown_live_with_its_distance(qtbot, make_panel, sim, tmp_path):
    panel = make_panel()
    _connect(qtbot, panel, sim.path, tmp_path / "s.csv")
    _press(qtbot, panel, sim, (10.0, 20.0, 30.0))
    sim.stylus = np.array([13.0, 24.0, 30.0])            # the technician moves the stylus
    qtbot.waitUntil(lambda: "13.00  24.00  30.00 cm" in panel.live.text(), timeout=TIMEOUT)
    assert "5.00 cm from the last point" in panel.live.text()
    assert panel.session.count.points == 1                # moving records nothing
    sim.set_error("x")
    qtbot.waitUntil(lambda: "motion box" in panel.live.text(), timeout=TIMEOUT)


def test_stop_lets_go_at_once_and_loses_no_press(qtbot, make_panel, sim, tmp_path):
    """Stop returns at once; a press the recorder journaled while the window was not looking
    is shown before the end; once stopped the port is free for another program."""
    panel = make_panel()
    out = tmp_path / "s.csv"
    _connect(qtbot, panel, sim.path, out)
    _press(qtbot, panel, sim, (1.0, 0.0, 0.0))
    panel.timer.stop()                                    # the window looks away
    assert sim.press((2.0, 0.0, 0.0))
    qtbot.waitUntil(lambda: out.read_bytes().count(b"recorded") == 2, timeout=TIMEOUT)
    with qtbot.waitSignal(panel.stopped, timeout=TIMEOUT) as stopped:
        panel.stop_button.click()
        assert not panel.stop_button.isEnabled() and not panel.connect_button.isEnabled()
        panel.timer.start()
    assert stopped.args == ["stopped"]
    assert panel.digitizing._proc is None and panel.connect_button.isEnabled()
    assert read_points(out).xyz[:, 0].tolist() == [1.0, 2.0]
    assert any(t.startswith("recorded plant 1 leaf 1 row 0 col 1") for t in _log(panel))
    assert "2 points" in panel.counts.text()
    other = FastrakPort(sim.path, answer_timeout=0.3)      # not busy
    other.configure()
    other.close()


def test_closing_the_window_while_recording_asks(qtbot, window, two_plants, tmp_path):
    w = window(two_plants, tile=1)
    out = tmp_path / "s.csv"
    rec = Recorder(Session(out, 3), None)
    w.digitizer.begin(rec)
    answers = []

    def answer(button_text):
        def click():
            box = QApplication.activeModalWidget()
            assert isinstance(box, QMessageBox)
            answers.append(box.text())
            for b in box.buttons():
                if b.text() == button_text:
                    b.click()
        QTimer.singleShot(200, click)

    answer("Keep recording")
    w.close()
    assert w.isVisible() and w.digitizer.recording        # nothing stopped
    assert f"recording into {out} (0 points, all on disk)" in answers[0]
    answer("Stop and close")
    w.close()
    qtbot.waitUntil(lambda: not w.isVisible(), timeout=TIMEOUT)
    assert not w.digitizer.recording and len(answers) == 2
    Session(out, 3, resume=True).close()                   # the journal was let go
