"""Tables of light per leaf and per time step, and the files they are written to (atomically):
what ``maizeviz light`` writes and the desktop app exports.

Per-leaf rows come from each result's ``leaf_rows(canopy)`` (sums over the leaf's triangles by
:func:`maizeviz.light.results.per_leaf.leaf_sums`: copies of a plant in a tile-periodic field
reported as one); per-plant rows from :func:`~maizeviz.light.results.per_leaf.plant_light`.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.ids import groups
from maizeviz.io.atomic import atomic_open
from maizeviz.light.results.diffuse import PeriodLight
from maizeviz.light.results.per_leaf import LightRow, tile_representatives


def leaf_values(canopy: Canopy, rows: list[LightRow], column: str, rect=None,
                periodic: bool = False, per_m2_leaf: bool = True) -> np.ndarray:
    """A per-leaf value on every leaf triangle, for colouring the canopy.

    Parameters
    ----------
    rows : leaf rows (``instance``, ``leaf``, ``leaf_area_cm2`` and ``column``), as
        a result's ``leaf_rows(canopy)`` gives
    column : the value; divided by the leaf's area in m2 when ``per_m2_leaf``
    rect, periodic : the sample rectangle and field the rows were summed with (copies of a
        plant in a tile-periodic field take the value of the copy that stands for them)

    Returns
    -------
    (F,) float64 per leaf triangle; 0 on leaves without a row (no light reached them), NaN on
    leaves of plants standing outside the rectangle in an open field (not sampled)
    """
    nf = canopy.n_triangles
    rep = tile_representatives(canopy.layout, rect, periodic)
    inst = canopy.face_instance.astype(np.int64)
    out = np.zeros(nf, np.float64)
    if rows:
        value = {(int(r["instance"]) - 1, int(r["leaf"])):
                 float(r[column]) / (float(r["leaf_area_cm2"]) * 1e-4 if per_m2_leaf else 1.0)
                 for r in rows}
        keys, leaf_of = groups(rep[inst], canopy.face_leaf)
        per_leaf = np.array([value.get((int(i), int(lf)), 0.0) for i, lf in keys], np.float64)
        out = per_leaf[leaf_of]
    if rect is not None and (rep == np.arange(len(rep))).all():
        x0, y0, x1, y1 = rect
        outside = np.array([not (x0 <= p.x <= x1 and y0 <= p.y <= y1)
                            for p in canopy.layout.placements], bool)
        out[outside[inst] & (out == 0)] = np.nan
    return out


def write_steps(path: str | Path, pl: PeriodLight) -> None:
    """One line per time step (sun up), atomically: time, step_s, zenith_deg, azimuth_deg,
    ghi_w_m2, direct_horizontal_w_m2, diffuse_w_m2, par_direct_mol_m2, par_diffuse_mol_m2,
    par_intercepted_mol_m2, fraction_intercepted, direct_transmission_h<h>cm...,
    par_transmitted_mol_m2_h<h>cm...; with a Perez diffuse split also perez_f1, perez_f2,
    isotropic_w_m2, circumsolar_w_m2 (on the horizontal), par_circumsolar_mol_m2 (traced with
    the sun) and par_diffuse_intercepted_mol_m2."""
    p = pl.period
    d = pl.diffuse
    hs = [f"{h:g}".replace(".", "p") for h in pl.heights_cm]
    head = (["time", "step_s", "zenith_deg", "azimuth_deg", "ghi_w_m2", "direct_horizontal_w_m2",
             "diffuse_w_m2", "par_direct_mol_m2", "par_diffuse_mol_m2", "par_intercepted_mol_m2",
             "fraction_intercepted"] + [f"direct_transmission_h{h}cm" for h in hs]
            + [f"par_transmitted_mol_m2_h{h}cm" for h in hs])
    if d is not None:
        head += ["perez_f1", "perez_f2", "isotropic_w_m2", "circumsolar_w_m2",
                 "par_circumsolar_mol_m2", "par_diffuse_intercepted_mol_m2"]
    with atomic_open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(head)
        for j in range(pl.n_steps):
            row = ([p.times[j].isoformat(), f"{p.step_s[j]:g}", f"{p.zenith_deg[j]:.3f}",
                    f"{p.azimuth_deg[j]:.3f}", f"{p.ghi[j]:.2f}",
                    f"{p.direct_horizontal[j]:.2f}", f"{p.dhi[j]:.2f}",
                    f"{pl.step_direct_mol_m2[j]:.6f}", f"{pl.step_diffuse_mol_m2[j]:.6f}",
                    f"{pl.step_intercepted_mol_m2[j]:.6f}",
                    f"{pl.step_fraction_intercepted[j]:.5f}"]
                   + [f"{t:.5f}" for t in pl.step_transmission[j]]
                   + [f"{t:.6f}" for t in pl.step_transmitted_mol_m2[j]])
            if d is not None:
                row += [f"{d.f1[j]:.4f}", f"{d.f2[j]:.4f}", f"{d.isotropic_w_m2[j]:.2f}",
                        f"{d.circumsolar_w_m2[j]:.2f}", f"{pl.step_circumsolar_mol_m2[j]:.6f}",
                        f"{pl.step_diffuse_intercepted_mol_m2[j]:.6f}"]
            w.writerow(row)
