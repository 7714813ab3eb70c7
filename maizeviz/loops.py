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
numbers, slower, said once a process (a RuntimeWarning, and ``maizeviz --info``).
``MAIZEVIZ_LOOPS=0`` in the environment turns them off without a word.

The B-spline basis of every surface fit and sample (The NURBS Book A2.2: a span search and
the Cox-de Boor recurrence, a dozen numpy passes over (L, A) arrays) is here too, point by
point, the same divisions, products and sums.

C trusts what it is handed: a knot vector too short for its degree, an index past a grid or
an ``out`` buffer of another type would be read or written outside its memory. Each wrapper
therefore checks its arguments first (:func:`check_grids`, :func:`check_chords`,
:func:`check_basis`: shapes, dtypes, contiguity, knot counts against the degree, index
ranges, out buffers) and refuses in one line, a ValueError naming the argument; the numpy
paths call the same checks, so both refuse alike (``tests/core/test_loops_fuzz.py``). The C
functions check the counts and indices again, where that costs a comparison, and write
nothing when they refuse.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import threading
import warnings
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
        return None, ("not built when maizeviz was installed (no C compiler?): reinstall "
                      "maizeviz with a C compiler to build them")
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
    lib.mz_chord_errors.argtypes = [p, p, p, i64, i64, i64, i64, p, p, p, p, p]
    lib.mz_basis_matrix.restype = ctypes.c_int
    lib.mz_basis_matrix.argtypes = [p, p, i64, i64, i64, i64, p]
    for name in ("mz_repeated_triangles", "mz_triangle_areas"):
        getattr(lib, name).restype = ctypes.c_int
    lib.mz_repeated_triangles.argtypes = [p, i64, p, i64, p, p]
    lib.mz_triangle_areas.argtypes = [p, i64, p, i64, p, p]
    return lib, ""


_warned = threading.Lock()
_said = False


def warn_fallback() -> None:
    """Say once a process that numpy does the compiled loops' work, and why (not when
    ``MAIZEVIZ_LOOPS=0`` turned them off: a choice)."""
    global _said
    why = _loaded()[1]
    if not why or why.startswith("turned off"):
        return
    with _warned:
        if _said:
            return
        _said = True
    warnings.warn(f"maizeviz: computing surface bases, reference areas and splitting with "
                  f"numpy (the same numbers, slower): the compiled loops were {why}",
                  RuntimeWarning, stacklevel=4)


def available() -> bool:
    """Whether the compiled loops are used (else numpy's own passes)."""
    return _lib() is not None


def _real(a, name: str, ndim: int | None = None) -> np.ndarray:
    """``a`` as an array of real numbers (not copied), refused in one line naming ``name``
    unless it is one (booleans, integers and floats are; objects, text, complex are not) of
    ``ndim`` dimensions."""
    try:
        arr = np.asarray(a)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{name}: not an array of numbers ({exc})") from None
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"{name}: numbers expected, not {arr.dtype} values")
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name}: {ndim} dimensions expected, not {arr.ndim} "
                         f"(shape {arr.shape})")
    return arr


def check_grids(vertices, out=None) -> np.ndarray:
    """Vertex grids as :func:`grid_twice_areas` hands them to C: (L, a, b, 3) real numbers,
    a, b >= 2, as C-contiguous float64 (a copy where they are not); ``out``, if given, two
    writable C-contiguous float64 arrays of at least L (a - 1) (b - 1) values each, not
    sharing memory. ValueError in one line naming the argument otherwise."""
    v = _real(vertices, "vertices", 4)
    if v.shape[3] != 3 or v.shape[1] < 2 or v.shape[2] < 2:
        raise ValueError(f"vertices: grids (L, a, b, 3) with a, b >= 2 expected, not shape "
                         f"{v.shape}")
    if out is not None:
        need = v.shape[0] * (v.shape[1] - 1) * (v.shape[2] - 1)
        if not isinstance(out, (tuple, list)) or len(out) != 2:
            raise ValueError("out: two arrays (first, second) expected")
        for k, o in enumerate(out):
            where = f"out[{k}]"
            if not isinstance(o, np.ndarray):
                raise ValueError(f"{where}: a numpy array expected, not {type(o).__name__}")
            if o.dtype != np.float64:
                raise ValueError(f"{where}: float64 expected, not {o.dtype}")
            if not o.flags.c_contiguous or not o.flags.writeable:
                raise ValueError(f"{where}: a writable C-contiguous array expected")
            if o.size < need:
                raise ValueError(f"{where}: {o.size} values, fewer than the {need} triangles "
                                 "of the grids")
        if np.shares_memory(out[0], out[1]):
            raise ValueError("out: the two arrays share memory")
    return np.ascontiguousarray(v, dtype=np.float64)


def check_chords(coords, leaf, line, lo, hi) -> tuple[tuple[np.ndarray, ...], list[np.ndarray]]:
    """The arguments of :func:`chord_errors` as C takes them: three (L, m, n) arrays of real
    numbers of one shape, n >= 1 (C-contiguous float64, copied where not), and four (R,)
    integer index arrays, each within its axis (0 <= leaf < L; line, lo, hi in [0, m)).
    ValueError in one line naming the argument otherwise (numpy's negative indices too: a
    line counted from the end is not what a splitting means)."""
    if not isinstance(coords, (tuple, list)) or len(coords) != 3:
        raise ValueError("coords: three arrays (x, y, z) expected")
    xyz = [_real(c, f"coords[{k}]", 3) for k, c in enumerate(coords)]
    if any(c.shape != xyz[0].shape for c in xyz):
        raise ValueError(f"coords: x, y, z of one shape expected, not "
                         f"{', '.join(str(c.shape) for c in xyz)}")
    nl, m, n = xyz[0].shape
    if n < 1:
        raise ValueError(f"coords: lines of at least one point expected, not shape "
                         f"{xyz[0].shape}")
    idx = []
    for name, a, size in (("leaf", leaf, nl), ("line", line, m), ("lo", lo, m), ("hi", hi, m)):
        arr = _real(a, name, 1)
        if arr.dtype.kind not in "iu":
            raise ValueError(f"{name}: integer indices expected, not {arr.dtype}")
        if len(arr) != len(np.asarray(leaf).reshape(-1)):
            raise ValueError(f"{name}: {len(arr)} indices for {np.size(leaf)} leaves")
        if len(arr) and (arr.min() < 0 or arr.max() >= size):
            bad = arr[(arr < 0) | (arr >= size)][0]
            raise ValueError(f"{name}: index {bad} outside 0..{size - 1}")
        idx.append(np.ascontiguousarray(arr, dtype=np.int64))
    return tuple(np.ascontiguousarray(c, dtype=np.float64) for c in xyz), idx


def check_basis(x, knots, degree) -> tuple[np.ndarray, np.ndarray, int]:
    """The arguments of a B-spline basis (:func:`basis_matrix`, and numpy's
    :func:`maizeviz.leaf.nurbs.basis_values`): points x (L, A) and knots (L, K) of real numbers
    with the same L, a whole degree >= 0, at least 2 (degree + 1) knots a row (a clamped
    vector: degree + 1 at each end), each row non-decreasing. Returned as C-contiguous float64
    (copies where not) and an int. ValueError in one line naming the argument otherwise."""
    if isinstance(degree, (bool, np.bool_)) or not isinstance(degree, (int, np.integer)):
        raise ValueError(f"degree: a whole number expected, not {degree!r}")
    degree = int(degree)
    if degree < 0:
        raise ValueError(f"degree: {degree} is negative")
    xa = _real(x, "x", 2)
    k = _real(knots, "knots", 2)
    if k.shape[0] != xa.shape[0]:
        raise ValueError(f"knots: {k.shape[0]} rows for {xa.shape[0]} rows of points")
    if k.shape[1] < 2 * (degree + 1):
        raise ValueError(f"knots: {k.shape[1]} a row, fewer than the 2 (degree + 1) = "
                         f"{2 * (degree + 1)} of a clamped vector of degree {degree}")
    k = np.ascontiguousarray(k, dtype=np.float64)
    if k.size and not np.all(k[:, 1:] >= k[:, :-1]):
        row = int(np.flatnonzero(~np.all(k[:, 1:] >= k[:, :-1], axis=1))[0])
        raise ValueError(f"knots: row {row} is not non-decreasing (or holds NaN)")
    return np.ascontiguousarray(xa, dtype=np.float64), k, degree


def grid_twice_areas(vertices: np.ndarray, rel_tol: float,
                     out: tuple[np.ndarray, np.ndarray] | None = None
                     ) -> tuple[np.ndarray, np.ndarray] | None:
    """Twice the area (cm2) of each triangle of vertex grids, as ``_grid_areas`` computes them.

    Parameters
    ----------
    vertices : (L, a, b, 3) real numbers, cm (copied as float64 if not C-contiguous float64),
        a, b >= 2
    rel_tol : a triangle with a grid edge no longer than ``rel_tol`` times its grid's longest
        edge counts 0
    out : two writable C-contiguous float64 arrays of at least L (a - 1) (b - 1) values to
        write into (their first ones, shaped as returned), or None for new ones

    Returns
    -------
    first, second : (L, (a - 1) (b - 1)) float64, cm2: the triangles (p00, p10, p11) and
    (p00, p11, p01) of each quad, row by row; None where the loops are not built.

    Raises
    ------
    ValueError
        In one line naming the argument (:func:`check_grids`), built or not.
    """
    v = check_grids(vertices, out)
    lib = _lib()
    if lib is None:
        warn_fallback()
        return None
    nl, a, b = v.shape[:3]
    q = (a - 1) * (b - 1)
    if out is None:
        first, second = np.empty((nl, q)), np.empty((nl, q))
    else:
        first, second = (o.reshape(-1)[:nl * q].reshape(nl, q) for o in out)
    rc = lib.mz_grid_twice_areas(v.ctypes.data, nl, a, b, float(rel_tol)**2,
                                 first.ctypes.data, second.ctypes.data)
    _check(rc, "grid_twice_areas")
    return first, second


def _check(rc: int, name: str) -> None:
    """Raise for a loop's error code (0: done; -2: refused its counts, which the checks above
    should have refused first; -3: out of memory)."""
    if rc == -3:  # pragma: no cover - a few kB
        raise MemoryError(f"{name}: out of memory")
    if rc != 0:  # pragma: no cover - the wrapper's checks come first
        raise ValueError(f"{name}: the compiled loop refused its arguments ({rc})")


def chord_errors(coords: tuple[np.ndarray, ...], leaf: np.ndarray, line: np.ndarray,
                 lo: np.ndarray, hi: np.ndarray) -> np.ndarray | None:
    """Largest distance (cm) of each line's points from the chords between two other lines,
    as ``simplify._segment_distance(...).max(axis=-1)`` computes it.

    Parameters
    ----------
    coords : three (L, m, n) arrays of real numbers, cm, n >= 1: the grids' x, y, z (copied
        as float64 if not C-contiguous float64)
    leaf, line, lo, hi : (R,) integers: line ``line[r]`` of grid ``leaf[r]`` measured from the
        chords joining its lines ``lo[r]`` and ``hi[r]`` point by point; 0 <= leaf < L, the
        others in [0, m)

    Returns
    -------
    (R,) float64, cm; None where the loops are not built.

    Raises
    ------
    ValueError
        In one line naming the argument (:func:`check_chords`), built or not.
    """
    (x, y, z), idx = check_chords(coords, leaf, line, lo, hi)
    lib = _lib()
    if lib is None:
        warn_fallback()
        return None
    nl, m, n = x.shape
    out = np.empty(len(idx[0]))
    rc = lib.mz_chord_errors(x.ctypes.data, y.ctypes.data, z.ctypes.data, nl, m, n, len(out),
                             *(i.ctypes.data for i in idx), out.ctypes.data)
    _check(rc, "chord_errors")
    return out


def basis_matrix(x: np.ndarray, knots: np.ndarray, degree: int) -> np.ndarray | None:
    """Dense B-spline basis values, as :func:`maizeviz.leaf.nurbs.basis_matrix` computes them.

    Parameters
    ----------
    x : (L, A) float64 in [0, 1]
    knots : (L, K) float64, clamped, non-decreasing, K >= 2 (degree + 1)
    degree : int, 0 to 15

    Returns
    -------
    (L, A, K - degree - 1) float64; None where the loops are not built (or past degree 15).

    Raises
    ------
    ValueError
        In one line naming the argument (:func:`check_basis`), built or not.
    """
    x, k, degree = check_basis(x, knots, degree)
    lib = _lib()
    if lib is None:
        warn_fallback()
    if lib is None or degree > 15:
        return None
    nl, na = x.shape
    out = np.empty((nl, na, k.shape[1] - degree - 1))
    rc = lib.mz_basis_matrix(x.ctypes.data, k.ctypes.data, nl, na, k.shape[1], degree,
                             out.ctypes.data)
    _check(rc, "basis_matrix")
    return out


def check_mesh(vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    """A mesh as :func:`repeated_triangles` and :func:`triangle_areas` hand it to C: vertices
    (V, 3) real numbers as C-contiguous float64, faces (T, 3) integers as C-contiguous int64,
    each index in [0, V) (copies where they are not). ValueError in one line naming the
    argument otherwise (numpy's negative indices too: a corner counted from the end is not
    what a mesh file means)."""
    v = _real(vertices, "vertices", 2)
    f = _real(faces, "faces", 2)
    if v.shape[1] != 3:
        raise ValueError(f"vertices: (V, 3) expected, not shape {v.shape}")
    if f.shape[1] != 3 or f.dtype.kind not in "iu":
        raise ValueError(f"faces: (T, 3) integer indices expected, not {f.dtype} of shape "
                         f"{f.shape}")
    f = np.ascontiguousarray(f, dtype=np.int64)
    if f.size and (f.min() < 0 or f.max() >= len(v)):
        bad = f[(f < 0) | (f >= len(v))][0]
        raise ValueError(f"faces: vertex index {bad} outside 0..{len(v) - 1}")
    return np.ascontiguousarray(v, dtype=np.float64), f


def _mesh_for_c(vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    """``vertices`` and ``faces`` as C takes them, checked in full only where C refuses them
    (C checks the indices in a pass of its own, cheaper than numpy's two)."""
    v, f = np.asarray(vertices), np.asarray(faces)
    if (v.dtype == np.float64 and f.dtype == np.int64 and v.ndim == 2 and f.ndim == 2
            and v.shape[1] == 3 and f.shape[1] == 3 and v.flags.c_contiguous
            and f.flags.c_contiguous):
        return v, f
    return check_mesh(v, f)


def _mesh_and_loops(vertices, faces):
    """The mesh as C takes it (:func:`_mesh_for_c`) and the loaded loops; the loops None where
    they are not built, the mesh then checked in full and the fallback said."""
    v, f = _mesh_for_c(vertices, faces)
    lib = _lib()
    if lib is None:
        check_mesh(v, f)
        warn_fallback()
    return v, f, lib


def _mesh_call_done(rc: int, v: np.ndarray, f: np.ndarray, name: str) -> None:
    """Raise for a mesh function's return code: an index C refused (-2) named by
    :func:`check_mesh`, any other failure by :func:`_check`."""
    if rc == -2:
        check_mesh(v, f)                     # says which index
    _check(rc, name)


def repeated_triangles(vertices: np.ndarray, faces: np.ndarray, used: bool = False
                       ) -> tuple[np.ndarray, np.ndarray | None] | None:
    """(T,) bool: the triangles whose three corners (by position, -0.0 as 0.0, in any order)
    are those of an earlier triangle, as :func:`maizeviz.canopy.from_mesh.repeated_triangles`
    finds them; and, if ``used``, the vertices the triangles use, read in the same pass.

    Parameters
    ----------
    vertices : (V, 3) real numbers
    faces : (T, 3) integers in [0, V), T < 2^31
    used : whether to say which vertices the faces use

    Returns
    -------
    repeat : (T,) bool
    used : (V,) bool, or None unless ``used``
    None where the loops are not built (or T is 2^31 or more).

    Raises
    ------
    ValueError
        In one line naming the argument (:func:`check_mesh`).
    """
    v, f, lib = _mesh_and_loops(vertices, faces)
    if lib is None or len(f) >= 2**31 - 1:
        return None
    out = np.empty(len(f), np.uint8)
    seen = np.empty(len(v), np.uint8) if used else None
    rc = lib.mz_repeated_triangles(v.ctypes.data, len(v), f.ctypes.data, len(f),
                                   out.ctypes.data, None if seen is None else seen.ctypes.data)
    _mesh_call_done(rc, v, f, "repeated_triangles")
    return out.view(bool), None if seen is None else seen.view(bool)


def triangle_areas(vertices: np.ndarray, faces: np.ndarray, centres: bool = False
                   ) -> tuple[np.ndarray, np.ndarray | None] | None:
    """Areas of triangles and their centroids seen from above, as
    ``maizeviz.canopy.from_mesh._areas_centres`` computes them (numpy's numbers to the bit).

    Parameters
    ----------
    vertices : (V, 3) real numbers, cm
    faces : (T, 3) integers in [0, V)
    centres : whether to compute the centroids

    Returns
    -------
    area : (T,) float64, cm2
    centre : (T, 2) float64, cm, or None unless ``centres``
    None where the loops are not built.

    Raises
    ------
    ValueError
        In one line naming the argument (:func:`check_mesh`).
    """
    v, f, lib = _mesh_and_loops(vertices, faces)
    if lib is None:
        return None
    area = np.empty(len(f))
    centre = np.empty((len(f), 2)) if centres else None
    rc = lib.mz_triangle_areas(v.ctypes.data, len(v), f.ctypes.data, len(f), area.ctypes.data,
                               None if centre is None else centre.ctypes.data)
    _mesh_call_done(rc, v, f, "triangle_areas")
    return area, centre
