"""From a points file to fitted leaves: read, grid, fit a NURBS surface through every leaf.

This is the first stage of every command and of the app; meshing the surfaces at a level is
:mod:`maizeviz.mesh.levels`'s job.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from maizeviz.errors import LeafError, MaizevizError
from maizeviz.io.points import read_points
from maizeviz.leaf.grid import LeafGrid, build_grids
from maizeviz.leaf.nurbs import NurbsSurfaces, fit_surfaces
from maizeviz.progress import ProgressCallback

#: Parameterisations of the data points (The NURBS Book, eqs. 9.5 and 9.6).
PARAMETER_METHODS = ("chord", "centripetal")


@dataclass(frozen=True)
class Leaf:
    """A reconstructed leaf: its point grid and the surface through it (a batch of one).

    ``cache`` holds values derived from the surface that later stages compute once per leaf
    (the reference-mesh area, deviation samples); it never changes what the leaf is.
    """

    grid: LeafGrid
    surface: NurbsSurfaces
    cache: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    @property
    def key(self) -> tuple[int, int]:
        return self.grid.key

    @property
    def plant(self) -> int:
        return self.grid.plant


def fit_leaves(grids: list[LeafGrid], degree: int = 3, method: str = "chord",
               strict: bool = False) -> tuple[list[Leaf], list[LeafError]]:
    """Fit every grid, leaves of equal shape in one batch. Order of ``grids`` is kept.

    A leaf that cannot be fitted is returned in the error list (or raised with ``strict``).
    """
    groups: dict[tuple[int, int], list[int]] = defaultdict(list)
    for i, g in enumerate(grids):
        groups[g.shape].append(i)
    result: dict[int, Leaf] = {}
    errors = []
    for idx in groups.values():
        batch = [grids[i] for i in idx]
        try:
            surf = fit_surfaces(np.stack([g.points for g in batch]), degree, degree, method,
                                [g.key for g in batch])
            for k, i in enumerate(idx):
                result[i] = Leaf(grids[i], surf[k])
        except LeafError:
            for i in idx:                                   # isolate the bad leaf or leaves
                try:
                    result[i] = Leaf(grids[i], fit_surfaces(grids[i].points, degree, degree,
                                                            method, [grids[i].key]))
                except LeafError as exc:
                    if strict:
                        raise
                    errors.append(exc)
    return [result[i] for i in sorted(result)], errors


@dataclass(frozen=True)
class LeavesFromFile:
    """What :func:`read_leaves` found.

    Attributes
    ----------
    leaves : fitted leaves, sorted by (plant, leaf)
    skipped : leaves refused (each error names plant, leaf, row, col)
    problems : lines of the file that were skipped, with the reason
    notes : repairs made (merged duplicates, resampled rows...)
    """

    leaves: list[Leaf]
    skipped: list[LeafError]
    problems: list[str]
    notes: list[str]

    @property
    def plants(self) -> set[int]:
        return {lf.plant for lf in self.leaves}


def read_leaves(path: str | Path, strict: bool = False, degree: int = 3,
                method: str = "chord",
                progress: ProgressCallback | None = None) -> LeavesFromFile:
    """Read, grid and fit a points file.

    ``progress(done, total)`` follows the gathering of leaf grids (in leaves); returning
    ``False`` stops with :class:`InterruptedError`.

    Raises
    ------
    MaizevizError
        The file cannot be read; with ``strict``, also the first skipped line or bad leaf.
    """
    if not isinstance(degree, int) or degree < 1:
        raise MaizevizError(f"the NURBS degree must be a whole number >= 1, got {degree}",
                            quantity="degree")
    if method not in PARAMETER_METHODS:
        raise MaizevizError(f"unknown parameterisation '{method}': use "
                            f"{' or '.join(PARAMETER_METHODS)}", quantity="params")
    table = read_points(path)
    problems = [f"{table.source}: {p}" for p in table.problems]
    if strict and problems:
        raise MaizevizError(problems[0])
    grids, errors = build_grids(table, strict=strict, progress=progress)
    notes = [f"plant {g.plant}, leaf {g.leaf}: {n}" for g in grids for n in g.notes]
    leaves, fit_errors = fit_leaves(grids, degree, method, strict=strict)
    return LeavesFromFile(leaves, errors + fit_errors, problems, notes)
