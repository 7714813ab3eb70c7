"""The Embree scenes light is traced on: a canopy's (open field), the same with the overhangs
copied across the plot edge (periodic field), or one block of a tiled canopy (periodic field,
:mod:`maizeviz.light.tiling`); :func:`light_scene` picks it.

A scene reports hits in the canopy's triangle ids (leaves, then stalks): ``resolve`` maps a
scene triangle hit in a field cell to them (:mod:`maizeviz.light.periodic`).
"""

from __future__ import annotations

import numpy as np

from maizeviz.canopy.scene import Canopy
from maizeviz.light.periodic import ANCHOR_CM, Rect, Wrap, overhang_copies, snap
from maizeviz.light.tiling import BlockTiling, block_mesh, block_tiling, tile_triangles
from maizeviz.mesh import packets as _packets
from maizeviz.mesh.instances import Instances
from maizeviz.mesh.raytrace import RayScene


class CanopyScene(RayScene):
    """A canopy's Embree scene: leaf triangles, then stalk triangles, then (for a periodic
    field) copies of the triangles that overhang the plot, moved to the opposite side.

    In a periodic field a ray that leaves the plot re-enters on the opposite side, so a leaf
    part hanging over the edge (3.7 % of the leaf area of the bundled block tiled 3 x 3) must
    also stand just inside the opposite edge, where the next tile's plants would put it. A
    periodic scene's x, y are on the field's grid (:mod:`maizeviz.light.periodic`).

    Attributes
    ----------
    n_original : int, leaf + stalk triangles (the ids hits are reported in)
    source : (F_scene,) int64, the original triangle of each scene triangle (None: identity)
    wrapped : (x0, y0, x1, y1) cm, the plot whose overhangs were copied, or None
    wrap : Wrap of the periodic field this scene repeats in (the plot), or None
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, n_original: int | None = None,
                 source: np.ndarray | None = None, wrapped: Rect | None = None,
                 wrap: Wrap | None = None):
        super().__init__(vertices, faces)
        self.n_original = len(faces) if n_original is None else n_original
        self.source = source
        self.wrapped = wrapped
        self.wrap = wrap

    def resolve(self, prim: np.ndarray, cell: np.ndarray | None) -> np.ndarray:
        """Canopy triangle ids (k,) of scene triangles ``prim`` (k,) hit in field cells
        ``cell`` (k, 2) (unused here: every cell holds the same canopy)."""
        return prim if self.source is None else self.source[prim]


class BlockScene(CanopyScene):
    """The scene of one block of a tiled canopy in a periodic field
    (:mod:`maizeviz.light.tiling`): the block's triangles and copies of its neighbours'
    overhangs; hits are reported as the tiled canopy's triangles (``n_original`` of them).

    Attributes
    ----------
    tiling : BlockTiling; plus those of :class:`CanopyScene` (``wrap``: the block's field)
    """

    def __init__(self, canopy: Canopy, tiling: BlockTiling, with_stalks: bool):
        verts, faces, self._local, self._cell = block_mesh(canopy, tiling, with_stalks)
        n = canopy.n_triangles + (len(canopy.stalk_faces) if with_stalks else 0)
        super().__init__(verts, faces, n, None, canopy.layout.bounds, tiling.wrap)
        self.tiling = tiling
        self._n_leaf = canopy.n_triangles
        # with the packet kernel: the block placed at every tile of the plot (Embree
        # instances), traced over the plot's period: the whole canopy's segments, the block's
        # build (without: the block's own period, more segments, the same hits)
        self.instanced: Instances | None = None
        if self._kernel is not None:
            a, b = tiling.shape
            i0, j0 = tiling.first_key
            keys = np.array([(i, j) for i in range(i0, i0 + a) for j in range(j0, j0 + b)])
            try:
                self.instanced = Instances(self, keys * tiling.wrap.period)
                self._keys = keys
            except (RuntimeError, ValueError):  # pragma: no cover - Embree refused
                self.instanced = None

    def wrapped_native(self, org: np.ndarray, dirs: np.ndarray, length: np.ndarray,
                       any_hit: bool, row: int):
        """:func:`~maizeviz.light.periodic.trace_wrapped` through the block's instances over
        the plot (same results); None where there are no instances."""
        if self.instanced is None or self._kernel is None:
            return None
        pw = self.tiling.plot_wrap
        got = _packets.wrapped(self._kernel, self.instanced.handle, org, dirs, length,
                               (pw.x0, pw.y0, pw.w, pw.h, pw.q, ANCHOR_CM), any_hit, row=row)
        if any_hit:
            return got
        prim, cell, dist, inst = got
        hit = prim >= 0
        # the hit block's key: its instance's, plus the plot periods the ray had crossed
        cell[hit] = self._keys[inst[hit]] + cell[hit] * np.array(self.tiling.shape)
        return prim, cell, dist

    def resolve(self, prim: np.ndarray, cell: np.ndarray | None) -> np.ndarray:
        """Canopy triangle ids (k,) of block triangles ``prim`` (k,) hit in the block copies
        of field cells ``cell`` (k, 2)."""
        if cell is None:  # pragma: no cover - a block scene traces periodic fields only
            raise ValueError("a block scene's hits need their field cells")
        return tile_triangles(self.tiling, self._n_leaf, self._local[prim],
                              cell + self._cell[prim])


def light_scene(canopy: Canopy, with_stalks: bool = False, periodic: bool = False,
                block: bool = True) -> CanopyScene:
    """The Embree scene of a canopy's leaves (and stalks): build it once, trace many suns.

    Parameters
    ----------
    with_stalks : stalks intercept light too
    periodic : for a periodic field (``--periodic``): leaf parts overhanging the plot edges are
        copied to the opposite side; such a scene traces periodic requests only
    block : for a periodic field, the scene of the canopy's block alone when the canopy tiles
        it exactly (:mod:`maizeviz.light.tiling`: the same hits, A x B times fewer triangles);
        False: always the whole canopy
    """
    verts, faces = canopy.vertices, canopy.faces
    if with_stalks:
        verts = np.vstack([verts, canopy.stalk_vertices])
        faces = np.vstack([faces, canopy.stalk_faces + len(canopy.vertices)])
    n = len(faces)
    if not periodic:
        return CanopyScene(verts, faces)
    if block:
        tiling = block_tiling(canopy)
        if tiling is not None:
            return BlockScene(canopy, tiling, with_stalks)
    bounds = canopy.layout.bounds
    wrap = Wrap.of(bounds)
    verts = snap(verts, wrap.q)
    cv, cf, src, _ = overhang_copies(verts, faces, wrap)
    return CanopyScene(np.vstack([verts, cv]), np.vstack([faces, cf + len(verts)]), n,
                       np.concatenate([np.arange(n, dtype=np.int64), src]), bounds, wrap)


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
