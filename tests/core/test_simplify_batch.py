"""The inverse multi-line segment splitting run over many leaves at once
(:func:`maizeviz.mesh.simplify.simplify_many`) gives, leaf by leaf, the very meshes of the
leaf-by-leaf splitting it replaced, kept here as the oracle (``simplify_oracle.py``): the same
rows and columns, the same widened vertices to the last bit, the same triangles."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from simplify_oracle import select_lines as oracle_select
from simplify_oracle import simplify as oracle_simplify

from maizeviz.leaf.fit import fit_leaves
from maizeviz.leaf.grid import LeafGrid
from maizeviz.leaf.synth import LeafShape, block_grids, leaf_points
from maizeviz.mesh.levels import Level, mesh_leaves, reference_areas
from maizeviz.mesh.simplify import select_lines, select_lines_many, simplify_many


def _grid(draw, m, n):
    """A leaf-like grid (m, n, 3) cm or a rougher one: random points, grids with coincident
    points and ties (integer coordinates), a collapsed tip."""
    kind = draw(st.sampled_from(["leaf", "random", "integer"]))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    if kind == "leaf":
        shape = LeafShape(length=rng.uniform(20, 110), width=rng.uniform(2, 12),
                          curvature_deg=rng.uniform(0, 120), azimuth_deg=rng.uniform(0, 360),
                          insertion_deg=rng.uniform(5, 80))
        return leaf_points(shape, m, n, rng=rng)
    if kind == "random":
        g = rng.normal(0, 10, (m, n, 3))
    else:
        g = rng.integers(-3, 4, (m, n, 3)).astype(float)
    if draw(st.booleans()):
        g[-1] = g[-1, 0]                                     # a collapsed tip
    return g


@st.composite
def batches(draw):
    m, n = draw(st.integers(2, 15)), draw(st.integers(2, 8))
    count = draw(st.integers(1, 6))
    grids = np.stack([_grid(draw, m, n) for _ in range(count)])
    # the tip is collapsed where its row is one point (a budget counts its band's slivers)
    tips = np.all(grids[:, -1] == grids[:, -1:, 0], axis=(1, 2))
    budget = draw(st.integers(1, 2 * (m - 1) * (n - 1) + 4))
    return grids, tips, budget


def _check_same(grids, tips, budget, targets=None):
    nl, m, n = grids.shape[:3]
    u = np.tile(np.linspace(0, 1, m), (nl, 1))
    v = np.tile(np.linspace(0, 1, n), (nl, 1))
    expected, refused = [], None
    for k in range(nl):
        target = None if targets is None else float(targets[k])
        try:
            expected.append(oracle_simplify(grids[k], u[k], v[k], budget, bool(tips[k]),
                                            target, plant=k, leaf=k + 1))
        except ValueError as exc:
            refused = refused or str(exc)
    if refused:
        with pytest.raises(ValueError) as got:
            simplify_many(grids, u, v, budget, tips, targets)
        assert str(got.value) == refused
        return
    meshes = simplify_many(grids, u, v, budget, tips, targets, range(nl), range(1, nl + 1))
    assert len(meshes) == nl
    for old, new in zip(expected, meshes):
        assert new.vertices.shape == old.vertices.shape
        assert np.array_equal(new.vertices, old.vertices, equal_nan=True)
        assert np.array_equal(new.u, old.u) and np.array_equal(new.v, old.v)
        assert np.array_equal(new.faces, old.faces)
        assert (new.level, new.plant, new.leaf) == (old.level, old.plant, old.leaf)
        assert new.n_triangles <= budget


@settings(max_examples=300, deadline=None)
@given(batches())
def test_selection_is_the_leaf_by_leaf_one(batch):
    grids, tips, budget = batch
    try:
        expected = [oracle_select(g, budget, bool(t)) for g, t in zip(grids, tips)]
    except ValueError:
        with pytest.raises(ValueError, match="below the coarsest"):
            select_lines_many(grids, budget, tips)
        return
    rows, cols = select_lines_many(grids, budget, tips)
    for k, sel in enumerate(expected):
        assert np.array_equal(np.flatnonzero(rows[k]), sel.rows)
        assert np.array_equal(np.flatnonzero(cols[k]), sel.cols)
        one = select_lines(grids[k], budget, bool(tips[k]))
        assert np.array_equal(one.rows, sel.rows) and np.array_equal(one.cols, sel.cols)


@settings(max_examples=200, deadline=None)
@given(batches(), st.booleans(), st.floats(0.3, 3.0))
def test_meshes_are_the_leaf_by_leaf_ones(batch, widen, scale):
    grids, tips, budget = batch
    targets = None
    if widen:                       # areas the secant steps must reach, near or far from the mesh's
        from maizeviz.mesh.measures import grid_areas
        targets = grid_areas(grids) * scale + 1e-3
    _check_same(grids, tips, budget, targets)


@pytest.mark.parametrize("budget", [3, 4, 8, 16, 36])
@pytest.mark.parametrize("preserve", [True, False])
def test_a_synthetic_block_through_mesh_leaves(budget, preserve):
    """Fitted leaves of a synthetic block (its grid shapes mixed) meshed by the level as the
    oracle meshes them one by one, with the reference areas the level uses."""
    leaves, errors = fit_leaves(block_grids(2, 3, seed=budget))
    assert not errors
    got = mesh_leaves(leaves, Level(triangles=budget), preserve_area=preserve)
    targets = reference_areas(leaves)
    for leaf, mesh, target in zip(leaves, got, targets):
        g = leaf.grid
        old = oracle_simplify(g.points, leaf.surface.params_u[0], leaf.surface.params_v[0],
                              budget, g.tip_collapsed, float(target) if preserve else None,
                              g.plant, g.leaf)
        assert np.array_equal(mesh.vertices, old.vertices)
        assert np.array_equal(mesh.faces, old.faces)
        assert (mesh.plant, mesh.leaf) == (g.plant, g.leaf)


def test_budget_error_names_the_first_leaf_refused():
    pts = leaf_points(LeafShape(), 5, 3, rng=np.random.default_rng(1))
    grids = [LeafGrid(1, 1, pts, True), LeafGrid(1, 2, pts + [0, 0, 5], False)]
    leaves, _ = fit_leaves(grids)
    from maizeviz.errors import MaizevizError
    with pytest.raises(MaizevizError, match="plant 1, leaf 2: a budget of 1 triangles"):
        mesh_leaves(leaves, Level(triangles=1))
