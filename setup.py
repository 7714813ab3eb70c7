"""maizeviz's compiled pieces, the ray-packet kernel (maizeviz/mesh/_packets.c) and the compiled
loops (maizeviz/_loops.c), built when maizeviz is installed; everything else is declared
in pyproject.toml.

The kernel is an extension module on Python's stable ABI (one wheel per platform for every
Python from 3.11). It needs no Embree header and no link: it calls Embree through addresses
taken at run time from the library embreex loads (maizeviz/mesh/packets.py). It is optional:
where it does not compile, maizeviz installs without it and traces with embreex's single
rays, saying so once (the same hits, slower). The compiled loops are optional too: without them
numpy computes the same numbers, slower.

A kernel that does not build leaves the install going, and is named at its end: pip hides a
build's output unless it fails (or runs with -v), so the warning is written to the terminal
the install runs in (/dev/tty, where there is one) as well as to the build's stderr, and
maizeviz says it again on first use and in ``maizeviz --info``.
"""

import hashlib
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCES = {"maizeviz.mesh._packets": "maizeviz/mesh/_packets.c",
           "maizeviz._loops": "maizeviz/_loops.c"}
#: What each kernel is, and what maizeviz does without it.
FALLBACKS = {
    "maizeviz.mesh._packets": ("the ray-packet kernel was", "light is traced with embreex's single "
                               "rays (the same hits, about 2x slower)"),
    "maizeviz._loops": ("the compiled loops were", "numpy computes surface bases, reference areas "
                        "and splitting (the same numbers, slower)"),
}


def not_built_warning(failed: list[tuple[str, str]]) -> str:
    """The lines said at the end of an install for the kernels in ``failed`` ((module, why))."""
    lines = []
    for name, why in failed:
        what, fallback = FALLBACKS[name]
        what, verb = what.rsplit(" ", 1)
        lines.append(f"maizeviz: warning: {what} ({name}, {SOURCES[name]}) {verb} not built "
                     f"({why}): {fallback}.")
    lines.append("maizeviz: install a C compiler (gcc, clang or MSVC) and reinstall maizeviz "
                 "to build it; 'maizeviz --info' says what is used.")
    return "\n".join(lines)


def _say(text: str) -> None:
    """``text`` on stderr, and on the terminal the install runs in, if any (pip shows a
    build's own output only with -v)."""
    print(text, file=sys.stderr, flush=True)
    try:
        with open("/dev/tty", "w") as tty:  # pragma: no cover - needs a terminal
            tty.write(text + "\n")
    except OSError:
        pass


class BuildExt(build_ext):
    """Flags by compiler: no fused multiply-add (the kernels' float64 steps must round as
    numpy's do), symbols hidden but the kernels' own; the compiled loops vectorized (-O3; a
    square root need not set errno nor a comparison trap, so that both run in SIMD lanes:
    the same values, no fast-math)."""

    def run(self):
        self.not_built: list[tuple[str, str]] = []
        super().run()
        if self.not_built:
            _say(not_built_warning(self.not_built))

    def build_extension(self, ext):
        """Build ``ext``, or note why not and go on (the install then uses the fallback)."""
        try:
            super().build_extension(ext)
        except Exception as exc:  # noqa: BLE001 - any compiler or linker failure
            cc = getattr(self.compiler, "compiler_so", None) or ["the C compiler"]
            self.not_built.append((ext.name, f"{type(exc).__name__} from {cc[0]!r}"))

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
    # not setuptools' optional=True, whose warning pip hides: BuildExt catches the failure
    return Extension(name, [source], py_limited_api=True,
                     define_macros=[("Py_LIMITED_API", "0x030B0000"),
                                    ("MZ_SOURCE_SHA256", digest)])


setup(
    ext_modules=[_extension(name, source) for name, source in SOURCES.items()],
    cmdclass={"build_ext": BuildExt},
    options={"bdist_wheel": {"py_limited_api": "cp311"}},
)
