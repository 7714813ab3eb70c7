"""Recording through a real pseudo-terminal and pyserial, against the simulator.

The recorder runs as a real process (``python -m maizeviz record``); the test plays the
technician: it presses the simulated stylus and types controls on the recorder's stdin.
"""

import os
import queue
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from maizeviz.digitizer.port import DeviceError, FastrakPort, PortLost
from maizeviz.digitizer.protocol import Record
from maizeviz.digitizer.replay import presses_of
from maizeviz.digitizer.session import Session, SessionError
from maizeviz.digitizer.simulator import FastrakSimulator
from maizeviz.io.points import read_points, write_points
from maizeviz.leaf.grid import LeafGrid, build_grids
from maizeviz.leaf.synth import LeafShape, leaf_points


class Recorder:
    """``maizeviz record`` in a subprocess, with its stdout lines in a queue."""

    def __init__(self, port, out, *extra, cols=3):
        width = [] if cols is None else ["--cols", str(cols)]
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "maizeviz", "record", "--port", port, "--out", str(out),
             *width, "--answer-timeout", "0.5", *map(str, extra)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
            bufsize=1)
        self.lines = queue.Queue()
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self):
        for line in self.proc.stdout:
            self.lines.put(line.rstrip("\n"))
        self.lines.put(None)

    def expect(self, prefix, timeout=10.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                line = self.lines.get(timeout=max(0.01, end - time.monotonic()))
            except queue.Empty:
                break
            if line is None:
                raise AssertionError(f"recorder ended while waiting for {prefix!r}: "
                                     f"{self.proc.stderr.read()}")
            if line.startswith(prefix):
                return line
        raise AssertionError(f"no line starting with {prefix!r} within {timeout} s")

    def type(self, text):
        self.proc.stdin.write(text + "\n")
        self.proc.stdin.flush()

    def finish(self, timeout=10):
        try:
            self.type("q")
        except (BrokenPipeError, OSError):
            pass
        out = self.proc.wait(timeout=timeout)
        return out, self.proc.stderr.read()


def small_plant(tmp_path, leaves=2):
    rng = np.random.default_rng(5)
    grids = [LeafGrid(1, k + 1, leaf_points(LeafShape(length=30 + 10 * k, base=(0, 0, 20 * k)),
                                            4, 3, noise=0.0, rng=rng), True) for k in range(leaves)]
    path = tmp_path / "plant.csv"
    write_points(path, grids)
    return path


def press(sim, point, **kw):
    while not sim.press(point, **kw):
        time.sleep(0.01)


def replay(sim, rec, path, start=0, stop=None, **kw):
    ids, xyz = presses_of(path)
    last = tuple(ids[start, :2]) if start else None
    for key, p in list(zip(ids, xyz))[start:stop]:
        leaf = tuple(key[:2])
        if last is not None and leaf != last:
            rec.type("n")
            rec.expect("next leaf")
        last = leaf
        press(sim, p, **kw)
        rec.expect("recorded")


@pytest.fixture
def sim():
    s = FastrakSimulator(press_gap_s=0.0)
    yield s
    s.close()


def test_replayed_plant_is_recorded_and_reconstructs(sim, tmp_path):
    src = small_plant(tmp_path)
    out = tmp_path / "rec.csv"
    rec = Recorder(sim.path, out)
    rec.expect("ready")
    replay(sim, rec, src)
    code, err = rec.finish()
    assert code == 0, err
    a, _ = build_grids(read_points(src))
    b, errors = build_grids(read_points(out))
    assert not errors and [g.key for g in b] == [g.key for g in a]
    for ga, gb in zip(a, b):
        assert np.abs(ga.points - gb.points).max() < 0.5          # 0.08 cm noise, 6 sigma
    from maizeviz.cli import main
    assert main(["leaf", str(out)]) == 0


def test_press_within_333_ms_is_not_invented(tmp_path):
    with FastrakSimulator() as sim:                                # the real 333 ms gap
        out = tmp_path / "rec.csv"
        rec = Recorder(sim.path, out)
        rec.expect("ready")
        assert sim.press([1, 2, 3])
        assert not sim.press([4, 5, 6])                             # 10 ms later: ignored
        rec.expect("recorded")
        time.sleep(0.4)
        assert sim.press([7, 8, 9])
        rec.expect("recorded")
        code, err = rec.finish()
    pts = read_points(out)
    assert len(pts) == 2 and pts.xyz[1] == pytest.approx([7, 8, 9], abs=0.5)


def test_garbled_truncated_and_bit_errors(sim, tmp_path):
    out = tmp_path / "rec.csv"
    rec = Recorder(sim.path, out)
    rec.expect("ready")
    press(sim, [1, 1, 1])
    rec.expect("recorded")
    sim.inject(b"\x00\xff\xfegarbage\r\n")
    sim.inject(b"01   12.34  -5\r\n")
    sim.set_error("x")
    press(sim, [2, 2, 2])
    line = rec.expect("refused")
    assert "motion box" in line
    sim.set_error("y")
    press(sim, [2, 2, 2])
    assert "angular envelope" in rec.expect("refused")
    sim.set_error(" ")
    press(sim, [3, 3, 3])
    rec.expect("recorded")
    code, _ = rec.finish()
    summary = [l for l in iter(rec.lines.get, None) if "points," in l][-1]
    assert code == 0
    assert "2 points" in summary and "2 refused" in summary and "2 garbled" in summary
    assert len(read_points(out)) == 2


def test_port_vanishing_mid_session(sim, tmp_path):
    out = tmp_path / "rec.csv"
    rec = Recorder(sim.path, out)
    rec.expect("ready")
    for p in ([1, 0, 0], [2, 0, 0], [3, 0, 0]):
        press(sim, p)
        rec.expect("recorded")
    sim.vanish()
    code = rec.proc.wait(timeout=10)
    err = rec.proc.stderr.read()
    assert code == 1 and "was lost (the device disconnected)" in err and "on disk (3)" in err
    assert "Traceback" not in err and err.count("\n") == 1
    assert len(read_points(out)) == 3


def test_kill_9_then_resume_loses_nothing(sim, tmp_path):
    src = small_plant(tmp_path)
    out = tmp_path / "rec.csv"
    rec = Recorder(sim.path, out)
    rec.expect("ready")
    ids, _ = presses_of(src)
    half = 6                                      # mid second leaf... first leaf has 4x3 - 2
    replay(sim, rec, src, 0, half)
    os.kill(rec.proc.pid, signal.SIGKILL)
    rec.proc.wait(timeout=10)
    assert len(read_points(out)) == half          # every reported point is on disk
    rec2 = Recorder(sim.path, out, "--resume")
    rec2.expect("ready")
    replay(sim, rec2, src, half)
    code, err = rec2.finish()
    assert code == 0, err
    assert "resuming" in err
    a, _ = build_grids(read_points(src))
    b, errors = build_grids(read_points(out))
    assert not errors and len(b) == len(a)
    assert all(np.abs(x.points - y.points).max() < 0.5 for x, y in zip(a, b))


def test_undo_is_recorded_not_rewritten(sim, tmp_path):
    out = tmp_path / "rec.csv"
    rec = Recorder(sim.path, out)
    rec.expect("ready")
    press(sim, [1, 1, 1])
    rec.expect("recorded")
    press(sim, [99, 99, 99])                       # a slip
    rec.expect("recorded plant 1 leaf 1 row 0 col 1")
    rec.type("u")
    assert "undone" in rec.expect("undone")
    press(sim, [2, 2, 2])
    rec.expect("recorded plant 1 leaf 1 row 0 col 1")
    rec.finish()
    text = out.read_text()
    assert "99.0" in text and ",undone," in text          # the slip is still in the file
    pts = read_points(out)
    assert len(pts) == 2 and pts.xyz[1] == pytest.approx([2, 2, 2], abs=0.5)


def test_end_row_and_next_plant_controls(sim, tmp_path):
    out = tmp_path / "rec.csv"
    rec = Recorder(sim.path, out)
    rec.expect("ready")
    press(sim, [0, 0, 0])
    rec.expect("recorded plant 1 leaf 1 row 0 col 0")
    rec.type("r")
    rec.expect("end row")
    press(sim, [1, 0, 0])
    rec.expect("recorded plant 1 leaf 1 row 1 col 0")
    rec.type("p")
    rec.expect("next plant")
    press(sim, [5, 0, 0])
    rec.expect("recorded plant 2 leaf 1 row 0 col 0")
    rec.type("zzz")
    assert "unknown control" in rec.expect("unknown control")
    rec.finish()


def _unwritable(tmp_path, kind):
    if kind == "full disk":
        return "/dev/full"                         # every write fails with ENOSPC
    if kind == "missing folder":
        return str(tmp_path / "missing" / "rec.csv")
    if kind == "under a file":
        (tmp_path / "afile").write_text("x")
        return str(tmp_path / "afile" / "rec.csv")
    d = tmp_path / "ro"
    d.mkdir()
    d.chmod(0o555)
    if os.access(d, os.W_OK):
        pytest.skip("running as root: permissions do not stop writes")
    return str(d / "rec.csv")


@pytest.mark.parametrize("kind", ["full disk", "missing folder", "under a file", "read-only"])
def test_unwritable_output_refused_before_first_point(tmp_path, kind):
    path = _unwritable(tmp_path, kind)
    with FastrakSimulator() as sim:
        proc = subprocess.run([sys.executable, "-m", "maizeviz", "record", "--port", sim.path,
                               "--out", path, "--cols", "3"],
                              capture_output=True, text=True, timeout=20)
        assert not any(c.startswith("e1,") for c in sim.commands), "device set up anyway"
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr and proc.stderr.count("\n") == 1
    assert any(w in proc.stderr for w in ("cannot write", "no such folder", "not a folder"))


def test_existing_file_needs_resume(sim, tmp_path):
    out = tmp_path / "rec.csv"
    out.write_text("plant,leaf,row,col,x,y,z\n1,1,0,0,1,2,3\n")
    proc = subprocess.run([sys.executable, "-m", "maizeviz", "record", "--port", sim.path,
                           "--out", str(out)], capture_output=True, text=True, timeout=20)
    assert proc.returncode == 1 and "not a maizeviz recording" in proc.stderr
    assert "record into another file" in proc.stderr
    assert out.read_text().count("\n") == 2


def test_silent_device_clear_message(tmp_path):
    with FastrakSimulator(silent=True) as sim:
        port = FastrakPort(sim.path, answer_timeout=0.2, retries=2)
        with pytest.raises(DeviceError, match="no answer from a FASTRAK.*DIP switches"):
            port.configure()
        port.close()


@pytest.mark.parametrize("kind", ["inches", "binary"])
def test_device_that_ignores_units_or_format(kind):
    opts = {"ignore_units": True} if kind == "inches" else {"start_binary": True,
                                                           "ignore_format": True}
    with FastrakSimulator(noise_cm=0.0, press_gap_s=0.0, **opts) as sim:
        port = FastrakPort(sim.path, answer_timeout=0.5)
        cfg = port.configure()
        assert any(kind in w for w in cfg.warnings)
        q = port.start_reader()
        sim.press([25.4, -10.0, 5.0])
        ev = q.get(timeout=5)
        port.close()
    assert isinstance(ev, Record)
    assert ev.position == pytest.approx([25.4, -10.0, 5.0], abs=0.02)


def test_reader_reports_a_vanished_port():
    with FastrakSimulator(press_gap_s=0.0) as sim:
        port = FastrakPort(sim.path, answer_timeout=0.5)
        port.configure()
        q = port.start_reader()
        sim.vanish()
        ev = q.get(timeout=5)
        port.close()
    assert isinstance(ev, PortLost) and "was lost" in ev.message and "plugged in" in ev.message


def test_motion_compensation_with_a_swaying_plant(tmp_path):
    rng = np.random.default_rng(2)
    plant_pts = rng.uniform(-40, 40, (9, 3))
    out = tmp_path / "rec.csv"
    with FastrakSimulator(stations=(1, 2), noise_cm=0.0, press_gap_s=0.0) as sim:
        rec = Recorder(sim.path, out, "--reference-station", "2")
        rec.expect("ready")
        for k, p in enumerate(plant_pts):
            sim.move_reference([10 + 5 * np.sin(k), -3 + 4 * np.cos(k), 2 * k],
                               [20 * np.sin(k), 8 * np.cos(k), 5 * k])
            press(sim, p, plant_frame=True)
            rec.expect("recorded")
        rec.finish()
    got = read_points(out).xyz
    # the simulator prints 0.01 cm and 0.01 deg steps; over 40 cm that is a few 0.01 cm
    assert np.abs(got - plant_pts).max() < 0.05


def test_session_resume_after_controls(tmp_path):
    out = tmp_path / "s.csv"
    s = Session(out, cols=2)
    rec = Record(1, " ", (1.0, 2.0, 3.0), (0, 0, 0), 1)
    s.on_event(rec)
    s.control("n")
    s.close()
    s2 = Session(out, cols=2, resume=True)
    assert (s2.pos.plant, s2.pos.leaf, s2.pos.row, s2.pos.col) == (1, 2, 0, 0)
    with pytest.raises(SessionError, match="already holds points"):
        Session(out, cols=2)
    bad = tmp_path / "bad.csv"
    bad.write_text("hello,world\n1,2\n")
    with pytest.raises(SessionError, match="cannot resume"):
        Session(bad, cols=2, resume=True)


def test_stylus_modes_and_continuous_output():
    """Point mode: a press acts like P; continuous: records stream at 120 Hz / stations and a
    press toggles the stream; mouse mode: the press shows only in the stylus item."""
    from maizeviz.digitizer import protocol as fp
    with FastrakSimulator(stations=(1, 2), noise_cm=0.0, press_gap_s=0.0) as sim:
        port = FastrakPort(sim.path, answer_timeout=0.5)
        port.configure((1, 2))
        q = port.start_reader()
        sim.press([1, 2, 3])
        got = [q.get(timeout=5), q.get(timeout=5)]
        assert [r.station for r in got] == [1, 2] and got[0].stylus == 1
        port._send(fp.START_CONTINUOUS)
        time.sleep(1.0)
        port._send(fp.STOP_CONTINUOUS)
        time.sleep(0.2)
        n = q.qsize()
        assert 10 <= n <= 140                       # at most 60 frames/s x 2 stations for 1 s
        while not q.empty():
            q.get()
        port._send(fp.stylus_mode(1, False))        # mouse mode
        time.sleep(0.1)
        sim.press([4, 5, 6])                         # no record in polled mouse mode
        time.sleep(0.3)
        assert q.empty()
        sim.press([4, 5, 6])
        port._send(fp.POLL)
        rec = q.get(timeout=5)
        assert rec.stylus == 1 and rec.position == pytest.approx([4, 5, 6], abs=0.02)
        port.close()


def test_reconnect_reopens_and_reconfigures():
    with FastrakSimulator(press_gap_s=0.0, noise_cm=0.0) as sim:
        port = FastrakPort(sim.path, answer_timeout=0.5)
        port.configure()
        sim.centimetres = False                     # as after a power cycle
        cfg = port.reconnect(attempts=2, wait=0.1)
        assert cfg.centimetres and sim.centimetres
        q = port.start_reader()
        sim.press([7, 8, 9])
        assert q.get(timeout=5).position == pytest.approx([7, 8, 9], abs=0.02)
        port.close()


# ------------------------------------------------------------------ the shape of a resumed session
def _record_then_kill(sim, out, presses, cols):
    rec = Recorder(sim.path, out, cols=cols)
    rec.expect("ready")
    for k in range(presses):
        press(sim, [k, 0, 0])
        rec.expect("recorded")
    os.kill(rec.proc.pid, signal.SIGKILL)
    rec.proc.wait(timeout=10)


def test_resume_without_cols_keeps_the_sessions_width(sim, tmp_path):
    out = tmp_path / "rec.csv"
    _record_then_kill(sim, out, 4, cols=3)           # row 0 whole, row 1 col 0
    rec = Recorder(sim.path, out, "--resume", cols=None)
    rec.expect("ready")
    for k in range(4, 7):
        press(sim, [k, 0, 0])
        rec.expect("recorded")
    code, err = rec.finish()
    assert code == 0, err
    assert "3 points per cross-section" in err
    table = read_points(out)
    rows_cols = [tuple(ids[2:]) for ids in table.ids.tolist()]
    # the data are the oracle: presses 4, 5, 6 finish row 1 and start row 2 of a 3-wide leaf
    assert rows_cols == [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2), (2, 0)]
    assert table.xyz[:, 0].round().tolist() == list(range(7))


def test_resume_with_contradicting_cols_is_one_line_and_writes_nothing(sim, tmp_path):
    out = tmp_path / "rec.csv"
    _record_then_kill(sim, out, 4, cols=3)
    before = out.read_bytes()
    rec = Recorder(sim.path, out, "--resume", cols=5)
    code = rec.proc.wait(timeout=20)
    err = rec.proc.stderr.read()
    errors = [ln for ln in err.splitlines() if ln.startswith(("error", "internal"))]
    assert code == 1 and len(errors) == 1, err
    assert "3 points per cross-section" in errors[0] and errors[0].endswith("(--cols)")
    assert out.read_bytes() == before


def test_resume_of_a_session_without_a_finished_row_needs_cols(sim, tmp_path):
    out = tmp_path / "rec.csv"
    _record_then_kill(sim, out, 2, cols=3)
    before = out.read_bytes()
    with pytest.raises(SessionError, match="give the points per cross-section") as err:
        Session(out, None, resume=True)
    assert err.value.quantity == "cols" and "\n" not in str(err.value)
    assert out.read_bytes() == before
    s = Session(out, 3, resume=True)                 # said once, it continues
    assert (s.pos.row, s.pos.col) == (0, 2)
    s.close()


def test_session_width_from_the_journal_after_undo_and_end_row(tmp_path):
    out = tmp_path / "rec.csv"
    s = Session(out, 4)
    for k in range(6):                               # row 0 whole, row 1 cols 0-1
        s.on_event(Record(1, " ", (float(k), 0.0, 0.0), (0, 0, 0), 1))
    s.control("u")
    s.control("r")                                   # row 1 ended early: one col
    s.on_event(Record(1, " ", (9.0, 0.0, 0.0), (0, 0, 0), 1))
    s.close()
    again = Session(out, None, resume=True)
    assert again.cols == 4 and (again.pos.row, again.pos.col) == (2, 1)
    again.close()
