"""Write a canopy as a mesh file: leaves with their ids (and any per-triangle values) plus stalks."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.layout import field_period
from maizeviz.io.meshfile import write_mesh


def canopy_cells(canopy: Canopy, cell_data: dict[str, np.ndarray] | None = None,
                 with_stalks: bool = True) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Vertices (V, 3) cm, faces (F, 3) and per-triangle arrays of a canopy for export.

    ``plant`` is the placement number from 1, ``leaf`` the leaf rank; stalk triangles (with
    ``with_stalks``) have ``leaf`` = 0 and 0 (or NaN for float arrays) in ``cell_data``.
    ``cell_data`` arrays are (canopy.n_triangles,), one value per leaf triangle.
    """
    cells = {"plant": (canopy.face_instance + 1).astype(np.int32),
             "leaf": canopy.face_leaf.astype(np.int32)}
    cells.update({k: np.asarray(v) for k, v in (cell_data or {}).items()})
    if not with_stalks or not len(canopy.stalk_faces):
        return canopy.vertices, canopy.faces, cells
    n_stalk = len(canopy.stalk_faces)
    if canopy.stalk_instance is not None:
        stalk_plant = (np.asarray(canopy.stalk_instance) + 1).astype(np.int32)
    else:
        per_stalk = n_stalk // max(canopy.n_plants, 1)
        stalk_plant = np.repeat(np.arange(1, canopy.n_plants + 1, dtype=np.int32), per_stalk)
    stalk = {"plant": stalk_plant, "leaf": np.zeros(n_stalk, np.int32)}
    for k, v in cells.items():
        if k not in stalk:
            fill = 0 if np.issubdtype(v.dtype, np.integer) else np.nan
            stalk[k] = np.full(n_stalk, fill, dtype=v.dtype)
    points = np.vstack([canopy.vertices, canopy.stalk_vertices])
    faces = np.vstack([canopy.faces, canopy.stalk_faces + len(canopy.vertices)])
    return points, faces, {k: np.concatenate([v, stalk[k]]) for k, v in cells.items()}


def export_canopy(path: str | Path, canopy: Canopy,
                  cell_data: dict[str, np.ndarray] | None = None) -> Path:
    """Write a canopy with its stalks as a mesh file, the format chosen by the extension.

    The file carries the plot (the layout's bounds) and, for a tiling, the period of its
    periodic field (:func:`~maizeviz.canopy.layout.field_period`), so that read back without
    a field it has the same ground, LAI and light (:mod:`maizeviz.canopy.from_mesh`).

    Parameters
    ----------
    path : str or Path
        The file to write (.ply, .obj, .vtp, .vtu, .vtk, .stl...), atomically.
    canopy : Canopy
        The canopy (its leaves, then its stalks).
    cell_data : dict of str to numpy.ndarray, optional
        Per-triangle values to carry, each (F,) over the canopy's leaf triangles (stalks get 0,
        or NaN for floats), beside ``plant`` and ``leaf`` (:func:`canopy_cells`).

    Returns
    -------
    pathlib.Path
        The file written.
    """
    return write_mesh(path, *canopy_cells(canopy, cell_data), field_cm=canopy.layout.bounds,
                      period_cm=field_period(canopy.layout))
