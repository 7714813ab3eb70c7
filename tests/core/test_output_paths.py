"""Output paths of every command against its inputs and its other outputs.

For every command, an output is pointed at an input or at another output (or an output
folder at a folder holding an input under a derived name), spelled every way a path can be:
as is, ``./``, ``sub/..``, absolute, through a symbolic link to the file or to its folder,
through a hard link. The data are the oracle: no byte of any file already there changes, no
file appears, and the refusal is one ``error:`` line with exit code 1 (docs/cli.md)."""

import contextlib
import hashlib
import io
import os
import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.cli import EXIT_FAIL, main
from maizeviz.resources import example_phenomenal

L = ["light", "pts.csv", "--sun-zenith", "10", "--sun-azimuth", "0", "--density", "0.05",
     "--heights", "0"]
P = ["light", "pts.csv", "--weather", "w.csv", "--lat", "40", "--lon", "116", "--density", "0.05",
     "--heights", "0", "--sky-directions", "6"]
TWO = ["--levels", "K=4,standard"]
#: (argv with "A" where the colliding path goes, the file or folder A names, how A may be
#: spelled: "file" (any spelling, links to the file included) or "name" (a name from which
#: the command derives others: no link to the file itself)).
CASES = [
    (["leaf", "pts.ply", "--export", "A"], "pts.ply", "file"),
    (["canopy", "pts.ply", "--export", "A"], "pts.ply", "file"),
    (["canopy", "pts.csv", "--save-layout", "A"], "pts.csv", "file"),
    (["canopy", "pts.csv", "--layout", "lay.json", "--save-layout", "A"], "lay.json", "file"),
    (["canopy", "pts.csv", "--export", "m.ply", "--save-layout", "A"], "m.ply", "file"),
    ([*L, "--leaf-light", "A"], "pts.csv", "file"),
    ([*L, "--leaf-light", "s.csv", "--plant-light", "A"], "s.csv", "file"),
    (["light", "s_K_4.csv", *L[2:], *TWO, "--plant-light", "A"], "s.csv", "name"),
    ([*L, "--heatmaps", ".", "--leaf-light", "A"], "transmission_K_4_h0cm.csv", "file"),
    ([*L, *TWO, "--leaf-light", "s.csv", "--plant-light", "A"], "s.csv", "name"),
    (["light", "transmission_K_4_h0cm.csv", *L[2:], "--heatmaps", "A"], ".", "name"),
    ([*L, "--heatmaps", "A"], "pts.csv", "file"),
    ([*P, "--steps", "A"], "w.csv", "file"),
    ([*P, "--steps", "t.csv", "--leaf-light", "A"], "t.csv", "file"),
    ([*P, "--steps", "t.csv", "--plant-light", "A"], "t.csv", "file"),
    (["light", "day_K_4.png", *P[2:], "--plots", "A"], ".", "name"),
    ([*P, "--heatmaps", "A"], "w.csv", "file"),
    (["import-phenomenal", "p.json.gz", "--out", "A"], "p.json.gz", "file"),
    (["record", "--port", "port.txt", "--out", "A"], "port.txt", "file"),
    (["sweep", "sweep.json", "--out", "A"], ".", "name"),
]
SPELLINGS = ["as is", "./", "sub/..", "absolute", "link to folder", "link to file",
             "hard link"]


def _spell(name: str, how: str, kind: str, work: Path) -> str | None:
    """``name`` (a file or ".") spelled ``how``; None where that spelling does not apply."""
    if how == "as is":
        return name
    if how == "./":
        return f"./{name}"
    if how == "sub/..":
        return f"sub/../{name}"
    if how == "absolute":
        return str(work / name)
    if how == "link to folder":
        return f"dirlink/{name}"
    if kind != "file" or name == ".":
        return None
    if how == "link to file":
        os.symlink(name, work / "filelink")
        return "filelink"
    if not (work / name).exists():            # hard links need the file to exist
        return None
    os.link(work / name, work / "hardlink")
    return "hardlink"


def _setup(work: Path, tiny: Path) -> None:
    (work / "sub").mkdir()
    os.symlink(work, work / "dirlink")
    for name in ("pts.csv", "pts.ply", "s_K_4.csv", "transmission_K_4_h0cm.csv", "day_K_4.png"):
        shutil.copy(tiny, work / name)
    shutil.copy(tiny.parent / "lay.json", work / "lay.json")
    (work / "w.csv").write_text("time,ghi\n2005-08-01T10:00+08:00,500\n"
                                "2005-08-01T11:00+08:00,600\n")
    (work / "p.json.gz").write_bytes(Path(example_phenomenal()).read_bytes())
    (work / "port.txt").write_text("not a port\n")
    (work / "sweep.json").write_text('[canopy]\npoints = ["pts.csv"]\nlevel = ["K4"]\n'
                                     '[light]\nsun = [{zenith = 30, azimuth = 180}]\n'
                                     'density = [0.05]\nheights = [0]\n')


def _snapshot(work: Path) -> dict:
    found = {}
    for root, dirs, files in os.walk(work, followlinks=False):
        for f in files + [d for d in dirs if os.path.islink(os.path.join(root, d))]:
            p = Path(root) / f
            found[str(p.relative_to(work))] = hashlib.sha256(
                os.readlink(p).encode() if p.is_symlink() else p.read_bytes()).hexdigest()
    return found


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tiny")
    assert main(["synth", "--plants", "1x1", "--sections", "4", "--points-across", "3",
                 "--out", str(folder / "tiny.csv")]) == 0
    assert main(["canopy", str(folder / "tiny.csv"), "--save-layout",
                 str(folder / "lay.json")]) == 0
    return folder / "tiny.csv"


@settings(max_examples=200, deadline=None)
@given(case=st.sampled_from(CASES), how=st.sampled_from(SPELLINGS))
def test_an_output_never_overwrites_an_input_or_another_output(tiny, case, how):
    argv, target, kind = case
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        _setup(work, tiny)
        spelled = _spell(target, how, kind, work)
        if spelled is None:
            return
        before = _snapshot(work)
        old = os.getcwd()
        os.chdir(work)
        try:
            err = io.StringIO()
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                code = main([spelled if a == "A" else a for a in argv])
        finally:
            os.chdir(old)
        after = _snapshot(work)
        lines = [ln for ln in err.getvalue().splitlines() if ln.startswith(("error", "internal"))]
        assert after == before, (f"{argv} {spelled}: files changed or appeared: "
                                 f"{sorted(set(after.items()) ^ set(before.items()))}")
        assert code == EXIT_FAIL and len(lines) == 1 and lines[0].startswith("error: "), \
            (argv, spelled, err.getvalue()[-600:])
