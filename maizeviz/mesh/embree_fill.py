"""Embree triangle geometry filled by memory copy, for scenes of embreex.

embreex's ``TriangleMesh`` copies the vertices and triangles into Embree's buffers one
element at a time through Python indexing: 3.1-3.3 s for the 2.68 million triangles of the
bundled canopy at K = 4, three times what Embree's own BVH build then takes. Here the same
buffers are filled as numpy views of the memory Embree allocates (``rtcSetNewGeometryBuffer``),
one vectorised copy each, through the Embree library embreex itself loads (its wheel vendors
``libembree4``; loading the same file again returns the library already loaded, so scene,
device and geometry are one Embree). ctypes rather than a compiled extension: embreex's wheel
ships its Cython declarations but not Embree's C headers, and a compiler is then not needed on
the user's machine.

The geometry is attached to the scene of an embreex ``EmbreeScene``, whose queries
(``run``, GIL released) stay embreex's. The scene handle is a private field of that object:
its place is checked on every new scene against what the object says publicly (its
``is_committed`` flag beside it, the type of its device after it) and against Embree (the
scene's device); where anything differs, or the library is not found, :func:`fill` returns
False and the caller falls back to embreex's own fill. ``tests/core/test_embree_fill.py`` checks
that both fills give the same hits, triangle by triangle.

References
----------
Wald, I., Woop, S., Benthin, C., Johnson, G. S. & Ernst, M. (2014). Embree: a kernel
framework for efficient CPU ray tracing. ACM Transactions on Graphics 33(4), 143.
Embree 4 API: rtcNewGeometry, rtcSetNewGeometryBuffer, rtcCommitGeometry, rtcAttachGeometry
(https://github.com/RenderKit/embree/blob/master/doc/src/api.md).
"""

from __future__ import annotations

import ctypes
import functools
from pathlib import Path

import numpy as np

# Embree 4 constants (rtcore_geometry.h, rtcore_buffer.h, rtcore_common.h)
RTC_GEOMETRY_TYPE_TRIANGLE = 0
RTC_BUFFER_TYPE_INDEX, RTC_BUFFER_TYPE_VERTEX = 0, 1
RTC_FORMAT_UINT3, RTC_FORMAT_FLOAT3 = 0x5003, 0x9003
#: Bytes per vertex in Embree's buffer: x, y, z and one float of padding, as embreex lays it.
VERTEX_STRIDE = 16

# Where an embreex EmbreeScene (a Cython object without virtual methods) keeps its fields
# after the object header: the scene handle, then ``is_committed``, then its device object.
_PTR = ctypes.sizeof(ctypes.c_void_p)
_SCENE_AT, _COMMITTED_AT, _DEVICE_AT = 2 * _PTR, 3 * _PTR, 4 * _PTR


@functools.cache
def _embree():
    """The Embree library embreex loaded, with the prototypes used here; None if not found."""
    try:
        import embreex
    except ImportError:
        return None
    folder = Path(embreex.__file__).resolve().parent.parent / "embreex.libs"
    found = sorted(folder.glob("libembree4*.so*"))
    if len(found) != 1:
        return None
    try:
        lib = ctypes.CDLL(str(found[0]))
    except OSError:
        return None
    p, u = ctypes.c_void_p, ctypes.c_uint
    for name, res, args in (
            ("rtcNewGeometry", p, [p, ctypes.c_int]),
            ("rtcSetNewGeometryBuffer", p, [p, ctypes.c_int, u, ctypes.c_int, ctypes.c_size_t,
                                            ctypes.c_size_t]),
            ("rtcCommitGeometry", None, [p]),
            ("rtcAttachGeometry", u, [p, p]),
            ("rtcReleaseGeometry", None, [p]),
            ("rtcGetSceneDevice", p, [p]),
            ("rtcReleaseDevice", None, [p]),
            # scenes of instances (maizeviz.mesh.instances)
            ("rtcNewScene", p, [p]),
            ("rtcCommitScene", None, [p]),
            ("rtcReleaseScene", None, [p]),
            ("rtcSetGeometryInstancedScene", None, [p, p]),
            ("rtcSetGeometryTransform", None, [p, u, ctypes.c_int, p])):
        fn = getattr(lib, name, None)
        if fn is None:
            return None
        fn.restype, fn.argtypes = res, args
    return lib


def _handles(scene) -> tuple[int, int] | None:
    """(scene handle, device handle) of an embreex EmbreeScene, or None where the object is not
    laid out as expected."""
    from embreex.rtcore import EmbreeDevice

    lib = _embree()
    if lib is None:
        return None
    base = id(scene)
    committed = ctypes.c_int.from_address(base + _COMMITTED_AT).value
    device_obj = ctypes.c_void_p.from_address(base + _DEVICE_AT).value
    handle = ctypes.c_void_p.from_address(base + _SCENE_AT).value
    if committed != scene.is_committed or not device_obj or not handle:
        return None
    device_type = ctypes.c_void_p.from_address(device_obj + _PTR).value   # ob_type
    if device_type != id(EmbreeDevice):
        return None
    device = ctypes.c_void_p.from_address(device_obj + 2 * _PTR).value    # its RTCDevice
    owner = lib.rtcGetSceneDevice(handle)            # what Embree says the scene belongs to
    if owner:
        lib.rtcReleaseDevice(owner)                  # rtcGetSceneDevice took a reference
    if not device or owner != device:
        return None
    return handle, device


def fill(scene, vertices: np.ndarray, faces: np.ndarray) -> bool:
    """Attach a triangle geometry with ``vertices`` (V, 3) and ``faces`` (F, 3) to the
    embreex ``scene`` (not committed yet), by memory copy; False (nothing attached) where this
    cannot be done safely: the caller then uses embreex's ``TriangleMesh``.

    Parameters
    ----------
    scene : embreex.rtcore_scene.EmbreeScene
    vertices : (V, 3) float, cm; faces : (F, 3) int, indices into ``vertices``
    """
    if scene.is_committed:
        return False
    handles = _handles(scene)
    if handles is None:
        return False
    lib = _embree()
    handle, device = handles
    nv, nt = len(vertices), len(faces)
    geom = lib.rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE)
    if not geom:
        return False
    try:
        vbuf = lib.rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                           VERTEX_STRIDE, nv)
        ibuf = lib.rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           12, nt)
        if not vbuf or not ibuf:
            return False
        vview = np.ctypeslib.as_array((ctypes.c_float * (nv * 4)).from_address(vbuf))
        vview.reshape(nv, 4)[:, :3] = vertices
        iview = np.ctypeslib.as_array((ctypes.c_uint32 * (nt * 3)).from_address(ibuf))
        iview.reshape(nt, 3)[:] = faces
        lib.rtcCommitGeometry(geom)
        lib.rtcAttachGeometry(handle, geom)
    finally:
        lib.rtcReleaseGeometry(geom)                 # the scene holds it once attached
    return True
