"""File modes of atomic writes: the umask is read once at import, so threads writing files
beside maizeviz's atomic writes (app workers, Dask threads) get the modes the umask gives,
never a world-writable file, and maizeviz's own files get the same mode."""

import json
import os
import stat
import subprocess
import sys
import threading

import pytest

from maizeviz.io import atomic


def mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


def test_the_umask_is_read_without_being_set(monkeypatch):
    expected = os.umask(0o022)
    os.umask(expected)
    assert atomic.read_umask() == expected
    assert atomic.FILE_MODE == 0o666 & ~atomic.UMASK


def test_atomic_writes_never_touch_the_umask(tmp_path, monkeypatch):
    def refuse(mask):
        raise AssertionError("os.umask called while writing")

    monkeypatch.setattr(os, "umask", refuse)
    atomic.write_text(tmp_path / "a.txt", "x")
    atomic.write_rows(tmp_path / "b.csv", [{"a": 1}])
    assert mode(tmp_path / "a.txt") == mode(tmp_path / "b.csv") == atomic.FILE_MODE


@pytest.mark.parametrize("umask", [0o022, 0o027, 0o002])
def test_threads_creating_files_during_atomic_writes_get_their_umask(tmp_path, umask):
    """Four threads write atomically while four others create plain files, 200 each, in a
    fresh process with ``umask``: every file has the mode that umask gives."""
    code = f"""
import os, stat, sys, threading
os.umask({umask:#o})
from maizeviz.io import atomic
folder = sys.argv[1]
go = threading.Event()

def writer(k):
    go.wait()
    for i in range(200):
        atomic.write_text(os.path.join(folder, f"atomic-{{k}}-{{i}}.txt"), "x")

def plain(k):
    go.wait()
    for i in range(200):
        with open(os.path.join(folder, f"plain-{{k}}-{{i}}.txt"), "w") as fh:
            fh.write("x")

threads = [threading.Thread(target=f, args=(k,)) for k in range(4) for f in (writer, plain)]
for t in threads:
    t.start()
go.set()
for t in threads:
    t.join()
modes = {{stat.S_IMODE(os.stat(os.path.join(folder, n)).st_mode) for n in os.listdir(folder)}}
print(json.dumps([len(os.listdir(folder)), sorted(modes), atomic.FILE_MODE]))
"""
    out = subprocess.run([sys.executable, "-c", "import json\n" + code, str(tmp_path)],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout) == [1600, [0o666 & ~umask], 0o666 & ~umask]


def test_where_proc_is_silent_the_umask_is_read_without_a_world_writable_moment(tmp_path,
                                                                               monkeypatch):
    """Without /proc/self/status the umask is read by setting it for an instant: a thread
    creating files meanwhile gets a private file at worst, never a world-writable one."""
    def no_proc(*args, **kwargs):
        raise OSError("no /proc here")

    monkeypatch.setattr(atomic, "open", no_proc, raising=False)
    expected = os.umask(0o022)
    os.umask(expected)
    assert atomic.read_umask() == expected
    stop = threading.Event()
    made: list[str] = []

    def create():
        i = 0
        while not stop.is_set():
            p = tmp_path / f"f{i}"
            p.write_text("x")
            made.append(str(p))
            i += 1

    t = threading.Thread(target=create)
    t.start()
    try:
        for _ in range(2000):
            atomic.read_umask()
    finally:
        stop.set()
        t.join()
    assert made and all(mode(p) & 0o002 == 0 for p in made)
