"""maizeviz's Caribu-compatible light model against Caribu itself, on the same scenes.

Caribu's C++ core (``canestrad``, OpenAlea's ``alinea.caribu``; its sources are public) is not
a PyPI package: build it from its sources and give its path (``--canestrad`` or the
``MAIZEVIZ_CANESTRAD`` environment variable); docs/fspm.md says how it was built here. Each
scene is written as Caribu's files (``.can``, ``.light``, ``.opt``, ``.8``) by
:mod:`maizeviz.io.canestra`, run by ``canestrad`` (ray casting, ``-1``: first interception, the
way ``CaribuScene.run(direct=True)`` calls it) and by :class:`maizeviz.fspm.caribu.CaribuScene`
on the same files, and compared:

- **intercepted**: the light the triangles intercept, summed (energy over the pattern, or over
  the scene), each model's, and their ratio;
- **per label**: the area-weighted difference of each label's mean ``Ei`` (two triangles a
  label), relative to the mean ``Ei``: how far the two models' leaf values are apart;
- **seconds**: each model's wall time (Caribu's: the process, reading its files included;
  maizeviz's: the run, scene build included), and their ratio (the anchor is Caribu).

Scenes: a homogeneous canopy of square leaves (``--leaf`` cm) with spherical normals at LAI
``--lai`` in a 1 m pattern, infinite (``-8``) and isolated, and the bundled digitized 3 x 3 block
at the standard mesh, isolated; suns at 0, 30 and 60 deg zenith.

    python benchmarks/bench_caribu.py --canestrad /path/to/canestrad [--json]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "core"))
from anchors import report  # noqa: E402
from square_leaves import spherical_normals, square_corners  # noqa: E402

from maizeviz.fspm.caribu import CaribuScene  # noqa: E402
from maizeviz.io.canestra import encode_label, write_can, write_light, write_opt, write_pattern  # noqa: E402


def homogeneous(lai: float, leaf_cm: float, seed: int = 1) -> dict[str, np.ndarray]:
    """Square leaves (two triangles each) with spherical normals, uniformly placed in a 1 x 1 m
    pattern between 0.1 and 1.1 m; labels are Canestra barcodes (species 1, translucent)."""
    rng = np.random.default_rng(seed)
    side = leaf_cm / 100.0
    n = int(round(lai / side ** 2))
    c = np.column_stack([rng.random(n), rng.random(n), 0.1 + rng.random(n)])
    p = square_corners(c, spherical_normals(rng, n), side)
    tris = np.stack([p[:, [0, 1, 2]], p[:, [0, 2, 3]]], 1)          # (n, 2, 3, 3)
    return {encode_label(1, True, 1 + i // 999, 1 + i % 999): tris[i] for i in range(n)}


def digitized() -> dict[str, np.ndarray]:
    """The bundled 3 x 3 block at the standard mesh, in metres, a label per leaf."""
    import maizeviz as mv

    canopy = mv.build_canopy(mv.read_points(mv.example_points()).leaves, tile=(1, 1),
                             level="standard")
    tri = canopy.vertices[canopy.faces] / 100.0
    out: dict[str, list] = {}
    for t, p, lf in zip(tri, canopy.face_plant, canopy.face_leaf):
        out.setdefault(encode_label(1, True, int(p), int(lf)), []).append(t)
    return {k: np.array(v) for k, v in out.items()}


def run_caribu(canestrad: str, folder: Path, infinite: bool) -> tuple[dict, float]:
    cmd = [canestrad, "-M", "scene.can", "-l", "sun.light", "-p", "par.opt", "-A", "-1",
           "-L", "1536"] + (["-8", "pat.8"] if infinite else [])
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=folder, check=True, capture_output=True)
    seconds = time.perf_counter() - t0
    sums: dict[str, list[float]] = {}
    for line in (folder / "Etri.vec0").read_text().splitlines()[2:]:
        f = line.split()
        area, ei = float(f[2]), float(f[4]) + float(f[5])
        if area == 0:                # periodise leaves some triangles without area (NaN)
            continue
        s = sums.setdefault(f[1].zfill(12), [0.0, 0.0])
        s[0] += area
        s[1] += ei * area
    return {k: (a, e) for k, (a, e) in sums.items()}, seconds


def compare(scene: dict, zenith: float, infinite: bool, canestrad: str, density: float) -> dict:
    z = np.radians(zenith)
    light = [(1.0, (float(np.sin(z)), 0.0, float(-np.cos(z))))]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write_can(folder / "scene.can", scene)
        write_light(folder / "sun.light", light)
        write_opt(folder / "par.opt", 0.1, {1: (0.1, 0.05)})
        write_pattern(folder / "pat.8", (0, 0, 1, 1))
        t0 = time.perf_counter()
        ours_scene = CaribuScene(scene=str(folder / "scene.can"), light=str(folder / "sun.light"),
                                 opt=[str(folder / "par.opt")],
                                 pattern=str(folder / "pat.8") if infinite else None,
                                 density=density)
        _, agg = ours_scene.run(direct=True, infinite=infinite)
        t_ours = time.perf_counter() - t0
        # after maizeviz: canestrad rewrites scene.can in place for an infinite canopy
        theirs, t_caribu = run_caribu(canestrad, folder, infinite)
    area, ei = agg["par"]["area"], agg["par"]["Ei"]
    labels = sorted(theirs)
    ours_e = np.array([ei[k] * area[k] for k in labels])
    their_e = np.array([theirs[k][1] for k in labels])
    w = np.array([area[k] for k in labels])
    mean = their_e.sum() / w.sum()
    diff = np.abs(ours_e / w - their_e / np.array([theirs[k][0] for k in labels]))
    return {"intercepted_caribu": round(float(their_e.sum()), 4),
            "intercepted_maizeviz": round(float(ours_e.sum()), 4),
            "ratio": round(float(ours_e.sum() / their_e.sum()), 4),
            "per_label_mean_abs_diff": round(float((diff * w).sum() / w.sum() / mean), 4),
            "seconds_caribu": round(t_caribu, 3), "seconds_maizeviz": round(t_ours, 3),
            "time_ratio": round(t_ours / t_caribu, 3)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--canestrad", default=os.environ.get("MAIZEVIZ_CANESTRAD"))
    ap.add_argument("--lai", type=float, default=2.0)
    ap.add_argument("--leaf", type=float, default=2.0, help="leaf side, cm")
    ap.add_argument("--density", type=float, default=16.0, help="maizeviz's rays per cm2")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    if not args.canestrad or not Path(args.canestrad).exists():
        sys.exit("bench_caribu: give the path of a canestrad built from Caribu's sources "
                 "(--canestrad or MAIZEVIZ_CANESTRAD); docs/fspm.md says how")
    out: dict[str, object] = {}
    hom = homogeneous(args.lai, args.leaf)
    for zen in (0, 30, 60):
        for infinite in (True, False):
            key = f"homogeneous {'infinite' if infinite else 'isolated'} {zen} deg"
            out[key] = compare(hom, zen, infinite, args.canestrad, args.density)
    dig = digitized()
    for zen in (0, 30, 60):
        out[f"digitized block isolated {zen} deg"] = compare(dig, zen, False, args.canestrad,
                                                            args.density)
    report(out, args.json, width=40)


if __name__ == "__main__":
    main()
