"""A tiled canopy in a periodic field, traced through one block of it.

The paper's canopy is a digitized block of plants tiled A x B times (``--tile 3x3``: 81 plants
from 9). In a periodic field the tiled plot repeats forever, and so does the block: the field
is the block repeated with the block's period. Its Embree scene can then be the block alone
(with its neighbours' overhangs copied in): A x B times fewer triangles to build a BVH over
(0.35 s instead of 3.1 s at K = 4 for the bundled 3 x 3 tiling), rays wrapped over the block's
period instead of the plot's (:mod:`maizeviz.light.scene.periodic`).

Hits still name the tiled canopy's triangles: a hit in the copy of the block under cell (i, j)
of the field (cell (0, 0) is the tile (0, 0), the digitized block) lies on the plant of tile
(i, j) folded into the plot (modulo A, B), and is reported as that tile's triangle, so per-leaf
and per-plant light, heatmaps and transmission are the tiled scene's.

Where it applies (:func:`block_tiling`): the canopy's placements form whole tiles, each tile
the same plants in the same order, every tile's triangles the block's moved by a whole number
of block periods once on the field's grid (:func:`maizeviz.light.scene.periodic.snap`), exactly, and
the plot exactly A x B periods. Then the block scene gives the same hits as the tiled scene,
ray for ray (``tests/core/test_tiling.py``). Otherwise (a layout file, an edited layout, a
spacing that is not a multiple of the grid step, 2^-12 cm here) :func:`block_tiling` returns None
and the whole canopy is traced.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.light.scene.periodic import Wrap, overhang_copies, snap


@dataclass(frozen=True)
class BlockTiling:
    """How a canopy tiles its block.

    Attributes
    ----------
    shape : (A, B) tiles along x and y
    first_key : (i0, j0) the smallest tile key (tile (0, 0) is the block)
    order : (A, B) int64, the tile's index in the canopy's placement order, by key - first_key
    base : index of tile (0, 0) in that order
    faces, stalk_faces, vertices, stalk_vertices : per tile (F_t, S_t, V_t, SV_t)
    wrap : Wrap of the block (its footprint, on the plot's grid)
    plot_wrap : Wrap of the plot
    """

    shape: tuple[int, int]
    first_key: tuple[int, int]
    order: np.ndarray
    base: int
    faces: int
    stalk_faces: int
    vertices: int
    stalk_vertices: int
    wrap: Wrap
    plot_wrap: Wrap


def _tiles(canopy: Canopy) -> tuple[list[tuple[int, int]], int] | None:
    """The tile keys in placement order and the placements per tile, when the placements come
    in whole tiles of the same plants; else None."""
    places = canopy.layout.placements
    keys: list[tuple[int, int]] = []
    for p in places:
        if not keys or keys[-1] != p.tile:
            keys.append(p.tile)
    if len(set(keys)) != len(keys) or len(places) % len(keys):
        return None
    per = len(places) // len(keys)
    first = [(p.plant, p.azimuth_deg) for p in places[:per]]
    for t in range(1, len(keys)):
        group = places[t * per:(t + 1) * per]
        if any(p.tile != keys[t] for p in group) or \
                [(p.plant, p.azimuth_deg) for p in group] != first:
            return None
    return keys, per


def _moved_exactly(v: np.ndarray, per_tile: int, keys: list[tuple[int, int]], base: int,
                   wrap: Wrap) -> bool:
    """Whether the vertices (T V_t, 3) of each tile, on the grid, are the base tile's moved by
    its key times the period, exactly."""
    if len(v) != per_tile * len(keys):
        return False
    ref = snap(v[base * per_tile:(base + 1) * per_tile], wrap.q)
    for t, (i, j) in enumerate(keys):
        moved = snap(v[t * per_tile:(t + 1) * per_tile], wrap.q)
        moved[:, 0] -= i * wrap.w
        moved[:, 1] -= j * wrap.h
        if not np.array_equal(moved, ref):
            return False
    return True


def _same_faces(f: np.ndarray, per_tile: int, n_vertices: int, n_tiles: int) -> bool:
    """Whether every tile's faces (T F_t, 3) are the first tile's, numbered in its vertices."""
    if len(f) != per_tile * n_tiles:
        return False
    ref = f[:per_tile]
    return all(np.array_equal(f[t * per_tile:(t + 1) * per_tile] - t * n_vertices, ref)
               for t in range(1, n_tiles))


def block_tiling(canopy: Canopy) -> BlockTiling | None:
    """The canopy's tiling of its central block when the periodic field of its plot is
    exactly the block's (see the module docstring); None otherwise."""
    found = _tiles(canopy)
    if found is None or len(found[0]) < 2 or (0, 0) not in found[0]:
        return None
    keys, _ = found
    ks = np.array(keys)
    lo = ks.min(axis=0)
    a, b = (ks.max(axis=0) - lo + 1).tolist()
    if a * b != len(keys):
        return None
    layout = canopy.layout
    plot_wrap = Wrap.of(layout.bounds)
    wrap = Wrap.of(layout.centre_bounds, layout.bounds)
    if wrap.q != plot_wrap.q or plot_wrap.w != a * wrap.w or plot_wrap.h != b * wrap.h:
        return None
    n = len(keys)
    nf, nv = canopy.n_triangles, len(canopy.vertices)
    ns, nsv = len(canopy.stalk_faces), len(canopy.stalk_vertices)
    if nf % n or nv % n or ns % n or nsv % n:
        return None
    base = keys.index((0, 0))
    ft, vt, st, svt = nf // n, nv // n, ns // n, nsv // n
    if not (_same_faces(canopy.faces, ft, vt, n) and _same_faces(canopy.stalk_faces, st, svt, n)
            and all(np.array_equal(c.reshape(n, -1), np.tile(c[:ft], (n, 1)))
                    for c in (canopy.face_plant, canopy.face_leaf))
            and _moved_exactly(canopy.vertices, vt, keys, base, wrap)
            and _moved_exactly(canopy.stalk_vertices, svt, keys, base, wrap)):
        return None
    order = np.empty((a, b), np.int64)
    for t, (i, j) in enumerate(keys):
        order[i - lo[0], j - lo[1]] = t
    return BlockTiling((a, b), (int(lo[0]), int(lo[1])), order, base, ft, st, vt, svt, wrap,
                       plot_wrap)


def block_mesh(canopy: Canopy, tiling: BlockTiling, with_stalks: bool
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The block's scene: vertices (V, 3) cm on the grid, faces (F, 3) (the block's leaves,
    its stalks if traced, then copies of its neighbours' overhangs), and for each face its
    triangle within a tile (F,) int64 (leaves 0 .. F_t - 1, then stalks) and the cell
    (F, 2) int64 of the block copy it stands for (0, 0 but for copies)."""
    t = tiling
    q = t.wrap.q
    verts = snap(canopy.vertices[t.base * t.vertices:(t.base + 1) * t.vertices], q)
    faces = canopy.faces[t.base * t.faces:(t.base + 1) * t.faces] - t.base * t.vertices
    if with_stalks and t.stalk_faces:
        sv = snap(canopy.stalk_vertices[t.base * t.stalk_vertices:
                                        (t.base + 1) * t.stalk_vertices], q)
        sf = canopy.stalk_faces[t.base * t.stalk_faces:(t.base + 1) * t.stalk_faces] \
            - t.base * t.stalk_vertices + len(verts)
        verts, faces = np.vstack([verts, sv]), np.vstack([faces, sf])
    cv, cf, src, cell = overhang_copies(verts, faces, t.wrap)
    local = np.concatenate([np.arange(len(faces), dtype=np.int64), src])
    cells = np.vstack([np.zeros((len(faces), 2), np.int64), cell])
    return np.vstack([verts, cv]), np.vstack([faces, cf + len(verts)]), local, cells


def tile_triangles(tiling: BlockTiling, n_leaf: int, local: np.ndarray,
                   cell: np.ndarray) -> np.ndarray:
    """Canopy triangle ids (k,) int64 of block triangles ``local`` (k,) (leaves, then stalks)
    hit in the block copies of field cells ``cell`` (k, 2): the tile is the cell folded into
    the plot; ``n_leaf`` is the canopy's leaf triangles (stalk ids follow them)."""
    t = tiling
    a, b = t.shape
    i = np.mod(cell[:, 0] - t.first_key[0], a)
    j = np.mod(cell[:, 1] - t.first_key[1], b)
    tile = t.order[i, j]
    return np.where(local < t.faces, tile * t.faces + local,
                    n_leaf + tile * t.stalk_faces + (local - t.faces))


def carried_period(canopy: Canopy, verts: np.ndarray, faces: np.ndarray,
                   plot_wrap: Wrap) -> Wrap | None:
    """The period a canopy's layout claims (a mesh file's, :attr:`CanopyLayout.period`) as a
    :class:`Wrap` on the plot's grid, when its triangles do repeat with it; else None.

    The claim is checked on the scene's triangles ``faces`` (F, 3) of ``verts`` (V, 3) cm on
    the grid of ``plot_wrap`` (:func:`maizeviz.light.scene.periodic.snap`): the plot must be a whole
    number A x B (> 1) of periods, and each triangle, moved back by whole periods to the cell
    its first vertex stands in, must be found exactly A x B times, once from every cell of
    the plot folded modulo A, B. Then the periodic field of the plot is that of the block,
    and the sensors can be read over the block as for the tiled canopy the file came from
    (:mod:`maizeviz.light.transmission`). The triangles are compared by a 64-bit hash of
    their nine grid coordinates (a false match is about 1 in 10^12 at K = 4).
    """
    period = canopy.layout.period
    if period is None or not len(faces):
        return None
    verts = snap(verts, plot_wrap.q)
    wrap = Wrap.of(period, canopy.layout.bounds)
    if wrap.q != plot_wrap.q:
        return None
    a, b = round(plot_wrap.w / wrap.w), round(plot_wrap.h / wrap.h)
    if a * wrap.w != plot_wrap.w or b * wrap.h != plot_wrap.h or a * b < 2:
        return None
    first = verts[faces[:, 0]]
    i = np.floor((first[:, 0] - wrap.x0) / wrap.w).astype(np.int64)
    j = np.floor((first[:, 1] - wrap.y0) / wrap.h).astype(np.int64)
    shift = (np.rint(i * (wrap.w / wrap.q)).astype(np.int64),
             np.rint(j * (wrap.h / wrap.q)).astype(np.int64))
    key = _moved_back_keys(verts, faces, shift, wrap.q)
    # sorted, not np.unique: numpy's hashed unique took 28 s on these 2.68 M keys
    ordered = np.sort(key)
    starts = np.flatnonzero(np.concatenate([[True], ordered[1:] != ordered[:-1]]))
    if not (np.diff(np.append(starts, len(ordered))) == a * b).all():
        return None
    cell = (np.mod(i, a) * b + np.mod(j, b)).astype(np.uint64)
    with np.errstate(over="ignore"):
        ordered = np.sort(key ^ (cell * np.uint64(0xBF58476D1CE4E5B9)))
    return wrap if not (ordered[1:] == ordered[:-1]).any() else None


def _moved_back_keys(verts: np.ndarray, faces: np.ndarray, shift: tuple[np.ndarray, ...],
                     q: float) -> np.ndarray:
    """(F,) uint64 hash of each triangle's nine coordinates, x and y in grid steps ``q``
    moved back by ``shift`` (F,) steps each, z as its bits."""
    key = np.zeros(len(faces), np.uint64)
    with np.errstate(over="ignore"):
        for k in range(3):
            corner = verts[faces[:, k]]
            for c in range(3):
                v = np.rint(corner[:, c] / q).astype(np.int64) - shift[c] if c < 2 else \
                    np.ascontiguousarray(corner[:, c]).view(np.int64)
                key = (key ^ v.view(np.uint64)) * np.uint64(0x9E3779B97F4A7C15)
                key ^= key >> np.uint64(29)
    return key
