"""Threads end with their window (issue 35, item 4): the warm-up thread, the thread starting
the core processes, the digitizer's recorder process, its pipe readers and the Demo's
simulator are all over when ``close()`` returns, so nothing touches Qt or imports after the
window is gone (a thread importing C extensions during interpreter shutdown is a candidate for
the segfaults without a Python frame)."""

import os
import subprocess
import sys
import textwrap
import threading

from PySide6.QtCore import QThreadPool

from maizeviz.resources import example_points

TIMEOUT = 120_000
#: Threads the window or its digitizer start.
OURS = ("maizeviz-warm-up", "maizeviz-processes", "recorder-", "fastrak-")

SCRIPT = textwrap.dedent("""
    import sys, threading, time
    OURS = tuple(sys.argv[3].split(","))
    from PySide6.QtWidgets import QApplication
    app = QApplication([])
    from maizeviz_app.main import gl_format
    gl_format()
    from maizeviz_app.main_window import MainWindow
    w = MainWindow(sys.argv[1], 1)
    w.confirm_unsaved = False
    w.show()
    end = time.monotonic() + float(sys.argv[2])
    while time.monotonic() < end:
        app.processEvents()
        time.sleep(0.005)
    w.close()
    left = [t.name for t in threading.enumerate() if t.name.startswith(OURS)]
    print("left:", left, flush=True)
""")


def _ours():
    return [t.name for t in threading.enumerate() if t.name.startswith(OURS) and t.is_alive()]


def test_close_right_after_start_leaves_no_thread(window, qtbot, capfd):
    """In this process (modules already imported after the first window) and in fresh
    processes (the warm-up still importing when the window closes)."""
    for delay in (0, 50, 150, 300, 600):
        w = window(wait_ready=False)
        qtbot.wait(delay)
        w.close()
        assert _ours() == [] and getattr(w, "_threads", []) == []
    assert QThreadPool.globalInstance().waitForDone(10_000)
    err = capfd.readouterr().err
    assert "RuntimeError" not in err and "Traceback" not in err, err
    env = dict(os.environ, QT_API="pyside6")
    for delay in ("0.05", "0.3", "1.0"):
        run = subprocess.run([sys.executable, "-c", SCRIPT, str(example_points()), delay,
                              ",".join(OURS)],
                             capture_output=True, text=True, timeout=120, env=env)
        assert run.returncode == 0, run.stderr[-2000:]
        assert "left: []" in run.stdout, (run.stdout, run.stderr[-2000:])
        assert "Traceback" not in run.stderr and "RuntimeError" not in run.stderr, run.stderr


def test_closing_while_the_demo_records_ends_the_recorder(window, qtbot, tmp_path):
    """The window closes during a Demo: the recorder's process has ended (its journal whole),
    and no pipe reader, replay or simulator thread is left."""
    from maizeviz.io.points import read_points

    w = window()
    d = w.digitizer
    d.confirm_close = False
    d.demo_pace = 0.35
    out = tmp_path / "demo.csv"
    d.out_edit.setText(str(out))
    with qtbot.waitSignal(d.started, timeout=TIMEOUT):
        d.demo_button.click()
    qtbot.waitUntil(lambda: d.digitizing.count.points >= 2, timeout=TIMEOUT)
    proc = d.digitizing._proc
    w.close()
    assert proc.poll() is not None                        # ended, not orphaned
    assert _ours() == [] and d.digitizing.sim is None
    n = len(read_points(out))
    assert n >= 2 and d.digitizing.count.points <= n      # all shown is on disk
