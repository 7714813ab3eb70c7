"""docs/cli.md's desktop-app commands run as written (issue 27), each as its own process on the
virtual screen with ``--screenshot`` added so that it builds the canopy, computes light once,
saves the window and quits (the page's last app command is exactly that): exit 0 and a PNG.
The files they open are bundled data: ``points.csv`` the bundled block, ``study.maizeviz`` a
project of it, ``canopy.ply`` its canopy exported at 36 triangles a leaf. A fresh home folder
holds the app's settings, so ``maizeviz`` alone opens the bundled block.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "core"))
from test_cli_docs import argv_of, doc_commands, kind_of  # noqa: E402

APP = [c for c in doc_commands() if kind_of(c) == "app"]


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    import maizeviz as mv
    from maizeviz.canopy.build import build_canopy
    from maizeviz.canopy.export import export_canopy
    from maizeviz.canopy.layout import layout_for
    from maizeviz.leaf.fit import read_leaves
    from maizeviz.mesh.levels import Level

    out = tmp_path_factory.mktemp("cli-docs-app")
    points = mv.example_points()
    shutil.copy(points, out / "points.csv")
    leaves = read_leaves(points).leaves
    layout = layout_for(leaves, (3, 3))
    mv.save_study(out / "study.maizeviz", points, layout, [])
    export_canopy(out / "canopy.ply", build_canopy(leaves, layout, Level(triangles=36)))
    (out / "home").mkdir()
    return out


def test_the_page_shows_the_app_commands():
    assert len(APP) >= 5 and any(c.startswith("xvfb-run") for c in APP)


@pytest.mark.parametrize("line", APP)
def test_each_app_command_opens_computes_and_quits(folder, line):
    args = argv_of(line)
    png = folder / f"shot{APP.index(line)}.png"
    if "--screenshot" in args:
        args[args.index("--screenshot") + 1] = str(png)
    else:
        args += ["--screenshot", str(png)]
    cmd = [sys.executable, "-m", "maizeviz", *args]
    if line.startswith("xvfb-run"):
        if shutil.which("xvfb-run") is None:                         # pragma: no cover
            pytest.skip("no xvfb-run here")
        cmd = ["xvfb-run", "-a", *cmd]
    env = dict(os.environ, HOME=str(folder / "home"),
               XDG_CONFIG_HOME=str(folder / "home" / ".config"))
    proc = subprocess.run(cmd, cwd=folder, env=env, capture_output=True, text=True,
                          timeout=400)
    assert proc.returncode == 0, f"{line}\n{proc.stdout[-2000:]}\n{proc.stderr[-3000:]}"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "Traceback" not in proc.stderr and "error:" not in proc.stderr, proc.stderr[-3000:]


def test_a_screenshot_into_a_missing_folder_is_refused_before_any_work(folder):
    """It said "saved" and exited 0 with nothing written (Qt's save returned False)."""
    png = folder / "no such folder" / "shot.png"
    cmd = [sys.executable, "-m", "maizeviz", "--screenshot", str(png)]
    if shutil.which("xvfb-run") is None:                             # pragma: no cover
        pytest.skip("no xvfb-run here")
    env = dict(os.environ, HOME=str(folder / "home"),
               XDG_CONFIG_HOME=str(folder / "home" / ".config"))
    proc = subprocess.run(["xvfb-run", "-a", *cmd], cwd=folder, env=env, capture_output=True,
                          text=True, timeout=400)
    assert proc.returncode == 1 and "saved" not in proc.stdout
    assert "no such folder" in proc.stderr and proc.stderr.count("\n") == 1, proc.stderr
    assert not png.parent.exists()
