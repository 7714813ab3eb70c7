"""The wrappers of the compiled loops (maizeviz.loops over _loops.c) check what they hand to
C, and the numpy paths refuse alike: hypothesis draws arguments well and badly formed (shapes,
dtypes, knot counts against the degree, knots out of order, indices outside the grids, out
buffers of another type, too small or not contiguous) and the compiled and numpy paths give the
same numbers or the same one-line ValueError naming the argument. The C functions refuse bad
counts and indices themselves too, writing nothing."""

import ctypes
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_loops import _same, without_loops

from maizeviz import loops
from maizeviz.leaf import nurbs
from maizeviz.mesh import measures, simplify

pytestmark = pytest.mark.skipif(not loops.available(),
                                reason="the compiled loops were not built at install")


def outcome(fn):
    """``fn()``'s array, or its ValueError's text (one line)."""
    try:
        with np.errstate(all="ignore"):
            return fn()
    except ValueError as exc:
        text = str(exc)
        assert len(text.splitlines()) == 1 and text
        return text


def same_outcome(fn):
    """The compiled and numpy paths of ``fn`` give the same bits or the same refusal."""
    got = outcome(fn)
    want = without_loops(lambda: outcome(fn))
    if isinstance(got, str) or isinstance(want, str):
        assert got == want
    else:
        _same(got, want)
    return got


@st.composite
def basis_cases(draw):
    degree = draw(st.one_of(st.integers(0, 6), st.sampled_from([-1, 2.0, True, 16])))
    nl = draw(st.integers(1, 3))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    d = degree if isinstance(degree, int) and not isinstance(degree, bool) and degree >= 0 else 2
    nk = draw(st.integers(0, 2 * (d + 1) + 6))
    kind = draw(st.sampled_from(["clamped", "clamped", "sorted", "unsorted", "nan"]))
    if kind == "clamped" and nk >= 2 * (d + 1):
        inner = np.sort(rng.uniform(0, 1, (nl, nk - 2 * (d + 1))), axis=1)
        knots = np.concatenate([np.zeros((nl, d + 1)), inner, np.ones((nl, d + 1))], axis=1)
    else:
        knots = rng.uniform(0, 1, (nl, nk))
        if kind != "unsorted":
            knots.sort(axis=1)
        if kind == "nan" and nk:
            knots[rng.integers(nl), rng.integers(nk)] = np.nan
    x = rng.uniform(-0.1, 1.1, (nl, draw(st.integers(0, 12))))
    shape = draw(st.sampled_from(["ok", "ok", "ok", "x1d", "rows", "text"]))
    if shape == "x1d":
        x = x[0]
    elif shape == "rows":
        knots = knots[:1].repeat(nl + 1, axis=0)
    elif shape == "text":
        knots = knots.astype(str)
    if draw(st.booleans()):
        knots = np.asfortranarray(knots)                       # not C-contiguous
    return x, knots, degree


@settings(max_examples=400, deadline=None)
@given(basis_cases())
def test_basis_matrix_gives_numpys_answer_or_its_refusal(case):
    x, knots, degree = case
    got = same_outcome(lambda: nurbs.basis_matrix(x, knots, degree))
    if isinstance(got, str):
        assert got.split(":")[0] in ("x", "knots", "degree")


def test_the_knots_that_wrote_outside_their_row_are_refused_200_times_over():
    """basis_matrix(x, [[0, 0, 0.5, 1, 1]], 3) read and wrote left of the knots; 200 calls
    ended in 'double free or corruption' (rc 134). Now each is refused, and so is numpy's."""
    code = ("import numpy as np\nfrom maizeviz.leaf.nurbs import basis_matrix\n"
            "from maizeviz import loops\nassert loops.available()\nx = np.linspace(0, 1, 50)[None]\n"
            "n = 0\nfor _ in range(200):\n    try:\n"
            "        basis_matrix(x, np.array([[0, 0, 0.5, 1, 1.0]]), 3)\n"
            "    except ValueError as exc:\n        n += 1; msg = str(exc)\nprint(n, msg)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("200 knots: 5 a row, fewer than the 2 (degree + 1) = 8")
    assert "5 a row" in without_loops(
        lambda: outcome(lambda: nurbs.basis_matrix(np.zeros((1, 3)), [[0, 0, .5, 1, 1]], 3)))


@st.composite
def chord_cases(draw):
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    nl, m, n = draw(st.integers(1, 3)), draw(st.integers(1, 6)), draw(st.integers(0, 5))
    coords = [rng.normal(0, 10, (nl, m, n)) for _ in range(3)]
    if draw(st.integers(0, 9)) == 0:
        coords[2] = coords[2][:, :, :max(n - 1, 0)]                   # shapes differ
    r = draw(st.integers(0, 8))
    idx = [rng.integers(-1 if draw(st.integers(0, 5)) == 0 else 0,
                        size + (1 if draw(st.integers(0, 5)) == 0 else 0), r)
           for size in (nl, m, m, m)]
    bad = draw(st.integers(0, 12))
    if bad == 0:
        idx[1] = idx[1].astype(float)                                # float indices
    elif bad == 1:
        idx[2] = idx[2][:-1]                                         # one short
    elif bad == 2:
        idx[0] = idx[0].astype(np.int32)                             # another integer type
    elif bad == 3:
        coords[0] = coords[0][:, ::-1]                               # not contiguous
    return tuple(coords), idx


@settings(max_examples=400, deadline=None)
@given(chord_cases())
def test_chord_errors_give_numpys_answer_or_its_refusal(case):
    coords, (leaf, line, lo, hi) = case
    got = same_outcome(lambda: simplify._chord_errors(coords, leaf, line, lo, hi))
    if isinstance(got, str):
        assert got.split(":")[0] in ("coords", "coords[0]", "leaf", "line", "lo", "hi")


@st.composite
def grid_cases(draw):
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    shape = [draw(st.integers(0, 3)), draw(st.integers(0, 5)), draw(st.integers(0, 5)),
             draw(st.sampled_from([3, 3, 3, 2]))]
    if draw(st.integers(0, 9)) == 0:
        shape = shape[1:]                                            # one grid, no L axis
    g = rng.normal(0, 10, shape)
    if draw(st.booleans()) and g.ndim == 4:
        g = g.astype(np.float32)
    return g


@settings(max_examples=300, deadline=None)
@given(grid_cases())
def test_grid_areas_give_numpys_answer_or_its_refusal(g):
    got = same_outcome(lambda: measures.grid_areas(g, 1e-9))
    if isinstance(got, str):
        assert got.startswith("vertices: ")


def grids(nl=2, a=4, b=3):
    return np.random.default_rng(1).normal(0, 10, (nl, a, b, 3))


@pytest.mark.parametrize("make, says", [
    (lambda q: (np.empty(q, np.float32), np.empty(q)), "out[0]: float64 expected, not float32"),
    (lambda q: (np.empty(q), np.empty(2 * q)[::2]), "out[1]: a writable C-contiguous array"),
    (lambda q: (np.empty(q - 1), np.empty(q)), "out[0]: 11 values, fewer than the 12"),
    (lambda q: (np.empty(q), [0.0] * q), "out[1]: a numpy array expected, not list"),
    (lambda q: (np.empty(q),), "out: two arrays (first, second) expected"),
    (lambda q: (lambda a: (a[:q], a[q - 1:]))(np.empty(2 * q)), "out: the two arrays share"),
])
def test_an_out_buffer_c_cannot_fill_is_refused(make, says):
    """A float32 out was written past its end, a non-contiguous one left unfilled: now each
    is refused naming it, before C runs."""
    g = grids()
    q = 2 * 3 * 2
    out = make(q)
    with pytest.raises(ValueError) as err:
        loops.grid_twice_areas(g, 1e-9, out)
    assert str(err.value).startswith(says)


def test_a_read_only_out_is_refused_and_a_good_one_is_filled_as_new_arrays_are():
    g = grids()
    ro = np.zeros(12)
    ro.flags.writeable = False
    with pytest.raises(ValueError, match="out\\[0\\]: a writable"):
        loops.grid_twice_areas(g, 1e-9, (ro, np.empty(12)))
    big = (np.full(20, -1.0), np.full(20, -1.0))
    got = loops.grid_twice_areas(g, 1e-9, big)
    new = loops.grid_twice_areas(g, 1e-9)
    for a, b in zip(got, new):
        _same(a, b)
    assert np.all(big[0][12:] == -1.0)                  # nothing past the grids' triangles


def test_the_c_functions_refuse_bad_counts_and_indices_themselves():
    """Past the wrappers (a caller of the C symbols): -2 and nothing written."""
    lib = loops._lib()
    out = np.full(64, 7.0)
    x = np.linspace(0, 1, 4)
    k = np.array([0, 0, 0.5, 1, 1.0])
    assert lib.mz_basis_matrix(x.ctypes.data, k.ctypes.data, 1, 4, 5, 3, out.ctypes.data) == -2
    v = grids(1, 1, 3)
    assert lib.mz_grid_twice_areas(v.ctypes.data, 1, 1, 3, 0.0, out.ctypes.data,
                                   out.ctypes.data) == -2
    c = np.zeros((2, 3, 4))
    i = np.array([0, 2], np.int64)
    bad = np.array([0, 3], np.int64)                    # line 3 of a grid of 3
    for args in ((i, bad, i, i), (bad, i, i, i), (i, i, i, -bad)):
        assert lib.mz_chord_errors(c.ctypes.data, c.ctypes.data, c.ctypes.data, 2, 3, 4, 2,
                                   *(a.ctypes.data for a in args), out.ctypes.data) == -2
    assert np.all(out == 7.0)
    assert isinstance(lib.mz_chord_errors.argtypes[3](2), ctypes.c_int64)


@pytest.mark.parametrize("bad", [-1, 4])
def test_a_mesh_corner_outside_the_vertices_is_refused_by_c_itself(bad):
    """Past the wrappers: a face naming a vertex the mesh does not have is -2, and the
    repeated-triangle flags are not written."""
    lib = loops._lib()
    v = np.zeros((4, 3))
    f = np.array([[0, 1, 2], [1, 2, bad]], np.int64)
    flags = np.full(2, 7, np.uint8)
    area = np.zeros(2)
    assert lib.mz_repeated_triangles(v.ctypes.data, 4, f.ctypes.data, 2, flags.ctypes.data,
                                     None) == -2
    assert np.all(flags == 7)
    assert lib.mz_triangle_areas(v.ctypes.data, 4, f.ctypes.data, 2, area.ctypes.data,
                                 None) == -2
    assert lib.mz_repeated_triangles(v.ctypes.data, 4, f.ctypes.data, -1, flags.ctypes.data,
                                     None) == -2
