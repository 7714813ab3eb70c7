"""The instruction set Embree traces with, chosen by ``MAIZEVIZ_EMBREE_ISA``.

Embree picks its kernels (SSE2, SSE4.2, AVX, AVX2, AVX-512) from the CPU when a device is
made; a device's configuration string can force one (``isa=avx2``; Embree 4's
``kernels/common/state.cpp``). embreex makes every scene's device with no configuration
(``rtcNewDevice(NULL)``), so the choice is otherwise the CPU's alone. Kernels of different
widths round a hit's distance differently (docs/performance.md, "Packets and single rays"):
to check what holds on other CPUs, and to reproduce a result computed on one, maizeviz makes
the device itself where ``MAIZEVIZ_EMBREE_ISA`` (or :class:`~maizeviz.mesh.raytrace.RayScene`'s
``isa``) names an instruction set, and hands it to embreex's scene.

embreex's ``EmbreeDevice`` keeps its Embree device in a private field (after the object
header, as :mod:`maizeviz.mesh.embree_fill` reads a scene's); the device made with the
configuration takes its place there, for the embreex releases whose layout is known.

References
----------
Embree 4 API: rtcNewDevice and its configuration (``isa``, ``max_isa``)
(https://github.com/RenderKit/embree/blob/master/doc/src/api/rtcNewDevice.md).
"""

from __future__ import annotations

import ctypes
import functools

from maizeviz.errors import MaizevizError

#: The instruction sets an Embree 4 release build (as embreex's wheels vendor it) carries
#: kernels for, lowest first, as its configuration string spells them.
ISAS = ("sse2", "sse4.2", "avx", "avx2", "avx512")
#: The environment variable naming one of :data:`ISAS` (unset or empty: the CPU's best).
ENV = "MAIZEVIZ_EMBREE_ISA"
_PTR = ctypes.sizeof(ctypes.c_void_p)


def check_isa(value: str | None, where: str = ENV) -> str | None:
    """``value`` as one of :data:`ISAS` (lower case; ``sse42`` read as ``sse4.2``), None for
    None or an empty text; else a MaizevizError naming ``where``."""
    if value is None or not value.strip():
        return None
    isa = value.strip().lower()
    isa = {"sse42": "sse4.2", "avx-512": "avx512"}.get(isa, isa)
    if isa not in ISAS:
        raise MaizevizError(f"{where}: {value!r} is not an instruction set Embree traces "
                            f"with ({', '.join(ISAS)})", quantity="embree_isa")
    return isa


def requested() -> str | None:
    """The instruction set ``MAIZEVIZ_EMBREE_ISA`` names (checked, as every variable, by
    :mod:`maizeviz.environment`), or None."""
    from maizeviz.environment import word

    return word(ENV)


def _new(lib, isa: str) -> int:
    """A new Embree device forced to ``isa`` (its handle), or 0 where Embree refuses it."""
    return lib.rtcNewDevice(f"isa={isa},verbose=0".encode()) or 0


@functools.cache
def supported() -> tuple[str, ...]:
    """The instruction sets of :data:`ISAS` Embree accepts on this CPU (Embree refuses a
    device forced to one the CPU lacks); () where the Embree library is not reached."""
    from maizeviz.mesh.embree_fill import embree

    lib = embree().lib
    if lib is None:
        return ()
    found = []
    for isa in ISAS:
        device = _new(lib, isa)
        if device:
            lib.rtcReleaseDevice(device)
            found.append(isa)
    return tuple(found)


def device(isa: str | None):
    """An embreex ``EmbreeDevice`` whose Embree device is forced to ``isa``, for
    ``EmbreeScene(device)``; None for None (embreex then makes its own, the CPU's best).

    Raises a MaizevizError in one line where ``isa`` is not one of :data:`ISAS`, the CPU lacks
    it, or embreex's device cannot be reached (an embreex release of unknown layout).
    """
    isa = check_isa(isa, "the Embree instruction set")
    if isa is None:
        return None
    from embreex.rtcore import EmbreeDevice

    from maizeviz.mesh.embree_fill import embree

    e = embree()
    if e.lib is None or not e.scene_field:
        raise MaizevizError(f"{ENV}={isa}: the Embree device cannot be configured ({e.why})",
                            quantity="embree_isa")
    new = _new(e.lib, isa)
    if not new:
        raise MaizevizError(f"{ENV}={isa}: Embree refuses it on this CPU (it accepts "
                            f"{', '.join(supported()) or 'none'})", quantity="embree_isa")
    dev = EmbreeDevice()
    slot = ctypes.c_void_p.from_address(id(dev) + 2 * _PTR)   # after ob_refcnt, ob_type
    if type(dev) is not EmbreeDevice or not slot.value:   # pragma: no cover - known layout
        e.lib.rtcReleaseDevice(new)
        raise MaizevizError(f"{ENV}={isa}: embreex's device is not laid out as maizeviz "
                            "reads it", quantity="embree_isa")
    old = slot.value
    slot.value = new                     # the object's __dealloc__ releases the new one
    e.lib.rtcReleaseDevice(old)
    return dev
