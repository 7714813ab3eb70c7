"""The stalks' share of a level's light for ``maizeviz light``: apart from the leaves, in the
JSON record (``stalks``: the field's totals), the printed tables and the plant CSV (``stalk_*``
columns, a plant's own stalk). The leaf CSV and every leaf and plant sum stay the leaves' own, so that
leaf rows still add up to plant rows and to the canopy's leaf totals."""

from __future__ import annotations

from typing import Any

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.light.results.stalks import stalk_part, stalk_rows
from maizeviz.mesh.tessellate import triangle_areas_normals


def stalk_record(canopy: Canopy, with_stalks: bool, res: Any, sky: Any, ab: Any,
                 period: Any = None, periodic: bool = False
                 ) -> tuple[dict[str, Any], list[dict]]:
    """The stalks' record of one level and their rows (one per plant whose stalk took light).

    ``res``, ``sky``, ``ab``, ``period``: the level's sun (LightResult), sky (SkyLight),
    absorbed light (AbsorbedLight or AbsorbedPeriod) and period (PeriodLight), each None when
    not traced; ``periodic``: rays wrapped across the plot (a plant's copies are reported as
    one, as its leaves are).
    """
    ns = len(canopy.stalk_faces)
    traced = bool(with_stalks and ns)
    area = float(triangle_areas_normals(canopy.stalk_vertices, canopy.stalk_faces)[0].sum()) \
        if ns else 0.0
    rec: dict[str, Any] = {"traced": traced, "triangles": ns, "area_m2": area / 1e4}
    columns: dict[str, np.ndarray] = {}
    if res is not None and res.first_hits is not None:
        rec["sun_intercepted_fraction"] = res.stalk_intercepted_fraction
        columns["sunlit_intercepted_cm2"] = res.first_hits * res.ray_area_cm2
    if sky is not None:
        rec["diffuse_intercepted_fraction"] = float(
            stalk_part(canopy, sky.triangle_share, "the sky's shares").sum())
        columns["diffuse_intercepted_cm2"] = sky.triangle_intercepted_cm2
    if period is not None and period.n_steps:
        x0, y0, x1, y1 = period.rect
        mol = np.asarray(period.triangle_direct_mol) + np.asarray(period.triangle_diffuse_mol)
        rec["par_intercepted_mol_m2"] = float(
            stalk_part(canopy, mol, "the period's PAR").sum()) / ((x1 - x0) * (y1 - y0) * 1e-4)
        columns["par_intercepted_mol"] = mol
    if ab is not None:
        rec["absorbed"] = ab.balance.absorbed_stalks
        per = getattr(ab, "triangle_absorbed_w", None)
        if per is not None:
            columns["absorbed_w"] = per
        else:
            columns["absorbed_mj"] = ab.triangle_absorbed_j * 1e-6
    # per plant in the --plant-light table only, as the leaves' rows: the record holds what
    # the field took, the same whatever names its plants (a project, its layout file, its
    # exported mesh number and place them differently)
    rect = next((r.rect for r in (res, sky, period, ab) if r is not None), None)
    rows = stalk_rows(canopy, columns, rect, periodic) if traced else []
    return rec, rows


def with_stalk_columns(plants: list[dict], rows: list[dict]) -> list[dict]:
    """Plant rows with each plant's stalk light as ``stalk_<column>`` (0 where its stalk took
    none)."""
    if not rows:
        return plants
    cols = [k for k in rows[0] if k not in ("instance", "plant", "leaf", "x_cm", "y_cm")]
    by = {int(r["instance"]): r for r in rows}
    for p in plants:
        r = by.get(int(p["instance"]), {})
        for k in cols:
            p[f"stalk_{k}"] = float(r.get(k, 0.0))
    return plants


def stalk_line(records: list[dict]) -> str | None:
    """One printed line: what the stalks took, level by level (None: no stalk traced)."""
    parts = []
    for r in records:
        s = r.get("stalks") or {}
        if not s.get("traced"):
            continue
        said = []
        if s.get("sun_intercepted_fraction") is not None:
            said.append(f"{s['sun_intercepted_fraction']:.4f} of the direct sunlight")
        if "diffuse_intercepted_fraction" in s:
            said.append(f"{s['diffuse_intercepted_fraction']:.4f} of the diffuse light")
        if "par_intercepted_mol_m2" in s:
            said.append(f"{s['par_intercepted_mol_m2']:.3f} mol/m2 of PAR over the period")
        if "absorbed" in s:
            units = (r.get("balance") or {}).get("units", "W/m2 of ground")
            said.append(f"absorb {s['absorbed']:.4g} {units}")
        if said:
            parts.append(f"{r['level']}: " + ", ".join(said))
    if not parts:
        return None
    return ("stalks (not leaf area, apart from the leaves; --leaves-only leaves them out) "
            "intercept " + "; ".join(parts))
