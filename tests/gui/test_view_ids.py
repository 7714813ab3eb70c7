"""The 3D view keeps ids as wide as the data: a vertex shared by leaves whose plant and leaf ids
are near 2^31 is split by (vertex, plant, leaf), never by a packed number (a product of two
id ranges of 2^32 overflows int64)."""

import numpy as np
from maizeviz_app.viewport import _point_values

BIG = 2**31 - 1


def test_shared_vertices_split_by_wide_ids():
    # two triangles sharing an edge, of two leaves whose ids differ only far from zero
    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    plant = np.array([BIG, -BIG], np.int64)
    leaf = np.array([BIG, BIG - 1], np.int64)
    pts, f, (pp, pl) = _point_values(points, faces, plant, leaf)
    assert len(pts) == 6                                  # vertices 0 and 2 split in two
    for t in range(2):
        assert np.all(pp[f[t]] == plant[t]) and np.all(pl[f[t]] == leaf[t])
        assert np.array_equal(pts[f[t]], points[faces[t]])
