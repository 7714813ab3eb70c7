"""The Embree scenes light is traced on: a canopy's (open field), the same with the overhangs
copied across the plot edge (periodic field), or one block of a tiled canopy (periodic field,
:mod:`maizeviz.light.scene.tiling`); :func:`light_scene` picks it.

A scene reports hits in the canopy's triangle ids (leaves, then stalks): ``resolve`` maps a
scene triangle hit in a field cell to them (:mod:`maizeviz.light.scene.periodic`).
"""

from __future__ import annotations

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.light.scene.periodic import (
    ANCHOR_CM,
    COPY_MARGIN_CM,
    Rect,
    Wrap,
    overhang_copies,
)
from maizeviz.light.scene.tiling import (
    BlockTiling,
    block_mesh,
    block_tiling,
    carried_period,
    tile_triangles,
)
from maizeviz.mesh import packets as _packets
from maizeviz.mesh.instances import Instances
from maizeviz.mesh.raytrace import RayScene


class CanopyScene(RayScene):
    """A canopy's Embree scene: leaf triangles, then stalk triangles, then (for a periodic
    field) copies of the triangles that overhang the plot, moved to the opposite side.

    In a periodic field a ray that leaves the plot re-enters on the opposite side, so a leaf
    part hanging over the edge (3.7 % of the leaf area of the bundled block tiled 3 x 3) must
    also stand just inside the opposite edge, where the next tile's plants would put it. A
    periodic scene's x, y are on the field's grid (:mod:`maizeviz.light.scene.periodic`).

    Attributes
    ----------
    n_original : int, leaf + stalk triangles (the ids hits are reported in)
    source : (C,) int64, the original triangle of each copy, the scene's triangles after the
        first ``n_original`` (None: no copy)
    wrapped : (x0, y0, x1, y1) cm, the plot whose overhangs were copied, or None
    wrap : Wrap of the periodic field this scene repeats in (the plot), or None
    period : Wrap of the field's smallest known period: the block of a tiled canopy (which
        the field repeats exactly, :func:`~maizeviz.light.scene.tiling.block_tiling`), or the one a
        mesh file carries once checked (:func:`~maizeviz.light.scene.tiling.carried_period`), else
        ``wrap``
    """

    def __init__(self, vertices, faces, n_original: int | None = None,
                 source: np.ndarray | None = None, wrapped: Rect | None = None,
                 wrap: Wrap | None = None, period: Wrap | None = None,
                 snap_q: float | None = None):
        super().__init__(vertices, faces, snap_q=snap_q)
        self.n_original = self.n_triangles if n_original is None else n_original
        self.source = source
        self.wrapped = wrapped
        self.wrap = wrap
        self.period = wrap if period is None else period

    def resolve(self, prim: np.ndarray, cell: np.ndarray | None) -> np.ndarray:
        """Canopy triangle ids (k,) of scene triangles ``prim`` (k,) hit in field cells
        ``cell`` (k, 2) (unused here: every cell holds the same canopy)."""
        if self.source is None:
            return prim
        out = np.asarray(prim).copy()
        copy = out >= self.n_original
        out[copy] = self.source[out[copy] - self.n_original]
        return out


class BlockScene(CanopyScene):
    """The scene of one block of a tiled canopy in a periodic field
    (:mod:`maizeviz.light.scene.tiling`); hits are reported as the tiled canopy's triangles
    (``n_original`` of them).

    The scene holds what reaches into the block's cell: the block's triangles there and copies
    of its neighbours' overhanging in (at K = 4, 298,000 triangles for the 2.68 million of the
    tiled canopy). With the packet kernel it is placed at every tile of the plot and a ring
    around (Embree instances, one BVH), and rays are wrapped over the plot as for the whole
    canopy; without it (embreex's single rays do not report instances) rays are wrapped over
    the block's own period: more segments, the same hits.

    Attributes
    ----------
    tiling : BlockTiling; instanced : Instances or None; plus those of :class:`CanopyScene`
        (``wrap``: the block's field)
    """

    def __init__(self, canopy: Canopy, tiling: BlockTiling, with_stalks: bool):
        verts, faces, local, cells = block_mesh(canopy, tiling, with_stalks)
        # only what reaches into the block's cell: the block's triangles there and its
        # neighbours' overhanging in (the rest stands in the neighbouring cells' copies)
        w = tiling.wrap
        tri = verts[faces]
        lo, hi = tri[:, :, :2].min(axis=1), tri[:, :, :2].max(axis=1)
        inside = np.all((hi > w.corner - COPY_MARGIN_CM) &
                        (lo < w.corner + w.period + COPY_MARGIN_CM), axis=1)
        # the block triangle and the cell offset of each scene triangle, gathered per hit
        self._local = local[inside].astype(np.int32)
        self._cell_x, self._cell_y = (np.ascontiguousarray(cells[inside, k]) for k in (0, 1))
        n = canopy.n_triangles + (len(canopy.stalk_faces) if with_stalks else 0)
        super().__init__(verts, faces[inside], n, None, canopy.layout.bounds, w)
        self.tiling = tiling
        self._n_leaf = canopy.n_triangles
        self.instanced: Instances | None = None
        if self._kernel is not None:
            # the cell's scene at every tile of the plot and a ring of tiles around it
            (a, b), (i0, j0) = tiling.shape, tiling.first_key
            keys = np.array([(i, j) for i in range(i0 - 1, i0 + a + 1)
                             for j in range(j0 - 1, j0 + b + 1)], dtype=np.int64)
            try:
                self.instanced = Instances(self, keys * w.period)
                self._keys = keys
            except (RuntimeError, ValueError):  # pragma: no cover - Embree refused
                self.instanced = None

    def trace_field(self, org: np.ndarray, dirs: np.ndarray, length: np.ndarray,
                    any_hit: bool, row: int, native: bool):
        """:func:`~maizeviz.light.scene.periodic.trace_wrapped` for this scene: blocked (N,) bool
        (``any_hit``), else the block triangles hit (N,) int32 (-1: none; leaves, then
        stalks), the tile keys (N, 2) int64 of the block copies they belong to and the
        distances (N,) float64 cm (inf: none); :meth:`resolve` names the canopy's triangles.

        With the packet kernel, the cell's scene is instanced at every tile of the plot and
        traced over the plot's period (the whole canopy's segments); otherwise (or
        ``native=False``) it is traced over the block's own period: more segments, the same
        hits."""
        from maizeviz.light.scene.periodic import wrap_segments

        if native and self.instanced is not None and self._kernel is not None:
            pw = self.tiling.plot_wrap
            got = _packets.wrapped(self._kernel, self.instanced.handle, org, dirs, length,
                                   (pw.x0, pw.y0, pw.w, pw.h, pw.q, ANCHOR_CM), any_hit,
                                   row=row, inst_cells=self._keys,
                                   frame_cells=self.tiling.shape)
            got = got if any_hit else got[:3]
        else:
            got = wrap_segments(self, self.tiling.wrap, org, dirs, length, any_hit, row=row,
                                native=native)
        if any_hit:
            return got
        prim, cell, dist = got
        assert prim is not None
        hit = np.flatnonzero(prim >= 0)
        p = prim[hit]
        cell[hit, 0] += self._cell_x[p]               # a copy stands for its neighbour's
        cell[hit, 1] += self._cell_y[p]
        prim[hit] = self._local[p]
        return prim, cell, dist

    def resolve(self, prim: np.ndarray, cell: np.ndarray | None) -> np.ndarray:
        """Canopy triangle ids (k,) of block triangles ``prim`` (k,) (leaves, then stalks)
        hit in the block copies standing at tile keys ``cell`` (k, 2)."""
        if cell is None:  # pragma: no cover - a block scene traces periodic fields only
            raise ValueError("a block scene's hits need their field cells")
        return tile_triangles(self.tiling, self._n_leaf, prim, cell)


def light_scene(canopy: Canopy, with_stalks: bool = False, periodic: bool = False,
                block: bool = True) -> CanopyScene:
    """The Embree scene of a canopy's leaves (and stalks): build it once, trace many suns.

    Parameters
    ----------
    with_stalks : stalks intercept light too
    periodic : for a periodic field (``--periodic``): leaf parts overhanging the plot edges are
        copied to the opposite side; such a scene traces periodic requests only
    block : for a periodic field, the scene of the canopy's block alone when the canopy tiles
        it exactly (:mod:`maizeviz.light.scene.tiling`: the same hits, A x B times fewer triangles);
        False: always the whole canopy
    """
    verts, faces = canopy.vertices, canopy.faces
    if with_stalks:
        verts = np.vstack([verts, canopy.stalk_vertices])
        faces = np.vstack([faces, canopy.stalk_faces + len(canopy.vertices)])
    n = len(faces)
    if not periodic:
        return CanopyScene(verts, faces)            # Embree reads the canopy's faces in place
    tiling = block_tiling(canopy)
    if block and tiling is not None:
        return BlockScene(canopy, tiling, with_stalks)
    bounds = canopy.layout.bounds
    wrap = Wrap.of(bounds)
    # the canopy on the field's grid as Embree's copy is made, with copies of the overhangs
    period = tiling.wrap if tiling is not None else carried_period(canopy, verts, faces, wrap)
    cv, cf, src, _ = overhang_copies(verts, faces, wrap, wrap.q)
    return CanopyScene([verts, cv], [faces, cf + len(verts)], n, src, bounds, wrap, period,
                       snap_q=wrap.q)


def scene_for(canopy: Canopy, periodic: bool, scene: RayScene | None,
              with_stalks: bool) -> tuple[RayScene, list[str]]:
    """The scene to trace a request with, and what to say about it: ``scene`` when it suits
    the request (built here when None).

    Raises
    ------
    MaizevizError
        A scene with copied overhangs (periodic) given for an open field.
    """
    from maizeviz.errors import MaizevizError

    if scene is None:
        return light_scene(canopy, with_stalks, periodic), []
    wrapped = getattr(scene, "wrapped", None)
    if wrapped is not None and not periodic:
        raise MaizevizError("this scene holds copies of the leaves overhanging the plot edges "
                            "(built for a periodic field): it cannot trace an open field",
                            quantity="periodic")
    if periodic and wrapped is None:
        return scene, ["the scene was built without the leaves overhanging the plot edges: the "
                       "periodic field misses them (build it with light_scene(canopy, "
                       "periodic=True))"]
    return scene, []
