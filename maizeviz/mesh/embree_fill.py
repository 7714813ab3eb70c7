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

The library is the one embreex loaded, found where the process mapped it (Linux, macOS,
Windows), else where embreex's wheels vendor it: ``embreex.libs/libembree4*.so*`` (manylinux,
auditwheel), ``embreex/.dylibs/libembree4*.dylib`` (macOS, delocate) and
``embreex.libs/embree4*.dll`` (Windows, delvewheel); :data:`WHEEL_LAYOUTS` was checked
against the embreex 4.4.0.post1 wheels of the three platforms.

The geometry is attached to the scene of an embreex ``EmbreeScene``, whose queries
(``run``, GIL released) stay embreex's. The scene handle is a private field of that object,
read only for the embreex releases whose layout is known (:data:`KNOWN_EMBREEX`); its place is
also checked on every new scene against what the object says publicly (its ``is_committed``
flag beside it, the type of its device after it) and against Embree (the scene's device).
Where anything differs, or the library is not found, :func:`fill` returns False and the
caller falls back to embreex's own fill, and :func:`embree` says why (``maizeviz --info``).
``tests/core/test_embree_fill.py`` checks that both fills give the same hits, triangle by
triangle.

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
import sys
from dataclasses import dataclass
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


#: Where embreex's wheels keep the Embree library, relative to the folder holding the
#: ``embreex`` package (site-packages): Linux (auditwheel), macOS (delocate), Windows
#: (delvewheel).
WHEEL_LAYOUTS = (("embreex.libs", "libembree4*.so*"), ("embreex/.dylibs", "libembree4*.dylib"),
                 ("embreex.libs", "embree4*.dll"))
#: embreex releases (major, minor) whose ``EmbreeScene`` keeps the scene handle where
#: ``_SCENE_AT`` says (read in their Cython declarations: 4.4.0 and 4.4.0.post1).
KNOWN_EMBREEX = ((4, 4),)


def wheel_library(site: Path) -> Path | None:
    """The Embree library of an embreex wheel installed in ``site`` (its site-packages), in
    any of the three layouts, or None (none, or more than one: not knowing which is loaded)."""
    found = [p for folder, pattern in WHEEL_LAYOUTS for p in sorted((site / folder).glob(pattern))]
    return found[0] if len(found) == 1 else None


def loaded_library() -> Path | None:
    """The Embree 4 library mapped into this process (embreex's, once it is imported): from
    /proc/self/maps on Linux, dyld's image list on macOS, the loaded module on Windows."""
    names: list[str] = []
    try:
        if sys.platform.startswith("linux"):
            with open("/proc/self/maps") as fh:
                names = [line.split(None, 5)[-1].strip() for line in fh if "/" in line]
        elif sys.platform == "darwin":  # pragma: no cover - macOS only
            dyld = ctypes.CDLL(None)
            dyld._dyld_get_image_name.restype = ctypes.c_char_p
            names = [dyld._dyld_get_image_name(i).decode()
                     for i in range(dyld._dyld_image_count())]
        elif sys.platform == "win32":  # pragma: no cover - Windows only
            k32 = ctypes.WinDLL("kernel32", use_last_error=True)
            k32.GetModuleHandleW.restype = ctypes.c_void_p
            k32.GetModuleHandleW.argtypes = [ctypes.c_wchar_p]
            k32.GetModuleFileNameW.argtypes = [ctypes.c_void_p, ctypes.c_wchar_p,
                                               ctypes.c_uint32]
            handle = k32.GetModuleHandleW("embree4.dll")
            if handle:
                buf = ctypes.create_unicode_buffer(32768)
                if k32.GetModuleFileNameW(handle, buf, len(buf)):
                    names = [buf.value]
    except (OSError, AttributeError, ValueError):
        return None
    hits = sorted({n for n in names if Path(n).name.lower().startswith(("libembree4", "embree4"))})
    return Path(hits[0]) if len(hits) == 1 else None


def _version_tuple(text: str) -> tuple[int, ...]:
    import re

    return tuple(int(x) for x in re.findall(r"\d+", text)[:2])


@dataclass(frozen=True)
class Embree:
    """The Embree library embreex loaded, as maizeviz reaches it.

    Attributes
    ----------
    lib : ctypes.CDLL or None
        The library with the prototypes used here; None where it was not found.
    path : Path or None
        Its file.
    embreex : str
        embreex's version ("" when it does not import).
    scene_field : bool
        Whether an ``EmbreeScene``'s private scene handle may be read (a known embreex).
    why : str
        Why the copy fill, instances and ray packets cannot be used ("" when they can).
    """

    lib: ctypes.CDLL | None
    path: Path | None
    embreex: str
    scene_field: bool
    why: str

    @property
    def version(self) -> str:
        """Embree's own version ("4.4.0"), asked of a device; "" without the library."""
        if self.lib is None:
            return ""
        device = self.lib.rtcNewDevice(b"verbose=0")
        if not device:  # pragma: no cover - Embree refusing a device
            return ""
        try:
            v = int(self.lib.rtcGetDeviceProperty(device, 0))    # RTC_DEVICE_PROPERTY_VERSION
        finally:
            self.lib.rtcReleaseDevice(device)
        return f"{v // 10000}.{v // 100 % 100}.{v % 100}"


@functools.cache
def embree() -> Embree:
    """What :func:`fill`, the instances and the ray packets use: the library embreex loaded,
    found once (:func:`loaded_library`, else :func:`wheel_library`)."""
    try:
        import embreex
        from embreex import rtcore_scene  # noqa: F401 - loads Embree
    except ImportError as exc:
        return Embree(None, None, "", False, f"embreex does not import ({exc})")
    from importlib.metadata import PackageNotFoundError, version

    try:
        release = version("embreex")
    except PackageNotFoundError:  # pragma: no cover - embreex without its metadata
        release = "unknown"
    site = Path(embreex.__file__).resolve().parent.parent
    path = loaded_library() or wheel_library(site)
    if path is None:
        return Embree(None, None, release, False,
                      f"the Embree library embreex {release} loads was not found (not mapped "
                      f"in this process, nor in {site} as embreex's wheels keep it)")
    try:
        lib = ctypes.CDLL(str(path))
    except OSError as exc:
        return Embree(None, path, release, False, f"{path} does not load ({exc})")
    p, u = ctypes.c_void_p, ctypes.c_uint
    for name, res, args in (
            ("rtcNewGeometry", p, [p, ctypes.c_int]),
            ("rtcSetNewGeometryBuffer", p, [p, ctypes.c_int, u, ctypes.c_int, ctypes.c_size_t,
                                            ctypes.c_size_t]),
            ("rtcCommitGeometry", None, [p]),
            ("rtcAttachGeometry", u, [p, p]),
            ("rtcReleaseGeometry", None, [p]),
            ("rtcGetSceneDevice", p, [p]),
            ("rtcNewDevice", p, [ctypes.c_char_p]),
            ("rtcGetDeviceProperty", ctypes.c_ssize_t, [p, ctypes.c_int]),
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
            return Embree(None, path, release, False, f"{path} has no {name}: not Embree 4")
        fn.restype, fn.argtypes = res, args
    if _version_tuple(release) not in KNOWN_EMBREEX:
        known = ", ".join(".".join(map(str, v)) + ".x" for v in KNOWN_EMBREEX)
        return Embree(lib, path, release, False,
                      f"embreex {release} is not a release whose scene layout maizeviz knows "
                      f"({known}): its scenes' private handle is not read")
    return Embree(lib, path, release, True, "")


def _embree():
    """The Embree library embreex loaded, with the prototypes used here; None where it was
    not found or embreex's scenes cannot be reached (:func:`embree` says why)."""
    e = embree()
    return e.lib if e.scene_field else None


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
