"""Fewer triangles for drawing: vertex clustering within each leaf.

Each leaf's vertices are snapped to a grid of cubes ``cell_cm`` on a side; the vertices of one
leaf in one cube become one (their mean), triangles whose corners fall in fewer than three
cubes vanish, and copies of a triangle are kept once (Rossignac and Borrel's clustering, as
VTK's ``vtkQuadricClustering`` does it for a whole mesh, here per leaf so that no triangle
joins two leaves and each keeps its leaf's ids). It is for drawing only: a canopy read from a
mesh file has no surfaces to re-mesh coarser, and its light is traced on every triangle.

Numpy only (sorts of int64 keys, which release the GIL): 2.7 M triangles in about 2 s.
"""

from __future__ import annotations

import math

import numpy as np

#: Bits of each packed key: the group, then each cube coordinate relative to the group's
#: first vertex (signed, so a group may span 2**(bits-1) cubes either way).
_GROUP_BITS, _AXIS_BITS = 21, 14


def cluster_triangles(vertices: np.ndarray, faces: np.ndarray, group: np.ndarray,
                      cell_cm: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cluster the vertices of each group of triangles (a leaf) on a grid of ``cell_cm``.

    Parameters
    ----------
    vertices : (n, 3) float, cm
    faces : (F, 3) int, indices into ``vertices``
    group : (F,) int, each triangle's group (a leaf); clusters never join two groups
    cell_cm : side of the grid's cubes, cm (> 0)

    Returns
    -------
    vertices : (m, 3) float64, cm, the clusters' means
    faces : (G, 3) int64, G <= F, none degenerate, none repeated
    source : (G,) int64, the triangle of ``faces`` each one comes from (its ids are the new
        triangle's)
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    group = np.asarray(group)
    if not cell_cm > 0 or not math.isfinite(cell_cm):
        raise ValueError(f"cell size {cell_cm} cm: give a positive number")
    if len(faces) == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros(0, np.int64)
    _, g = np.unique(group, return_inverse=True)
    if g.max() >= 2 ** _GROUP_BITS:
        raise ValueError(f"{int(g.max()) + 1:,} groups: at most {2 ** _GROUP_BITS:,}")
    corner = faces.ravel()
    corner_g = np.repeat(g.astype(np.int64), 3)
    # each vertex in one group (a leaf's own vertices); a vertex two groups share is split
    vg = np.full(len(vertices), -1, np.int64)
    vg[corner] = corner_g
    if not np.array_equal(vg[corner], corner_g):
        pairs, corner = np.unique(corner * (int(g.max()) + 1) + corner_g, return_inverse=True)
        vertices, vg = vertices[pairs // (int(g.max()) + 1)], pairs % (int(g.max()) + 1)
    used = np.flatnonzero(vg >= 0)
    ug = vg[used]
    cube = np.floor(vertices[used] / cell_cm).astype(np.int64)             # (u, 3)
    # relative to the group's first vertex: small numbers whatever the field's size
    first = np.empty(int(g.max()) + 1, np.int64)
    first[ug[::-1]] = np.arange(len(used) - 1, -1, -1)
    rel = cube - cube[first[ug]]
    half = 2 ** (_AXIS_BITS - 1)
    if np.abs(rel).max() >= half:
        raise ValueError(f"a group spans over {half:,} cells of {cell_cm:g} cm: give a larger "
                         "cell")
    key = ug << (3 * _AXIS_BITS)
    for axis in range(3):
        key |= (rel[:, axis] + half) << ((2 - axis) * _AXIS_BITS)
    _, of_used, members = np.unique(key, return_inverse=True, return_counts=True)
    where = vertices[used]
    means = np.column_stack([np.bincount(of_used, weights=where[:, k]) for k in range(3)])
    means = means / members[:, None].astype(np.float64)
    cluster = np.empty(len(vertices), np.int64)
    cluster[used] = of_used
    new = cluster[corner].reshape(-1, 3)
    keep = (new[:, 0] != new[:, 1]) & (new[:, 1] != new[:, 2]) & (new[:, 0] != new[:, 2])
    kept = np.flatnonzero(keep)
    # one of each triangle (same three clusters, any order)
    s = np.sort(new[kept], axis=1)
    bits = max(int(len(means) - 1).bit_length(), 1)
    if 3 * bits <= 63:
        tri_key = (s[:, 0] << (2 * bits)) | (s[:, 1] << bits) | s[:, 2]
        _, once = np.unique(tri_key, return_index=True)
    else:
        _, once = np.unique(s, axis=0, return_index=True)
    once.sort()
    source = kept[once]
    return means, new[source], source


def cell_for(area_cm2: float, triangles: int) -> float:
    """A cube side (cm) that clusters leaves of total area ``area_cm2`` into about
    ``triangles`` triangles (a surface crossing cubes of side h keeps about two triangles per
    h**2 of its area)."""
    return math.sqrt(2.0 * max(area_cm2, 1e-9) / max(triangles, 1))
