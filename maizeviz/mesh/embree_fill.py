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
            ("rtcSetGeometryTransform", None, [p, u, ctypes.c_int, p]),
            # memory (maizeviz.mesh.raytrace): the index buffer shared, a compact BVH
            ("rtcSetSharedGeometryBuffer", None, [p, ctypes.c_int, u, ctypes.c_int, p,
                                                  ctypes.c_size_t, ctypes.c_size_t,
                                                  ctypes.c_size_t]),
            ("rtcSetSceneFlags", None, [p, ctypes.c_int]),
            ("rtcGetSceneFlags", ctypes.c_int, [p])):
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


#: Scene flag of a compact BVH (rtcore_scene.h): triangles kept as vertex indices.
RTC_SCENE_FLAG_COMPACT = 1 << 1
#: Vertices converted (and snapped) at a time while filling Embree's buffer.
FILL_CHUNK = 1 << 20


def compact(scene) -> bool:
    """Ask for a compact BVH in the embreex ``scene`` (not committed yet): about 33 bytes a
    triangle instead of 70, and no transient copy of every triangle's bounds while it is
    built (the build's peak 54 bytes a triangle instead of 123, measured on the bundled canopy
    at K = 4 with the buffers); the same triangles, the same float32 tests, the same hits
    (``tests/core/test_embree_fill.py``), traced as fast here. False where the scene's handle
    cannot be found (the scene then builds Embree's default BVH)."""
    if scene.is_committed:
        return False
    handles = _handles(scene)
    if handles is None:
        return False
    lib = _embree()
    lib.rtcSetSceneFlags(handles[0], lib.rtcGetSceneFlags(handles[0]) | RTC_SCENE_FLAG_COMPACT)
    return True


def _parts(a) -> list[np.ndarray]:
    return [a] if isinstance(a, np.ndarray) else list(a)


def fill(scene, vertices, faces, snap_q: float | None = None, share: bool = False) -> int:
    """Attach a triangle geometry with ``vertices`` (V, 3) and ``faces`` (F, 3) to the
    embreex ``scene`` (not committed yet), by memory copy; False (nothing attached) where this
    cannot be done safely: the caller then uses embreex's ``TriangleMesh``.

    Parameters
    ----------
    scene : embreex.rtcore_scene.EmbreeScene
    vertices : (V, 3) float, cm, or a sequence of such arrays (one after the other); converted
        to float32 as they are copied, :data:`FILL_CHUNK` at a time (no float32 copy of the
        whole)
    faces : (F, 3) int, indices into ``vertices``, or a sequence of such arrays
    snap_q : when given, x and y are rounded to multiples of it (cm, a power of two: the
        periodic field's grid, :func:`maizeviz.light.scene.periodic.snap`, the same numbers)
        chunk by chunk as they are copied
    share : where ``faces`` is one C-contiguous int32 array, Embree reads it in place (it
        must stay alive and unchanged while the scene lives: the caller keeps it) instead of
        a copy of its own

    Returns
    -------
    0 where nothing was attached, 1 where both buffers were copied, 2 where the index buffer
    is ``faces`` itself (``share``)
    """
    if scene.is_committed:
        return 0
    handles = _handles(scene)
    if handles is None:
        return 0
    lib = _embree()
    handle, device = handles
    vparts, fparts = _parts(vertices), _parts(faces)
    nv, nt = sum(len(v) for v in vparts), sum(len(f) for f in fparts)
    shared = share and len(fparts) == 1 and fparts[0].dtype == np.int32 and \
        fparts[0].flags.c_contiguous and fparts[0].shape[1:] == (3,)
    geom = lib.rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE)
    if not geom:
        return 0
    try:
        vbuf = lib.rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                           VERTEX_STRIDE, nv)
        if shared:
            lib.rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           fparts[0].ctypes.data, 0, 12, nt)
            ibuf = fparts[0].ctypes.data
        else:
            ibuf = lib.rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                               12, nt)
        if not vbuf or not ibuf:
            return 0
        vview = np.ctypeslib.as_array((ctypes.c_float * (nv * 4)).from_address(vbuf))
        vview = vview.reshape(nv, 4)
        at = 0
        for part in vparts:
            for s in range(0, len(part), FILL_CHUNK):
                chunk = part[s:s + FILL_CHUNK]
                if snap_q is None:
                    vview[at:at + len(chunk), :3] = chunk
                else:           # q a power of two: x * (1 / q) is x / q, to the bit
                    xy = np.multiply(chunk[:, :2], 1.0 / snap_q)
                    np.round(xy, out=xy)
                    vview[at:at + len(chunk), :2] = np.multiply(xy, snap_q, out=xy)
                    vview[at:at + len(chunk), 2] = chunk[:, 2]
                at += len(chunk)
        if not shared:
            iview = np.ctypeslib.as_array((ctypes.c_uint32 * (nt * 3)).from_address(ibuf))
            iview = iview.reshape(nt, 3)
            at = 0
            for part in fparts:
                iview[at:at + len(part)] = part
                at += len(part)
        lib.rtcCommitGeometry(geom)
        lib.rtcAttachGeometry(handle, geom)
    finally:
        lib.rtcReleaseGeometry(geom)                 # the scene holds it once attached
    return 2 if shared else 1
