"""Inputs that are not regular files are refused at once, never read forever."""

import os
import threading

import pytest

from maizeviz.cli import EXIT_FAIL, main
from maizeviz.errors import MaizevizError
from maizeviz.io.inputs import read_input


def test_regular_file_read_within_its_limit(tmp_path):
    p = tmp_path / "a.json"
    p.write_bytes(b"x" * 100)
    assert read_input(p, "layout file", 100) == b"x" * 100
    with pytest.raises(MaizevizError, match="more than the 99 bytes limit for a layout file"):
        read_input(p, "layout file", 99)


@pytest.mark.parametrize("make, says", [
    (lambda p: os.mkfifo(p), "is a FIFO (named pipe), not a regular file"),
    (lambda p: p.mkdir(), "is a folder, not a layout file"),
    (lambda p: None, "no such layout file"),
])
def test_pipes_folders_and_missing_files_are_refused_at_once(tmp_path, make, says):
    p = tmp_path / "x.json"
    make(p)
    done = []
    t = threading.Thread(target=lambda: done.append(_refusal(p)), daemon=True)
    t.start()
    t.join(10)
    assert done and says in done[0], "reading must not block on a pipe"


def _refusal(p):
    try:
        read_input(p, "layout file", 1000)
    except MaizevizError as exc:
        return str(exc)
    return "read"


def test_a_character_device_is_refused():
    with pytest.raises(MaizevizError, match="is a character device"):
        read_input("/dev/zero", "weather file", 10)


@pytest.mark.parametrize("argv", [
    ["canopy", "POINTS", "--layout", "FIFO"],
    ["import-phenomenal", "FIFO", "--out", "OUT"],
    ["light", "POINTS", "--layout", "FIFO", "--sun-zenith", "10", "--sun-azimuth", "0"],
])
def test_cli_refuses_a_pipe_in_one_line(capsys, tmp_path, argv):
    from maizeviz.resources import example_points

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    args = [str(fifo) if a == "FIFO" else str(example_points()) if a == "POINTS"
            else str(tmp_path / "o.csv") if a == "OUT" else a for a in argv]
    assert main(args) == EXIT_FAIL
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("error")]
    assert len(err) == 1 and "FIFO (named pipe)" in err[0]
