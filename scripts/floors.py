"""The minimum versions pyproject.toml declares, as pip constraints (``name==floor``), for the
second virtual environment of scripts/min_versions.sh; ``--check`` compares them with what
is installed.

Every runtime dependency and the ``sweep`` extra are held at their floors (numpy, scipy,
pandas, pvlib, embreex, meshio, matplotlib, pyserial, dask, pyarrow, tqdm); the test tools
are not. Needs Python 3.11 (tomllib).

    python scripts/floors.py            # name==floor, one a line
    python scripts/floors.py --check    # exit 1 naming any installed version off its floor
"""

from __future__ import annotations

import re
import sys
import tomllib
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

PYPROJECT = Path(__file__).resolve().parent.parent / "pyproject.toml"
#: name[extras] >= floor (then anything: upper bounds, markers)
REQUIREMENT = re.compile(r"^\s*([A-Za-z0-9_.\-]+)(?:\[[^\]]*\])?\s*>=\s*([0-9][0-9A-Za-z.]*)")


def floors() -> dict[str, str]:
    """Distribution name -> its declared floor, for the runtime dependencies and the sweep
    extra (requirements without a ``>=`` floor are left out)."""
    project = tomllib.loads(PYPROJECT.read_text())["project"]
    found: dict[str, str] = {}
    for req in [*project["dependencies"], *project["optional-dependencies"]["sweep"]]:
        m = REQUIREMENT.match(req)
        if m:
            found[m.group(1)] = m.group(2)
    if "dask" in found:                        # dask[distributed] pins distributed to its own
        found.setdefault("distributed", found["dask"])
    return found


def _same(installed: str, floor: str) -> bool:
    """1.24.0 is the floor 1.24; 2024.1.0 the floor 2024.1."""
    a = [int(x) for x in re.findall(r"\d+", installed)]
    b = [int(x) for x in re.findall(r"\d+", floor)]
    width = max(len(a), len(b))
    return a + [0] * (width - len(a)) == b + [0] * (width - len(b))


def main(argv: list[str]) -> int:
    found = floors()
    if "--check" not in argv:
        print("\n".join(f"{name}=={floor}" for name, floor in found.items()))
        return 0
    off = []
    for name, floor in found.items():
        try:
            got = version(name)
        except PackageNotFoundError:
            continue                           # not for this platform or Python (markers)
        print(f"{name} {got} (floor {floor})")
        if not _same(got, floor):
            off.append(f"{name} {got} is not its floor {floor}")
    for line in off:
        print(f"error: {line}", file=sys.stderr)
    return 1 if off else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
