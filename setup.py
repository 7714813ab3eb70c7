"""maizeviz's one compiled piece, the ray-packet kernel (maizeviz/mesh/_packets.c), built when
maizeviz is installed; everything else is declared in pyproject.toml.

The kernel is an extension module on Python's stable ABI (one wheel per platform for every
Python from 3.11). It needs no Embree header and no link: it calls Embree through addresses
taken at run time from the library embreex loads (maizeviz/mesh/packets.py). It is optional:
where it does not compile, maizeviz installs without it and traces with embreex's single
rays, saying so once (the same hits, slower).
"""

import hashlib
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE = "maizeviz/mesh/_packets.c"


class BuildExt(build_ext):
    """Flags by compiler: no fused multiply-add (the kernel's float64 steps must round as
    numpy's do), symbols hidden but the kernel's own."""

    def build_extensions(self):
        msvc = self.compiler.compiler_type == "msvc"
        flags = ["/O2", "/fp:precise"] if msvc else \
            ["-O2", "-ffp-contract=off", "-fvisibility=hidden"]
        for ext in self.extensions:
            ext.extra_compile_args = flags
        super().build_extensions()


digest = hashlib.sha256((Path(__file__).parent / SOURCE).read_bytes()).hexdigest()
setup(
    ext_modules=[Extension("maizeviz.mesh._packets", [SOURCE], optional=True,
                           py_limited_api=True,
                           define_macros=[("Py_LIMITED_API", "0x030B0000"),
                                          ("MZ_SOURCE_SHA256", digest)])],
    cmdclass={"build_ext": BuildExt},
    options={"bdist_wheel": {"py_limited_api": "cp311"}},
)
