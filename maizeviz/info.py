"""What maizeviz runs on, for bug reports (``maizeviz --info``, as ``napari --info`` and
``pyvista.Report()`` do): versions, the Embree library, the ray kernel in use and why, the
scene fill, threads.

Versions are read from the installed packages' metadata (nothing is imported for them); the
Embree part imports embreex and loads its library, as the first light computation would.
"""

from __future__ import annotations

import os
import platform
import sys
from importlib.metadata import PackageNotFoundError, version

#: The packages maizeviz needs, then those of its extras (gui, sweep), as their
#: distributions are named (pyproject.toml's; tests/core/test_hostile_surfaces.py holds
#: them to it: plyfile was missing and pyarrow, required, was listed as optional).
REQUIRED = ("numpy", "scipy", "pandas", "pvlib", "embreex", "meshio", "plyfile", "matplotlib",
            "pyserial", "pyarrow")
OPTIONAL = ("PySide6", "pyvista", "pyvistaqt", "psygnal", "dask", "distributed", "tqdm",
            "pydantic")


def _version(name: str) -> str:
    try:
        return version(name)
    except PackageNotFoundError:
        return "not installed"


def usable_cores() -> int:
    """Cores this process may run on (its CPU affinity where the system says; else all)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):                # macOS, Windows
        return os.cpu_count() or 1


def info() -> dict[str, object]:
    """Everything :func:`report` prints, as a dictionary.

    Returns
    -------
    dict
        ``maizeviz``, ``python``, ``platform``, ``packages`` and ``optional`` (name ->
        version), ``embreex``, ``embree`` (Embree's version), ``embree_library`` (its file),
        ``kernel`` ("packets" or "embreex"), ``kernel_why``, ``kernel_module`` (the built
        kernel's file), ``scene_fill`` ("copy" or "embreex"), ``scene_fill_why``, ``loops``
        ("compiled" or "numpy": the loops of :mod:`maizeviz.loops`), ``loops_why``, ``cores``,
        ``usable_cores``, ``threads`` (what light traces on by default), ``embree_isa`` (the
        instruction set Embree traces with: ``MAIZEVIZ_EMBREE_ISA``'s, or the CPU's best, or
        why the variable is refused), ``embree_isas`` (those Embree accepts on this CPU).
    """
    from maizeviz import __version__, loops
    from maizeviz.mesh.embree_fill import embree
    from maizeviz.mesh.packets import DEFAULT_WIDTH, status

    e = embree()
    k = status()
    from maizeviz.errors import MaizevizError
    from maizeviz.mesh.embree_isa import requested, supported

    try:
        isa = requested() or "the CPU's best"
    except MaizevizError as exc:
        isa = f"refused: {exc}"
    return {
        "maizeviz": __version__,
        "python": f"{platform.python_version()} ({platform.python_implementation()}, "
                  f"{sys.executable})",
        "platform": f"{platform.platform()} ({platform.machine()})",
        "packages": {name: _version(name) for name in REQUIRED},
        "optional": {name: _version(name) for name in OPTIONAL},
        "embreex": e.embreex or "not importable",
        "embree": e.version or "not found",
        "embree_library": str(e.path) if e.path else None,
        "embree_isa": isa,
        "embree_isas": list(supported()),
        "kernel": k.name,
        "kernel_why": k.why or f"Embree's ray packets of {DEFAULT_WIDTH}",
        "kernel_module": str(k.path) if k.path else None,
        "scene_fill": "copy" if e.scene_field else "embreex",
        "scene_fill_why": e.why or "Embree's buffers filled by memory copy",
        "loops": "compiled" if loops.available() else "numpy",
        "loops_why": loops.why() or "surface bases, reference areas and splitting in C",
        "cores": os.cpu_count() or 1,
        "usable_cores": usable_cores(),
        "threads": os.cpu_count() or 1,
    }


def report() -> str:
    """:func:`info` as lines of text."""
    d = info()
    packages = ", ".join(f"{n} {v}" for n, v in d["packages"].items())  # type: ignore[attr-defined]
    optional = ", ".join(f"{n} {v}" for n, v in d["optional"].items())  # type: ignore[attr-defined]
    kernel = ("packets" if d["kernel"] == "packets" else "embreex's single rays") + \
        f" ({d['kernel_why']})"
    return "\n".join([
        f"maizeviz {d['maizeviz']}",
        f"Python {d['python']}",
        f"platform: {d['platform']}",
        f"packages: {packages}",
        f"optional: {optional}",
        f"Embree {d['embree']} (embreex {d['embreex']}): {d['embree_library'] or 'not found'}",
        f"Embree instruction set: {d['embree_isa']} (this CPU: "
        f"{', '.join(d['embree_isas']) or 'none'}; MAIZEVIZ_EMBREE_ISA chooses)",  # type: ignore[arg-type]
        f"ray kernel: {kernel}" + (f": {d['kernel_module']}" if d["kernel_module"] else ""),
        f"scene fill: {d['scene_fill']} ({d['scene_fill_why']})",
        f"compiled loops: {d['loops']} ({d['loops_why']})",
        f"threads: {d['cores']} cores, {d['usable_cores']} usable; light traces on "
        f"{d['threads']} threads by default (maizeviz light --threads)",
    ])
