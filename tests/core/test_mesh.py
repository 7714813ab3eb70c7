"""Mesh levels and leaf measures."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.errors import MaizevizError
from maizeviz.leaf.fit import fit_leaves
from maizeviz.leaf.grid import LeafGrid
from maizeviz.leaf.synth import LeafShape, example_leaf, leaf_points
from maizeviz.mesh import measures
from maizeviz.mesh.levels import Level, measure, mesh_leaf, mesh_leaves, parse_level, parse_levels
from maizeviz.mesh.simplify import count_triangles, select_lines


def leaf_of(points, tip=False, plant=1, leaf=1):
    leaves, errors = fit_leaves([LeafGrid(plant, leaf, points, tip)])
    assert not errors
    return leaves[0]


def rectangle(m=5, n=4, length=50.0, width=8.0, tilt_deg=0.0):
    """A flat rectangle along x, tilted about the x axis by ``tilt_deg``."""
    s = np.linspace(0, length, m)
    t = np.linspace(-width / 2, width / 2, n)          # col 0 = right margin: -y, tip at +x
    x, y = np.meshgrid(s, t, indexing="ij")
    c, sn = np.cos(np.radians(tilt_deg)), np.sin(np.radians(tilt_deg))
    return np.stack([x, y * c, y * sn], axis=-1)


@pytest.mark.parametrize("k", [0, 1, 4])
def test_flat_rectangle_area_exact(k):
    leaf = leaf_of(rectangle())
    mesh = mesh_leaf(leaf, Level(interp=k))
    assert measures.area(mesh) == pytest.approx(400.0, rel=1e-12)
    assert measures.projected_area(mesh) == pytest.approx(400.0, rel=1e-12)


@pytest.mark.parametrize("tilt", [0.0, 30.0, 60.0, 85.0])
def test_tilted_rectangle_projects_by_cosine(tilt):
    mesh = mesh_leaf(leaf_of(rectangle(tilt_deg=tilt)), Level(interp=2))
    assert measures.area(mesh) == pytest.approx(400.0, rel=1e-9)
    assert measures.projected_area(mesh) == pytest.approx(400.0 * np.cos(np.radians(tilt)),
                                                          rel=1e-9, abs=1e-9)


def test_upper_face_normals_point_up():
    mesh = mesh_leaf(leaf_of(rectangle()), Level(interp=0))
    from maizeviz.mesh.tessellate import triangle_areas_normals
    _, n = triangle_areas_normals(mesh.points, mesh.faces)
    assert np.allclose(n, [0, 0, 1])


@pytest.mark.parametrize("m, n, k", [(13, 5, 0), (13, 5, 4), (7, 3, 1), (2, 2, 3), (40, 9, 2)])
def test_triangle_counts_per_interp_level(m, n, k):
    mesh = mesh_leaf(leaf_of(rectangle(m, n)), Level(interp=k))
    assert mesh.n_triangles == 2 * (m - 1) * (k + 1) * (n - 1) * (k + 1)


def test_collapsed_tip_drops_degenerate_triangles(leaf_grid):
    leaf = leaf_of(leaf_grid, tip=True)
    std = mesh_leaf(leaf, Level(interp=0))
    assert std.n_triangles == 2 * 12 * 4 - 4
    ref = mesh_leaf(leaf, Level(interp=4))
    assert ref.n_triangles == 2 * 12 * 5 * 4 * 5 - 4 * 5


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 120), st.integers(0, 2**31))
def test_budget_never_exceeded_and_tip_kept(budget, seed):
    rng = np.random.default_rng(seed)
    shape = LeafShape(length=rng.uniform(30, 100), width=rng.uniform(4, 11),
                      curvature_deg=rng.uniform(0, 90), azimuth_deg=rng.uniform(0, 360))
    pts = leaf_points(shape, int(rng.integers(5, 16)), int(rng.choice([3, 5, 7])), rng=rng)
    leaf = leaf_of(pts, tip=True)
    mesh = mesh_leaf(leaf, Level(triangles=budget))
    assert 1 <= mesh.n_triangles <= budget
    used = np.unique(mesh.faces)
    assert np.any(np.all(np.isclose(mesh.points[used], pts[-1, 0]), axis=1)), "tip dropped"
    assert mesh.u[0] == 0.0 and mesh.u[-1] == 1.0, "collar or tip cross-section dropped"


def test_budget_below_coarsest_refused(leaf_grid):
    with pytest.raises(ValueError, match="below the coarsest"):
        select_lines(rectangle(), 1, tip_collapsed=False)
    assert count_triangles(2, 2, True) == 1


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("budget", [8, 16, 36])
def test_area_within_5_percent_of_reference_from_8_triangles(seed, budget):
    rng = np.random.default_rng(seed)
    shape = LeafShape(length=rng.uniform(50, 100), width=rng.uniform(6, 11),
                      curvature_deg=rng.uniform(20, 90), insertion_deg=rng.uniform(20, 60))
    leaf = leaf_of(leaf_points(shape, 13, 5, rng=rng), tip=True)
    for preserve in (True, False):
        m = measure(leaf, mesh_leaf(leaf, Level(triangles=budget), preserve_area=preserve))
        limit = 5.0 if preserve else 12.0
        assert abs(m.area_error_pct) < limit
        assert m.triangles <= budget
    m = measure(leaf, mesh_leaf(leaf, Level(triangles=budget)))
    assert abs(m.area_error_pct) < 1e-6                       # area preserved exactly
    assert abs(m.projected_area_cm2 / measure(leaf, mesh_leaf(leaf, Level(interp=4)))
               .projected_area_cm2 - 1) < 0.10


def test_midrib_kept_where_budget_allows(leaf_grid):
    leaf = leaf_of(leaf_grid, tip=True)
    mesh = mesh_leaf(leaf, Level(triangles=36))
    assert mesh.vertices.shape[1] >= 3
    assert np.any(np.isclose(mesh.v, leaf.surface.params_v[0][2]))


def test_deviation_grows_as_mesh_coarsens(leaf_grid):
    leaf = leaf_of(leaf_grid, tip=True)
    devs = [measure(leaf, mesh_leaf(leaf, lv)).max_deviation_cm
            for lv in parse_levels("K8,K4,standard,36,8,3")]
    assert devs[0] < 1e-9
    assert devs == sorted(devs)
    assert devs[-1] > 1.0


def test_batch_meshing_matches_single(leaf_grid):
    grids = [LeafGrid(1, i, example_leaf(seed=i), True) for i in range(3)]
    grids.append(LeafGrid(2, 1, example_leaf(rows=9, cols=3, seed=9), True))
    leaves, _ = fit_leaves(grids)
    for level in (Level(interp=3), Level(triangles=8)):
        batch = mesh_leaves(leaves, level)
        for lf, mb in zip(leaves, batch):
            one = mesh_leaf(lf, level)
            assert (mb.plant, mb.leaf) == lf.key
            assert np.allclose(one.points, mb.points) and np.array_equal(one.faces, mb.faces)


def test_progress_and_cancel():
    grids = [LeafGrid(1, i, example_leaf(seed=i), True) for i in range(4)]
    leaves, _ = fit_leaves(grids)
    seen = []
    mesh_leaves(leaves, Level(triangles=8), progress=lambda d, t: seen.append((d, t)))
    assert seen[-1] == (4, 4)
    with pytest.raises(InterruptedError):
        mesh_leaves(leaves, Level(triangles=8), progress=lambda d, t: False)


@pytest.mark.parametrize("text, level", [("K4", Level(interp=4)), ("k=1", Level(interp=1)),
                                         ("standard", Level(interp=0)), ("36", Level(triangles=36)),
                                         ("8t", Level(triangles=8))])
def test_parse_levels(text, level):
    assert parse_level(text) == level


@pytest.mark.parametrize("bad", ["K-1", "fine", "0", ""])
def test_parse_bad_levels(bad):
    with pytest.raises(MaizevizError, match="mesh level|triangle budget"):
        parse_level(bad)
