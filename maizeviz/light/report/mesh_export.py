"""The light a canopy received, per triangle, for mesh exports (``maizeviz light --export``,
the app's canopy export): arrays named with their units, each triangle holding its leaf's
value as the per-leaf tables give it (``--leaf-light``), so a file opened in ParaView shows
the numbers of the tables.

Stalk triangles (leaf id 0 in the file) hold 0 in ``sun_class`` and NaN in the others
(:func:`maizeviz.canopy.export.canopy_cells`).
"""

from __future__ import annotations

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.light.report.tables import leaf_values

#: The arrays a light export may hold: name -> what it is, with its unit.
LIGHT_ARRAYS = {
    "sun_class": "the sun's hit class of the triangle (the paper's): 2 direct (some ray's "
                 "first hit), 1 second class only, 0 none, -1 out of reach of the sampled rays",
    "diffuse_cm2_per_cm2_leaf": "diffuse light its leaf intercepted, cm2 of open ground's "
                                "worth per cm2 of leaf (1: what a horizontal cm2 of open "
                                "ground receives)",
    "par_mol_per_m2_leaf": "PAR its leaf intercepted over the period, mol per m2 of leaf",
    "absorbed_w_per_m2_leaf": "light its leaf absorbed with scattering, W per m2 of leaf",
    "gross_umol_co2_per_m2_leaf_s": "its leaf's gross CO2 assimilation (a leaf model on the "
                                    "absorbed PAR), umol CO2 per m2 of leaf per s",
}


def light_cells(canopy: Canopy, sun=None, sky=None, period=None, absorbed=None,
                assimilation=None) -> dict[str, np.ndarray]:
    """Per leaf triangle (F,) arrays of the light computed on ``canopy``: ``sun`` a
    :class:`~maizeviz.light.results.direct.LightResult` traced with its hit classes, ``sky``
    a :class:`~maizeviz.light.results.diffuse.SkyLight`, ``period`` a
    :class:`~maizeviz.light.results.diffuse.PeriodLight`, ``absorbed`` an
    :class:`~maizeviz.light.results.absorbed.AbsorbedLight`, ``assimilation`` its
    :class:`~maizeviz.light.results.assimilation.Assimilation` (see :data:`LIGHT_ARRAYS`)."""
    out: dict[str, np.ndarray] = {}
    if sun is not None and sun.first_hits is not None:
        out["sun_class"] = sun.triangle_light(canopy).astype(np.int32)
    for name, light, column, scale in (
            ("diffuse_cm2_per_cm2_leaf", sky, "diffuse_intercepted_cm2", 1e-4),
            ("par_mol_per_m2_leaf", period, "par_intercepted_mol", 1.0),
            ("absorbed_w_per_m2_leaf", absorbed, "absorbed_w", 1.0)):
        if light is not None:
            out[name] = scale * leaf_values(canopy, light.leaf_rows(canopy), column, light.rect,
                                            light.periodic)
    if assimilation is not None:
        out["gross_umol_co2_per_m2_leaf_s"] = leaf_values(
            canopy, assimilation.table("leaf", canopy).to_dict("records"), "gross_umol_s",
            assimilation.rect, assimilation.periodic)
    return out
