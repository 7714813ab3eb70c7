"""Square leaves about given centres and normals: the homogeneous canopies the light tests
draw (test_scatter, test_leaf_invariants, test_caribu, benchmarks/bench_caribu)."""

from __future__ import annotations

import numpy as np


def square_corners(centre: np.ndarray, normal: np.ndarray, side: float) -> np.ndarray:
    """(n, 4, 3) corners, in order around each square, of squares of edge ``side`` centred at
    ``centre`` (n, 3) and facing the unit ``normal`` (n, 3), in the units of ``centre``."""
    helper = np.where(np.abs(normal[:, :1]) > 0.9, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
    t1 = np.cross(normal, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normal, t1)
    h = side / 2
    return np.stack([centre - h * t1 - h * t2, centre + h * t1 - h * t2,
                     centre + h * t1 + h * t2, centre - h * t1 + h * t2], axis=1)


def spherical_normals(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 3) unit normals uniform on the sphere (a spherical leaf angle distribution)."""
    normal = rng.normal(size=(n, 3))
    return normal / np.linalg.norm(normal, axis=1, keepdims=True)
