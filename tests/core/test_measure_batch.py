"""Batched leaf measures: the same numbers as measuring one leaf at a time with trimesh.

The reference here is the per-leaf measure as it was before batching (trimesh's closest point
on 18 candidate triangles per surface point, areas from ``triangle_areas_normals``, the
reference mesh area from ``mesh_grid``), kept in this file so the batched code is checked
against it on random leaves, on the bundled example and on surfaces made to defeat its
pruning.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from maizeviz.leaf.fit import Leaf, fit_leaves, read_leaves
from maizeviz.leaf.grid import LeafGrid
from maizeviz.leaf.synth import LeafShape, example_leaf, leaf_points
from maizeviz.mesh import measures
from maizeviz.mesh.levels import (
    DEVIATION_K,
    REFERENCE_K,
    Level,
    _sample,
    measure,
    measure_leaves,
    mesh_leaves,
    parse_levels,
    reference_areas,
)
from maizeviz.mesh.tessellate import grid_faces, mesh_grid, triangle_areas_normals
from maizeviz.resources import example_points

#: Every level of the paper's Table 1 plus a finer one.
LEVELS = parse_levels("K4,K1,standard,36,8,4,3") + [Level(interp=2)]


# ------------------------------------------------------------------ the reference (before)
def old_max_deviation(mesh, ref_points, ref_u, ref_v):
    """The deviation as maizeviz measured it leaf by leaf with trimesh (before batching)."""
    from trimesh.triangles import closest_point

    a, b = mesh.vertices.shape[:2]
    faces = grid_faces(a, b).reshape(a - 1, b - 1, 2, 3)
    ci = np.clip(np.searchsorted(mesh.u, ref_u, side="right") - 1, 0, a - 2)
    cj = np.clip(np.searchsorted(mesh.v, ref_v, side="right") - 1, 0, b - 2)
    ci, cj = np.meshgrid(ci, cj, indexing="ij")
    pts = ref_points.reshape(-1, 3)
    ci, cj = ci.ravel(), cj.ravel()
    best = np.full(len(pts), np.inf)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            ii = np.clip(ci + di, 0, a - 2)
            jj = np.clip(cj + dj, 0, b - 2)
            for t in range(2):
                tri = mesh.points[faces[ii, jj, t]]
                with np.errstate(all="ignore"):
                    q = closest_point(tri, pts)
                d = np.linalg.norm(q - pts, axis=1)
                best = np.fmin(best, np.where(np.isfinite(d), d, np.inf))
    return float(best.max()) if len(best) else 0.0


def old_measure(leaf, mesh):
    """(area, projected area, max deviation, reference area) leaf by leaf, as before."""
    a, n = triangle_areas_normals(mesh.points, mesh.faces)
    pts, u, v = _sample(leaf.surface, REFERENCE_K)
    ref = mesh_grid(pts[0], u[0], v[0])
    pts, u, v = _sample(leaf.surface, DEVIATION_K)
    return (float(a.sum()), float((a * np.abs(n[:, 2])).sum()),
            old_max_deviation(mesh, pts[0], u[0], v[0]),
            float(triangle_areas_normals(ref.points, ref.faces)[0].sum()))


def as_tuple(m):
    return m.area_cm2, m.projected_area_cm2, m.max_deviation_cm, m.reference_area_cm2


def assert_same(new, old):
    """Areas to 1e-9 relative, the deviation to 1e-9 cm."""
    (a, p, d, r), (a0, p0, d0, r0) = new, old
    assert a == pytest.approx(a0, rel=1e-9, abs=1e-12)
    assert p == pytest.approx(p0, rel=1e-9, abs=1e-12)
    assert r == pytest.approx(r0, rel=1e-9, abs=1e-12)
    assert abs(d - d0) <= 1e-9


def random_leaves(seed, count=6):
    rng = np.random.default_rng(seed)
    grids = []
    for k in range(count):
        shape = LeafShape(length=rng.uniform(20, 110), width=rng.uniform(3, 12),
                          curvature_deg=rng.uniform(0, 120), azimuth_deg=rng.uniform(0, 360),
                          insertion_deg=rng.uniform(10, 70), fold_deg=rng.uniform(0, 40),
                          wave_amplitude=rng.uniform(0, 1.5), twist_deg=rng.uniform(-60, 60))
        rows = int(rng.choice([5, 9, 13]))          # shapes repeat, so batches hold several
        cols = int(rng.choice([3, 5]))
        pts = leaf_points(shape, rows, cols, rng=rng)
        tip = bool(rng.integers(2))
        if not tip:                                  # an open tip: a last row across
            pts[-1] = pts[-2] + 0.3 * (pts[-2] - pts[-3])
        grids.append(LeafGrid(1, k + 1, pts, tip))
    leaves, errors = fit_leaves(grids)
    assert not errors
    return leaves


# ------------------------------------------------------------------ point-to-triangle distance
finite = st.floats(-50, 50, allow_nan=False, allow_infinity=False)
vec = st.tuples(finite, finite, finite)


@settings(max_examples=300, deadline=None)
@given(vec, vec, vec, st.lists(vec, min_size=1, max_size=20))
# a sliver whose |bc|^2 cancelled to 0 as e00 - 2 e01 + e11: NaN before (hypothesis found it)
@example((0.0, 0.0, 0.0), (6.0, 0.0, 0.0), (6.0, 0.0, 5.960464477539063e-08), [(0.0, 0.0, 0.0)])
def test_point_triangle_distance_is_trimesh_closest_point(a, b, c, points):
    from trimesh.triangles import closest_point

    a, b, c = (np.array(x) for x in (a, b, c))
    p = np.array(points)
    cross = np.linalg.norm(np.cross(b - a, c - a))
    scale = max(np.linalg.norm(b - a), np.linalg.norm(c - a), 1e-3)
    d = measures.point_triangle_distance(p, a, b, c)
    assert d.shape == (len(p),) and np.all(d >= 0)
    if cross > 1e-6 * scale**2:                        # a proper triangle: trimesh is right
        q = closest_point(np.broadcast_to(np.stack([a, b, c]), (len(p), 3, 3)), p)
        assert np.allclose(d, np.linalg.norm(q - p, axis=1), rtol=1e-9, atol=1e-9 * scale)
    # never closer than the triangle allows: sampled points of the triangle are no nearer
    s, t = np.meshgrid(np.linspace(0, 1, 41), np.linspace(0, 1, 41))
    keep = s + t <= 1
    tri_pts = a + s[keep, None] * (b - a) + t[keep, None] * (c - a)
    brute = np.linalg.norm(p[:, None] - tri_pts[None], axis=2).min(axis=1)
    assert np.all(d <= brute + 1e-9 * scale)
    assert np.all(d >= brute - np.linalg.norm([b - a, c - a, c - b], axis=1).max() / 40 - 1e-9)


@pytest.mark.parametrize("corners", [
    ((0, 0, 0), (0, 0, 0), (0, 0, 0)),                 # a point
    ((0, 0, 0), (4, 0, 0), (4, 0, 0)),                 # a collapsed tip: b = c
    ((0, 0, 0), (0, 0, 0), (0, 3, 0)),                 # a = b
    ((0, 0, 0), (2, 0, 0), (5, 0, 0)),                 # collinear, c beyond b
    ((0, 0, 0), (4, 0, 0), (4, 1e-14, 0)),             # b and c apart by rounding only
])
def test_degenerate_triangles_are_their_edges(corners):
    a, b, c = (np.array(x, dtype=float) for x in corners)
    rng = np.random.default_rng(0)
    p = rng.uniform(-6, 9, (200, 3))
    d = measures.point_triangle_distance(p, a, b, c)
    ends = np.stack([a, b, c])
    gap = np.linalg.norm(ends[:, None] - ends[None], axis=2)
    i, j = np.unravel_index(np.argmax(gap), gap.shape)      # the segment: the farthest corners
    lo, seg = ends[i], ends[j] - ends[i]
    f = np.clip((p - lo) @ seg / max(seg @ seg, 1e-300), 0, 1)
    assert np.allclose(d, np.linalg.norm(p - (lo + f[:, None] * seg), axis=1), atol=1e-9)


def test_broadcasting_over_leading_axes():
    a, b, c = np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    p = np.array([[[0.2, 0.2, 2.0], [2.0, 0.0, 0.0]], [[-1.0, -1.0, 0.0], [0.5, 0.5, 0.0]]])
    d = measures.point_triangle_distance(p, a, b, c)
    assert d.shape == (2, 2)
    assert np.allclose(d, [[2.0, 1.0], [np.sqrt(2), 0.0]])


# ------------------------------------------------------------------ measures of many leaves
@pytest.mark.parametrize("seed", range(3))
def test_batched_measures_equal_the_per_leaf_trimesh_ones(seed):
    leaves = random_leaves(seed)
    for level in LEVELS:
        meshes = mesh_leaves(leaves, level)
        fresh = [Leaf(lf.grid, lf.surface) for lf in leaves]      # nothing cached
        for new, lf, ms in zip(measure_leaves(fresh, meshes), leaves, meshes):
            assert (new.plant, new.leaf, new.rows, new.cols) == (lf.grid.plant, lf.grid.leaf,
                                                                 *lf.grid.shape)
            assert new.level == ms.level and new.triangles == ms.n_triangles
            assert_same(as_tuple(new), old_measure(lf, ms))


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**31), st.sampled_from(LEVELS))
def test_batched_measures_on_random_leaves(seed, level):
    leaves = random_leaves(seed, count=3)
    meshes = mesh_leaves(leaves, level)
    for new, lf, ms in zip(measure_leaves(leaves, meshes), leaves, meshes):
        assert_same(as_tuple(new), old_measure(lf, ms))


def test_bundled_example_all_levels():
    leaves = read_leaves(example_points()).leaves
    rng = np.random.default_rng(3)
    sample = [leaves[i] for i in sorted(rng.choice(len(leaves), 25, replace=False))]
    for level in LEVELS:
        meshes = mesh_leaves(leaves, level)
        got = measure_leaves(leaves, meshes)
        for lf in sample:
            i = leaves.index(lf)
            assert_same(as_tuple(got[i]), old_measure(lf, meshes[i]))


def test_one_leaf_measure_is_the_batched_one():
    leaves = random_leaves(7, count=5)
    for level in (Level(interp=0), Level(triangles=8)):
        meshes = mesh_leaves(leaves, level)
        batch = measure_leaves(leaves, meshes)
        for lf, ms, b in zip(leaves, meshes, batch):
            assert as_tuple(measure(lf, ms)) == pytest.approx(as_tuple(b), rel=1e-13, abs=1e-13)


def test_pruning_never_misses_a_nearer_neighbour():
    """A leaf folded so tightly that surface points lie nearer other cells' triangles than
    their own: the deviation is still the exhaustive one."""
    rng = np.random.default_rng(11)
    s = np.linspace(0, 1, 9)
    t = np.linspace(-1, 1, 5)
    grids = []
    for k in range(4):
        x = 40 * s[:, None] + 0 * t
        y = 6 * t[None, :] * (1 - 0.8 * s[:, None])
        z = 8 * np.sin(9 * np.pi * s)[:, None] + 3 * t**2 + rng.normal(0, 0.5, (9, 5))
        grids.append(LeafGrid(1, k + 1, np.stack([x, y, z], axis=-1), False))
    leaves, _ = fit_leaves(grids)
    for level in (Level(interp=0), Level(triangles=6), Level(interp=1)):
        meshes = mesh_leaves(leaves, level)
        for new, lf, ms in zip(measure_leaves(leaves, meshes), leaves, meshes):
            assert_same(as_tuple(new), old_measure(lf, ms))


def test_flat_leaf_deviation_is_zero_and_k8_mesh_matches_its_samples():
    leaf = fit_leaves([LeafGrid(1, 1, np.stack([*np.meshgrid(
        np.linspace(0, 50, 5), np.linspace(-4, 4, 4), indexing="ij"), np.zeros((5, 4))],
        axis=-1), False)])[0][0]
    for level in (Level(interp=0), Level(interp=8), Level(triangles=4)):
        assert measure(leaf, mesh_leaves([leaf], level)[0]).max_deviation_cm < 1e-9
    curved = random_leaves(5, count=2)
    for m in measure_leaves(curved, mesh_leaves(curved, Level(interp=DEVIATION_K))):
        assert m.max_deviation_cm < 1e-9


def test_reference_areas_batched_and_cached():
    leaves = random_leaves(2, count=6)
    fresh = [Leaf(lf.grid, lf.surface) for lf in leaves]
    got = reference_areas(fresh)
    for lf, a in zip(leaves, got):
        assert a == pytest.approx(old_measure(lf, mesh_leaves([lf], Level(interp=0))[0])[3],
                                  rel=1e-12)
    assert all(lf.cache["reference_area_cm2"] == a for lf, a in zip(fresh, got))
    fresh[0].cache["reference_area_cm2"] = 123.0            # taken from the cache, not redone
    assert reference_areas(fresh)[0] == 123.0


def test_grid_areas_and_areas_equal_the_per_mesh_ones(leaf_grid):
    leaves = random_leaves(4, count=6)
    for level in (Level(interp=0), Level(interp=3), Level(triangles=5)):
        meshes = mesh_leaves(leaves, level)
        area, proj = measures.areas(meshes)
        for ms, a, p in zip(meshes, area, proj):
            assert a == pytest.approx(measures.area(ms), rel=1e-13)
            assert p == pytest.approx(measures.projected_area(ms), rel=1e-13)
            assert measures.grid_areas(ms.vertices[None])[0] == pytest.approx(
                measures.area(mesh_grid(ms.vertices, ms.u, ms.v)), rel=1e-13)
    tip = example_leaf(seed=3)                                # a collapsed tip: 4 triangles out
    assert measures.grid_areas(tip[None])[0] == pytest.approx(
        measures.area(mesh_grid(tip, np.arange(13.0), np.arange(5.0))), rel=1e-13)
    assert measures.areas([])[0].shape == (0,)


def test_measure_progress_and_cancel():
    leaves = random_leaves(1, count=4)
    meshes = mesh_leaves(leaves, Level(interp=0))
    seen = []
    measure_leaves(leaves, meshes, progress=lambda d, t: seen.append((d, t)))
    assert seen[-1] == (4, 4) and [d for d, _ in seen] == sorted(d for d, _ in seen)
    with pytest.raises(InterruptedError):
        measure_leaves(leaves, meshes, progress=lambda d, t: False)
    with pytest.raises(ValueError, match="meshes"):
        measure_leaves(leaves, meshes[:2])
    assert measure_leaves([], []) == []


def test_memory_bounded_chunks(monkeypatch):
    """Leaves are measured a few at a time: the same numbers with chunks of one leaf."""
    import maizeviz.mesh.levels as levels

    leaves = random_leaves(9, count=6)
    meshes = mesh_leaves(leaves, Level(interp=1))
    whole = [as_tuple(m) for m in measure_leaves(leaves, meshes)]
    monkeypatch.setattr(levels, "MEASURE_POINTS", 1)
    monkeypatch.setattr(measures, "CHUNK_PAIRS", 7)
    fresh = [Leaf(lf.grid, lf.surface) for lf in leaves]
    again = [as_tuple(m) for m in measure_leaves(fresh, meshes)]
    assert np.allclose(again, whole, rtol=1e-13, atol=0)
