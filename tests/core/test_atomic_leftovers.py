"""Temporary files of atomic writes: a writer killed with SIGKILL leaves one; the next write of
the same target removes it, and never a live writer's."""

import os
import signal
import subprocess
import sys
from pathlib import Path

from maizeviz.io.atomic import remove_leftovers, temp_leftovers, write_text

WRITER = """
import sys, time
from maizeviz.io.atomic import atomic_open
with atomic_open(sys.argv[1], "wb") as fh:
    fh.write(b"x" * (4 << 20))
    fh.flush()
    print("writing", flush=True)
    time.sleep(600)
"""


def _start_writer(target: Path) -> subprocess.Popen:
    proc = subprocess.Popen([sys.executable, "-c", WRITER, str(target)],
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None
    assert proc.stdout.readline().strip() == "writing"
    return proc


def _parts(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if ".part" in p.name)


def test_a_killed_writers_part_file_is_removed_by_the_next_write(tmp_path):
    target = tmp_path / "table.csv"
    write_text(target, "old\n")
    proc = _start_writer(target)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(timeout=30)
    left = _parts(tmp_path)
    assert len(left) == 1 and left[0].stat().st_size == 4 << 20    # what kill -9 leaves
    assert target.read_text() == "old\n"                           # the old file intact
    assert temp_leftovers(target) == left
    write_text(target, "new\n")
    assert _parts(tmp_path) == []
    assert target.read_text() == "new\n"


def test_a_live_writers_part_file_is_kept(tmp_path):
    target = tmp_path / "table.csv"
    proc = _start_writer(target)
    try:
        live = _parts(tmp_path)
        assert len(live) == 1
        assert temp_leftovers(target) == []
        write_text(target, "mine\n")          # another writer of the same target meanwhile
        assert _parts(tmp_path) == live
        assert target.read_text() == "mine\n"
    finally:
        proc.kill()
        proc.wait(timeout=30)
    assert remove_leftovers(target) == 1
    assert _parts(tmp_path) == []


def test_other_targets_part_files_are_not_touched(tmp_path):
    other = tmp_path / f".table.csv2.{2**22 + 7}.abc.part.csv2"     # another target's name
    other.write_bytes(b"y")
    stranger = tmp_path / ".table.csv.notapid.abc.part.csv"
    stranger.write_bytes(b"z")
    write_text(tmp_path / "table.csv", "a\n")
    assert other.exists() and stranger.exists()
