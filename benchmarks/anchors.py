"""The anchor the benchmarks divide by: a fixed piece of numpy work timed in the same run.

Ratios against it travel between machines and loads better than seconds do.
"""

from __future__ import annotations

import time

import numpy as np


def matmul_anchor() -> float:
    """Seconds for 20 products of a 400 x 400 matrix with itself (renormalised each time)."""
    a = np.random.default_rng(0).random((400, 400))
    t0 = time.perf_counter()
    for _ in range(20):
        a = a @ a
        a /= np.abs(a).max()
    return time.perf_counter() - t0


def best(fn, repeat: int = 3) -> float:
    """Shortest of ``repeat`` timed calls of ``fn()``, seconds."""
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return min(out)


def report(out: dict, as_json: bool, width: int = 28) -> None:
    """Print a benchmark's results: JSON, or one ``name: value`` line each."""
    if as_json:
        import json

        print(json.dumps(out, indent=1))
    else:
        for k, v in out.items():
            print(f"{k:>{width}}: {v}")
