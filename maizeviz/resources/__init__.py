"""Data shipped with maizeviz, installed as the package ``maizeviz.resources``.

- ``block3x3.csv``: a synthetic digitized 3 x 3 block of maize plants at silking (``maizeviz
  synth --plants 3x3 --seed 7``), 140 leaves, points format, cm: the bundled example.
- ``phenotrack3d/1649057232.json.gz``: one real maize plant segmented by the Phenomenal pipeline
  (PhenoTrack3D, CeCILL-C; see ``phenotrack3d/README.md``).
- ``sweep-example.toml``: a small scenario sweep over the bundled block.

Files are found through :mod:`importlib.resources`, so they work from a wheel as from a
checkout, whatever the current folder.
"""

from __future__ import annotations

import atexit
import contextlib
from importlib import resources
from pathlib import Path

_extracted = contextlib.ExitStack()
atexit.register(_extracted.close)


def resource_path(name: str) -> Path:
    """A real file path for a bundled resource (``"block3x3.csv"``, ``"phenotrack3d/..."``).

    Installed packages keep their data as plain files, so this is normally the file inside
    site-packages; from a zip import it is a temporary copy kept until the process ends.
    """
    ref = resources.files(__name__).joinpath(*name.split("/"))
    if not ref.is_file():
        raise FileNotFoundError(f"maizeviz resource '{name}' is not installed")
    if isinstance(ref, Path):
        return ref
    return Path(_extracted.enter_context(resources.as_file(ref)))


def example_points() -> Path:
    """The bundled example: a digitized 3 x 3 block (points CSV, cm)."""
    return resource_path("block3x3.csv")


def example_phenomenal() -> Path:
    """The bundled real plant (Phenomenal JSON, gzip, mm)."""
    return resource_path("phenotrack3d/1649057232.json.gz")
