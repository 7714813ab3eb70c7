"""maizeviz's compiled pieces, the ray-packet kernel (maizeviz/mesh/_packets.c) and the compiled
loops (maizeviz/_loops.c), built when maizeviz is installed; everything else is declared
in pyproject.toml.

The kernel is an extension module on Python's stable ABI (one wheel per platform for every
Python from 3.11). It needs no Embree header and no link: it calls Embree through addresses
taken at run time from the library embreex loads (maizeviz/mesh/packets.py). It is optional:
where it does not compile, maizeviz installs without it and traces with embreex's single
rays, saying so once (the same hits, slower). The compiled loops are optional too: without them
numpy computes the same numbers, slower.
"""

import hashlib
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCES = {"maizeviz.mesh._packets": "maizeviz/mesh/_packets.c",
           "maizeviz._loops": "maizeviz/_loops.c"}


class BuildExt(build_ext):
    """Flags by compiler: no fused multiply-add (the kernels' float64 steps must round as
    numpy's do), symbols hidden but the kernels' own; the compiled loops vectorized (-O3; a
    square root need not set errno nor a comparison trap, so that both run in SIMD lanes:
    the same values, no fast-math)."""

    def build_extensions(self):
        msvc = self.compiler.compiler_type == "msvc"
        for ext in self.extensions:
            if msvc:
                ext.extra_compile_args = ["/O2", "/fp:precise"]
            else:
                fast = ["-O3", "-fno-math-errno", "-fno-trapping-math"] \
                    if ext.name.endswith("_loops") else ["-O2"]
                ext.extra_compile_args = [*fast, "-ffp-contract=off", "-fvisibility=hidden"]
        super().build_extensions()




def _extension(name: str, source: str) -> Extension:
    digest = hashlib.sha256((Path(__file__).parent / source).read_bytes()).hexdigest()
    return Extension(name, [source], optional=True, py_limited_api=True,
                     define_macros=[("Py_LIMITED_API", "0x030B0000"),
                                    ("MZ_SOURCE_SHA256", digest)])


setup(
    ext_modules=[_extension(name, source) for name, source in SOURCES.items()],
    cmdclass={"build_ext": BuildExt},
    options={"bdist_wheel": {"py_limited_api": "cp311"}},
)
