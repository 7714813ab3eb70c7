"""NURBS interpolation: through every point, equal to geomdl, sensible where data is thin."""

import numpy as np
import pytest
from geomdl import fitting
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import BSpline

from maizeviz.errors import LeafError
from maizeviz.leaf.nurbs import (
    averaged_knots,
    basis_matrix,
    data_parameters,
    fit_surface,
    fit_surfaces,
    refine_parameters,
)


def random_grid(rng, m, n):
    """A grid with no coincident rows or columns (steps of at least 0.5 cm)."""
    steps_u = rng.uniform(0.5, 3.0, (m, n, 3))
    steps_v = rng.uniform(0.5, 3.0, (m, n, 3)) * np.array([0.2, 1.0, 0.3])
    return np.cumsum(steps_u, axis=0) + np.cumsum(steps_v, axis=1)


grids = st.tuples(st.integers(2, 14), st.integers(2, 9), st.integers(0, 2**32 - 1))


@settings(max_examples=40, deadline=None)
@given(grids)
def test_surface_passes_through_every_point(args):
    m, n, seed = args
    pts = random_grid(np.random.default_rng(seed), m, n)
    s = fit_surface(pts)
    back = s.evaluate_grid(s.params_u, s.params_v)[0]
    assert np.abs(back - pts).max() < 1e-9


@settings(max_examples=25, deadline=None)
@given(grids, st.sampled_from(["chord", "centripetal"]))
def test_agrees_with_geomdl(args, method):
    m, n, seed = args
    pts = random_grid(np.random.default_rng(seed), m, n)
    pu, pv = min(3, m - 1), min(3, n - 1)
    ref = fitting.interpolate_surface(pts.reshape(-1, 3).tolist(), m, n, pu, pv,
                                      centripetal=(method == "centripetal"))
    s = fit_surface(pts, method=method)
    assert (s.degree_u, s.degree_v) == (pu, pv)
    assert np.allclose(s.knots_u[0], ref.knotvector_u, atol=1e-12)
    assert np.allclose(s.knots_v[0], ref.knotvector_v, atol=1e-12)
    u = np.linspace(0, 1, 7)
    v = np.linspace(0, 1, 5)
    theirs = np.array(ref.evaluate_list([(a, b) for a in u for b in v])).reshape(7, 5, 3)
    assert np.abs(s.evaluate_grid(u, v)[0] - theirs).max() < 1e-9


def test_basis_matches_scipy(rng):
    params = np.sort(np.concatenate([[0, 1], rng.random(8)]))
    for p in (1, 2, 3):
        knots = averaged_knots(params, p)
        x = np.linspace(0, 1, 31)
        ours = basis_matrix(x[None], knots[None], p)[0]
        theirs = BSpline.design_matrix(x, knots, p).toarray()
        assert np.abs(ours - theirs).max() < 1e-14


def test_degree_lowered_for_few_points():
    pts = random_grid(np.random.default_rng(0), 2, 3)
    s = fit_surface(pts)
    assert (s.degree_u, s.degree_v) == (1, 2)
    assert np.abs(s.evaluate_grid(s.params_u, s.params_v)[0] - pts).max() < 1e-12


def test_collapsed_tip_and_normals_point_up(leaf_grid):
    s = fit_surface(leaf_grid)
    u, v = s.params_u[0], s.params_v[0]
    assert np.abs(s.evaluate_grid(u, v)[0] - leaf_grid).max() < 1e-9
    # near the collar the blade of the synthetic leaf rises: upper face looks up
    n = s.normals(np.full(5, 0.05), np.linspace(0.1, 0.9, 5))
    assert np.all(n[:, 2] > 0.3)
    assert np.allclose(np.linalg.norm(s.normals([1.0], [0.5]), axis=1), 1.0)


def test_derivatives_match_finite_differences(leaf_grid):
    s = fit_surface(leaf_grid)
    u, v, h = np.array([0.3, 0.61]), np.array([0.4, 0.77]), 1e-6
    du, dv = s.derivatives(u, v)
    fd_u = (s.evaluate(u + h, v) - s.evaluate(u - h, v)) / (2 * h)
    fd_v = (s.evaluate(u, v + h) - s.evaluate(u, v - h)) / (2 * h)
    assert np.allclose(du, fd_u, rtol=1e-5, atol=1e-4)
    assert np.allclose(dv, fd_v, rtol=1e-5, atol=1e-4)


def test_batch_equals_single(rng):
    pts = np.stack([random_grid(rng, 9, 5) for _ in range(4)])
    batch = fit_surfaces(pts)
    u = refine_parameters(batch.params_u, 2)
    v = refine_parameters(batch.params_v, 2)
    all_at_once = batch.evaluate_grid(u, v)
    for k in range(4):
        one = fit_surface(pts[k])
        assert np.allclose(one.evaluate_grid(u[k], v[k])[0], all_at_once[k], atol=1e-12)


def test_coincident_rows_refused_with_names():
    pts = random_grid(np.random.default_rng(1), 4, 3)
    pts[2] = pts[1]
    with pytest.raises(LeafError, match="plant 4, leaf 9: rows 1 and 2 coincide"):
        fit_surface(pts, plant=4, leaf=9)


def test_refine_keeps_data_parameters():
    t = np.array([0.0, 0.2, 0.7, 1.0])
    r = refine_parameters(t, 4)
    assert len(r) == 3 * 5 + 1
    assert np.allclose(r[::5], t)
    with pytest.raises(ValueError):
        refine_parameters(t, -1)


def test_parameters_skip_collapsed_tip_row(leaf_grid):
    u, v = data_parameters(leaf_grid)
    assert u[0] == 0 and u[-1] == 1 and np.all(np.diff(u) > 0)
    assert v[0] == 0 and v[-1] == 1 and np.all(np.diff(v) > 0)


# ------------------------------------------------------------------ banded, for huge leaves
def _old_derivatives(s, u, v):
    """dS/du, dS/dv as maizeviz computed them before the banded basis: scipy's BSpline of
    the whole control net, contracted with the dense basis (the oracle)."""
    hom = s._homogeneous()[0]
    bu = basis_matrix(u[None], s.knots_u[:1], s.degree_u)[0]
    bv = basis_matrix(v[None], s.knots_v[:1], s.degree_v)[0]
    a = np.einsum("ki,ijc,kj->kc", bu, hom, bv)
    p = a[:, :3] / a[:, 3:]
    su = BSpline(s.knots_u[0], hom, s.degree_u).derivative()(u)
    sv = BSpline(s.knots_v[0], hom.transpose(1, 0, 2), s.degree_v).derivative()(v)
    au = np.einsum("kjc,kj->kc", su, bv)
    av = np.einsum("kic,ki->kc", sv, bu)
    w = a[:, 3:]
    return p, (au[:, :3] - au[:, 3:] * p) / w, (av[:, :3] - av[:, 3:] * p) / w


@settings(max_examples=25, deadline=None)
@given(st.integers(2, 90), st.integers(2, 80), st.integers(0, 2**32 - 1))
def test_banded_fit_and_evaluation_equal_the_dense_ones(m, n, seed):
    """Past BANDED_FROM control points a direction is solved and evaluated through its
    banded basis (memory of the points, not their square); the numbers are the dense ones."""
    import maizeviz.leaf.nurbs as nurbs

    rng = np.random.default_rng(seed)
    pts = random_grid(rng, m, n)
    u, v = np.sort(rng.uniform(0, 1, 37)), np.sort(rng.uniform(0, 1, 23))
    old = nurbs.BANDED_FROM
    try:
        nurbs.BANDED_FROM = 10**9                   # dense everywhere
        dense = fit_surface(pts)
        dense_grid = dense.evaluate_grid(u, v)
        nurbs.BANDED_FROM = 2                       # banded everywhere
        banded = fit_surface(pts)
        banded_grid = banded.evaluate_grid(u, v)
        dense_on_banded = fit_surface(pts)
    finally:
        nurbs.BANDED_FROM = old
    scale = np.abs(pts).max()
    assert np.abs(banded.control - dense.control).max() <= 1e-9 * scale
    assert np.abs(banded_grid - dense_grid).max() <= 1e-9 * scale
    assert np.abs(dense_on_banded.evaluate_grid(banded.params_u, banded.params_v)[0]
                  - pts).max() <= 1e-9 * scale          # still through every point
    k = rng.uniform(0, 1, (2, 50))
    want = _old_derivatives(dense, k[0], k[1])
    try:
        nurbs.BANDED_FROM = 2                       # points and derivatives, banded
        got = dense._at(k[0], k[1], derivative=True)
    finally:
        nurbs.BANDED_FROM = old
    for g, w in zip(got, want):
        assert np.abs(g - w).max() <= 1e-9 * max(1.0, np.abs(w).max())


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 5), st.integers(1, 40), st.integers(1, 30), st.integers(0, 2**32 - 1))
def test_count_at_most_row_by_row_equals_the_broadcast(nl, na, nk, seed):
    import maizeviz.leaf.nurbs as nurbs

    rng = np.random.default_rng(seed)
    rows = np.sort(rng.choice([0.0, 0.25, 0.5, 1.0, *rng.uniform(0, 1, 8)], (nl, nk)), axis=1)
    x = rng.choice([0.0, 0.25, 0.5, 1.0, *rng.uniform(0, 1, 8)], (nl, na))
    want = (x[:, :, None] >= rows[:, None, :]).sum(axis=2)
    old = nurbs.BROADCAST_MOST
    try:
        nurbs.BROADCAST_MOST = 0
        assert np.array_equal(nurbs.count_at_most(rows, x), want)
    finally:
        nurbs.BROADCAST_MOST = old
    assert np.array_equal(nurbs.count_at_most(rows, x), want)
