"""A field of distinct plants read plant chunk by plant chunk: points too many to hold as
fitted leaves at once (a hectare: 70,000 plants, 1.1 million leaves, 72 million points, where
the fitted leaves alone would take about 5 GB).

A Parquet points file with more than :data:`FIELD_POINTS` records whose plants' records lie
together (as every writer of maizeviz writes them) is read twice, :data:`CHUNK_POINTS` at a
time, whole plants per chunk (:func:`maizeviz.io.parquet.point_chunks`):

1. the survey (:class:`FieldLeaves`): each chunk's leaf grids are built and only what the
   commands need before any long work is kept: each leaf's plant and grid shape (the cost
   estimates), each plant's stalk base (the layout), the leaves refused and the repairs made;
   with workers, the chunks' bounds are read from the plant column alone
   (:func:`~maizeviz.io.parquet.plant_chunk_bounds`) and each chunk surveyed on a process;
2. the build (:meth:`FieldLeaves.canopy`): each chunk's grids are built again, fitted and
   meshed at the level (:func:`~maizeviz.canopy.build.plant_meshes`), the chunk's leaves let
   go; the plants' meshes are then placed (:func:`~maizeviz.canopy.build.place_plants`).

Leaves are gridded, fitted and meshed alone or in batches alike (every stage works leaf by
leaf, whatever the batch), so the canopy is the one the whole file read at once gives, to the
bit (``tests/core/test_field.py``); memory follows one chunk plus the meshes.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from maizeviz.canopy.build import Canopy, PlantMesh, place_plants, plant_meshes
from maizeviz.canopy.layout import CanopyLayout
from maizeviz.errors import LeafError
from maizeviz.io.parquet import (
    NotStreamable,
    is_parquet,
    parquet_rows,
    plant_chunk_bounds,
    point_chunks,
)
from maizeviz.leaf.fit import fit_leaves
from maizeviz.leaf.grid import base_of_collars, build_grids
from maizeviz.mesh.levels import Level
from maizeviz.progress import ProgressCallback, report

#: Parquet points files with more records than this are read plant chunk by plant chunk;
#: None: ``MAIZEVIZ_FIELD_POINTS`` or 4,000,000 (:mod:`maizeviz.environment`).
FIELD_POINTS: int | None = None
#: Points read, gridded, fitted and meshed at a time.
CHUNK_POINTS = 1 << 20
#: Processes building a field's chunks side by side, unless a FieldLeaves says (the command
#: line: one per core; from Python, which starts new processes only from a script guarded by
#: ``if __name__ == "__main__"``, this process alone).
WORKERS: int | None = None


def field_input(path: str | Path) -> bool:
    """Whether ``path`` is read as a field (:class:`FieldLeaves`): a Parquet points file of
    more than :data:`FIELD_POINTS` records."""
    if not is_parquet(path):
        return False
    from maizeviz.environment import whole_number

    limit = whole_number("MAIZEVIZ_FIELD_POINTS") if FIELD_POINTS is None else FIELD_POINTS
    rows = parquet_rows(path)
    return rows is not None and rows > limit


class LeafShapes:
    """Plant and grid shape of every leaf of a field, as arrays (L,): ``plant`` int64,
    ``rows`` and ``cols`` int32, ``tip`` bool (a collapsed tip row)."""

    def __init__(self, plant: np.ndarray, rows: np.ndarray, cols: np.ndarray, tip: np.ndarray):
        self.plant, self.rows, self.cols, self.tip = plant, rows, cols, tip

    def __len__(self) -> int:
        return len(self.plant)


class FieldLeaves:
    """The leaves of a field points file, surveyed chunk by chunk (see the module docstring).

    Stands in for the list of fitted leaves where the commands take one: its length is the
    number of leaves, :attr:`shapes` gives the cost estimates their grid shapes, :attr:`bases`
    the layout its plants' stalk bases; :meth:`canopy` builds a canopy at a level.

    Attributes
    ----------
    path : the points file
    shapes : LeafShapes of the leaves kept
    bases : {plant: (x, y) cm}, stalk bases (median of the leaves' insertions)
    skipped : LeafError of each leaf refused
    notes : repairs made, in words ("plant 3, leaf 2: ...")
    rows : records in the file
    extents : {plant: (x0, y0, x1, y1) cm}, the bounding box of its points from above
    highest : cm, the highest point
    worker_cpu_s : CPU seconds the worker processes spent on its chunks so far (survey and
        builds; 0 when this process did all the work)
    """

    def __init__(self, path: str | Path, strict: bool = False, degree: int = 3,
                 method: str = "chord", progress: ProgressCallback | None = None,
                 survey: bool = True, workers: int = 1):
        self.path = Path(path)
        #: processes building chunks side by side (:meth:`plant_meshes`)
        self.workers = workers
        self.strict, self.degree, self.method = strict, degree, method
        self.rows = parquet_rows(path) or 0
        self.worker_cpu_s = 0.0
        #: records [start, stop) of each chunk of whole plants, in the file's order
        self.chunks: list[tuple[int, int]] = []
        parts: Iterable[_Survey] = ()
        pool = None
        if survey and workers > 1 and not strict:
            # the chunks' bounds from the plant column alone, then each chunk surveyed in a
            # worker (the same numbers: each chunk's leaves are gridded alone either way)
            self.chunks = plant_chunk_bounds(path, CHUNK_POINTS)
            if len(self.chunks) > 1:
                pool = _pool(min(workers, len(self.chunks)))
                parts = pool.map(_survey_rows, [str(path)] * len(self.chunks),
                                 *zip(*self.chunks))
            else:
                parts = (_survey_rows(str(path), a, b) for a, b in self.chunks)
        elif survey:
            parts = (_survey_table(t, strict) for t in point_chunks(path, CHUNK_POINTS))
        try:
            self._gather(parts, progress)
        finally:
            if pool is not None:
                pool.shutdown(cancel_futures=True)

    def _gather(self, parts: Iterable[_Survey], progress: ProgressCallback | None) -> None:
        """The survey's attributes from each chunk's, in the file's order."""
        plant: list[int] = []
        nrows: list[int] = []
        ncols: list[int] = []
        tip: list[bool] = []
        collars: dict[int, list] = defaultdict(list)      # (x, y) of each leaf's collar
        self.skipped: list[LeafError] = []
        self.notes: list[str] = []
        lo: dict[int, np.ndarray] = {}
        hi: dict[int, np.ndarray] = {}
        self.highest = -np.inf
        bounds = []
        done = 0
        for part in parts:
            self.worker_cpu_s += part.cpu_s
            bounds.append(part.bounds)
            self.skipped += [LeafError(*e) for e in part.errors]
            plant += part.plant
            nrows += part.rows
            ncols += part.cols
            tip += part.tip
            for p, xy in zip(part.plant, part.collars):
                collars[p].append(xy)
            self.notes += part.notes
            for p, a, b in zip(part.extent_plants, part.lo, part.hi):
                lo[p] = np.minimum(lo[p], a) if p in lo else a
                hi[p] = np.maximum(hi[p], b) if p in hi else b
            self.highest = max(self.highest, part.highest)
            done += part.records
            report(progress, done, max(self.rows, done), "reading the field")
        self.chunks = bounds
        self.shapes = LeafShapes(np.array(plant, np.int64), np.array(nrows, np.int32),
                                 np.array(ncols, np.int32), np.array(tip, bool))
        self.bases = {p: base_of_collars(np.array(c)) for p, c in collars.items()}
        self.extents = {p: (float(lo[p][0]), float(lo[p][1]), float(hi[p][0]), float(hi[p][1]))
                        for p in self.bases}

    def spread(self, plant: int) -> float:
        """How far (cm) the plant's points lie from its stalk base, seen from above (at most)."""
        x0, y0, x1, y1 = self.extents[plant]
        bx, by = self.bases[plant]
        return float(max(np.hypot(x - bx, y - by) for x in (x0, x1) for y in (y0, y1)))

    def __len__(self) -> int:
        return len(self.shapes)

    @property
    def plants(self) -> set[int]:
        return set(self.bases)

    def plant_meshes(self, level: Level, preserve_area: bool = True, only: set[int] | None = None,
                     progress: ProgressCallback | None = None,
                     workers: int | None = None) -> dict[int, PlantMesh]:
        """The meshes of the field's plants (those in ``only``, default all) at ``level``,
        relative to their stalk bases, chunk by chunk; ``progress`` counts chunks.

        ``workers``: processes building chunks side by side (default: :attr:`workers`, else
        :data:`WORKERS`); each reads its chunk's records from the file. The meshes are the same
        either way.
        """
        chunks = self.chunks                               # none when not surveyed
        n = workers or WORKERS or self.workers
        out: dict[int, PlantMesh] = {}
        jobs = [(str(self.path), a, b, level, preserve_area, self.strict, self.degree,
                 self.method, only) for a, b in chunks]
        if not jobs:                                        # a field known only by its path
            for table in point_chunks(self.path, CHUNK_POINTS):
                meshes, errors = _mesh_table(table, level, preserve_area, self.strict,
                                             self.degree, self.method, only)
                out.update(meshes)
                self.skipped += errors
            return out
        results: Iterable
        if n <= 1 or len(jobs) <= 1:
            results = (_mesh_rows(*job) for job in jobs)
            pool = None
        else:
            pool = _pool(min(n, len(jobs)))
            results = pool.map(_mesh_rows, *zip(*jobs))
        try:
            for k, (meshes, errors, cpu_s) in enumerate(results, start=1):
                self.worker_cpu_s += cpu_s
                out.update(meshes)
                self.skipped += [LeafError(*e) for e in errors]
                report(progress, k, len(jobs), f"building the field at {level}")
        finally:
            if pool is not None:
                pool.shutdown(cancel_futures=True)
        return out

    def canopy(self, layout: CanopyLayout, level: Level, preserve_area: bool = True,
               progress: ProgressCallback | None = None) -> Canopy:
        """The canopy of the plants ``layout`` places, meshed at ``level``: the canopy
        :func:`~maizeviz.canopy.build.build_canopy` makes of the same leaves."""
        placed = {p.plant for p in layout.placements}
        meshes = self.plant_meshes(level, preserve_area, placed, progress)
        return place_plants(meshes, layout, level.label)


@dataclass
class _Survey:
    """What the survey keeps of one chunk of whole plants (pickles: errors as tuples)."""

    bounds: tuple[int, int]
    records: int
    errors: list[tuple]
    plant: list[int]
    rows: list[int]
    cols: list[int]
    tip: list[bool]
    collars: list[np.ndarray]
    notes: list[str]
    extent_plants: list[int]
    lo: np.ndarray
    hi: np.ndarray
    highest: float
    cpu_s: float = 0.0                  # CPU seconds a worker process spent on it


def _survey_table(table, strict: bool = False) -> _Survey:
    """The survey of one table of whole plants (:class:`FieldLeaves`)."""
    grids, errors = build_grids(table, strict=strict)
    # each plant's points seen from above (its records lie together in the chunk)
    ids, xyz = table.ids[:, 0], table.xyz
    starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]]) if len(ids) else \
        np.zeros(0, np.int64)
    some = len(xyz) > 0
    return _Survey(
        bounds=(int(table.line[0]) - 2, int(table.line[-1]) - 1) if some else (0, 0),
        records=len(table), errors=[(e.plant, e.leaf, e.detail) for e in errors],
        plant=[g.plant for g in grids], rows=[g.points.shape[0] for g in grids],
        cols=[g.points.shape[1] for g in grids], tip=[g.tip_collapsed for g in grids],
        collars=[g.collar[:2].copy() for g in grids],
        notes=[f"plant {g.plant}, leaf {g.leaf}: {n}" for g in grids if g.notes
               for n in g.notes],
        extent_plants=ids[starts].tolist(),
        lo=np.minimum.reduceat(xyz, starts) if some else np.zeros((0, 3)),
        hi=np.maximum.reduceat(xyz, starts) if some else np.zeros((0, 3)),
        highest=float(xyz[:, 2].max()) if some else -np.inf)


def _survey_rows(path: str, start: int, stop: int) -> _Survey:
    """:func:`_survey_table` of the records [start, stop) of a Parquet points file (in a
    worker process)."""
    import time

    from maizeviz.io.parquet import read_rows

    t = time.process_time()
    out = _survey_table(read_rows(path, start, stop))
    out.cpu_s = time.process_time() - t if _in_worker() else 0.0
    return out


def _in_worker() -> bool:
    """Whether this process is a worker started by :mod:`multiprocessing`."""
    import multiprocessing

    return multiprocessing.parent_process() is not None


def _pool(n: int):
    """Processes for a field's chunks (started by forkserver: no copy of this process's
    memory, nor of its threads' locks)."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    return ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("forkserver"))


def _mesh_table(table, level: Level, preserve_area: bool, strict: bool, degree: int,
                method: str, only: set[int] | None):
    """The plant meshes of a table of whole plants (those in ``only``), and the leaves that
    could not be fitted (as LeafErrors)."""
    if only is not None:
        keep = np.isin(table.ids[:, 0], list(only))
        if not keep.any():
            return {}, []
        table = type(table)(ids=table.ids[keep], xyz=table.xyz[keep], line=table.line[keep],
                            source=table.source)
    grids, _ = build_grids(table, strict=strict)                  # said by the survey
    leaves, errors = fit_leaves(grids, degree, method, strict=strict)
    return plant_meshes(leaves, level, preserve_area), errors


def _mesh_rows(path: str, start: int, stop: int, level: Level, preserve_area: bool,
               strict: bool, degree: int, method: str, only: set[int] | None):
    """:func:`_mesh_table` of the records [start, stop) of a Parquet points file (in a worker
    process: errors as (plant, leaf, detail), which pickle)."""
    import time

    from maizeviz.io.parquet import read_rows

    t = time.process_time()
    meshes, errors = _mesh_table(read_rows(path, start, stop), level, preserve_area, strict,
                                 degree, method, only)
    cpu_s = time.process_time() - t if _in_worker() else 0.0
    return meshes, [(e.plant, e.leaf, e.detail) for e in errors], cpu_s


def canopy_of(leaves, layout: CanopyLayout, level: Level, preserve_area: bool = True,
              progress: ProgressCallback | None = None) -> Canopy:
    """:func:`~maizeviz.canopy.build.build_canopy` of a list of fitted leaves, or
    :meth:`FieldLeaves.canopy` of a field: what the commands build a canopy with."""
    if isinstance(leaves, FieldLeaves):
        return leaves.canopy(layout, level, preserve_area, progress)
    from maizeviz.canopy.build import build_canopy

    return build_canopy(leaves, layout, level, preserve_area, progress)


def read_field(path: str | Path, strict: bool = False,
               progress: ProgressCallback | None = None, workers: int = 1) -> FieldLeaves | None:
    """The survey of a field points file (:func:`field_input`), or None where the file
    cannot be read chunk by chunk (records the CSV reader must check, a plant's records not
    together): the caller then reads it whole."""
    try:
        return FieldLeaves(path, strict, progress=progress, workers=workers)
    except NotStreamable:
        return None

