"""The recording journal: torn last lines, files that are not recordings, failed starts, the
lock, and a real full disk.

Where a user meets the case through ``maizeviz record``, the recorder runs as a real process
on a real pseudo-terminal against the FASTRAK simulator, as in test_fastrak_record.py.
"""

import errno
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from maizeviz.digitizer import session as session_mod
from maizeviz.digitizer.protocol import Record
from maizeviz.digitizer.replay import presses_of
from maizeviz.digitizer.session import HEADER, JournalInUse, Session, SessionError, lock_path
from maizeviz.digitizer.simulator import FastrakSimulator
from maizeviz.io.points import parse_points, read_points
from maizeviz.leaf.grid import build_grids
from tests.core.test_fastrak_record import Recorder, press, replay, small_plant


@pytest.fixture
def sim():
    s = FastrakSimulator(press_gap_s=0.0, noise_cm=0.0)
    yield s
    s.close()


def rec(x, y=2.0, z=3.0, error=" "):
    return Record(1, error, (float(x), float(y), float(z)), (0.0, 0.0, 0.0), 1)


def record_points(path, n, cols=2):
    """A recording of ``n`` points made by a Session, closed; returns its bytes."""
    with Session(path, cols=cols) as s:
        for k in range(n):
            assert s.on_event(rec(k + 0.5, 2.0, 22.18)).startswith("recorded")
    return Path(path).read_bytes()


def tear(data: bytes, how: str) -> bytes:
    """The recording cut as a crash or a full disk cuts it, in its last line."""
    body, last, _ = data.rsplit(b"\r\n", 2)
    body += b"\r\n"
    status = last.index(b",recorded")
    cut = {"inside z": status - 1,                      # ...,22.18 (z was 22.180)
           "after z": status,                            # ...,22.180 (the reported case)
           "inside status": status + 5,                  # ...,22.180,reco
           "inside ids": 3,                              # 1,1
           "no line end": len(last)}.get(how)
    if how == "CR without LF":
        return body + last + b"\r"
    return body + last[:cut]


TEARS = ["inside z", "after z", "inside status", "inside ids", "no line end", "CR without LF"]


# ----------------------------------------------------------------------- torn last lines
@pytest.mark.parametrize("how", TEARS)
def test_torn_last_line_marked_and_never_appended_to(tmp_path, how):
    out = tmp_path / "rec.csv"
    good = record_points(out, 5)
    torn = tear(good, how)
    out.write_bytes(torn)
    # read as it is: the torn line is skipped with a note, never taken for a point
    table = read_points(out)
    assert len(table) == 4 and any("line 6: cut short (no line end)" in p for p in table.problems)
    s = Session(out, cols=2, resume=True)
    assert s.count.points == 4
    assert (s.pos.row, s.pos.col) == (2, 0)                 # the torn point is pressed again
    assert len(s.messages) == 1
    msg = s.messages[0]
    assert "line 6 was cut short" in msg and "NOT recorded" in msg and "4 points are kept" in msg
    if how != "inside ids":
        assert "plant 1, leaf 1, row 2, col 0" in msg
    s.on_event(rec(9, 9, 9))
    s.close()
    data = out.read_bytes()
    assert data.startswith(torn)                            # nothing before it rewritten
    tail = data[len(torn):].split(b"\r\n")
    assert tail[0] == b"" and tail[1].startswith(b",,,,,,,discarded,")   # ended, then marked
    assert tail[2].startswith(b"1,1,2,0,9.000,9.000,9.000,recorded,")   # a clean new line
    table = read_points(out)
    assert len(table) == 5 and table.xyz[-1].tolist() == [9, 9, 9]
    assert table.xyz[:4, 0].tolist() == [0.5, 1.5, 2.5, 3.5]
    assert any("line 6: cut short by a crash or a full disk" in p for p in table.problems)
    # and a second resume finds a clean file
    with Session(out, cols=2, resume=True) as again:
        assert again.count.points == 5 and not again.messages


def test_complete_last_line_is_kept(tmp_path):
    out = tmp_path / "rec.csv"
    good = record_points(out, 5)
    with Session(out, cols=2, resume=True) as s:
        assert s.count.points == 5 and not s.messages
        s.on_event(rec(9))
    assert out.read_bytes().startswith(good) and b"discarded" not in out.read_bytes()
    assert len(read_points(out)) == 6


def test_blank_after_last_line_end_is_only_ended(tmp_path):
    out = tmp_path / "rec.csv"
    good = record_points(out, 3)
    out.write_bytes(good + b"\r")
    with Session(out, cols=2, resume=True) as s:
        assert s.count.points == 3 and not s.messages
        s.on_event(rec(9))
    assert b"discarded" not in out.read_bytes()
    assert len(read_points(out)) == 4


def test_torn_control_and_undo_lines(tmp_path):
    out = tmp_path / "rec.csv"
    with Session(out, cols=2) as s:
        s.on_event(rec(1))
        s.on_event(rec(2))
        s.control("n")
    data = out.read_bytes()
    out.write_bytes(data[:-12])                          # inside the control's time
    with Session(out, cols=2, resume=True) as s:
        assert (s.pos.leaf, s.pos.row, s.pos.col) == (1, 1, 0)     # the control never happened
        assert "'next_leaf' line was NOT recorded" in s.messages[0]
        s.on_event(rec(3))
        s.control("u")
    out.write_bytes(out.read_bytes()[:-5])               # the undo cut short: not undone
    with Session(out, cols=2, resume=True) as s:
        assert s.count.points == 3
    assert len(read_points(out)) == 3


def test_writes_cut_short_in_process_are_repaired_before_the_next(tmp_path, monkeypatch):
    """ENOSPC after part of a line: the session knows its file ends in a torn line, says the
    point was NOT recorded, and ends and marks that line before its next write."""
    out = tmp_path / "rec.csv"
    s = Session(out, cols=2)
    s.on_event(rec(1))
    real = os.write
    budget = {"bytes": 20}

    def short_write(fd, data):
        if budget["bytes"] is None:
            return real(fd, data)
        n = min(len(data), budget["bytes"])
        budget["bytes"] -= n
        if n == 0:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(fd, data[:n])

    monkeypatch.setattr(session_mod.os, "write", short_write)
    with pytest.raises(SessionError, match="NOT recorded; 1 points are safe"):
        s.on_event(rec(2))
    budget["bytes"] = 0
    with pytest.raises(SessionError, match="'next leaf' was NOT recorded"):
        s.control("n")
    assert (s.pos.leaf, s.pos.col) == (1, 1)             # a control that failed changed nothing
    with pytest.raises(SessionError, match="the undo was NOT recorded"):
        s.control("u")
    assert s.count.points == 1 and len(s.history) == 1
    budget["bytes"] = 3                                   # the repair itself cut short: "\r\n,"
    with pytest.raises(SessionError):
        s.on_event(rec(3))
    budget["bytes"] = None
    assert s.on_event(rec(4)).startswith("recorded plant 1 leaf 1 row 0 col 1")
    s.close()
    table = read_points(out)
    assert table.xyz[:, 0].tolist() == [1, 4]
    lines = out.read_bytes().split(b"\r\n")
    assert lines[2].startswith(b"1,1,0,1,2.000,2.0") and len(lines[2]) == 20   # the torn one
    assert lines[3] == b"," and lines[4].startswith(b",,,,,,,discarded,")
    with Session(out, cols=2, resume=True) as again:
        assert again.count.points == 2 and not again.messages


def test_repair_cut_after_its_line_end_still_marks_the_torn_line():
    """A recorder killed between ending a torn line and marking it (the rarest double
    fault): readers see an unfinished mark and still skip the torn line."""
    head = ",".join(session_mod.COLUMNS) + "\r\n"
    ok = "1,1,0,0,1.000,2.000,3.000,recorded,1.0,1,\r\n"
    torn = "1,1,0,1,2.000,2.000,3.000,recorded,2.0,1,\r\n"      # complete-looking once ended
    t = parse_points(head + ok + torn + ",,,,,,,disc")
    assert len(t) == 1 and "line 3: cut short" in t.problems[0]
    t = parse_points(head + ok + torn + ",,,,,,,disc\r\n,,,,,,,discarded,3.0,,\r\n" + ok)
    assert len(t) == 2 and any("line 3: cut short" in p for p in t.problems)


# ----------------------------------------------------------------------- the reported case
def test_reported_disk_full_case_through_the_recorder(sim, tmp_path):
    """After a full disk the file ended '...,22.180' without a line end; resume counted the
    torn point, the next press ran into it and 'leaf' gave +48% area. Now the torn point is
    not counted, the next press starts a clean line and the leaves match the plant."""
    src = small_plant(tmp_path)
    out = tmp_path / "rec.csv"
    r = Recorder(sim.path, out)
    r.expect("ready")
    half = 14                                            # the 4th point of leaf 2
    replay(sim, r, src, 0, half)
    r.finish()
    out.write_bytes(tear(out.read_bytes(), "after z"))   # the disk filled inside the last line
    r2 = Recorder(sim.path, out, "--resume")
    r2.expect("ready")
    replay(sim, r2, src, half - 1)                       # the torn point is pressed again
    code, err = r2.finish()
    assert code == 0, err
    assert f"resuming {out}: {half - 1} points on disk" in err
    ids, _ = presses_of(src)
    row, col = ids[half - 1, 2:]
    assert f"next point is plant 1 leaf 2 row {row} col {col}" in err
    a, _ = build_grids(read_points(src))
    table = read_points(out)
    b, errors = build_grids(table)
    assert not errors and [g.key for g in b] == [g.key for g in a]
    for ga, gb in zip(a, b):
        assert ga.shape == gb.shape and np.abs(ga.points - gb.points).max() < 0.05
    assert any("cut short by a crash or a full disk" in p for p in table.problems)
    from maizeviz.cli import main
    assert main(["leaf", str(out), "--json"]) == 0


# -------------------------------------------------------------- files that are not recordings
PLAIN = "plant,leaf,row,col,x,y,z\n1,1,0,0,1,2,3\n1,1,0,1,2,2,3\n"


@pytest.mark.parametrize("content, says", [
    (PLAIN, "its header is 'plant,leaf,row,col,x,y,z'"),
    ("plant,leaf,row,col,x,y,z,status\n1,1,0,0,1,2,3,recorded\n", "its header is"),
    ("z,y,x,col,row,leaf,plant,status,time,station,error\n", "its header is"),
    ("hello,world\n1,2\n", "missing column"),
    ("\x89PNG\r\n\x1a\n\x00\x00", "binary"),
])
def test_resume_refuses_what_is_not_a_recording(tmp_path, content, says):
    out = tmp_path / "f.csv"
    out.write_bytes(content.encode("latin-1"))
    with pytest.raises(SessionError, match="cannot resume") as exc:
        Session(out, cols=3, resume=True)
    assert says in str(exc.value) and "not a maizeviz recording" in str(exc.value)
    assert "\n" not in str(exc.value)
    assert out.read_bytes() == content.encode("latin-1")
    assert not lock_path(out).exists()


def test_resume_on_a_plain_points_file_through_the_recorder(sim, tmp_path):
    out = tmp_path / "plain.csv"
    out.write_text(PLAIN)
    proc = subprocess.run([sys.executable, "-m", "maizeviz", "record", "--port", sim.path,
                           "--out", str(out), "--resume"], capture_output=True, text=True,
                          timeout=30)
    assert proc.returncode == 1 and proc.stderr.count("\n") == 1
    assert "not a maizeviz recording" in proc.stderr and "Traceback" not in proc.stderr
    assert out.read_text() == PLAIN
    assert not any(c.startswith("e1,") for c in sim.commands)     # the device was not set up
    t = read_points(out)
    assert len(t) == 2                                  # no leaf spoiled, no phantom one


@pytest.mark.parametrize("kind", ["FIFO", "character device", "folder"])
def test_recording_must_be_a_regular_file(tmp_path, kind):
    path = {"FIFO": tmp_path / "fifo", "character device": Path("/dev/zero"),
            "folder": tmp_path}[kind]
    if kind == "FIFO":
        os.mkfifo(path)
    for resume in (False, True):
        with pytest.raises(SessionError, match="folder" if kind == "folder" else kind):
            Session(path, cols=3, resume=resume)


# ----------------------------------------------------------------------- failed starts
@pytest.mark.parametrize("content", [HEADER, HEADER[:-2] + b"\n", HEADER[:20], b"",
                                     b"\r\n", HEADER[:-1]])
@pytest.mark.parametrize("resume", [False, True])
def test_header_only_file_of_a_failed_start_is_reused(tmp_path, content, resume):
    out = tmp_path / "rec.csv"
    out.write_bytes(content)
    with Session(out, cols=2, resume=resume) as s:
        assert s.count.points == 0 and not s.messages
        s.on_event(rec(1))
    data = out.read_bytes()
    assert data.count(b"plant,leaf") == 1 and data.startswith(HEADER[:-2])
    assert read_points(out).xyz.tolist() == [[1, 2, 3]]


def test_journal_without_points_is_not_said_to_hold_points(tmp_path):
    out = tmp_path / "rec.csv"
    with Session(out, cols=2) as s:
        s.control("n")
        s.on_event(rec(1))
        s.control("u")
    with Session(out, cols=2) as s:                    # nothing recorded: a new session
        assert (s.pos.plant, s.pos.leaf) == (1, 1)
        s.on_event(rec(2))
    with pytest.raises(SessionError, match=r"already holds points \(1 recorded\)"):
        Session(out, cols=2)
    assert read_points(out).xyz[:, 0].tolist() == [2]


def test_wrong_port_then_right_port_without_resume(sim, tmp_path):
    out = tmp_path / "rec.csv"
    bad = subprocess.run([sys.executable, "-m", "maizeviz", "record", "--port",
                          str(tmp_path / "no-such-port"), "--out", str(out), "--cols", "3"],
                         capture_output=True, text=True, timeout=30)
    assert bad.returncode == 1 and "no serial port" in bad.stderr
    assert not out.exists()                             # a failed start leaves no file
    assert not lock_path(out).exists()
    r = Recorder(sim.path, out)                          # no --resume, no fight
    r.expect("ready")
    press(sim, [1, 2, 3])
    r.expect("recorded plant 1 leaf 1 row 0 col 0")
    code, err = r.finish()
    assert code == 0 and "already holds" not in err
    assert read_points(out).xyz.tolist() == [[1, 2, 3]]


# --------------------------------------------------------------------------------- the lock
def test_second_recorder_is_kept_off_and_told_the_pid(sim, tmp_path):
    out = tmp_path / "rec.csv"
    first = Recorder(sim.path, out)
    first.expect("ready")
    press(sim, [1, 2, 3])
    first.expect("recorded")
    assert lock_path(out).read_text().strip() == str(first.proc.pid)
    second = subprocess.run([sys.executable, "-m", "maizeviz", "record", "--port", sim.path,
                             "--out", str(out), "--resume"], capture_output=True, text=True,
                            timeout=30)
    assert second.returncode == 1 and second.stderr.count("\n") == 1
    assert f"pid {first.proc.pid}" in second.stderr and "another recorder" in second.stderr
    press(sim, [4, 5, 6])                                 # the first goes on undisturbed
    first.expect("recorded plant 1 leaf 1 row 0 col 1")
    code, _ = first.finish()
    assert code == 0 and not lock_path(out).exists()
    assert len(read_points(out)) == 2 and out.read_text().count("\n") == 3


def test_lock_of_a_killed_recorder_is_no_obstacle(sim, tmp_path):
    out = tmp_path / "rec.csv"
    first = Recorder(sim.path, out)
    first.expect("ready")
    press(sim, [1, 2, 3])
    first.expect("recorded")
    os.kill(first.proc.pid, signal.SIGKILL)
    first.proc.wait(timeout=10)
    assert lock_path(out).exists()                        # stale, but the kernel let go
    second = Recorder(sim.path, out, "--resume")
    second.expect("ready")
    assert lock_path(out).read_text().strip() == str(second.proc.pid)
    press(sim, [4, 5, 6])
    second.expect("recorded plant 1 leaf 1 row 0 col 1")
    assert second.finish()[0] == 0
    assert len(read_points(out)) == 2


def test_lock_within_one_process(tmp_path):
    out = tmp_path / "rec.csv"
    with Session(out, cols=2) as s:
        s.on_event(rec(1))
        with pytest.raises(JournalInUse, match=f"this program \\(pid {os.getpid()}\\)") as exc:
            Session(out, cols=2, resume=True)
        assert exc.value.pid == os.getpid()
    with Session(out, cols=2, resume=True) as s:          # let go at close
        assert s.count.points == 1


# ------------------------------------------------------------------------ a real full disk
@pytest.fixture
def small_disk(tmp_path):
    """A 2 MiB tmpfs (a recording needs 1 MiB free to start), unmounted afterwards."""
    where = tmp_path / "disk"
    where.mkdir()
    if os.geteuid() != 0 or not shutil.which("mount"):
        pytest.skip("mounting a small tmpfs needs root; the full disk is tested in-process")
    proc = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(where)],
                          capture_output=True, text=True)
    if proc.returncode != 0:
        pytest.skip(f"this machine does not allow mounting a tmpfs ({proc.stderr.strip()})")
    yield where
    subprocess.run(["umount", "-l", str(where)], capture_output=True)


def fill(disk: Path) -> Path:
    """Take every free byte of the disk; returns the filler file."""
    filler = disk / "filler"
    fd = os.open(filler, os.O_WRONLY | os.O_CREAT)
    try:
        for size in (1 << 16, 1):
            try:
                while True:
                    os.write(fd, b"\0" * size)
            except OSError as exc:
                assert exc.errno == errno.ENOSPC
    finally:
        os.close(fd)
    return filler


def test_real_full_disk_then_resume(sim, small_disk):
    out = small_disk / "rec.csv"
    r = Recorder(sim.path, out, cols=3)
    r.expect("ready")
    for k in range(4):
        press(sim, [10.0 + k, 20.0, 22.18])
        r.expect("recorded")
    line = len(out.read_bytes().split(b"\r\n")[-2]) + 2
    if (4096 - out.stat().st_size % 4096) % line == 0:   # the page would end on a line end
        r.type("r")
        r.expect("end row")
    filler = fill(small_disk)
    said = []
    for k in range(200):                                # until the page of the file is full
        press(sim, [30.0 + k, 20.0, 22.18])
        got = r.lines.get(timeout=10)
        if got is None or "points," in got:           # the recorder stopped: its summary
            break
        said.append(got)
    code = r.proc.wait(timeout=10)
    err = r.proc.stderr.read()
    assert code == 1 and "No space left on device" in err and "NOT recorded" in err
    assert "Traceback" not in err
    recorded = sum(1 for s in said if s.startswith("recorded"))
    assert f"{4 + recorded} points are safe on disk" in err
    data = out.read_bytes()
    assert not data.endswith(b"\n")                      # a torn line, as the full disk left it
    assert len(read_points(out)) == 4 + recorded         # every point reported is on disk
    # still full: resuming is refused before anything is written
    proc = subprocess.run([sys.executable, "-m", "maizeviz", "record", "--port", sim.path,
                           "--out", str(out), "--resume"], capture_output=True, text=True,
                          timeout=30)
    assert proc.returncode == 1 and "free some space" in proc.stderr
    assert out.read_bytes() == data
    filler.unlink()
    with Session(out, cols=3, resume=True) as s:
        assert s.count.points == 4 + recorded
        assert "was NOT recorded" in s.messages[0]
        assert s.on_event(rec(99)).startswith("recorded")
    assert out.read_bytes().startswith(data)
    table = read_points(out)
    assert len(table) == 5 + recorded and table.xyz[-1, 0] == 99
    assert np.all(table.xyz[:-1, 2] == 22.18)           # no z ran into the next press


# ------------------------------------------------------------------ reading what it left
def test_reader_skips_lines_run_together_by_the_old_recorder():
    head = ",".join(session_mod.COLUMNS) + "\r\n"
    ok = "1,1,0,0,1.000,2.000,3.000,recorded,1.0,1,\r\n"
    merged = "1,1,0,1,2.000,2.000,22.1801,1,0,1,5.000,2.000,3.000,recorded,2.0,1,\r\n"
    t = parse_points(head + ok + merged)
    assert len(t) == 1 and "line 3: 17 fields where a recording line has 11" in t.problems[0]


def test_reader_refuses_special_files_at_once(tmp_path):
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    sock_path = tmp_path / "s.sock"
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(sock_path))
    try:
        for path, kind in [(fifo, "a FIFO"), ("/dev/zero", "a character device"),
                           (sock_path, "a socket")]:
            t0 = time.monotonic()
            proc = subprocess.run([sys.executable, "-m", "maizeviz", "leaf", str(path)],
                                  capture_output=True, text=True, timeout=60)
            assert proc.returncode == 1 and proc.stderr.count("\n") == 1, proc.stderr
            assert f"{path}: is {kind}" in proc.stderr and "not a regular file" in proc.stderr
            assert time.monotonic() - t0 < 30
    finally:
        sock.close()


def test_hand_made_status_file_keeps_its_last_line_without_line_end():
    """Only a recording (its exact header) has torn lines; a file made by hand with a status
    column and no final line end keeps its last point, as before."""
    t = parse_points("plant,leaf,row,col,x,y,z,status\n1,1,0,0,1,2,3,\n1,1,0,1,2,2,3,ok")
    assert len(t) == 2 and not t.problems
