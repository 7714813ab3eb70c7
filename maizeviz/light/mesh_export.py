"""The light a canopy received, per triangle, for mesh exports (``maizeviz light --export``,
the app's canopy export): arrays named with their units, each triangle holding its leaf's
value as the per-leaf tables give it (``--leaf-light``), so a file opened in ParaView shows
the numbers of the tables.

Stalk triangles (leaf id 0 in the file) hold 0 in ``sun_class`` and NaN in the others
(:func:`maizeviz.canopy.export.canopy_cells`).
"""

from __future__ import annotations

import numpy as np

from maizeviz.canopy.scene import Canopy
from maizeviz.light.leaf_light import triangle_light
from maizeviz.light.reports import leaf_values, period_leaf_rows, sky_leaf_rows

#: The arrays a light export may hold: name -> what it is, with its unit.
LIGHT_ARRAYS = {
    "sun_class": "the sun's hit class of the triangle (the paper's): 2 direct (some ray's "
                 "first hit), 1 second class only, 0 none, -1 out of reach of the sampled rays",
    "diffuse_cm2_per_cm2_leaf": "diffuse light its leaf intercepted, cm2 of open ground's "
                                "worth per cm2 of leaf (1: what a horizontal cm2 of open "
                                "ground receives)",
    "par_mol_per_m2_leaf": "PAR its leaf intercepted over the period, mol per m2 of leaf",
    "absorbed_w_per_m2_leaf": "light its leaf absorbed with scattering, W per m2 of leaf",
}


def light_cells(canopy: Canopy, sun=None, sky=None, period=None, absorbed=None
                ) -> dict[str, np.ndarray]:
    """Per leaf triangle (F,) arrays of the light computed on ``canopy``: ``sun`` a
    :class:`~maizeviz.light.result.LightResult` traced with its hit classes, ``sky`` a
    :class:`~maizeviz.light.daylight.SkyLight`, ``period`` a
    :class:`~maizeviz.light.daylight.PeriodLight`, ``absorbed`` an
    :class:`~maizeviz.light.scatter.AbsorbedLight` (see :data:`LIGHT_ARRAYS`)."""
    out: dict[str, np.ndarray] = {}
    if sun is not None and sun.first_hits is not None:
        out["sun_class"] = triangle_light(canopy, sun).astype(np.int32)
    if sky is not None:
        out["diffuse_cm2_per_cm2_leaf"] = 1e-4 * leaf_values(
            canopy, sky_leaf_rows(canopy, sky), "diffuse_intercepted_cm2", sky.rect,
            sky.periodic)
    if period is not None:
        out["par_mol_per_m2_leaf"] = leaf_values(
            canopy, period_leaf_rows(canopy, period), "par_intercepted_mol", period.rect,
            period.periodic)
    if absorbed is not None:
        from maizeviz.light.scatter import absorbed_leaf_rows

        out["absorbed_w_per_m2_leaf"] = leaf_values(
            canopy, absorbed_leaf_rows(canopy, absorbed), "absorbed_w", absorbed.rect,
            absorbed.periodic)
    return out
