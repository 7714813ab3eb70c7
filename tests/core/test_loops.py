"""The compiled loops (``maizeviz/_loops.c``) give numpy's numbers to the bit:
grid areas (the reference areas a triangle budget widens its leaves to) and the splitting's
chord distances, on hypothesis-drawn grids (leaf-like, random, integer ties, zero-length edges,
collapsed tips, NaN and infinite points), and whole canopies at triangle budgets built with and
without them are the same arrays; B-spline bases too, and so surfaces fitted and sampled."""

import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz import loops
from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.leaf import nurbs
from maizeviz.leaf.fit import fit_leaves
from maizeviz.leaf.synth import LeafShape, block_grids, leaf_points
from maizeviz.mesh import measures, simplify
from maizeviz.mesh.levels import Level, reference_areas

pytestmark = pytest.mark.skipif(not loops.available(),
                                reason="the compiled loops were not built at install")


def without_loops(fn):
    """``fn()`` run with numpy's passes instead of the compiled loops."""
    old = os.environ.get("MAIZEVIZ_LOOPS")
    os.environ["MAIZEVIZ_LOOPS"] = "0"
    loops._loaded.cache_clear()
    try:
        assert not loops.available() and "MAIZEVIZ_LOOPS=0" in loops.why()
        return fn()
    finally:
        if old is None:
            del os.environ["MAIZEVIZ_LOOPS"]
        else:
            os.environ["MAIZEVIZ_LOOPS"] = old
        loops._loaded.cache_clear()


@st.composite
def grids(draw, max_rows=12, max_cols=9):
    nl = draw(st.integers(1, 5))
    a, b = draw(st.integers(2, max_rows)), draw(st.integers(2, max_cols))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    kind = draw(st.sampled_from(["leaf", "random", "integer", "tiny"]))
    if kind == "leaf":
        g = np.stack([leaf_points(LeafShape(length=rng.uniform(20, 110),
                                            width=rng.uniform(2, 12),
                                            curvature_deg=rng.uniform(0, 120)), a, b, rng=rng)
                      for _ in range(nl)])
    elif kind == "random":
        g = rng.normal(0, 10, (nl, a, b, 3))
    elif kind == "integer":                                   # ties, coincident points
        g = rng.integers(-2, 3, (nl, a, b, 3)).astype(float)
    else:                                                     # edges near the tolerance
        g = rng.normal(0, 1, (nl, a, b, 3)) * 10.0 ** rng.integers(-12, 3, (nl, a, b, 1))
    if draw(st.booleans()):
        g[:, -1] = g[:, -1, :1]                               # collapsed tips
    if draw(st.booleans()):
        g[:, :, 0] = g[:, :, 1]                               # a zero-length edge column
    special = draw(st.sampled_from([None, np.nan, np.inf]))
    if special is not None:
        g[rng.integers(nl), rng.integers(a), rng.integers(b), rng.integers(3)] = special
    return g


def _same(x, y):
    """Equal to the bit (signed zeros too), NaN where NaN (whatever its sign bit or payload:
    numpy's own loops differ there)."""
    assert x.dtype == y.dtype and x.shape == y.shape
    nan = np.isnan(x)
    assert np.array_equal(nan, np.isnan(y))
    assert np.array_equal(x[~nan].view(np.int64), y[~nan].view(np.int64)), \
        np.flatnonzero(x != y)[:5]


@settings(max_examples=300, deadline=None)
@given(grids(), st.sampled_from([1e-9, 0.0, 0.3]))
def test_grid_areas_are_numpys_to_the_bit(g, rel_tol):
    with np.errstate(all="ignore"):
        got = measures.grid_areas(g, rel_tol)
        want = without_loops(lambda: measures.grid_areas(g, rel_tol))
    _same(got, want)


@settings(max_examples=300, deadline=None)
@given(grids(), st.data())
def test_chord_errors_are_numpys_to_the_bit(g, data):
    nl, m, n = g.shape[:3]
    coords = tuple(np.ascontiguousarray(g[..., k]) for k in range(3))
    r = data.draw(st.integers(1, 40))
    pick = st.lists(st.integers(0, m - 1), min_size=r, max_size=r)
    leaf = np.array(data.draw(st.lists(st.integers(0, nl - 1), min_size=r, max_size=r)))
    line, lo, hi = (np.array(data.draw(pick)) for _ in range(3))
    with np.errstate(all="ignore"):
        got = simplify._chord_errors(coords, leaf, line, lo, hi)
        want = without_loops(lambda: simplify._chord_errors(coords, leaf, line, lo, hi))
    _same(got, want)


@pytest.mark.parametrize("budget", [3, 8, 36])
def test_canopies_at_budgets_are_the_same_arrays(budget):
    """A synthetic field's canopy at a triangle budget, widened to the reference areas, built
    with and without the loops: every vertex, triangle and id the same (the triangles of
    before the loops), and the reference areas the same."""
    grids = block_grids(3, 4, seed=budget)

    def build():                              # fitted, sampled and meshed either way
        leaves, errors = fit_leaves(grids)
        assert not errors
        layout = layout_for(leaves, (1, 1), 60.0, 30.0, None, None)
        return reference_areas(leaves), build_canopy(leaves, layout, Level(triangles=budget))

    areas, got = build()
    old_areas, want = without_loops(build)
    _same(areas, old_areas)
    for name in ("vertices", "faces", "face_instance", "face_plant", "face_leaf"):
        assert np.array_equal(getattr(got, name), getattr(want, name)), name
    _same(got.vertices, want.vertices)


@st.composite
def knots_and_points(draw):
    degree = draw(st.integers(0, 5))
    nl = draw(st.integers(1, 4))
    inner = draw(st.integers(0, 8))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    # clamped knot vectors, interior knots repeated at times; points on knots, 0 and 1 too
    interior = np.sort(rng.choice([0.25, 0.5, 0.5, 0.75], inner) if draw(st.booleans())
                       else rng.uniform(0, 1, (nl, inner)), axis=-1)
    interior = np.broadcast_to(interior, (nl, inner))
    knots = np.concatenate([np.zeros((nl, degree + 1)), interior,
                            np.ones((nl, degree + 1))], axis=1)
    na = draw(st.integers(1, 30))
    x = rng.uniform(0, 1, (nl, na))
    x[:, :min(na, 2)] = [0.0, 1.0][:min(na, 2)]
    if inner and na > 2:
        x[:, 2] = interior[:, 0]
    return x, knots, degree


@settings(max_examples=300, deadline=None)
@given(knots_and_points())
def test_basis_matrices_are_numpys_to_the_bit(case):
    x, knots, degree = case
    with np.errstate(all="ignore"):
        got = nurbs.basis_matrix(x, knots, degree)
        want = without_loops(lambda: nurbs.basis_matrix(x, knots, degree))
    _same(got, want)


@st.composite
def meshes(draw):
    """A mesh whose triangles repeat others: corners on a coarse lattice (positions shared by
    several vertices, -0.0 beside 0.0), faces drawn among them, some copied with their corners
    turned or reversed; or leaf-like float corners."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    n = draw(st.integers(1, 60))
    if draw(st.booleans()):
        v = rng.integers(-2, 3, (n, 3)).astype(np.float64) * 0.5
        v[rng.random(n) < 0.3] *= -1.0
    else:
        v = rng.normal(0, 30, (n, 3))
    f = rng.integers(0, n, (draw(st.integers(0, 4 * n)), 3))
    if len(f) and draw(st.booleans()):
        copies = f[rng.integers(0, len(f), len(f) // 2 + 1)]
        copies = np.take_along_axis(copies, rng.permuted(np.tile([0, 1, 2], (len(copies), 1)),
                                                         axis=1), axis=1)
        f = rng.permutation(np.concatenate([f, copies]))
    return v, f


@settings(max_examples=300, deadline=None)
@given(meshes())
def test_mesh_repeats_and_areas_are_numpys(mesh):
    """A mesh file's repeated triangles, the same ones found either way (exact), and their
    areas and centres numpy's to the bit."""
    from maizeviz.canopy.from_mesh import _areas_centres, repeated_triangles

    v, f = mesh
    got = repeated_triangles(v, f)
    want = without_loops(lambda: repeated_triangles(v, f))
    assert got.dtype == bool and np.array_equal(got, want)
    area, centre = _areas_centres(v, f)
    old_area, old_centre = without_loops(lambda: _areas_centres(v, f))
    _same(area, old_area)
    _same(centre, old_centre)


@pytest.mark.parametrize("bad", [-1, 7])
def test_a_corner_outside_the_vertices_is_refused_either_way(bad):
    v, f = np.zeros((7, 3)), np.array([[0, 1, 2], [3, 4, bad]])
    for fn in (loops.repeated_triangles, loops.triangle_areas):
        with pytest.raises(ValueError, match=f"faces: vertex index {bad} outside 0..6"):
            fn(v, f)
        with pytest.raises(ValueError, match=f"faces: vertex index {bad} outside 0..6"):
            without_loops(lambda fn=fn: fn(v, f))


def test_a_large_mesh_dealt_into_parts_finds_the_same_repeats():
    """Past 2^16 triangles the compiled loops deal the triangles into parts by their hash:
    300,000 triangles, a tenth of them copies turned or reversed, some copied twice, and a
    few vertices written twice at one place: the repeats numpy finds, and the vertices used."""
    rng = np.random.default_rng(11)
    v = rng.normal(0, 50, (100_000, 3))
    v[-500:] = v[:500]                                       # the same places twice
    f = rng.integers(0, len(v), (270_000, 3))
    copies = f[rng.integers(0, len(f), 30_000)][:, ::-1]
    copies[::2] = np.roll(copies[::2], 1, axis=1)
    f = np.concatenate([f, copies])
    rng.shuffle(f)
    got, used = loops.repeated_triangles(v, f, used=True)
    from maizeviz.canopy.from_mesh import repeated_triangles

    want = without_loops(lambda: repeated_triangles(v, f))
    assert got.sum() >= 30_000 - 100 and np.array_equal(got, want)
    expect = np.zeros(len(v), bool)
    expect[f.ravel()] = True
    assert np.array_equal(used, expect)
