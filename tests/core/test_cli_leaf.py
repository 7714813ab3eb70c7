"""`maizeviz leaf` as a user runs it: outputs, exports, and one-line errors for bad input."""

import json
import subprocess
import sys

import meshio
import numpy as np
import pytest

from maizeviz.cli import EXIT_FAIL, EXIT_OK, EXIT_PARTIAL, main
from maizeviz.leaf.synth import example_leaf
from tests.conftest import grid_csv


@pytest.fixture
def two_leaves(write_csv):
    text = grid_csv(example_leaf(seed=1), 1, 1) + grid_csv(example_leaf(seed=2, rows=9), 1, 2,
                                                           header=False)
    return write_csv(text)


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_json_interp(capsys, two_leaves):
    code, out, err = run(capsys, "leaf", two_leaves, "--interp", "4", "--json")
    assert code == EXIT_OK, err
    data = json.loads(out)
    leaves = data["leaves"]
    assert [(lf["plant"], lf["leaf"]) for lf in leaves] == [(1, 1), (1, 2)]
    first = leaves[0]
    assert (first["rows"], first["cols"]) == (13, 5)
    assert first["triangles"] == 2 * 12 * 5 * 4 * 5 - 4 * 5
    assert 300 < first["area_cm2"] < 1000
    assert 0 < first["projected_area_cm2"] <= first["area_cm2"]


def test_table_and_levels(capsys, two_leaves):
    code, out, _ = run(capsys, "leaf", two_leaves)
    assert code == EXIT_OK and "area cm2" in out and "total: 2 leaves" in out
    code, out, _ = run(capsys, "leaf", two_leaves, "--levels", "--json")
    data = json.loads(out)
    assert data["levels"] == ["K=4", "K=1", "standard", "36 triangles", "8 triangles",
                              "4 triangles", "3 triangles"]
    tri = [lv["triangles"] for lv in data["leaves"][0]["levels"]]
    assert tri == sorted(tri, reverse=True) and tri[-1] <= 3
    code, out, _ = run(capsys, "leaf", two_leaves, "--levels", "K2,20")
    assert "K=2" in out and "20 triangles" in out


@pytest.mark.parametrize("ext", [".ply", ".obj", ".vtk", ".vtu", ".vtp", ".stl"])
def test_export_formats(capsys, two_leaves, tmp_path, ext):
    path = tmp_path / f"leaf{ext}"
    code, _, err = run(capsys, "leaf", two_leaves, "--triangles", "8", "--export", path)
    assert code == EXIT_OK, err
    assert path.stat().st_size > 0
    if ext == ".vtp":
        import pyvista  # tests may use pyvista; the core does not
        mesh = pyvista.read(path)
        assert mesh.n_cells <= 16
        assert set(np.unique(mesh.cell_data["leaf"])) == {1, 2}
    elif ext == ".ply":
        raw = path.read_bytes()
        assert b"property int plant" in raw and b"property int leaf" in raw
        import pyvista
        mesh = pyvista.read(path)
        assert 2 <= mesh.n_cells <= 16
    elif ext == ".obj":
        text = path.read_text()
        assert "g plant1_leaf1" in text and "g plant1_leaf2" in text
    else:
        mesh = meshio.read(path)
        assert 2 <= len(mesh.cells[0].data) <= 16
        if ext != ".stl":
            assert set(np.unique(mesh.cell_data["leaf"][0])) == {1, 2}


def test_bad_leaf_skipped_exit_partial(capsys, write_csv):
    text = grid_csv(example_leaf(seed=1), 1, 1) + grid_csv(example_leaf(seed=2), 1, 2, False)
    text = text.replace("\n1,2,3,", "\n1,2,3x,", 1)
    code, out, err = run(capsys, "leaf", write_csv(text), "--json")
    assert code == EXIT_PARTIAL
    data = json.loads(out)
    assert [lf["leaf"] for lf in data["leaves"]] == [1]
    assert data["skipped"][0]["leaf"] == 2 and "row/col" in data["skipped"][0]["error"]
    assert "skipped: plant 1, leaf 2" in err and "1 leaves done, 1 skipped" in err
    code, out, err = run(capsys, "leaf", write_csv(text), "--strict")
    assert code == EXIT_FAIL and "plant 1, leaf 2" in err


@pytest.mark.parametrize("text, says", [
    ("", "empty"),
    ("plant,leaf,row,col,x,y,z\n", "header only"),
    ("a,b,c\n1,2,3\n", "missing column"),
    ("plant,leaf,row,col,x,y,z\n1,1,0,0,0,0,nan\n1,1,0,1,1,0,0\n1,1,1,0,0,1,0\n1,1,1,1,1,1,0\n",
     "row 0, col 0 (line 2): z is nan (not a number)"),
    ("plant,leaf,row,col,x,y,z\n1,1,0,0,0,0,1e30\n1,1,0,1,1,0,0\n1,1,1,0,0,1,0\n1,1,1,1,1,1,0\n",
     "beyond"),
    ("plant,leaf,row,col,x,y,z\n1,1,0,0,0,0,0\n1,1,0,1,1,0,0\n", "at least 2 cross-sections"),
])
def test_bad_input_one_line_error(capsys, write_csv, text, says):
    code, out, err = run(capsys, "leaf", write_csv(text))
    assert code == EXIT_FAIL
    assert says in err
    assert "Traceback" not in err


def test_bad_options(capsys, two_leaves, tmp_path):
    code, _, err = run(capsys, "leaf", two_leaves, "--interp", "-1")
    assert code == EXIT_FAIL and "must be between 0 and 50, got -1 (--interp)" in err
    code, _, err = run(capsys, "leaf", two_leaves, "--triangles", "0")
    assert code == EXIT_FAIL and "triangle budget must be >= 1, got 0 (--triangles)" in err
    code, _, err = run(capsys, "leaf", two_leaves, "--levels", "K4,lots")
    assert code == EXIT_FAIL and "'lots' is not a mesh level" in err
    code, _, err = run(capsys, "leaf", two_leaves, "--export", tmp_path / "x.docx")
    assert code == EXIT_FAIL and "unknown mesh format" in err
    code, out, err = run(capsys, "leaf", two_leaves, "--export", tmp_path / "no" / "dir" / "x.ply")
    assert code == EXIT_FAIL and "does not exist" in err and not out   # refused before any work


def test_console_script_never_shows_traceback(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_bytes(b"\x00\x01\x02garbage")
    proc = subprocess.run([sys.executable, "-m", "maizeviz", "leaf", str(bad)],
                          capture_output=True, text=True)
    assert proc.returncode == EXIT_FAIL
    assert proc.stderr.strip().count("\n") == 0 and "binary" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_no_command_without_screen_runs_the_headless_report():
    import os
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    proc = subprocess.run([sys.executable, "-m", "maizeviz"], capture_output=True, text=True,
                          env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "no screen" in proc.stderr
    assert "4 triangles, widths unscaled" in proc.stdout and "LAI" in proc.stdout
    helped = subprocess.run([sys.executable, "-m", "maizeviz", "--help"], capture_output=True,
                            text=True, env=env)
    assert helped.returncode == 0 and "canopy" in helped.stdout


def test_a_file_given_without_screen_is_the_one_reported(tmp_path):
    """`maizeviz FILE` with no screen reports on FILE (not on the bundled example); a missing
    file or a project is one line and exit 1, never a report on other plants with exit 0."""
    import os
    import shutil

    from maizeviz.resources import example_points

    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    mine = tmp_path / "mine.csv"
    shutil.copy(example_points(), mine)

    def run(*args):
        return subprocess.run([sys.executable, "-m", "maizeviz", *args], capture_output=True,
                              text=True, env=env, timeout=300)

    proc = run(str(mine))
    assert proc.returncode == 0, proc.stderr
    assert f"the headless report on {mine}" in proc.stderr and "LAI" in proc.stdout
    missing = run(str(tmp_path / "nosuch.csv"))
    assert missing.returncode == 1 and "nosuch.csv: no such file" in missing.stderr
    assert "LAI" not in missing.stdout
    project = tmp_path / "study.maizeviz"
    project.write_bytes(b"PK")
    proc = run(str(project))
    assert proc.returncode == 1 and "is a project" in proc.stderr and "LAI" not in proc.stdout
