"""Light taken by the stalks, reported apart from the leaves.

A canopy's stalks (one tube per plant, :func:`~maizeviz.canopy.build.stalk_mesh`) intercept
and scatter light like any organ when traced (``LightEngine(..., with_stalks=True)``, the
default; ``--leaves-only`` on the command line leaves them out, the paper's canopy). Per-triangle
results then hold the canopy's F leaf triangles followed by its G stalk triangles; the leaf
tables sum the first F only (:func:`~maizeviz.light.results.per_leaf.leaf_part`), and the
stalks' part is summed here, per plant standing in the canopy. A stalk is not leaf area: it
counts in no leaf area index.
"""

from __future__ import annotations

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.errors import MaizevizError
from maizeviz.light.results.per_leaf import LightRow, tile_representatives
from maizeviz.mesh.tessellate import triangle_areas_normals


def stalk_placements(canopy: Canopy) -> np.ndarray:
    """The placement (index into ``canopy.layout.placements``) of each stalk triangle: (G,)
    int64 (equal shares in placement order where the canopy does not say)."""
    g = len(canopy.stalk_faces)
    if canopy.stalk_instance is not None:
        return canopy.stalk_instance.astype(np.int64)
    n = max(canopy.n_plants, 1)
    return np.minimum(np.arange(g) // max(g // n, 1), n - 1).astype(np.int64)


def stalk_part(canopy: Canopy, values: np.ndarray, what: str) -> np.ndarray:
    """The stalk triangles' part (G,) of light given per scene triangle: empty (0,) where the
    stalks were not traced (``values`` of length F).

    Raises
    ------
    MaizevizError
        ``values`` is neither F nor F + G long: traced on another canopy.
    """
    nf, ns = canopy.n_triangles, len(canopy.stalk_faces)
    values = np.asarray(values)
    if values.ndim != 1 or len(values) not in (nf, nf + ns):
        raise MaizevizError(f"{what} holds light for {len(values):,} triangles, but the canopy "
                            f"has {nf:,} leaf triangles ({nf + ns:,} with its stalks): it was "
                            "traced on another canopy")
    return values[nf:]


def stalk_rows(canopy: Canopy, columns: dict[str, np.ndarray],
               rect: tuple[float, float, float, float] | None = None,
               periodic: bool = False) -> list[LightRow]:
    """Per plant whose stalk took light: the columns summed over its stalk's triangles (and,
    as the leaf rows are, over the copies of its plant in a tile-periodic field sampled on
    ``rect``: :func:`~maizeviz.light.results.per_leaf.tile_representatives`).

    Parameters
    ----------
    canopy : Canopy
        The canopy the light was traced on.
    columns : dict of str to numpy.ndarray
        Name -> (F + G,) float64 per scene triangle, leaves then stalks (a column of length
        F, traced without stalks, gives nothing).
    rect : (x0, y0, x1, y1) tuple of float, optional
        The sample rectangle [cm].
    periodic : bool
        Rays wrapped across the plot.

    Returns
    -------
    list of dict
        Rows with ``instance`` (from 1), ``plant``, ``leaf`` (0: the stalk), ``x_cm``,
        ``y_cm``, ``stalk_area_cm2`` [cm2] and the columns.
    """
    parts = {k: stalk_part(canopy, v, f"the column {k}").astype(np.float64)
             for k, v in columns.items()}
    ns = len(canopy.stalk_faces)
    if not ns or not parts or any(len(v) != ns for v in parts.values()):
        return []
    own = stalk_placements(canopy)
    rep = tile_representatives(canopy.layout, rect, periodic)
    inst = rep[own]                                  # a copy's light goes to its plant
    area, _ = triangle_areas_normals(canopy.stalk_vertices, canopy.stalk_faces)
    n = max(canopy.n_plants, 1)
    sums = {k: np.bincount(inst, weights=v, minlength=n) for k, v in parts.items()}
    areas = np.bincount(own, weights=area, minlength=n)     # one stalk's, not its copies
    rows: list[LightRow] = []
    for i in np.flatnonzero(np.any([s != 0 for s in sums.values()], axis=0)):
        p = canopy.layout.placements[i]
        row: LightRow = {"instance": int(i) + 1, "plant": int(p.plant), "leaf": 0,
                         "x_cm": p.x, "y_cm": p.y, "stalk_area_cm2": float(areas[i])}
        row.update({k: float(s[i]) for k, s in sums.items()})
        rows.append(row)
    return rows
