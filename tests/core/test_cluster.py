"""Vertex clustering per leaf, for drawing large canopies read from mesh files."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.leaf.synth import example_leaf
from maizeviz.mesh.cluster import cell_for, cluster_triangles
from maizeviz.mesh.tessellate import grid_faces, triangle_areas_normals


def _leaves(n: int, shift: float = 0.0):
    """``n`` fine leaf grids (13 x 5 points refined 4 times each way), side by side along y
    by ``shift`` cm (0: all in the same place, so their cubes coincide)."""
    verts, faces, group = [], [], []
    for k in range(n):
        g = example_leaf(seed=k + 1)
        from scipy.ndimage import zoom

        fine = np.stack([zoom(g[..., a], 4, order=1) for a in range(3)], axis=-1)
        fine[..., 1] += k * shift
        r, c = fine.shape[:2]
        off = sum(len(v) for v in verts)
        verts.append(fine.reshape(-1, 3))
        f = grid_faces(r, c) + off
        faces.append(f)
        group.append(np.full(len(f), 10 + 7 * k))
    return np.vstack(verts), np.vstack(faces), np.concatenate(group)


def _triangles(vertices, faces):
    """The triangles as sets of rounded corner coordinates (order-free)."""
    return {frozenset(map(tuple, np.round(vertices[f], 6))) for f in faces}


@settings(max_examples=25, deadline=None)
@given(st.floats(0.3, 6.0), st.integers(0, 2**31 - 1))
def test_clusters_keep_leaves_apart_and_never_add_triangles(cell, seed):
    v, f, g = _leaves(3, shift=0.0)                     # three leaves in the same cubes
    rng = np.random.default_rng(seed)
    order = rng.permutation(len(f))
    nv, nf, src = cluster_triangles(v, f[order], g[order], cell)
    assert len(nf) <= len(f) and len(src) == len(nf)
    assert np.all((nf[:, 0] != nf[:, 1]) & (nf[:, 1] != nf[:, 2]) & (nf[:, 0] != nf[:, 2]))
    assert len({tuple(sorted(t)) for t in nf.tolist()}) == len(nf)          # no copies
    group = g[order][src]
    # no vertex is shared by two leaves, and each stays inside its leaf's bounding box
    for vertex in np.unique(nf):
        assert len(np.unique(group[(nf == vertex).any(axis=1)])) == 1
    for leaf in np.unique(g):
        mine = v[np.unique(f[g == leaf])]
        drawn = nv[np.unique(nf[group == leaf])]
        assert len(drawn) > 0
        assert np.all(drawn >= mine.min(axis=0) - 1e-9) and np.all(drawn <= mine.max(axis=0)
                                                                      + 1e-9)
    # the order of the triangles does not change the result
    nv2, nf2, _ = cluster_triangles(v, f, g, cell)
    assert _triangles(nv, nf) == _triangles(nv2, nf2)


def test_a_small_cell_keeps_the_mesh_and_a_larger_one_thins_it_by_its_area():
    # vertices 1 cm apart, each at the centre of its own 0.25 cm cube: nothing merges
    ii, jj = np.meshgrid(np.arange(12.0), np.arange(7.0), indexing="ij")
    lattice = np.column_stack([ii.ravel(), jj.ravel(), 0.3 * ii.ravel()]) + 0.125
    faces = grid_faces(12, 7)
    nv, nf, src = cluster_triangles(lattice, faces, np.zeros(len(faces)), 0.25)
    assert _triangles(nv, nf) == _triangles(lattice, faces)
    np.testing.assert_array_equal(np.sort(src), np.arange(len(faces)))
    v, f, g = _leaves(4, shift=20.0)
    area, _ = triangle_areas_normals(v, f)
    target = len(f) // 6
    _, coarse, _ = cluster_triangles(v, f, g, cell_for(float(area.sum()), target))
    assert 0.3 * target < len(coarse) < 3 * target
    with pytest.raises(ValueError, match="cell size"):
        cluster_triangles(v, f, g, 0.0)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(2, 40))
def test_repeated_triangles_are_those_with_the_corners_of_an_earlier_one(seed, n):
    """Against numpy's unique rows: the same corners by position (-0.0 is 0.0), in any order
    and orientation, repeat an earlier triangle."""
    from maizeviz.canopy.from_mesh import repeated_triangles

    rng = np.random.default_rng(seed)
    vertices = rng.integers(-2, 3, (n, 3)).astype(np.float64) * 0.5
    vertices[rng.random(n) < 0.3] *= -1.0                  # -0.0 where 0.0 was
    faces = rng.integers(0, n, (3 * n, 3))
    got = repeated_triangles(vertices, faces)
    _, same = np.unique(vertices, axis=0, return_inverse=True)
    corners = [tuple(sorted(same.reshape(-1)[f])) for f in faces]
    want = [c in corners[:k] for k, c in enumerate(corners)]
    np.testing.assert_array_equal(got, want)
