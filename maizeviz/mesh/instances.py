"""A scene of translated copies (Embree instances) of one built scene: Embree's two-level BVH.

One block of a tiled canopy, built once, placed at each tile of the plot: the plot's scene for
the price of the block's BVH (:mod:`maizeviz.light.scene.tiling`). An instance moves a ray into the
block's frame by ``org - offset`` (a pure translation: Embree's inverse of the transform is
exact), so with the coordinates on a common grid (:mod:`maizeviz.light.scene.periodic`) an instance
gives the float32 hits of the triangles it stands for, moved, exactly.

Made through the Embree library embreex loads (:func:`maizeviz.mesh.embree_fill._embree`, the
same device as the block's scene); traced only through the ray-packet kernel
(:mod:`maizeviz.mesh.packets`), which reports the instance hit (embreex does not).
"""

from __future__ import annotations

import ctypes

import numpy as np

from maizeviz.mesh.embree_fill import _embree, _handles

RTC_GEOMETRY_TYPE_INSTANCE = 121
RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR = 0x9234


class Instances:
    """Embree scene of ``base`` placed at each of ``offsets`` (k, 2) cm (x, y translations,
    exact in float32): instance i is ``offsets[i]``.

    Attributes
    ----------
    handle : int, the Embree scene to trace (through :mod:`maizeviz.mesh.packets`)
    offsets : (k, 2) float64 cm

    Embree counts references: the instances keep the base scene's BVH (and the device) alive
    as long as this scene lives, so no Python reference to ``base`` is kept (the base scene
    usually owns this one).
    """

    def __init__(self, base, offsets: np.ndarray):
        lib = _embree()
        handles = _handles(base._scene) if lib is not None else None
        if lib is None or handles is None:
            raise RuntimeError("Embree's library is not reachable for instances")
        scene, device = handles
        self.offsets = np.asarray(offsets, dtype=np.float64).reshape(-1, 2)
        if not np.array_equal(self.offsets.astype(np.float32), self.offsets):
            raise ValueError("instance offsets must be exact in float32")
        self._lib = lib
        self.handle = lib.rtcNewScene(device)
        if not self.handle:
            raise RuntimeError("Embree could not make a scene")
        for dx, dy in self.offsets:
            geom = lib.rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE)
            if not geom:  # pragma: no cover - Embree out of memory
                raise RuntimeError("Embree could not make an instance")
            try:
                lib.rtcSetGeometryInstancedScene(geom, scene)
                xfm = (ctypes.c_float * 12)(1, 0, 0, 0, 1, 0, 0, 0, 1, dx, dy, 0)
                lib.rtcSetGeometryTransform(geom, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm)
                lib.rtcCommitGeometry(geom)
                lib.rtcAttachGeometry(self.handle, geom)     # ids 0, 1, ... in order
            finally:
                lib.rtcReleaseGeometry(geom)
        lib.rtcCommitScene(self.handle)

    def __del__(self):
        handle = getattr(self, "handle", None)
        if handle:
            self._lib.rtcReleaseScene(handle)
            self.handle = None
