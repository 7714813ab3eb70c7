"""Giving freed memory back to the system between the stages of large work.

Building a canopy makes many mid-sized arrays (each leaf's mesh, each plant's) and frees them
once the canopy's own arrays hold the triangles. The C library keeps such freed blocks for
later use instead of returning them: at K = 4 on 900 plants the process held 98 bytes a
triangle after the build for a canopy of 28, and every later stage (the Embree scene, the
rays) came on top. :func:`release` asks it to return what it keeps (glibc's
``malloc_trim``); elsewhere it does nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools


@functools.cache
def _trim():
    name = ctypes.util.find_library("c")
    if not name:
        return None
    try:
        fn = ctypes.CDLL(name).malloc_trim
    except (OSError, AttributeError):
        return None
    fn.argtypes, fn.restype = [ctypes.c_size_t], ctypes.c_int
    return fn


def release() -> bool:
    """Return the memory the C library holds freed to the system; whether it could be asked."""
    fn = _trim()
    if fn is None:
        return False
    fn(0)
    return True
