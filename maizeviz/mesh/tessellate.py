"""Triangle meshes of leaves: a structured grid of vertices split into triangles.

Every mesh level of maizeviz (dense reference, standard, simplified) is a grid of vertices
over the leaf's (u, v) parameter lines, so one triangulation serves all of them. Each quad
(i, j) - (i+1, j) - (i+1, j+1) - (i, j+1) gives two triangles wound so that their normal is
dS/du x dS/dv: the upper face under the column convention of docs/method.md. Zero-area triangles
(at a collapsed tip) are dropped.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np


@lru_cache(maxsize=256)
def grid_faces(a: int, b: int) -> np.ndarray:
    """Triangles of an a x b vertex grid (row-major vertex ids): (2 (a-1)(b-1), 3) int32."""
    idx = np.arange(a * b, dtype=np.int32).reshape(a, b)
    p00, p10 = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    p11, p01 = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    tri = np.empty((2 * len(p00), 3), dtype=np.int32)
    tri[0::2] = np.column_stack([p00, p10, p11])
    tri[1::2] = np.column_stack([p00, p11, p01])
    tri.setflags(write=False)
    return tri


def triangle_areas_normals(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Areas (F,) cm2 and unit normals (F, 3) of triangles; works with a leading batch axis."""
    v0 = np.take(vertices, faces[..., 0], axis=-2)
    e1 = np.take(vertices, faces[..., 1], axis=-2) - v0
    e2 = np.take(vertices, faces[..., 2], axis=-2) - v0
    cross = np.cross(e1, e2)
    twice = np.linalg.norm(cross, axis=-1)
    normals = cross / np.where(twice > 0, twice, 1.0)[..., None]
    return 0.5 * twice, normals


@dataclass(frozen=True)
class LeafMesh:
    """A leaf's triangle mesh at one level.

    Attributes
    ----------
    vertices : (a, b, 3) float64, cm
        Vertex grid over parameter lines ``u`` (along the midrib) and ``v`` (across).
    u : (a,) float64, v : (b,) float64
        Surface parameters of the grid lines.
    faces : (F, 3) int32
        Triangles into ``vertices.reshape(-1, 3)``, zero-area ones removed, upper face out.
    level : str
        Human label of the level ("K=4", "standard", "8 triangles").
    plant, leaf : int
    """

    vertices: np.ndarray
    u: np.ndarray
    v: np.ndarray
    faces: np.ndarray
    level: str = ""
    plant: int = -1
    leaf: int = -1

    @property
    def points(self) -> np.ndarray:
        """(a * b, 3) float64, cm: the vertices as a flat list, indexed by ``faces``."""
        return self.vertices.reshape(-1, 3)

    @property
    def n_triangles(self) -> int:
        return len(self.faces)


def degenerate_faces(vertices: np.ndarray, rel_tol: float = 1e-9) -> np.ndarray:
    """Mask (2 (a-1)(b-1),) of the triangles of a vertex grid (a, b, 3) with a zero-length edge.

    On a grid, a triangle has zero area where two of its corners coincide (a collapsed tip
    row); checking the grid edges once is much cheaper than computing every area.
    """
    h = np.diff(vertices, axis=1)
    h = np.einsum("ijk,ijk->ij", h, h)                                  # (a, b-1) squared
    w = np.diff(vertices, axis=0)
    w = np.einsum("ijk,ijk->ij", w, w)                                  # (a-1, b)
    tol = rel_tol**2 * max(h.max(initial=0.0), w.max(initial=0.0), 1e-300)
    h0, w0 = h <= tol, w <= tol
    bad = np.empty((vertices.shape[0] - 1, vertices.shape[1] - 1, 2), dtype=bool)
    bad[..., 0] = h0[1:] | w0[:, :-1]          # (p00, p10, p11): edges p10-p11 and p00-p10
    bad[..., 1] = h0[:-1] | w0[:, 1:]          # (p00, p11, p01): edges p00-p01 and p11-p01
    return bad.reshape(-1)


def mesh_grid(vertices: np.ndarray, u: np.ndarray, v: np.ndarray, level: str = "",
              plant: int = -1, leaf: int = -1) -> LeafMesh:
    """Triangulate a vertex grid (a, b, 3) and drop zero-area triangles."""
    a, b = vertices.shape[:2]
    faces = grid_faces(a, b)
    bad = degenerate_faces(vertices)
    return LeafMesh(vertices, u, v, faces[~bad] if bad.any() else faces, level, plant, leaf)


def degenerate_faces_many(vertices: np.ndarray, rel_tol: float = 1e-9) -> np.ndarray:
    """:func:`degenerate_faces` of many grids (L, a, b, 3) at once: (L, 2 (a-1)(b-1)) bool."""
    h = np.diff(vertices, axis=2)
    h = np.einsum("lijk,lijk->lij", h, h)                               # (L, a, b-1) squared
    w = np.diff(vertices, axis=1)
    w = np.einsum("lijk,lijk->lij", w, w)                               # (L, a-1, b)
    nl = len(vertices)
    longest = np.maximum(h.reshape(nl, -1).max(axis=1, initial=0.0),
                         w.reshape(nl, -1).max(axis=1, initial=0.0))
    tol = (rel_tol**2 * np.maximum(longest, 1e-300))[:, None, None]
    h0, w0 = h <= tol, w <= tol
    bad = np.empty((nl, vertices.shape[1] - 1, vertices.shape[2] - 1, 2), dtype=bool)
    bad[..., 0] = h0[:, 1:] | w0[:, :, :-1]
    bad[..., 1] = h0[:, :-1] | w0[:, :, 1:]
    return bad.reshape(nl, -1)


def mesh_grids(vertices: np.ndarray, u: np.ndarray, v: np.ndarray, level: str = "",
               plants=None, leaves=None) -> list[LeafMesh]:
    """:func:`mesh_grid` of many vertex grids of one shape at once.

    Parameters
    ----------
    vertices : (L, a, b, 3) float64, cm; u : (L, a), v : (L, b) float64
    plants, leaves : (L,) ints, the ids of each mesh (default -1)

    Returns
    -------
    L meshes, their vertices and parameters views of the arrays given.
    """
    nl, a, b = vertices.shape[:3]
    faces = grid_faces(a, b)
    bad = degenerate_faces_many(vertices)
    some = list(np.any(bad, axis=1))
    plants = [-1] * nl if plants is None else np.asarray(plants).tolist()
    leaves = [-1] * nl if leaves is None else np.asarray(leaves).tolist()
    return [LeafMesh(vertices[k], u[k], v[k], faces[~bad[k]] if some[k] else faces, level,
                     plants[k], leaves[k]) for k in range(nl)]


def merge_meshes(meshes: list[LeafMesh]) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Concatenate leaf meshes for export.

    Returns
    -------
    points : (V, 3) float64 cm, faces : (F, 3) int64,
    cell data : {"plant": (F,) int32, "leaf": (F,) int32}
    """
    from maizeviz.errors import MaizevizError

    if not meshes:
        raise MaizevizError("nothing to export: no leaf mesh")
    offsets = np.cumsum([0] + [len(m.points) for m in meshes[:-1]])
    faces = np.concatenate([m.faces.astype(np.int64) + o for m, o in zip(meshes, offsets)])
    plant = np.concatenate([np.full(len(m.faces), m.plant, np.int32) for m in meshes])
    leaf = np.concatenate([np.full(len(m.faces), m.leaf, np.int32) for m in meshes])
    return np.concatenate([m.points for m in meshes]), faces, {"plant": plant, "leaf": leaf}
