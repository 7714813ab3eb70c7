"""Loops compiled from ``_loops.c`` (meshing and surface sampling), called through ctypes.

numpy computes a grid's triangle areas in some thirty passes over temporaries (subtract, square,
add, compare, cross, root...), each a trip through memory: at K = 4, 14,400 leaves' reference
areas took 0.58 s of CPU, the largest part of a coarse canopy's build. ``_loops.c`` makes the
same floating-point operations element by element in one pass and leaves the sums to numpy
(pairwise summation, whose order only numpy knows), so the numbers are numpy's to the bit
(``tests/core/test_loops.py``).

The loops are built when maizeviz is installed (``setup.py``, the extension module
``maizeviz._loops``). Where they are not (no C compiler at install, a module built from
another ``_loops.c``), :func:`grid_twice_areas` returns None and numpy does the work: the same
numbers, slower. ``MAIZEVIZ_LOOPS=0`` in the environment turns them off.

The B-spline basis of every surface fit and sample (The NURBS Book A2.2: a span search and
the Cox-de Boor recurrence, a dozen numpy passes over (L, A) arrays) is here too, point by
point, the same divisions, products and sums.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
from pathlib import Path

import numpy as np

SOURCE = Path(__file__).with_name("_loops.c")


def _lib() -> ctypes.CDLL | None:
    return _loaded()[0]


def why() -> str:
    """Why numpy does the compiled loops' work ("" when the compiled loops do it)."""
    return _loaded()[1]


@functools.cache
def _loaded() -> tuple[ctypes.CDLL | None, str]:
    from maizeviz.environment import switch

    if not switch("MAIZEVIZ_LOOPS"):
        return None, "turned off by MAIZEVIZ_LOOPS=0"
    try:
        from maizeviz import _loops as ext
    except ImportError:
        return None, "not built when maizeviz was installed (no C compiler?)"
    if SOURCE.is_file() and \
            hashlib.sha256(SOURCE.read_bytes()).hexdigest() != ext.source_sha256:
        return None, ("built from another _loops.c: rebuild it (pip install -e . or "
                      "scripts/setup.sh)")
    try:
        lib = ctypes.CDLL(str(ext.__file__))
    except OSError as exc:  # pragma: no cover - it was imported a moment ago
        return None, f"{ext.__file__} does not load through ctypes ({exc})"
    p, i64, f64 = ctypes.c_void_p, ctypes.c_int64, ctypes.c_double
    lib.mz_grid_twice_areas.restype = ctypes.c_int
    lib.mz_grid_twice_areas.argtypes = [p, i64, i64, i64, f64, p, p]
    lib.mz_chord_errors.restype = ctypes.c_int
    lib.mz_chord_errors.argtypes = [p, p, p, i64, i64, i64, p, p, p, p, p]
    lib.mz_basis_matrix.restype = ctypes.c_int
    lib.mz_basis_matrix.argtypes = [p, p, i64, i64, i64, i64, p]
    return lib, ""


def available() -> bool:
    """Whether the compiled loops are used (else numpy's own passes)."""
    return _lib() is not None


def grid_twice_areas(vertices: np.ndarray, rel_tol: float,
                     out: tuple[np.ndarray, np.ndarray] | None = None
                     ) -> tuple[np.ndarray, np.ndarray] | None:
    """Twice the area (cm2) of each triangle of vertex grids, as ``_grid_areas`` computes them.

    Parameters
    ----------
    vertices : (L, a, b, 3) float64, cm (copied if not C-contiguous), a, b >= 2
    rel_tol : a triangle with a grid edge no longer than ``rel_tol`` times its grid's longest
        edge counts 0
    out : two C-contiguous float64 arrays of at least L (a - 1) (b - 1) values to write into
        (their first ones, shaped as returned), or None for new ones

    Returns
    -------
    first, second : (L, (a - 1) (b - 1)) float64, cm2: the triangles (p00, p10, p11) and
    (p00, p11, p01) of each quad, row by row; None where the loops are not built.
    """
    lib = _lib()
    if lib is None:
        return None
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    nl, a, b = v.shape[:3]
    q = (a - 1) * (b - 1)
    if out is None:
        first, second = np.empty((nl, q)), np.empty((nl, q))
    else:
        first, second = (o.reshape(-1)[:nl * q].reshape(nl, q) for o in out)
    if lib.mz_grid_twice_areas(v.ctypes.data, nl, a, b, rel_tol**2, first.ctypes.data,
                               second.ctypes.data) != 0:
        raise MemoryError("no memory for a grid's edges")   # pragma: no cover - a few kB
    return first, second


def chord_errors(coords: tuple[np.ndarray, ...], leaf: np.ndarray, line: np.ndarray,
                 lo: np.ndarray, hi: np.ndarray) -> np.ndarray | None:
    """Largest distance (cm) of each line's points from the chords between two other lines,
    as ``simplify._segment_distance(...).max(axis=-1)`` computes it.

    Parameters
    ----------
    coords : three (L, m, n) float64 arrays, cm: the grids' x, y, z (copied if not
        C-contiguous)
    leaf, line, lo, hi : (R,) integers: line ``line[r]`` of grid ``leaf[r]`` measured from the
        chords joining its lines ``lo[r]`` and ``hi[r]`` point by point

    Returns
    -------
    (R,) float64, cm; None where the loops are not built.
    """
    lib = _lib()
    if lib is None:
        return None
    x, y, z = (np.ascontiguousarray(c, dtype=np.float64) for c in coords)
    _, m, n = x.shape
    idx = [np.ascontiguousarray(i, dtype=np.int64) for i in (leaf, line, lo, hi)]
    out = np.empty(len(idx[0]))
    if lib.mz_chord_errors(x.ctypes.data, y.ctypes.data, z.ctypes.data, m, n, len(out),
                           *(i.ctypes.data for i in idx), out.ctypes.data) != 0:
        raise MemoryError("no memory for a line's distances")  # pragma: no cover - bytes
    return out


def basis_matrix(x: np.ndarray, knots: np.ndarray, degree: int) -> np.ndarray | None:
    """Dense B-spline basis values, as :func:`maizeviz.leaf.nurbs.basis_matrix` computes them.

    Parameters
    ----------
    x : (L, A) float64 in [0, 1]
    knots : (L, K) float64, clamped, increasing
    degree : int, 0 to 15

    Returns
    -------
    (L, A, K - degree - 1) float64; None where the loops are not built (or past degree 15).
    """
    lib = _lib()
    if lib is None or not 0 <= degree <= 15:
        return None
    x = np.ascontiguousarray(x, dtype=np.float64)
    k = np.ascontiguousarray(knots, dtype=np.float64)
    nl, na = x.shape
    out = np.empty((nl, na, k.shape[1] - degree - 1))
    lib.mz_basis_matrix(x.ctypes.data, k.ctypes.data, nl, na, k.shape[1], degree,
                        out.ctypes.data)
    return out
