"""The Embree scene filled by memory copy is the scene embreex fills element by element: the
same hits, triangle by triangle, on the bundled canopy (real Embree, no mock)."""

import numpy as np
import pytest
from embreex.rtcore_scene import EmbreeScene

from maizeviz.canopy.layout import layout_for
from maizeviz.canopy.scene import build_canopy
from maizeviz.leaf.fit import read_leaves
from maizeviz.mesh.embree_fill import fill
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
    assert fill(scene, v, np.array([[0, 1, 2]], np.int32)) is False
