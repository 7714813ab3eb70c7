"""The API reference (docs/api) builds from the numpydoc docstrings with the tutorial as its
worked example, warnings as errors, and names every export of ``import maizeviz as mv``."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("sphinx")
pytest.importorskip("numpydoc")
pytest.importorskip("myst_parser")

import maizeviz as mv  # noqa: E402

API = Path(__file__).resolve().parents[2] / "docs" / "api"


def test_the_reference_page_names_every_export():
    text = (API / "reference.rst").read_text()
    named = set(re.findall(r"^\.\. auto\w+:: (\w+)$", text, re.M))
    exports = set(mv.__all__) - {"__version__"}
    assert exports - named == set(), "exports the API reference does not show"
    assert named - exports == set(), "names the API reference shows that are not exported"


def test_the_api_reference_builds_without_a_warning(tmp_path):
    done = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b",
                           "html", str(API), str(tmp_path)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    reference = (tmp_path / "reference.html").read_text()
    for name in set(mv.__all__) - {"__version__"}:
        assert f'id="maizeviz.{name}"' in reference, name
    assert 'id="maizeviz.LightEngine.sun"' in reference        # a class's methods too
    tutorial = (tmp_path / "tutorial.html").read_text()
    assert "Tutorial: from a points file to light tables" in tutorial
    assert tutorial.count('class="highlight-python') >= 5      # its cells, as code
