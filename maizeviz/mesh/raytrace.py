"""Embree (through embreex) ray queries on triangle soups.

Facts measured on these machines (docs/method.md, direct light): a scene must be committed (one small
query) before threads share it; ``robust=False`` is about 25% faster; coherent, spatially
sorted rays are about twice as fast as shuffled ones; ``run`` releases the GIL.

Queries go through Embree's ray packets (:mod:`maizeviz.mesh.packets`, 2 to 3 times faster on
coherent rays) where that kernel is available, else through embreex's single rays: the same
hits, ray for ray.
"""

from __future__ import annotations

import numpy as np

try:  # optional native piece: fail only when ray tracing is used
    from embreex.mesh_construction import TriangleMesh
    from embreex.rtcore_scene import EmbreeScene
except ImportError as _exc:  # exercised by tests/core/test_packets.py in a subprocess
    EmbreeScene = None
    _IMPORT_ERROR = _exc

from maizeviz.errors import MaizevizError
from maizeviz.mesh import packets as _packets
from maizeviz.mesh.embree_fill import _handles, compact, embree, fill
from maizeviz.mesh.embree_isa import check_isa, device, requested

#: Why the fast paths are off when embreex's scene object is not laid out as expected.
_UNREAD = "embreex's EmbreeScene is not laid out as maizeviz reads it (its scene handle)"


def no_embreex(exc: BaseException) -> str:
    """One line for light asked where embreex does not import: its wheels' platforms, and this
    one."""
    import platform
    import sys

    return (f"light is traced by Embree through embreex, which does not import here ({exc}): "
            f"embreex has wheels for Linux x86-64, Windows x86-64 and macOS 13 or later, this "
            f"is {sys.platform} {platform.machine()} (pip install embreex, or build it against "
            "an Embree 4 of the system)")


def _writable(a) -> np.ndarray:
    """float32, C-contiguous and writable, as embreex's typed memoryviews require."""
    a = np.asarray(a)
    if a.dtype == np.float32 and a.flags.c_contiguous and a.flags.writeable:
        return a
    return np.array(a, dtype=np.float32, order="C")


def _per_ray(directions, n: int) -> np.ndarray:
    """Directions (N, 3) from (N, 3) or one (1, 3) / (3,) for all (embreex's single rays read
    one per ray, or the first for all only when given exactly one)."""
    d = np.asarray(directions).reshape(-1, 3)
    return d if len(d) == n else np.broadcast_to(d[:1], (n, 3))


class RayScene:
    """An Embree scene over triangles (V, 3) cm and faces (F, 3); ray queries by numpy arrays.

    Triangle ids returned by queries are indices into ``faces``.

    Memory: Embree's own float32 copy of the vertices (16 bytes each), the index buffer shared
    with ``faces`` where they are one int32 array (an open field's canopy) and a compact BVH:
    about 45 bytes a triangle in all at K = 4, where embreex's default (a float32 and an int32
    copy made first, Embree's copies, its default BVH) held 115 and peaked at 140 while
    building.
    """

    def __init__(self, vertices, faces, robust: bool = False, by_copy: bool = True,
                 packets: bool = True, snap_q: float | None = None, isa: str | None = None):
        """``vertices`` (V, 3) cm and ``faces`` (F, 3): arrays, or sequences of arrays taken one
        after the other (the faces numbered over all the vertices). ``snap_q``: x and y rounded
        to multiples of it (cm) as Embree's copy is made (a periodic field's grid).
        ``by_copy``: fill Embree's buffers by memory copy (:mod:`maizeviz.mesh.embree_fill`,
        about 20x faster, no transient copy); False, or where that cannot be done, embreex's
        element-by-element ``TriangleMesh`` (the same scene: ``filled_by_copy`` says which was
        used). ``packets``: trace through Embree's ray packets where the kernel is available
        (``self.packets`` says whether it is used), else embreex's single rays. ``isa``: the
        instruction set Embree traces with (:data:`maizeviz.mesh.embree_isa.ISAS`; None:
        ``MAIZEVIZ_EMBREE_ISA``'s, else the CPU's best)."""
        if EmbreeScene is None:
            raise MaizevizError(no_embreex(_IMPORT_ERROR), quantity="embreex")
        n = len(faces) if isinstance(faces, np.ndarray) else sum(len(f) for f in faces)
        if n == 0:
            raise MaizevizError("the scene is empty: no triangle to trace against")
        self.n_triangles = n
        self.isa = check_isa(isa, "the Embree instruction set") or requested()
        self._scene = EmbreeScene(device(self.isa), robust=robust)
        self.compact = by_copy and compact(self._scene)
        filled = fill(self._scene, vertices, faces, snap_q, share=True) if by_copy else 0
        self.filled_by_copy = bool(filled)
        #: the canopy's faces Embree reads in place (kept alive with the scene), or None
        self._shared = faces if filled == 2 else None
        if not filled:
            if by_copy:
                _packets.warn_once(embree().why or _UNREAD, "filling Embree's scenes through "
                                   "embreex (the same scene, about 3x slower to build)")
            verts = np.vstack(vertices) if not isinstance(vertices, np.ndarray) else vertices
            if snap_q is not None:
                verts = np.array(verts, dtype=np.float64)
                verts[:, :2] = np.round(verts[:, :2] / snap_q) * snap_q
            tris = np.vstack(faces) if not isinstance(faces, np.ndarray) else faces
            self._mesh = TriangleMesh(self._scene, np.ascontiguousarray(verts, np.float32),
                                      np.ascontiguousarray(tris, np.int32))
        # commit now: the lazy first build is not thread-safe
        self._scene.run(np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32))
        self._kernel = _packets.kernel() if packets else None
        handles = _handles(self._scene) if self._kernel is not None else None
        self._handle = handles[0] if handles else 0
        if packets and not self._handle:
            _packets.warn_once(_packets.status().why if self._kernel is None else _UNREAD)
            self._kernel = None

    @property
    def packets(self) -> bool:
        """Whether queries go through Embree's ray packets (else embreex's single rays)."""
        return self._kernel is not None

    def first_hit(self, origins: np.ndarray, directions: np.ndarray, tfar=None, row: int = 0):
        """Nearest triangle along each ray within ``tfar`` (default: unbounded).

        (N, 3), (N, 3) or (1, 3), (N,) -> ids (N,) int32 (-1: none), distances (N,) float32 (the
        ray's ``tfar`` where none). ``row``: rays per row when the rays are a grid laid out row
        by row (packets then take compact tiles of it).
        """
        if self._kernel is not None:
            return _packets.intersect(self._kernel, self._handle, origins, directions, tfar,
                                      row=row)
        o = _writable(origins)
        d = _writable(_per_ray(directions, len(o)))
        dists = None
        if tfar is not None:
            dists = _writable(np.broadcast_to(np.asarray(tfar, np.float32), (len(o),)))
        out = self._scene.run(o, d, dists=dists, output=True)
        return out["primID"], out["tfar"]

    def distance(self, origins: np.ndarray, directions: np.ndarray, tfar, row: int = 0):
        """Distance to the nearest triangle within ``tfar``; ``tfar`` itself where none (N,)."""
        if self._kernel is not None:
            return _packets.intersect(self._kernel, self._handle, origins, directions, tfar,
                                      ids=False, row=row)[1]
        o = _writable(origins)
        d = _writable(_per_ray(directions, len(o)))
        t = _writable(np.broadcast_to(np.asarray(tfar, np.float32), (len(o),)))
        return self._scene.run(o, d, dists=t, query="DISTANCE")

    def occluded(self, origins: np.ndarray, directions: np.ndarray, tfar: np.ndarray | float,
                 row: int = 0):
        """True where a triangle lies on the ray between 0 and ``tfar``: (N,) bool."""
        if self._kernel is not None:
            return _packets.occluded(self._kernel, self._handle, origins, directions, tfar,
                                     row=row)
        o = _writable(origins)
        d = _writable(_per_ray(directions, len(o)))
        t = _writable(np.broadcast_to(np.asarray(tfar, np.float32), (len(o),)))
        return self._scene.run(o, d, dists=t, query="OCCLUDED") >= 0
