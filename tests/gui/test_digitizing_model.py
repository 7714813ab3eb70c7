"""The digitizing session without a window (issue 37: the session and its recorder owned by a
Qt-free object the panel binds to): a script drives it from the study model, the recorder in
its own process on a simulated FASTRAK (a real pty)."""

import subprocess
import sys
import time

from maizeviz.digitizer.simulator import FastrakSimulator
from maizeviz.io.points import read_points


def _until(session, check, timeout=20.0):
    """Poll as the panel's timer does until ``check(updates so far)``; returns the updates."""
    seen = []
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        seen += session.poll()
        if check(seen):
            return seen
        time.sleep(0.02)
    raise AssertionError(f"not reached; updates: {[(u.kind, u.message) for u in seen]}")


def test_the_session_is_qt_free():
    code = ("import sys; import maizeviz_app.digitizing, maizeviz_app.model; "
            "print(sorted(m for m in sys.modules if m.startswith(('PySide', 'pyvista'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"


def test_a_script_records_through_the_models_session(tmp_path):
    from maizeviz_app.model import StudyModel

    d = StudyModel(1).digitizing
    out = tmp_path / "s.csv"
    with FastrakSimulator(press_gap_s=0.0, noise_cm=0.0) as sim:
        d.start(sim.path, out, cols=2)
        assert d.state == "connecting"
        _until(d, lambda u: any(x.kind == "started" for x in u))
        assert d.state == "recording" and d.recording
        for x in (1.0, 3.0, 1.0):
            assert sim.press((x, 0.0, 0.0))
            n = d.count.points
            _until(d, lambda u, n=n: d.count.points > n)
        assert (d.pos.row, d.pos.col) == (1, 1)
        d.control("u")
        _until(d, lambda u: d.count.points == 2 and d.count.undone == 1)
        d.control("n")
        _until(d, lambda u: d.pos.leaf == 2)
        d.stop()
        updates = _until(d, lambda u: d.final is not None)
    assert d.final.kind == "finished" and updates[-1] is d.final
    d.release()
    assert d.state == "idle" and d._proc is None
    assert "2 points, 1 leaf, 1 plant" in d.summary() and "1 undone" in d.summary()
    assert read_points(out).xyz[:, 0].tolist() == [1.0, 3.0]
