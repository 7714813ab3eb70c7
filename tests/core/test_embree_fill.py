"""The Embree scene filled by memory copy is the scene embreex fills element by element: the
same hits, triangle by triangle, on the bundled canopy (real Embree, no mock)."""

import numpy as np
import pytest
from embree_contract import assert_same_hits
from embreex.rtcore_scene import EmbreeScene

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.leaf.fit import read_leaves
from maizeviz.mesh.embree_fill import fill
from maizeviz.mesh.embree_isa import device, requested
from maizeviz.mesh.levels import parse_level
from maizeviz.mesh.raytrace import RayScene
from maizeviz.resources import example_points


@pytest.fixture(scope="module")
def canopy():
    leaves = read_leaves(example_points()).leaves
    return build_canopy(leaves, layout_for(leaves, (3, 3)), parse_level("K1"))


@pytest.fixture(scope="module")
def rays(canopy):
    """Rays from above the canopy in many directions, through its whole extent."""
    rng = np.random.default_rng(3)
    n = 200_000
    lo, hi = canopy.vertices.min(axis=0), canopy.vertices.max(axis=0)
    org = np.column_stack([rng.uniform(lo[0], hi[0], n), rng.uniform(lo[1], hi[1], n),
                           np.full(n, hi[2] + 10.0)])
    zen, az = np.arccos(rng.uniform(0.2, 1.0, n)), rng.uniform(0, 2 * np.pi, n)
    d = -np.column_stack([np.sin(zen) * np.sin(az), np.sin(zen) * np.cos(az), np.cos(zen)])
    return org, d


def test_the_copy_fill_is_used_and_gives_embreexs_hits(canopy, rays):
    fast = RayScene(canopy.vertices, canopy.faces)
    slow = RayScene(canopy.vertices, canopy.faces, by_copy=False)
    assert fast.filled_by_copy and not slow.filled_by_copy
    org, d = rays
    ids_f, t_f = fast.first_hit(org, d)
    ids_s, t_s = slow.first_hit(org, d)
    assert 0.2 < (ids_f >= 0).mean() < 1.0          # the rays meet leaves and gaps
    np.testing.assert_array_equal(ids_f, ids_s)
    np.testing.assert_array_equal(t_f, t_s)
    np.testing.assert_array_equal(fast.occluded(org, d, 150.0), slow.occluded(org, d, 150.0))
    np.testing.assert_array_equal(fast.distance(org, d, 150.0), slow.distance(org, d, 150.0))


def test_every_triangle_is_where_its_faces_say(canopy):
    """One ray straight down through the centroid of each of a sample of triangles hits that
    triangle or one above it, never a triangle below it or nothing: vertices and indices were
    copied in place."""
    scene = RayScene(canopy.vertices, canopy.faces)
    pick = np.random.default_rng(0).choice(len(canopy.faces), 5000, replace=False)
    tri = canopy.vertices[canopy.faces[pick]]
    centre = tri.mean(axis=1)
    org = centre + [0, 0, 500.0]
    ids, t = scene.first_hit(org, np.tile([0.0, 0.0, -1.0], (len(pick), 1)))
    assert (ids >= 0).all()
    assert (t <= 500.0 + 1e-3).all()
    assert (ids == pick).mean() > 0.3                # many are the topmost at their centroid


def test_a_committed_scene_is_left_to_embreex():
    scene = EmbreeScene(robust=False)
    scene.run(np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32))
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    assert not fill(scene, v, np.array([[0, 1, 2]], np.int32))


def test_embree_reads_the_canopys_faces_in_place_and_builds_a_compact_bvh(canopy, rays):
    """The canopy's int32 faces are Embree's index buffer (no copy) and the BVH is compact;
    the hits are those of a scene with copied buffers, and, within the contract of Embree's
    paths (tests/core/embree_contract.py), of Embree's default BVH."""
    fast = RayScene(canopy.vertices, canopy.faces)
    assert fast.compact and fast._shared is canopy.faces
    copied = RayScene(canopy.vertices, canopy.faces.astype(np.int64))      # not int32: copied
    assert copied._shared is None
    default = EmbreeScene(device(requested()), robust=False)   # MAIZEVIZ_EMBREE_ISA's too
    assert fill(default, canopy.vertices, canopy.faces.astype(np.int64)) == 1
    org, d = rays
    ids, t = fast.first_hit(org, d)
    for other in (copied,):
        i2, t2 = other.first_hit(org, d)
        np.testing.assert_array_equal(ids, i2)
        np.testing.assert_array_equal(t, t2)
    out = default.run(org.astype(np.float32), d.astype(np.float32), output=True)
    # another BVH layout, other code (the compact one computes each normal as it goes): the
    # contract between Embree's paths, not the same bits
    assert_same_hits(canopy.vertices, canopy.faces, org, d, None, (ids, t),
                     (out["primID"], out["tfar"]))


def test_parts_and_snapping_as_they_are_copied(canopy, rays):
    """Vertices and faces given in parts, x and y rounded to a grid as Embree's copy is made:
    the scene of the whole arrays rounded first."""
    from maizeviz.light.scene.periodic import snap

    q = 2.0 ** -12
    k = len(canopy.vertices) // 3
    faces = canopy.faces.astype(np.int64)
    first = faces[np.all(faces < k, axis=1)]
    rest = faces[~np.all(faces < k, axis=1)]
    parts = RayScene([canopy.vertices[:k], canopy.vertices[k:]], [first, rest], snap_q=q)
    whole = RayScene(snap(canopy.vertices, q), np.vstack([first, rest]))
    assert parts.n_triangles == len(canopy.faces)
    org, d = rays
    for a, b in zip(parts.first_hit(org, d), whole.first_hit(org, d)):
        np.testing.assert_array_equal(a, b)
