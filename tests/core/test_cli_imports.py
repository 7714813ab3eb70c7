"""What ``maizeviz light`` imports on the sun's path: only what the run uses.

A fresh interpreter runs the command (a points file, a sun from angles and from a date and a
place) and lists its ``sys.modules``. Importing a module nobody calls costs every run: scipy.sparse
alone took 0.33 s and pulled numpy.f2py in; the mesh parsers, the VTK writer's XML (and with it
urllib, http, email and ssl) belong to other inputs and outputs.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from maizeviz.resources import example_points

#: Modules the sun's path over a points file must not import (a prefix names the package).
NOT_ON_THE_SUN_PATH = ("scipy.sparse", "numpy.f2py", "pandas", "pvlib", "matplotlib", "dask",
                       "pyarrow", "plyfile", "maizeviz.io.mesh_canopy", "maizeviz.io.mesh_ply",
                       "maizeviz.io.mesh_obj", "maizeviz.sweep", "xml.sax", "urllib.request",
                       "http.client")

RUN = """
import contextlib, io, json, sys
from maizeviz.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    code = main(sys.argv[1:])
print(json.dumps({"code": code, "modules": sorted(sys.modules)}))
"""


def _modules(*args: str) -> tuple[int, list[str]]:
    done = subprocess.run([sys.executable, "-c", RUN, "light", str(example_points()), "--json",
                           "--interp", "2", *args], capture_output=True, text=True, check=True)
    out = json.loads(done.stdout.splitlines()[-1])
    return out["code"], out["modules"]


@pytest.mark.parametrize("sun", [
    ["--sun-zenith", "30", "--sun-azimuth", "180"],
    ["--date", "2005-08-01", "--time", "12:00", "--lat", "39.9", "--lon", "116.4",
     "--tz", "Asia/Shanghai"]], ids=["angles", "date-and-place"])
def test_the_sun_path_imports_only_what_it_uses(sun):
    code, modules = _modules(*sun)
    assert code == 0
    assert "maizeviz.light.engine" in modules               # the run did trace
    extra = [m for m in modules
             if any(m == p or m.startswith(p + ".") for p in NOT_ON_THE_SUN_PATH)]
    assert not extra, f"imported on the sun's path without being used: {extra}"
