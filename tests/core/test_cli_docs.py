"""docs/cli.md runs as written (issue 27): every command of its ``bash`` blocks, in the page's
order, in a folder holding bundled data that stands in for the reader's own files, exits 0
and writes the files it names. The desktop app's commands run in
tests/gui/test_cli_docs_app.py; the digitizer's (``record``, ``fastrak-sim``) here, against
the simulator the page tells to start, its port standing for ``/dev/ttyUSB0``.

The stand-ins (made once, before the page's commands):

- ``points.csv``: the bundled digitized block;
- ``field.ply``: a canopy from elsewhere, in metres, without maizeviz's field comments: the
  bundled block tiled 3 x 3 at 36 triangles a leaf, its coordinates divided by 100;
- ``scan.obj``: a scan in millimetres with y up, a group per leaf: the bundled block (one
  tile, standing in 0..180 x 0..90 cm) at 36 triangles, file (x, y, z) = 10 field (x, z, -y);
- ``station.csv``: a day of measured irradiance and air temperature at 30 minutes: NSRDB's
  2 July 2017 at 40.5 N 108.5 W (tests/data/weather) on Beijing's clock of 1 August 2005;
- ``maizeviz/resources/``: the bundled files, where the page finds them.
"""

from __future__ import annotations

import contextlib
import csv
import io
import os
import re
import shlex
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from maizeviz.cli import COMMANDS, EXIT_OK, main

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "cli.md"
WEATHER = ROOT / "tests" / "data" / "weather" / "psm3_401182_july.csv"
#: Options whose value is a file or folder the command writes.
OUTPUTS = ("--out", "--export", "--leaf-light", "--plant-light", "--steps", "--save-layout",
           "--heatmaps", "--plots")
SERIAL = ("record", "fastrak-sim")


def doc_commands() -> list[str]:
    """Every command line of the page's bash blocks, continuations joined, comments cut."""
    out = []
    for block in re.findall(r"```bash\n(.*?)```", DOC.read_text(), re.S):
        for line in block.replace("\\\n", " ").splitlines():
            line = re.sub(r"\s#.*$", "", line).strip()
            if line:
                out.append(line)
    return out


def argv_of(line: str) -> list[str]:
    """The arguments after the program (``maizeviz``, ``.venv/bin/maizeviz``, under
    ``xvfb-run -a``)."""
    words = shlex.split(line)
    if words[:2] == ["xvfb-run", "-a"]:
        words = words[2:]
    assert Path(words[0]).name == "maizeviz", f"not a maizeviz command: {line}"
    return words[1:]


#: What the command line answers itself, without the app: ``maizeviz --info`` and friends.
CORE_OPTIONS = ("--info", "--version", "-h", "--help")


def kind_of(line: str) -> str:
    """"app" (no subcommand), "serial" (the digitizer) or "headless"."""
    args = argv_of(line)
    if args and args[0] in CORE_OPTIONS:
        return "headless"
    if not args or args[0] not in COMMANDS:
        return "app"
    return "serial" if args[0] in SERIAL else "headless"


def written(args: list[str]) -> list[str]:
    return [args[k + 1] for k, a in enumerate(args[:-1]) if a in OUTPUTS]


# ------------------------------------------------------------------------------ stand-ins
def make_stand_ins(folder: Path) -> None:
    """The bundled data standing in for the page's files (see the module's text)."""
    from maizeviz.canopy.build import build_canopy
    from maizeviz.canopy.export import canopy_cells
    from maizeviz.canopy.layout import layout_for
    from maizeviz.io.meshfile import write_mesh
    from maizeviz.leaf.fit import read_leaves
    from maizeviz.mesh.levels import Level
    from maizeviz.resources import example_points

    res = folder / "maizeviz" / "resources"
    shutil.copytree(ROOT / "maizeviz" / "resources", res,
                    ignore=shutil.ignore_patterns("*.py", "__pycache__"))
    shutil.copy(example_points(), folder / "points.csv")
    leaves = read_leaves(example_points()).leaves
    field = build_canopy(leaves, layout_for(leaves, (3, 3)), Level(triangles=36))
    pts, faces, cells = canopy_cells(field)
    write_mesh(folder / "field.ply", pts / 100.0, faces, cells)
    block = build_canopy(leaves, layout_for(leaves, (1, 1)), Level(triangles=36))
    pts, faces, cells = canopy_cells(block)
    write_mesh(folder / "scan.obj", 10.0 * np.column_stack([pts[:, 0], pts[:, 2], -pts[:, 1]]),
               faces, cells)
    with open(WEATHER, newline="") as fh:
        rows = list(csv.reader(fh))
    names = rows[2]
    col = {k: names.index(k) for k in ("Hour", "Minute", "GHI", "DNI", "DHI", "Temperature")}
    lines = ["time,ghi,dni,dhi,temp_air"]
    for r in rows[3:]:
        if r[2] == "2":                                            # 2 July
            lines.append(f"2005-08-01T{int(r[col['Hour']]):02d}:{int(r[col['Minute']]):02d}"
                         f"+08:00," + ",".join(r[col[k]] for k in ("GHI", "DNI", "DHI",
                                                                  "Temperature")))
    (folder / "station.csv").write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def ran(tmp_path_factory):
    """Each headless command of the page run in order: {line: (exit code, stderr)}."""
    folder = tmp_path_factory.mktemp("cli-docs")
    make_stand_ins(folder)
    results = {}
    here = os.getcwd()
    os.chdir(folder)
    try:
        for line in doc_commands():
            if kind_of(line) != "headless":
                continue
            err = io.StringIO()
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                code = main(argv_of(line))
            results[line] = (code, err.getvalue(), [str(folder / p) for p in
                                                    written(argv_of(line))])
    finally:
        os.chdir(here)
    return results


def test_the_page_has_commands_of_every_kind():
    kinds = [kind_of(line) for line in doc_commands()]
    assert kinds.count("headless") >= 25 and "app" in kinds and "serial" in kinds
    # every subcommand of maizeviz is shown on the page
    shown = {argv_of(line)[0] for line in doc_commands() if kind_of(line) != "app"}
    shown -= set(CORE_OPTIONS)
    assert shown >= set(COMMANDS) - {"sweep"}


@pytest.mark.parametrize("line", [c for c in doc_commands() if kind_of(c) == "headless"])
def test_each_command_runs_and_writes_its_files(ran, line):
    code, err, outputs = ran[line]
    assert code == EXIT_OK, f"{line}\n{err}"
    assert "error:" not in err and "Traceback" not in err, f"{line}\n{err}"
    for path in outputs:
        assert Path(path).exists(), f"{line}: {path} was not written"


def test_the_mesh_round_trip_of_the_page_needs_no_field(ran):
    """`canopy ... --export canopy.ply` then `light canopy.ply --periodic`: the file's own
    plot and period, said on stderr."""
    line = next(c for c in ran if c.startswith("maizeviz light canopy.ply"))
    assert "the field is the file's" in ran[line][1]


# ------------------------------------------------------------------------------ the digitizer
class Started:
    """A page command started as a process, its output lines gathered."""

    def __init__(self, line: str, folder: Path, stdin: bool = False):
        self.line = line
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "maizeviz", *argv_of(line)], cwd=folder, text=True,
            stdin=subprocess.PIPE if stdin else subprocess.DEVNULL, stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT, bufsize=1)
        self.lines: list[str] = []
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self):
        for ln in self.proc.stdout:
            self.lines.append(ln.rstrip("\n"))

    def wait_for(self, pattern: str, count: int = 1, timeout: float = 60.0) -> list[str]:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            found = [ln for ln in self.lines if re.search(pattern, ln)]
            if len(found) >= count:
                return found
            if self.proc.poll() is not None and not self.lines[len(found):]:
                time.sleep(0.2)
                found = [ln for ln in self.lines if re.search(pattern, ln)]
                if len(found) >= count:
                    return found
                raise AssertionError(f"{self.line}: ended ({self.proc.returncode}) without "
                                     f"{pattern!r}: {self.lines[-5:]}")
            time.sleep(0.05)
        raise AssertionError(f"{self.line}: no {pattern!r} within {timeout} s: "
                             f"{self.lines[-5:]}")

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            self.proc.wait(10)


def test_the_digitizer_commands_run_against_the_simulator(tmp_path):
    """The page's `synth` of plant.csv, `fastrak-sim --replay plant.csv` and `record` (a new
    file, then `--resume`), the simulator's port standing for `/dev/ttyUSB0` and
    `/dev/pts/N`: points recorded, more after the resume, each file a points file."""
    from maizeviz.io.points import read_points

    lines = doc_commands()
    synth = next(argv_of(c) for c in lines if kind_of(c) == "headless"
                 and argv_of(c)[0] == "synth" and "plant.csv" in c)
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        assert main(synth) == EXIT_OK
    finally:
        os.chdir(cwd)
    serial = [c for c in lines if kind_of(c) == "serial"]
    sim_line = next(c for c in serial if argv_of(c)[0] == "fastrak-sim")
    records = [c for c in serial if argv_of(c)[0] == "record"]
    assert any("--resume" in c for c in records)
    points = {}
    for line in records:
        # presses every 0.4 s instead of the default 1 s: the same session, sooner
        sim = Started(sim_line.replace("--replay", "--pace 0.4 --replay"), tmp_path)
        try:
            port = re.search(r"/dev/pts/\d+", sim.wait_for(r"/dev/pts/\d+")[0]).group(0)
            rec = Started(line.replace("/dev/ttyUSB0", port).replace("/dev/pts/N", port),
                          tmp_path, stdin=True)
            try:
                # a finished cross-section (5 points) and more: --resume knows --cols from it
                rec.wait_for(r"recorded", count=7, timeout=90)
                rec.proc.stdin.write("q\n")
                rec.proc.stdin.flush()
                assert rec.proc.wait(30) == 0, rec.lines[-5:]
            finally:
                rec.stop()
        finally:
            sim.stop()
        args = argv_of(line)
        out = tmp_path / args[args.index("--out") + 1]
        points.setdefault(out.name, []).append(len(read_points(out)))
    # plant3.csv recorded, then resumed with more points; rec.csv recorded
    assert points["plant3.csv"][1] > points["plant3.csv"][0] >= 7
    assert points["rec.csv"][0] >= 7
