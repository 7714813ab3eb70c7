"""What the technician hears and sees for each press (issue 35, item 6): a beep and the running
count once a point is on disk, a jump named with its distance, a cross-section ended early
named by plant, leaf and section, no file left by a Connect that failed, and after a crash the
last session offered for resume. A simulated FASTRAK on a real pty, the recorder in its own
process, the panel a real widget under Xvfb."""

import pytest

from maizeviz.digitizer.feedback import JUMP_CM
from maizeviz.digitizer.simulator import FastrakSimulator
from maizeviz.io.points import read_points

TIMEOUT = 20_000


@pytest.fixture
def sim():
    s = FastrakSimulator(press_gap_s=0.0, noise_cm=0.0)
    yield s
    s.close()


def _connect(qtbot, panel, port, out, cols=3, resume=False):
    panel.ports.set_port(port)
    panel.out_edit.setText(str(out))
    panel.cols.setValue(cols)
    panel.resume.setChecked(resume)
    with qtbot.waitSignal(panel.started, timeout=TIMEOUT):
        panel.connect_button.click()


def _press(qtbot, panel, sim, point):
    n = panel.session.count.points
    assert sim.press(point)
    qtbot.waitUntil(lambda: panel.session.count.points > n, timeout=TIMEOUT)


def test_each_press_is_confirmed_and_counted(qtbot, make_panel, sim, tmp_path):
    panel = make_panel()
    _connect(qtbot, panel, sim.path, tmp_path / "s.csv")
    for k in range(3):
        _press(qtbot, panel, sim, (2.0 * k, 0.0, 0.0))
        assert panel.press_beeps == k + 1
        assert panel.press_count.text() == f"{k + 1} point{'s' if k else ''}"
    assert panel.beeps == 0 and panel.band.state == "ok"


def test_a_jump_is_said_with_its_distance(qtbot, make_panel, sim, tmp_path):
    panel = make_panel()
    alerts = []
    panel.alert.connect(alerts.append)
    out = tmp_path / "s.csv"
    _connect(qtbot, panel, sim.path, out)
    _press(qtbot, panel, sim, (0.0, 0.0, 0.0))
    _press(qtbot, panel, sim, (3.0, 0.0, 0.0))
    assert not alerts
    _press(qtbot, panel, sim, (3.0, 70.0, 0.0))            # a slipped stylus, 70 cm away
    qtbot.waitUntil(lambda: panel.band.state == "warn", timeout=TIMEOUT)
    text = panel.band.message.text()
    assert "70 cm from the point before it" in text and "plant 1 leaf 1 row 0 col 2" in text
    assert f"more than {JUMP_CM:.0f} cm" in text and "press U" in text
    assert alerts and "70 cm" in alerts[-1] and panel.beeps == 1
    assert len(read_points(out)) == 3                     # recorded all the same: U takes it back
    # the first point of the next leaf is far from the last one's tip: no word
    panel.control("n")
    # the N on disk before the press: the control goes down the recorder's pipe, the press
    # down the pty, and a loaded machine can deliver the press first
    qtbot.waitUntil(lambda: panel.session.pos.leaf == 2, timeout=TIMEOUT)
    _press(qtbot, panel, sim, (3.0, 0.0, 90.0))
    assert panel.beeps == 1


def test_a_row_ended_early_is_flagged_and_the_tip_is_not(qtbot, make_panel, sim, tmp_path):
    panel = make_panel()
    _connect(qtbot, panel, sim.path, tmp_path / "s.csv", cols=3)
    for k in range(3):                                     # section 0: 3 points
        _press(qtbot, panel, sim, (2.0 * k, 0.0, 10.0))
    _press(qtbot, panel, sim, (0.0, 0.0, 18.0))            # section 1: 2 points, then R
    _press(qtbot, panel, sim, (2.0, 0.0, 18.0))
    panel.control("r")
    qtbot.waitUntil(lambda: panel.session.pos.row == 2, timeout=TIMEOUT)   # the R on disk
    assert panel.beeps == 0
    _press(qtbot, panel, sim, (0.0, 0.0, 26.0))            # section 2 begins: 1 was short
    qtbot.waitUntil(lambda: panel.band.state == "warn", timeout=TIMEOUT)
    assert "plant 1, leaf 1, section 1 has 2 points, the others 3" in panel.band.message.text()
    assert panel.beeps == 1
    panel.control("r")                                     # the tip: one point, then the next
    panel.control("n")                                     # leaf: nothing to say
    qtbot.waitUntil(lambda: panel.session.pos.leaf == 2, timeout=TIMEOUT)
    _press(qtbot, panel, sim, (0.0, 5.0, 40.0))
    assert panel.beeps == 1 and len(panel.digitizing.warnings) == 1


def test_a_failed_connect_leaves_no_file(qtbot, make_panel, tmp_path):
    panel = make_panel()
    with FastrakSimulator(silent=True) as silent:
        for port in (str(tmp_path / "ttyUSB9"), silent.path):
            out = tmp_path / "never.csv"
            panel.ports.set_port(port)
            panel.out_edit.setText(str(out))
            with qtbot.waitSignal(panel.stopped, timeout=TIMEOUT) as stopped:
                panel.connect_button.click()
            assert stopped.args == ["could not connect"]
            assert list(tmp_path.iterdir()) == [], port    # no header-only file, no lock


def test_after_a_crash_the_last_session_is_offered_for_resume(qtbot, make_panel, sim, tmp_path):
    """The app dies while recording: its recorder sees its input end and finishes with every
    point on disk; the next start offers that file, resume ticked, and goes on in it."""
    out = tmp_path / "field.csv"
    first = make_panel()
    _connect(qtbot, first, sim.path, out)
    _press(qtbot, first, sim, (1.0, 0.0, 0.0))
    _press(qtbot, first, sim, (3.0, 0.0, 0.0))
    first.timer.stop()                                     # the window is gone ...
    proc = first.digitizing._proc
    proc.stdin.close()                                     # ... as its pipes close with it
    proc.wait(TIMEOUT / 1000)
    assert proc.returncode == 0 and len(read_points(out)) == 2
    again = make_panel()                                   # the app starts again
    assert again.out_edit.text() == str(out) and again.resume.isChecked()
    assert again.band.state == "warn" and "did not end cleanly" in again.band.message.text()
    first.digitizing.release()
    with qtbot.waitSignal(again.started, timeout=TIMEOUT):
        again.connect_button.click()
    assert again.session.count.points == 2 and again.session.pos.col == 2
    _press(qtbot, again, sim, (5.0, 0.0, 0.0))
    with qtbot.waitSignal(again.stopped, timeout=TIMEOUT):
        again.stop_button.click()
    assert read_points(out).xyz[:, 0].tolist() == [1.0, 3.0, 5.0]
    assert not make_panel().resume.isChecked()            # stopped cleanly: nothing to offer
