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
