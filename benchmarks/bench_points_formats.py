"""Reading the points of 900 distinct plants (``maizeviz synth --plants 30x30``: 14,400 leaves,
a 27 MB CSV) as CSV and as Parquet, against ``pandas.read_csv`` of the same CSV (issue 30:
within 3x).

In one process, pandas and pyarrow imported first, each reader timed in turns, best of
``--repeat`` (wall seconds): ``maizeviz.io.points.read_points`` on the CSV and on the Parquet
file, ``pandas.read_csv`` (the anchor) and ``pyarrow.parquet.read_table``. Also checks that the
two files give the same table. A fresh process's first CSV read also imports pyarrow (about
0.3 s; files under ``COLUMNAR_BYTES`` go through numpy instead).

    python benchmarks/bench_points_formats.py [--json] [--plants 30x30] [--repeat 5]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from anchors import report


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--plants", default="30x30")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    import pandas as pd
    import pyarrow.csv  # noqa: F401 - imported before timing, as pandas is
    import pyarrow.parquet as pq

    from maizeviz.canopy.layout import parse_shape
    from maizeviz.io.points import read_points, write_points
    from maizeviz.leaf.synth import block_grids

    rows, per_row = parse_shape(args.plants, "plants")
    grids = block_grids(rows, per_row)
    out: dict = {"leaves": len(grids)}
    with tempfile.TemporaryDirectory() as tmp:
        csv, parquet = Path(tmp) / "points.csv", Path(tmp) / "points.parquet"
        t0 = time.perf_counter()
        write_points(csv, grids)
        out["write_csv_s"] = round(time.perf_counter() - t0, 3)
        t0 = time.perf_counter()
        write_points(parquet, grids)
        out["write_parquet_s"] = round(time.perf_counter() - t0, 3)
        out["csv_mb"] = round(csv.stat().st_size / 1e6, 1)
        out["parquet_mb"] = round(parquet.stat().st_size / 1e6, 1)
        a, b = read_points(csv), read_points(parquet)
        out["same_table"] = bool(np.array_equal(a.ids, b.ids) and np.array_equal(a.xyz, b.xyz))
        readers = {"pandas_read_csv": lambda: pd.read_csv(csv),
                   "read_points_csv": lambda: read_points(csv),
                   "pyarrow_read_parquet": lambda: pq.read_table(parquet),
                   "read_points_parquet": lambda: read_points(parquet)}
        best = dict.fromkeys(readers, float("inf"))
        for _ in range(args.repeat):
            for name, fn in readers.items():
                t0 = time.perf_counter()
                fn()
                best[name] = min(best[name], time.perf_counter() - t0)
    out.update({f"{k}_s": round(v, 4) for k, v in best.items()})
    out["csv_over_pandas"] = round(best["read_points_csv"] / best["pandas_read_csv"], 2)
    out["parquet_over_pandas"] = round(best["read_points_parquet"] / best["pandas_read_csv"], 2)
    out["target"] = "csv_over_pandas <= 3"
    report(out, args.json)


if __name__ == "__main__":
    main()
