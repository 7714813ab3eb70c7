"""The layout of a project and the identity of its stands, so results stay on their plants.

Per-plant and per-leaf light (a sky's triangle shares, a day's mol per triangle, a sun's hits)
is stored in the order of the canopy's triangles, which follows the order of the layout's
stands. A layout document groups stands into rows sorted by x, so rebuilding a layout from it
alone renumbers the stands of a tiling or an edited layout: the light of one plant would be
shown on another. A project therefore stores:

- the layout document (readable by people and by ``maizeviz canopy --layout``);
- ``layout_placements``, (n, 6) float64: plant id, x (cm), y (cm), azimuth (degrees), tile i,
  tile j of every stand, in the canopy's order; the layout is rebuilt in exactly this order;
- with each result, ``stands``: the count and SHA-256 of those placements on the canopy it was
  traced on (:func:`stands_identity`).

On opening, a result whose stands are not the project's is reported (one line) and dropped,
never shown on other plants.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from maizeviz.canopy.layout import (
    PLACEMENT_COLUMNS,
    CanopyLayout,
    Placement,
    layout_from_dict,
    layout_to_dict,
    placements_array,
)
from maizeviz.canopy.layout import stands_identity as stands_identity
from maizeviz.io.archive import ProjectError


def layout_parts(layout: CanopyLayout) -> tuple[dict, dict[str, np.ndarray]]:
    """A layout as a document plus its arrays (ground cells, centre cells, ground area and
    the stands in order)."""
    arrays = {"layout_cells": np.asarray(layout.cells, np.float64),
              "layout_centre_cells": np.asarray(layout.centre_cells, np.float64).reshape(-1, 4),
              "layout_ground_area": np.array([layout.ground_area_cm2], np.float64),
              "layout_placements": placements_array(layout)}
    return layout_to_dict(layout), arrays


def _in_order(layout: CanopyLayout, stands: np.ndarray, where: str) -> CanopyLayout:
    """``layout`` with its placements in the order (and with the tiles) of ``stands``, which
    must hold the same stands as the document."""
    if stands.ndim != 2 or stands.shape[1] != len(PLACEMENT_COLUMNS) or \
            not np.all(np.isfinite(stands)):
        raise ProjectError(f"{where}: 'layout_placements' must be n x "
                           f"{len(PLACEMENT_COLUMNS)} finite numbers; the project is damaged")
    placements = tuple(Placement(int(p), float(x), float(y), float(a), (int(i), int(j)))
                       for p, x, y, a, i, j in stands)

    def key(p: Placement) -> tuple:
        return p.plant, round(p.x, 6), round(p.y, 6), round(p.azimuth_deg, 6)

    if Counter(map(key, placements)) != Counter(map(key, layout.placements)):
        raise ProjectError(f"{where}: 'layout_placements' and the layout document do not hold "
                           "the same stands; the project is damaged")
    return replace(layout, placements=placements)


def layout_from_parts(doc: dict, arrays: Mapping[str, Any], plants: set[int],
                      where: str) -> CanopyLayout:
    """The layout a project stored, validated like a layout file against the plants read, its
    stands in the order they were saved (projects without ``layout_placements``, from
    maizeviz 0.1: in the document's order)."""
    layout = layout_from_dict(doc, plants, f"{where}: layout")
    stands = arrays.get("layout_placements")
    if stands is not None:
        layout = _in_order(layout, stands, where)
    cells = arrays.get("layout_cells")
    centre = arrays.get("layout_centre_cells")
    area = arrays.get("layout_ground_area")
    if cells is None or centre is None or area is None:
        return layout
    ok = (cells.ndim == 2 and cells.shape[1:] == (4,) and len(cells) >= 1 and
          centre.ndim == 2 and centre.shape[1:] == (4,) and area.shape == (1,) and
          np.all(np.isfinite(cells)) and np.all(np.isfinite(centre)) and
          float(area[0]) > 0 and np.isfinite(area[0]))
    if not ok:
        raise ProjectError(f"{where}: the layout's ground cells are damaged")
    return replace(layout, cells=np.array(cells, np.float64),
                   centre_cells=np.array(centre, np.float64), ground_area=float(area[0]))
