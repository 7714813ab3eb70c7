"""``maizeviz --info`` (versions, the Embree library, the ray kernel and why, threads) and the
``"kernel"`` of ``maizeviz light --json``: what they say is what the process uses."""

import json
import os
import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import pytest

import maizeviz as mv
from maizeviz.cli import main
from maizeviz.mesh import packets
from maizeviz.mesh.embree_fill import embree


def run(*args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "maizeviz", *args], capture_output=True,
                          text=True, timeout=300, env={**os.environ, **(env or {})})


def test_info_names_the_versions_the_library_and_the_kernel_in_use(capsys):
    assert main(["--info"]) == 0
    lines = capsys.readouterr().out.splitlines()
    text = "\n".join(lines)
    assert lines[0] == f"maizeviz {mv.__version__}"
    for name in ("numpy", "scipy", "pandas", "pvlib", "embreex", "matplotlib"):
        assert f"{name} {version(name)}" in text
    e = embree()
    embree_line = next(line for line in lines if line.startswith("Embree "))
    assert embree_line == f"Embree {e.version} (embreex {version('embreex')}): {e.path}"
    assert Path(str(e.path)).is_file()
    kernel = next(line for line in lines if line.startswith("ray kernel: "))
    assert kernel.startswith("ray kernel: packets (Embree's ray packets of 8): ")
    assert kernel.endswith(str(packets.status().path))
    assert "scene fill: copy" in text
    assert "compiled loops: compiled (" in text
    assert f"threads: {os.cpu_count()} cores" in text


def test_info_says_why_the_packets_are_off():
    out = run("--info", env={"MAIZEVIZ_PACKETS": "0"})
    assert out.returncode == 0, out.stderr
    assert "ray kernel: embreex's single rays (turned off by MAIZEVIZ_PACKETS=0)" in out.stdout
    out = run("--info", env={"MAIZEVIZ_LOOPS": "0"})
    assert "compiled loops: numpy (turned off by MAIZEVIZ_LOOPS=0)" in out.stdout


@pytest.fixture(scope="module")
def light_args():
    return ["light", str(mv.example_points()), "--triangles", "8", "--density", "0.3",
            "--sun-zenith", "35", "--sun-azimuth", "140", "--periodic", "--json"]


def test_light_json_says_which_kernel_traced_and_both_give_the_same_light(capsys, light_args):
    assert main(light_args) == 0
    fast = json.loads(capsys.readouterr().out)
    assert fast["kernel"] == "packets"
    out = run(*light_args, env={"MAIZEVIZ_PACKETS": "0"})
    assert out.returncode == 0, out.stderr
    slow = json.loads(out.stdout)
    assert slow["kernel"] == "embreex" and "warning" not in out.stderr
    assert slow["transmission"] == fast["transmission"]
