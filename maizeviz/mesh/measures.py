"""Leaf measures: area, projected area, deviation from the smooth surface."""

from __future__ import annotations

import numpy as np

from maizeviz.mesh.tessellate import LeafMesh, grid_faces, triangle_areas_normals


def area(mesh: LeafMesh) -> float:
    """One-sided leaf area (cm2): the sum of the triangle areas."""
    a, _ = triangle_areas_normals(mesh.points, mesh.faces)
    return float(a.sum())


def projected_area(mesh: LeafMesh, direction=(0.0, 0.0, 1.0)) -> float:
    """Area projected on the plane normal to ``direction`` (cm2): sum of A |n . d|.

    The default is the horizontal projected area (on the ground, light from the zenith). For a
    single leaf it cannot exceed the leaf area; overlapping parts are counted twice.
    """
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    a, n = triangle_areas_normals(mesh.points, mesh.faces)
    return float((a * np.abs(n @ d)).sum())


def max_deviation(mesh: LeafMesh, ref_points: np.ndarray, ref_u: np.ndarray,
                  ref_v: np.ndarray) -> float:
    """Largest distance (cm) from points of the smooth surface to the mesh.

    Each reference point at parameters (u, v) is measured against the triangles of the mesh
    cell that covers (u, v) and of its eight neighbours, so the cost is linear in the number of
    reference points. Measuring from the surface to the mesh (not the other way) is what
    catches a shortened leaf: a collapsed tip leaves surface points far from any triangle.

    Parameters
    ----------
    ref_points : (A, B, 3) float64, cm: the surface sampled on the grid ``ref_u`` x ``ref_v``.
    ref_u : (A,), ref_v : (B,) float64 in [0, 1]
    """
    from trimesh.triangles import closest_point  # ~0.6 s to import: only when measuring

    a, b = mesh.vertices.shape[:2]
    faces = grid_faces(a, b).reshape(a - 1, b - 1, 2, 3)
    ci = np.clip(np.searchsorted(mesh.u, ref_u, side="right") - 1, 0, a - 2)
    cj = np.clip(np.searchsorted(mesh.v, ref_v, side="right") - 1, 0, b - 2)
    ci, cj = np.meshgrid(ci, cj, indexing="ij")
    pts = ref_points.reshape(-1, 3)
    ci, cj = ci.ravel(), cj.ravel()
    best = np.full(len(pts), np.inf)
    flat = mesh.points
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            ii = np.clip(ci + di, 0, a - 2)
            jj = np.clip(cj + dj, 0, b - 2)
            for t in range(2):
                tri = flat[faces[ii, jj, t]]                       # (P, 3, 3)
                with np.errstate(all="ignore"):
                    q = closest_point(tri, pts)
                d = np.linalg.norm(q - pts, axis=1)
                best = np.fmin(best, np.where(np.isfinite(d), d, np.inf))
    return float(best.max()) if len(best) else 0.0
