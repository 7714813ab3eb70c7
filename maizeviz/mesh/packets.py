"""Embree ray packets through a small C kernel (``_packets.c``), called through ctypes.

embreex exposes Embree's single-ray queries only (``rtcIntersect1``/``rtcOccluded1``). Embree
traces coherent rays faster in packets (``rtcIntersect8``/``16``, ``rtcOccluded8``/``16``, with
the coherent flag): ``_packets.c`` loops over a batch of rays in packets and writes the hits
into numpy arrays. It needs no Embree header and no link: the packet functions' addresses are
taken from the ``libembree4`` embreex loads (:func:`maizeviz.mesh.embree_fill.embree`) and
passed in as integers, with the scene handle. ctypes releases the GIL during the call, so
threads trace chunks in parallel.

The kernel is built when maizeviz is installed, as the extension module
``maizeviz.mesh._packets`` (``setup.py``; a platform wheel carries it built): nothing is
compiled or written at run time. Where it cannot be used, :func:`kernel` returns None and
:class:`~maizeviz.mesh.raytrace.RayScene` traces with embreex's single rays, the same hits ray
for ray (``tests/core/test_packets.py``), saying once why (:func:`status`: not built at
install, built from another ``_packets.c``, Embree's library or embreex's scenes not reachable,
a packet layout other than Embree 4's); ``MAIZEVIZ_PACKETS=0`` in the environment turns it off
without a word. ``maizeviz --info`` prints what is used and why.

References
----------
Wald, I., Benthin, C., Wagner, M. & Slusallek, P. (2001). Interactive rendering with coherent
ray tracing. Computer Graphics Forum 20(3), 153-165. https://doi.org/10.1111/1467-8659.00508
Embree 4 API: rtcIntersect4/8/16, rtcOccluded4/8/16, RTCIntersectArguments
(https://github.com/RenderKit/embree/blob/master/doc/src/api.md).
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import threading
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

SOURCE = Path(__file__).with_name("_packets.c")
#: Rays per packet: 8 matches AVX2 (this machine); 16 is Embree's widest
#: (``MAIZEVIZ_PACKET_WIDTH``, read by :func:`maizeviz.environment.whole_number` when the
#: kernel loads).
DEFAULT_WIDTH = 8
#: sizeof(RTCRay16) * 1000 + offsetof(RTCRayHit16, hit), as Embree 4 lays them out.
_LAYOUT = 768 * 1000 + 768


@dataclass(frozen=True)
class Kernel:
    """The loaded kernel and the Embree packet functions it calls (addresses)."""

    lib: ctypes.CDLL
    intersect: dict[int, int]           # width -> address of rtcIntersect<width>
    occluded: dict[int, int]            # width -> address of rtcOccluded<width>
    width: int


@dataclass(frozen=True)
class Status:
    """Which kernel traces rays, and why.

    Attributes
    ----------
    name : {"packets", "embreex"}
        Embree's ray packets through the built kernel, or embreex's single rays.
    why : str
        Why the packets are not used ("" when they are).
    path : Path or None
        The kernel's extension module, where it was built.
    """

    name: str
    why: str
    path: Path | None


def _load() -> tuple[Kernel | None, Status]:
    from maizeviz.environment import switch, whole_number

    width = whole_number("MAIZEVIZ_PACKET_WIDTH")    # a bad value refused before anything
    if not switch("MAIZEVIZ_PACKETS"):
        return None, Status("embreex", "turned off by MAIZEVIZ_PACKETS=0", None)
    try:
        from maizeviz.mesh import _packets as ext
    except ImportError as exc:
        return None, Status("embreex", "the ray-packet kernel was not built when maizeviz was "
                            f"installed ({exc}): install a maizeviz wheel for this platform, "
                            "or reinstall with a C compiler", None)
    path = Path(ext.__file__)
    if SOURCE.is_file() and \
            hashlib.sha256(SOURCE.read_bytes()).hexdigest() != ext.source_sha256:
        return None, Status("embreex", f"the ray-packet kernel {path.name} was built from "
                            "another _packets.c: rebuild it (pip install -e . or "
                            "scripts/setup.sh)", path)
    if ext.layout != _LAYOUT:
        return None, Status("embreex", f"the kernel's packets are laid out as {ext.layout}, "
                            f"not as Embree 4's ({_LAYOUT})", path)
    from maizeviz.mesh.embree_fill import embree

    e = embree()
    if e.lib is None or not e.scene_field:
        return None, Status("embreex", e.why, path)
    try:
        lib = ctypes.CDLL(str(path))
    except OSError as exc:  # pragma: no cover - it was imported a moment ago
        return None, Status("embreex", f"{path} does not load through ctypes ({exc})", path)
    p, i64, i32 = ctypes.c_void_p, ctypes.c_int64, ctypes.c_int
    lib.mz_intersect.restype = i32
    lib.mz_intersect.argtypes = [p, i32, p, i64, p, p, i32, p, p, p, p, i32, i64]
    lib.mz_occluded.restype = i32
    lib.mz_occluded.argtypes = [p, i32, p, i64, p, p, i32, p, p, i32, i64]
    lib.mz_wrapped.restype = i32
    lib.mz_wrapped.argtypes = [p, p, i32, p, i64, p, p, i32, p, p, i32, p, p, p, p, p, i32, i64,
                               p, p]
    inter: dict[int, int] = {}
    occl: dict[int, int] = {}
    for w in (4, 8, 16):
        fi = getattr(e.lib, f"rtcIntersect{w}", None)
        fo = getattr(e.lib, f"rtcOccluded{w}", None)
        ai = ctypes.cast(fi, ctypes.c_void_p).value if fi is not None else None
        ao = ctypes.cast(fo, ctypes.c_void_p).value if fo is not None else None
        if not ai or not ao:
            return None, Status("embreex", f"{e.path} has no rtcIntersect{w}/rtcOccluded{w}",
                                path)
        inter[w], occl[w] = ai, ao
    width = width if width in inter else DEFAULT_WIDTH
    return Kernel(lib, inter, occl, width), Status("packets", "", path)


@functools.cache
def _loaded() -> tuple[Kernel | None, Status]:
    return _load()


def kernel() -> Kernel | None:
    """The packet kernel, loaded on first use; None where it cannot be used (then embreex's
    single rays are used: :func:`status` says why)."""
    return _loaded()[0]


def status() -> Status:
    """Which kernel traces rays (``"packets"`` or ``"embreex"``) and why."""
    return _loaded()[1]


_warned = threading.Lock()
_said: set[tuple[str, str]] = set()


def warn_once(why: str, what: str = "tracing with embreex's single rays (the same hits, "
              "about 2x slower)") -> None:
    """A RuntimeWarning saying ``what`` is done instead of a fast path and ``why``, once per
    reason in a process (``MAIZEVIZ_PACKETS=0``, a deliberate choice, is not warned about)."""
    if not why or why.startswith("turned off by MAIZEVIZ_PACKETS"):
        return
    with _warned:
        if (what, why) in _said:
            return
        _said.add((what, why))
    warnings.warn(f"maizeviz: {what}: {why}", RuntimeWarning, stacklevel=3)


def _rays(origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """Origins (N, 3) and directions (N, 3) or (1, 3) as C-contiguous float32, and the
    kernel's direction step (1: one direction per ray, 0: one for all)."""
    o = np.ascontiguousarray(origins, dtype=np.float32).reshape(-1, 3)
    d = np.ascontiguousarray(directions, dtype=np.float32).reshape(-1, 3)
    if len(d) != 1 and len(d) != len(o):
        raise ValueError(f"{len(d)} directions for {len(o)} rays")
    return o, d, int(len(d) == len(o) and len(o) > 1)


def _ptr(a: np.ndarray | None) -> int | None:
    return None if a is None else a.ctypes.data


def _check(rc: int, width: int) -> None:
    """Raise for a kernel's error code (0: done; -1: unknown width; -3: out of memory)."""
    if rc == -3:  # pragma: no cover - a few kilobytes a call
        raise MemoryError("the ray packet kernel ran out of memory")
    if rc != 0:  # pragma: no cover - widths come from the kernel's own table
        raise ValueError(f"packet width {width} not supported")


def intersect(k: Kernel, scene_handle: int, origins: np.ndarray, directions: np.ndarray,
              tfar: np.ndarray | None, ids: bool = True, coherent: bool = True,
              width: int | None = None, row: int = 0, inst: np.ndarray | None = None
              ) -> tuple[np.ndarray | None, np.ndarray]:
    """Nearest hits of rays from ``origins`` (N, 3) cm along ``directions`` (N, 3) or (1, 3)
    within ``tfar`` (N,) cm (None: unbounded). ``row``: rays per row when the rays are a
    regular grid laid out row by row (packets then take compact tiles of it), else 0.

    Returns triangle ids (N,) int32, -1 where none (None unless ``ids``), and distances (N,)
    float32 cm: the hit's, or the ray's ``tfar`` (1e37 when unbounded) where none. ``inst``:
    an (N,) int32 array to receive the instance hit in a scene of instances (-1: none).
    """
    o, d, step = _rays(origins, directions)
    n = len(o)
    t = None if tfar is None else \
        np.ascontiguousarray(np.broadcast_to(np.asarray(tfar, np.float32), (n,)))
    prim = np.empty(n, np.int32) if ids else None
    dist = np.empty(n, np.float32)
    w = width or k.width
    if n:
        _check(k.lib.mz_intersect(k.intersect[w], w, scene_handle, n, _ptr(o), _ptr(d), step,
                                  _ptr(t), _ptr(prim), _ptr(dist), _ptr(inst), int(coherent),
                                  int(row)), w)
    return prim, dist


def occluded(k: Kernel, scene_handle: int, origins: np.ndarray, directions: np.ndarray,
             tfar: np.ndarray | float, coherent: bool = True, width: int | None = None,
             row: int = 0) -> np.ndarray:
    """True where a triangle lies on the ray from ``origins`` (N, 3) cm along ``directions``
    (N, 3) or (1, 3) between 0 and ``tfar`` (N,) cm: (N,) bool (``row`` as :func:`intersect`)."""
    o, d, step = _rays(origins, directions)
    n = len(o)
    t = np.ascontiguousarray(np.broadcast_to(np.asarray(tfar, np.float32), (n,)))
    out = np.zeros(n, np.uint8)
    w = width or k.width
    if n:
        _check(k.lib.mz_occluded(k.occluded[w], w, scene_handle, n, _ptr(o), _ptr(d), step,
                                 _ptr(t), _ptr(out), int(coherent), int(row)), w)
    return out.view(bool)


def wrapped(k: Kernel, scene_handle: int, origins: np.ndarray, directions: np.ndarray,
            length: np.ndarray, wrap: tuple[float, float, float, float, float, float],
            any_hit: bool = False, coherent: bool = True, width: int | None = None,
            row: int = 0, inst_cells: np.ndarray | None = None,
            frame_cells: tuple[int, int] = (1, 1)):
    """Rays through a periodic field, in C: :func:`maizeviz.light.scene.periodic.trace_wrapped`'s
    algorithm, the same float64 steps, the same queries.

    Parameters
    ----------
    origins : (N, 3) cm; directions : (N, 3) or (1, 3) unit vectors; length : (N,) cm
    wrap : (x0, y0, w, h, q, anchor_cm): cell (0, 0)'s corner and size, the grid step and the
        re-anchoring travel, cm
    any_hit, coherent, width, row : as :func:`intersect` / :func:`occluded`
    inst_cells : (k, 2) int64, for a scene of k instances tiling each cell of ``wrap``: the
        cells are then reported as the instance's cell plus the ``wrap`` cell's index times
        ``frame_cells`` (the instances along x and y)

    Returns
    -------
    any_hit: blocked (N,) bool; else triangle ids (N,) int32 (-1: none), cells (N, 2) int64,
    distances (N,) float64 cm (inf: none) and the instances hit (N,) int32 (-1: none; in a
    scene of instances).
    """
    o = np.ascontiguousarray(origins, dtype=np.float64).reshape(-1, 3)
    d = np.ascontiguousarray(directions, dtype=np.float64).reshape(-1, 3)
    n = len(o)
    if len(d) != 1 and len(d) != n:
        raise ValueError(f"{len(d)} directions for {n} rays")
    t = np.ascontiguousarray(np.broadcast_to(np.asarray(length, np.float64), (n,)))
    w = np.array(wrap, dtype=np.float64)
    width = width or k.width
    blocked = np.zeros(n, np.uint8) if any_hit else None
    prim = None if any_hit else np.empty(n, np.int32)
    cell = None if any_hit else np.empty((n, 2), np.int64)
    dist = None if any_hit else np.empty(n, np.float64)
    inst = None if any_hit else np.empty(n, np.int32)
    ic = None if inst_cells is None else np.ascontiguousarray(inst_cells, dtype=np.int64)
    fc = np.array(frame_cells, dtype=np.int64)
    if n:
        rc = k.lib.mz_wrapped(k.intersect[width], k.occluded[width], width, scene_handle, n,
                              _ptr(o), _ptr(d), int(len(d) == n and n > 1), _ptr(t), _ptr(w),
                              int(any_hit), _ptr(prim), _ptr(cell), _ptr(dist), _ptr(inst),
                              _ptr(blocked), int(coherent), int(row), _ptr(ic), _ptr(fc))
        if rc != 0:  # pragma: no cover - a segment always ends at an edge, anchor or the end
            raise RuntimeError(f"periodic tracing failed ({rc})")
    if any_hit:
        assert blocked is not None
        return blocked.view(bool)
    return prim, cell, dist, inst
