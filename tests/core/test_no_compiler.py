"""An install that could not build a kernel says so: setup.py names each kernel not built and
its fallback at the end of the build (a failing compiler, CC=false, as where none is
installed), and maizeviz says it again once a process when the fallback runs, and in
``maizeviz --info``."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_a_build_whose_compiler_fails_names_each_kernel_and_its_fallback(tmp_path):
    # setup.py run by hand uses this environment's setuptools; pyproject's build-system asks
    # for >= 77 (its SPDX licence), which pip's isolated build gets but a bare venv lacks
    pytest.importorskip("setuptools", minversion="77")
    env = {**os.environ, "CC": "false"}
    out = subprocess.run([sys.executable, "setup.py", "-q", "build_ext", "--build-lib",
                          str(tmp_path / "lib"), "--build-temp", str(tmp_path / "tmp")],
                         cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr                  # the install goes on
    said = [line for line in out.stderr.splitlines() if line.startswith("maizeviz: ")]
    assert said[0] == ("maizeviz: warning: the ray-packet kernel (maizeviz.mesh._packets, "
                       "maizeviz/mesh/_packets.c) was not built (CompileError from 'false'): "
                       "light is traced with embreex's single rays (the same hits, about 2x "
                       "slower).")
    assert said[1].startswith("maizeviz: warning: the compiled loops (maizeviz._loops, "
                              "maizeviz/_loops.c) were not built (CompileError from 'false'): "
                              "numpy computes")
    assert "install a C compiler" in said[2] and "maizeviz --info" in said[2]
    assert not list((tmp_path / "lib").rglob("*.so"))


def _without_loops(code: str, env: dict | None = None) -> subprocess.CompletedProcess:
    prog = ("import sys, warnings\nsys.modules['maizeviz._loops'] = None\n"
            "import maizeviz as mv\n"
            "with warnings.catch_warnings(record=True) as said:\n"
            "    warnings.simplefilter('always')\n"
            "    for _ in range(2):\n"
            "        mv.build_canopy(mv.read_points(mv.example_points()), tile=(1, 1), "
            "level='8')\n" + code +
            "for w in said:\n    print(w.category.__name__, w.message)\n")
    return subprocess.run([sys.executable, "-c", prog], capture_output=True, text=True,
                          timeout=300, env={**os.environ, **(env or {})})


def test_the_loops_fallback_is_said_once_a_process_and_by_info():
    out = _without_loops("from maizeviz.info import report\n"
                         "print([l for l in report().splitlines() if 'loops' in l][0])\n")
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0].startswith("compiled loops: numpy (not built when maizeviz was installed")
    warned = [line for line in lines[1:] if "compiled loops" in line]
    assert len(warned) == 1 and warned[0].startswith(
        "RuntimeWarning maizeviz: computing surface bases, reference areas and splitting "
        "with numpy (the same numbers, slower): the compiled loops were not built")


def test_loops_turned_off_on_purpose_are_not_warned_about():
    out = _without_loops("", {"MAIZEVIZ_LOOPS": "0"})
    assert out.returncode == 0, out.stderr
    assert "compiled loops" not in out.stdout
