"""``maizeviz record`` driven by a program (the app): events as JSON lines, the end of its input
as the end of the session, and a reader that stops reading never holds up the journal. A real
recorder process on a simulated FASTRAK (a real pty)."""

import json
import subprocess
import sys
import time

from maizeviz.digitizer.simulator import FastrakSimulator
from maizeviz.io.points import read_points


def _recorder(port, out, *more):
    return subprocess.Popen([sys.executable, "-m", "maizeviz", "record", "--port", port,
                             "--out", str(out), "--cols", "3", "--answer-timeout", "0.5",
                             "--events", "json", "--end-with-input", *more],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, bufsize=1)


def _points_on_disk(out, n, timeout=20.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if out.exists() and out.read_bytes().count(b",recorded,") >= n:
            return
        time.sleep(0.02)
    raise AssertionError(f"fewer than {n} points in {out}")


def test_events_are_json_lines_and_the_end_of_input_finishes(tmp_path):
    out = tmp_path / "s.csv"
    with FastrakSimulator(press_gap_s=0.0, noise_cm=0.0) as sim:
        proc = _recorder(sim.path, out, "--live", "0.05")
        ready = json.loads(proc.stdout.readline())
        assert ready["kind"] == "ready" and ready["cols"] == 3 and ready["points"] == 0
        assert sim.press((1.0, 2.0, 3.0))
        _points_on_disk(out, 1)
        time.sleep(0.3)                                   # a few live answers
        proc.stdin.close()                                # the driving program has gone
        assert proc.wait(20) == 0
        events = [json.loads(line) for line in proc.stdout]
    kinds = [e["kind"] for e in events]
    assert "recorded" in kinds and "live" in kinds and kinds[-1] == "summary"
    assert kinds.count("recorded") == 1 and "finished" in kinds
    live = next(e for e in events if e["kind"] == "live")
    assert len(live["xyz"]) == 3 and live["trustworthy"] is True
    assert events[-1]["points"] == 1 and read_points(out).xyz.tolist() == [[1.0, 2.0, 3.0]]


def test_a_reader_that_goes_away_does_not_stop_the_journal(tmp_path):
    """The app reading the events dies (its end of the pipe closes): the recorder goes on
    journaling every press, then finishes when its input ends."""
    out = tmp_path / "s.csv"
    with FastrakSimulator(press_gap_s=0.0, noise_cm=0.0) as sim:
        proc = _recorder(sim.path, out, "--live", "0.05")
        assert json.loads(proc.stdout.readline())["kind"] == "ready"
        proc.stdout.close()                               # nobody reads any more
        for k in range(5):
            assert sim.press((float(k), 0.0, 0.0))
            _points_on_disk(out, k + 1)
        proc.stdin.close()
        assert proc.wait(20) == 0
    assert read_points(out).xyz[:, 0].tolist() == [0.0, 1.0, 2.0, 3.0, 4.0]
