"""Reading a sweep file of 10,000 scenarios: ``load_spec`` against the hashing it cannot avoid.

The file: 2 points files x 2 tilings x 5 mesh levels x 50 suns x 5 ray densities x 2 optics
= 10,000 scenarios. ``load_spec`` checks every key against the declared schema
(``maizeviz.sweep.schema``), then lists and keys the scenarios. Printed:

- ``load_spec_s``: best of ``--repeat`` calls (the schema's import is not counted);
- ``cold_load_spec_s``: the first call in a fresh interpreter (maizeviz.sweep.spec imported
  before the clock starts; pydantic and the schema's models are read by the call), median of
  three processes;
- ``validate_s``: the schema's check alone, on the parsed TOML (its share: ``validate_share``);
- ``anchor_s``: the sha256 of the 10,000 scenarios' key inputs as JSON, the work every reader
  of this file has to do; ``load_spec_over_anchor`` is the figure to compare across machines;
- with ``--against REV`` (a git revision, e.g. the last one with the hand-written checker,
  ``e2766fe``), that revision's ``maizeviz/sweep/spec.py`` timed in the same run on the same
  file, and ``over_against``: this one's time over it (target: at most 1.5), also cold
  (``cold_over_against``).

    python benchmarks/bench_sweep_spec.py [--json] [--repeat 5] [--against e2766fe]
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import json
import statistics
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

from anchors import best, report

from maizeviz.sweep.spec import load_spec

ROOT = Path(__file__).resolve().parents[1]


def write_sweep(folder: Path) -> Path:
    """A sweep file of 10,000 scenarios and its two (tiny: only hashed) points files."""
    (folder / "a.csv").write_text("plant,leaf\n1,1\n")
    (folder / "b.csv").write_text("plant,leaf\n2,2\n")
    suns = ", ".join(f"{{zenith = {z}, azimuth = {a}}}" for z in range(0, 50, 2)
                     for a in (90, 180))
    text = ('[canopy]\npoints = ["a.csv", "b.csv"]\ntile = ["1x1", "3x3"]\n'
            'level = ["K4", "standard", "36", "8", "16"]\n'
            f'[light]\nsun = [{suns}]\ndensity = [1, 2, 4, 8, 16]\n'
            'optics = ["black", {band = "par"}]\nheights = [0, 50, 100]\n')
    path = folder / "big.toml"
    path.write_text(text)
    return path


COLD = """
import importlib.util, sys, time
if sys.argv[2]:
    spec = importlib.util.spec_from_file_location("old_spec", sys.argv[2])
    module = importlib.util.module_from_spec(spec)
    sys.modules["old_spec"] = module
    spec.loader.exec_module(module)
else:
    import maizeviz.sweep.spec as module
t0 = time.perf_counter()
module.load_spec(sys.argv[1], yes=True)
print(time.perf_counter() - t0)
"""


def cold(path: Path, old_spec: Path | None = None) -> float:
    """Seconds of the first ``load_spec`` in a fresh interpreter, median of three."""
    times = [float(subprocess.run([sys.executable, "-c", COLD, str(path), str(old_spec or "")],
                                  capture_output=True, text=True, check=True).stdout)
             for _ in range(3)]
    return statistics.median(times)


def old_spec_file(rev: str) -> Path:
    """``maizeviz/sweep/spec.py`` at git revision ``rev``, in a temporary folder."""
    text = subprocess.run(["git", "show", f"{rev}:maizeviz/sweep/spec.py"], cwd=ROOT,
                          capture_output=True, text=True, check=True).stdout
    path = Path(tempfile.mkdtemp()) / "old_spec.py"
    path.write_text(text)
    return path


def old_loader(path: Path):
    """``load_spec`` of an older ``spec.py`` file."""
    spec = importlib.util.spec_from_file_location("old_spec", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["old_spec"] = module                        # its dataclasses look it up
    spec.loader.exec_module(module)
    return module.load_spec


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--repeat", type=int, default=5, help="best of N (default 5)")
    ap.add_argument("--against", metavar="REV", help="also time spec.py of this git revision")
    args = ap.parse_args()
    from maizeviz.sweep import spec as spec_module
    from maizeviz.sweep.schema import validate

    path = write_sweep(Path(tempfile.mkdtemp(prefix="bench_sweep_spec_")))
    spec = load_spec(path, yes=True)                         # imports the schema, warms up
    doc = tomllib.loads(path.read_text())
    inputs = [spec_module._scenario_inputs(
        spec_module._group_inputs(s.points, s.arrangement, s.level, s.preserve_area,
                                  s.cover_resolution), s.sun, s.density, s.periodic,
        s.heights_cm, s.rect_cm, s.optics, s.photosynthesis) for s in spec.scenarios]

    def anchor():
        for full in inputs:
            hashlib.sha256(json.dumps(full, sort_keys=True, separators=(",", ":"),
                                      default=str).encode()).hexdigest()

    out = {"scenarios": len(spec.scenarios),
           "load_spec_s": best(lambda: load_spec(path, yes=True), args.repeat),
           "validate_s": best(lambda: validate(doc, str(path), path.parent), args.repeat),
           "anchor_s": best(anchor, args.repeat)}
    out["validate_share"] = out["validate_s"] / out["load_spec_s"]
    out["load_spec_over_anchor"] = out["load_spec_s"] / out["anchor_s"]
    out["cold_load_spec_s"] = cold(path)
    if args.against:
        old_file = old_spec_file(args.against)
        old = old_loader(old_file)
        assert [s.key for s in old(path, yes=True).scenarios] == [s.key for s in spec.scenarios]
        out["against"] = args.against
        out["against_load_spec_s"] = best(lambda: old(path, yes=True), args.repeat)
        out["over_against"] = out["load_spec_s"] / out["against_load_spec_s"]
        out["against_cold_load_spec_s"] = cold(path, old_file)
        out["cold_over_against"] = out["cold_load_spec_s"] / out["against_cold_load_spec_s"]
    report(out, args.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
