"""Every way a serial port can fail, through a real pseudo-terminal and pyserial: the driver's
error names the case (``kind``) and says the likely fix in one line, and ``maizeviz record``
prints that same line."""

import os
import subprocess
import sys
import time

import pytest

from maizeviz.digitizer.detect import detect, probe
from maizeviz.digitizer.port import FastrakPort
from maizeviz.digitizer.port_problems import DeviceError, holders
from maizeviz.digitizer.ports import list_serial_ports
from maizeviz.digitizer.recorder import Recorder
from maizeviz.digitizer.session import Session
from maizeviz.digitizer.simulator import FastrakSimulator
from maizeviz.io.points import read_points


def _record_cli(port, out, timeout=30):
    """``maizeviz record`` in a new process."""
    return subprocess.run([sys.executable, "-m", "maizeviz", "record", "--port", port, "--out",
                           str(out), "--cols", "3", "--answer-timeout", "0.3"],
                          capture_output=True, text=True, timeout=timeout)


def _one_line_error(proc):
    assert proc.returncode == 1, proc.stderr
    assert "Traceback" not in proc.stderr and proc.stderr.count("\n") == 1, proc.stderr
    return proc.stderr


def _kind_of(port, **kw):
    with pytest.raises(DeviceError) as err:
        dev = FastrakPort(port, answer_timeout=0.3, retries=1, **kw)
        try:
            dev.configure()
        finally:
            dev.close()
    return err.value


def test_no_such_port_names_the_ports_present(tmp_path):
    err = _kind_of(str(tmp_path / "ttyUSB9"))
    assert err.kind == "missing"
    text = str(err)
    assert text.startswith(f"no serial port {tmp_path / 'ttyUSB9'}: nothing is plugged in")
    assert "plugged in?" in text
    present = [p.device for p in list_serial_ports()]
    assert all(d in text for d in present[:6])
    assert ("No serial port is present" in text) == (not present)
    # the command line says the same line, and leaves no recording behind it
    proc = _record_cli(str(tmp_path / "ttyUSB9"), tmp_path / "rec.csv")
    assert f"no serial port {tmp_path / 'ttyUSB9'}: nothing is plugged in" in _one_line_error(proc)


@pytest.mark.parametrize("what", ["a regular file", "a folder"])
def test_a_file_or_folder_is_not_a_serial_port(tmp_path, what):
    path = tmp_path / "notaport"
    if what == "a folder":
        path.mkdir()
    else:
        path.write_text("hello\n")
    err = _kind_of(str(path))
    assert err.kind == "not_serial" and f"{path} is not a serial port ({what})" in str(err)
    if what == "a regular file":
        assert path.read_text() == "hello\n"              # nothing written into it


def test_permission_denied_names_the_group_and_the_fix(tmp_path):
    """A pty whose permissions refuse (owned by root:dialout, 0660, like a USB adapter): as
    a user outside that group the port cannot be opened and the message says how to join."""
    import grp
    import pwd

    with FastrakSimulator() as sim:
        try:
            group = grp.getgrnam("dialout")
        except KeyError:
            group = grp.getgrgid(os.stat(sim.path).st_gid)
        if os.geteuid() == 0:
            # root opens anything: open it as an unprivileged user for a moment (the effective
            # ids only, so they can be taken back; nothing else runs meanwhile)
            user = pwd.getpwnam("nobody")
            os.chown(sim.path, 0, group.gr_gid)
            os.chmod(sim.path, 0o660)
            groups = os.getgroups()
            os.setgroups([])
            os.setegid(user.pw_gid)
            os.seteuid(user.pw_uid)
            try:
                err = _kind_of(sim.path)
            finally:
                os.seteuid(0)
                os.setegid(0)
                os.setgroups(groups)
            text, name = str(err), user.pw_name
        else:
            if group.gr_gid in os.getgroups():
                pytest.skip(f"this user is in {group.gr_name}: the port would open")
            os.chmod(sim.path, 0o000)
            err = _kind_of(sim.path)
            name = pwd.getpwuid(os.geteuid()).pw_name
            # the command line says the same line
            proc = _record_cli(sim.path, tmp_path / "rec.csv")
            text = _one_line_error(proc)
            assert str(err) in text
        assert err.kind == "denied"
        assert not any(c.startswith("e1,") for c in sim.commands)     # nothing reached it
    assert f"permission denied on {sim.path}" in text
    assert f"group '{group.gr_name}'" in text and f"your user {name} is not in" in text
    assert f"sudo usermod -aG {group.gr_name} {name}" in text and "log out and back in" in text


def test_a_port_held_by_another_recorder_is_busy_and_says_by_whom(tmp_path):
    with FastrakSimulator() as sim:
        first = FastrakPort(sim.path, answer_timeout=0.3)
        first.configure()
        try:
            err = _kind_of(sim.path)
            assert err.kind == "busy"
            assert f"{sim.path} is busy: this program already has it open" in str(err)
            # another process: the command line names this one by its pid
            proc = _record_cli(sim.path, tmp_path / "rec.csv")
            text = _one_line_error(proc)
            assert f"{sim.path} is busy:" in text and f"(pid {os.getpid()}) has it open" in text
            assert os.getpid() in [pid for pid, _ in holders(sim.path)]
        finally:
            first.close()
        # once let go, the port opens
        second = FastrakPort(sim.path, answer_timeout=0.3)
        assert second.configure().centimetres
        second.close()


def test_a_silent_device(tmp_path):
    with FastrakSimulator(silent=True) as sim:
        err = _kind_of(sim.path)
        assert err.kind == "silent" and err.quantity == "baud"
        assert f"no answer from a FASTRAK on {sim.path} at 115200 baud" in str(err)
        assert "switched on" in str(err) and "DIP switches" in str(err)
        proc = _record_cli(sim.path, tmp_path / "rec.csv")
        assert "no answer from a FASTRAK" in _one_line_error(proc)


def test_a_device_that_answers_garbage_is_not_a_fastrak(tmp_path):
    with FastrakSimulator(garbage=True) as sim:
        err = _kind_of(sim.path)
        assert err.kind == "not_fastrak"
        text = str(err)
        assert f"something answers on {sim.path}, but not as a FASTRAK does" in text
        assert "the baud rate (115200) differs" in text and "\n" not in text
        proc = _record_cli(sim.path, tmp_path / "rec.csv")
        assert "not as a FASTRAK does" in _one_line_error(proc)


def test_a_port_that_vanishes_mid_session_loses_nothing_recorded(tmp_path):
    out = tmp_path / "rec.csv"
    with FastrakSimulator(press_gap_s=0.0, noise_cm=0.0) as sim:
        port = FastrakPort(sim.path, answer_timeout=0.3)
        port.configure()
        rec = Recorder(Session(out, 3), port)
        rec.start(live_every=0.05)
        updates = []
        for k in range(5):
            assert sim.press((float(k), 1.0, 2.0))
            deadline = time.monotonic() + 5
            while rec.session.count.points <= k and time.monotonic() < deadline:
                updates += rec.poll(timeout=0.1)
        sim.vanish()
        deadline = time.monotonic() + 5
        while not rec.finished and time.monotonic() < deadline:
            updates += rec.poll(timeout=0.1)
        rec.close()
    assert rec.final is not None and rec.final.kind == "lost" and rec.final.code == 1
    assert f"the connection to {sim.path} was lost" in rec.final.message
    assert "on disk (5)" in rec.final.message
    assert [u.kind for u in updates].count("recorded") == 5
    assert read_points(out).xyz[:, 0].tolist() == [0, 1, 2, 3, 4]


def test_list_serial_ports_is_pyserials_list_likely_ones_first():
    from serial.tools import list_ports

    ports = list_serial_ports()
    assert sorted(p.device for p in ports) == sorted(p.device for p in list_ports.comports())
    ranks = [(not p.polhemus, not p.usb) for p in ports]
    assert ranks == sorted(ranks)


def test_detect_finds_the_fastrak_among_other_ports(tmp_path):
    with FastrakSimulator() as good, FastrakSimulator(silent=True) as silent, \
            FastrakSimulator(garbage=True) as other:
        missing = str(tmp_path / "ttyUSB7")
        seen = []
        t0 = time.monotonic()
        found = detect([silent.path, missing, other.path, good.path, good.path], timeout=0.3,
                       progress=seen.append)
        took = time.monotonic() - t0
        assert [p.port for p in found] == [silent.path, missing, other.path, good.path]
        assert seen == found
        assert [p.kind for p in found] == ["silent", "missing", "not_fastrak", "fastrak"]
        assert [p.found for p in found] == [False, False, False, True]
        assert "a FASTRAK answers on" in found[-1].message
        # the probe asked for the status and nothing else: the unit is left as it was
        assert good.commands == ["c", "S"] and not good.centimetres
        assert took < 3.0
        # a probe lets go of the port: the recorder can open it at once
        dev = FastrakPort(good.path, answer_timeout=0.3)
        dev.configure()
        dev.close()
    assert probe(missing).kind == "missing"
