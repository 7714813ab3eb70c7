"""The plant being digitized, drawn as it grows.

After every batch of presses the panel hands the session's history here. Only a leaf whose
finished cross-sections changed (a section completed, an undo took one back) is fitted and
meshed again, on a one-thread pool so a press never waits for geometry; the GUI thread only
swaps that leaf's actor and the points. The camera reframes when the plant outgrows the view.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QObject, QThreadPool, Signal

from maizeviz.digitizer.recorder import plant_sections
from maizeviz.errors import MaizevizError
from maizeviz_app.workers import JobRunner

#: Mesh of the live preview: the standard mesh refined twice (smooth enough, about 10 ms).
PREVIEW_INTERP = 2


def mesh_sections(plant: int, leaf: int, rows: dict[int, np.ndarray]):
    """Fit and mesh one leaf from its finished cross-sections {row: (k, 3) cm}.

    Returns (vertices (n, 3) cm, faces (F, 3) int), or None when the sections make no leaf
    yet (a technician's half-done leaf is not an error).
    """
    from maizeviz.leaf.fit import Leaf
    from maizeviz.leaf.grid import grid_from_rows
    from maizeviz.leaf.nurbs import fit_surface
    from maizeviz.mesh.levels import Level, mesh_leaf

    try:
        grid = grid_from_rows(plant, leaf, rows)
        surface = fit_surface(grid.points, plant=plant, leaf=leaf)
        mesh = mesh_leaf(Leaf(grid, surface), Level(interp=PREVIEW_INTERP))
    except (MaizevizError, ValueError, np.linalg.LinAlgError):
        return None
    return mesh.points, mesh.faces


def _leaf_actor(plant: int, leaf: int) -> str:
    return f"leafsurf-p{plant}-l{leaf}"


class GrowingPlant(QObject):
    """Keeps the viewport's picture of the current plant in step with a session.

    ``leaf_meshed(plant, leaf)`` is emitted when a leaf's new surface is shown.
    """

    leaf_meshed = Signal(int, int)

    def __init__(self, viewport, parent=None):
        super().__init__(parent)
        self.viewport = viewport
        self.pool = QThreadPool(self)
        self.pool.setMaxThreadCount(1)
        self.runner = JobRunner(self, pool=self.pool)
        self._generation = 0
        self._plant: int | None = None
        self._wanted: dict[int, bytes] = {}     # leaf -> key of the sections asked for
        self._shown: set[int] = set()           # leaves with an actor
        self._framed: np.ndarray | None = None  # bounds the camera was last pointed at

    def update(self, history: list, pos) -> None:
        """Show the plant at ``pos`` (Session.pos) as recorded in ``history``."""
        vp = self.viewport
        if vp is None:
            return
        plant = pos.plant
        if plant != self._plant:
            self._drop_leaves()
            self._plant, self._framed = plant, None
        sections = plant_sections(history, plant, pos)
        for leaf, rows in sections.items():
            if len(rows) < 2:
                continue
            key = np.concatenate(list(rows.values())).tobytes() + bytes(
                str([len(v) for v in rows.values()]), "ascii")
            if self._wanted.get(leaf) != key:
                self._wanted[leaf] = key
                self._submit(plant, leaf, rows, key)
        gone = [lf for lf in set(self._wanted) | self._shown
                if lf not in sections or len(sections[lf]) < 2]
        for lf in gone:
            self._wanted.pop(lf, None)
        self._remove(gone, render=False)
        pts = np.array([xyz for p, xyz in history if p.plant == plant], float).reshape(-1, 3)
        last = np.asarray(history[-1][1], float) if history and history[-1][0].plant == plant \
            else None
        vp.show_digitized_points(pts, last, render=False)
        self._reframe(pts)
        vp.render()

    def clear(self) -> None:
        """Forget the plant and drop pending work; results still in flight are ignored."""
        self._generation += 1
        self.runner.cancel()                            # their results are dropped
        self._plant, self._framed = None, None
        self._wanted.clear()
        self._shown.clear()
        if self.viewport is not None:
            self.viewport.clear_digitized()

    def wait(self, msecs: int = 5000) -> bool:
        """Wait for the leaf being meshed (at most one); True when none is left."""
        return self.pool.waitForDone(msecs)

    # ------------------------------------------------------------------------ internals
    def _submit(self, plant: int, leaf: int, rows: dict, key: bytes) -> None:
        generation = self._generation
        # one job per leaf: a newer press on the same leaf supersedes its meshing
        self.runner.run(f"leaf {plant}/{leaf}", f"meshing leaf {leaf}",
                        lambda job: mesh_sections(plant, leaf, rows),
                        on_done=lambda result: self._on_meshed(generation, plant, leaf, key,
                                                               result))

    def _on_meshed(self, generation: int, plant: int, leaf: int, key: bytes, result) -> None:
        if generation != self._generation or plant != self._plant \
                or self._wanted.get(leaf) != key or self.viewport is None:
            return                                      # superseded while it was meshed
        if result is None:
            self._remove([leaf])
            return
        vertices, faces = result
        self.viewport.show_digitized_leaf(_leaf_actor(plant, leaf), vertices, faces)
        self._shown.add(leaf)
        self.leaf_meshed.emit(plant, leaf)

    def _remove(self, leaves, render: bool = True) -> None:
        leaves = [lf for lf in leaves if lf in self._shown]
        self._shown.difference_update(leaves)
        if leaves and self._plant is not None:
            self.viewport.remove_digitized([_leaf_actor(self._plant, lf) for lf in leaves],
                                           render)

    def _drop_leaves(self) -> None:
        self._remove(list(self._shown), render=False)
        self._wanted.clear()

    def _reframe(self, pts: np.ndarray) -> None:
        """Frame the plant when it first shows and whenever it grows out of the framed box."""
        if not len(pts):
            return
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        if self._framed is not None:
            f = self._framed
            if np.all(lo >= f[0::2]) and np.all(hi <= f[1::2]):
                return
        size = np.maximum(hi - lo, 20.0)                # at least 20 cm around a first point
        centre = (lo + hi) / 2
        lo, hi = centre - 0.55 * size, centre + 0.55 * size
        self._framed = np.column_stack([lo, hi]).ravel()
        self.viewport.frame_bounds(self._framed, render=False)
