"""Reading a large points file: seconds and peak memory, against the old reader.

Writes a points file of about ``--mb`` megabytes (200 by default): a synthetic 3 x 3 block
(``maizeviz.leaf.synth``) repeated with shifted plant ids. Each read runs in a fresh process and
reports its wall time and its peak resident memory above the interpreter with maizeviz
imported (``resource.getrusage``), and the ratio of that peak to the file size.

The anchor is the reader before streaming (the text read whole, then lists of lists), taken
from git at ``--anchor-rev`` and run on a file ``--anchor-mb`` megabytes large (it needs about
20 times the file in memory); the streaming reader runs on that file too, so the ratios
compare like with like. Absolute times mean little on a shared machine; the ratios do.

    python benchmarks/bench_read_points.py [--json] [--mb 200] [--anchor-mb 20]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import importlib.util, json, resource, sys, time
import numpy
import maizeviz.errors
which, path = sys.argv[1], sys.argv[2]
if which == "new":
    from maizeviz.io.points import read_points
else:
    spec = importlib.util.spec_from_file_location("old_points", which)
    mod = sys.modules["old_points"] = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    read_points = mod.read_points
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t0 = time.perf_counter()
table = read_points(path)
seconds = time.perf_counter() - t0
after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"seconds": seconds, "peak_bytes": (after - before) * 1024,
                  "points": len(table)}))
"""


def write_points_file(path: Path, megabytes: float) -> int:
    """A points file of about ``megabytes`` MB: a 3 x 3 block again and again, each copy with
    new plant ids. Returns its size in bytes."""
    from maizeviz.leaf.synth import block_grids

    rests = []                                   # (plant index in the block, rest of the line)
    for g in block_grids(3, 3):
        for r in range(g.points.shape[0]):
            row = g.points[r][:1] if r == g.points.shape[0] - 1 and g.tip_collapsed else g.points[r]
            for c, p in enumerate(row):
                rests.append((g.plant, f",{g.leaf},{r},{c},{p[0]:.3f},{p[1]:.3f},{p[2]:.3f}\n"))
    target = int(megabytes * 1e6)
    size = 0
    with path.open("w") as fh:
        fh.write("plant,leaf,row,col,x,y,z\n")
        copy = 0
        while size < target:
            text = "".join(f"{copy * 9 + pid}{rest}" for pid, rest in rests)
            fh.write(text)
            size += len(text)
            copy += 1
    return path.stat().st_size


def run_reader(which: str, path: Path) -> dict:
    """Read ``path`` in a fresh process with the new reader (``"new"``) or the module file
    ``which``; returns seconds, peak bytes above the start, points, and the peak per byte."""
    out = subprocess.run([sys.executable, "-c", CHILD, which, str(path)], capture_output=True,
                         text=True, cwd=ROOT)
    if out.returncode:
        raise SystemExit(f"the {which} reader failed: {out.stderr.strip()[-500:]}")
    res = json.loads(out.stdout.strip().splitlines()[-1])
    size = path.stat().st_size
    res.update(file_bytes=size, peak_per_file_byte=res["peak_bytes"] / size,
               mb_per_s=size / 1e6 / res["seconds"])
    return res


def old_module(rev: str, module: str, folder: Path) -> Path | None:
    """The file ``module`` (a path in the repository) as it was at ``rev``, written into
    ``folder`` (None without git)."""
    try:
        text = subprocess.run(["git", "show", f"{rev}:{module}"], cwd=ROOT,
                              capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    path = folder / f"old_{Path(module).name}"
    path.write_text(text)
    return path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--mb", type=float, default=200.0, help="size of the large file (MB)")
    ap.add_argument("--anchor-mb", type=float, default=20.0,
                    help="size of the file both readers read (MB)")
    ap.add_argument("--anchor-rev", default="21427d1",
                    help="git revision of the old reader (default: the last one before streaming)")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="bench-read-points-") as tmp:
        tmp = Path(tmp)
        small, large = tmp / "small.csv", tmp / "large.csv"
        write_points_file(small, args.anchor_mb)
        write_points_file(large, args.mb)
        result = {"large": run_reader("new", large), "small_new": run_reader("new", small)}
        old = old_module(args.anchor_rev, "maizeviz/io/points.py", tmp)
        if old is not None:
            result["small_old"] = run_reader(str(old), small)
            a, b = result["small_new"], result["small_old"]
            result["new_over_old"] = {"seconds": a["seconds"] / b["seconds"],
                                      "peak_memory": a["peak_bytes"] / b["peak_bytes"]}
        s, l = result["small_new"], result["large"]
        result["large_over_small"] = {"bytes": l["file_bytes"] / s["file_bytes"],
                                      "seconds": l["seconds"] / s["seconds"],
                                      "peak_memory": l["peak_bytes"] / s["peak_bytes"]}
    if args.json:
        print(json.dumps(result, indent=1))
        return 0
    for name in ("large", "small_new", "small_old"):
        if name in result:
            r = result[name]
            print(f"{name:10s} {r['file_bytes'] / 1e6:7.1f} MB  {r['points']:>10,} points  "
                  f"{r['seconds']:7.2f} s ({r['mb_per_s']:5.1f} MB/s)  peak "
                  f"{r['peak_bytes'] / 1e6:8.1f} MB = {r['peak_per_file_byte']:.2f} x the file")
    if "new_over_old" in result:
        r = result["new_over_old"]
        print(f"streaming / old at {args.anchor_mb:g} MB: time x{r['seconds']:.2f}, "
              f"peak memory x{r['peak_memory']:.3f}")
    r = result["large_over_small"]
    print(f"{args.mb:g} MB / {args.anchor_mb:g} MB: bytes x{r['bytes']:.1f}, time "
          f"x{r['seconds']:.1f}, peak memory x{r['peak_memory']:.1f} (linear: the same three)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
