"""Direct light received per leaf and per plant from the hit classes of a light result."""

from __future__ import annotations

import numpy as np

from maizeviz.canopy.scene import Canopy
from maizeviz.errors import MaizevizError
from maizeviz.light.transmission import LightResult
from maizeviz.mesh.tessellate import triangle_areas_normals

#: Per-leaf sums that :func:`plant_light` adds up per plant.
LIGHT_SUMS = ("sunlit_area_cm2", "second_class_area_cm2", "sunlit_intercepted_cm2",
              "second_class_intercepted_cm2")

LightRow = dict[str, "int | float | str"]


def leaf_light(canopy: Canopy, result: LightResult) -> list[LightRow]:
    """Per leaf of the canopy that received rays: sunlit and second-class areas (cm2).

    ``*_intercepted_cm2`` is the rays' horizontal footprint (ray count x cell area: the share of
    the sample rectangle's sunlight the leaf takes); ``*_area_cm2`` is the leaf surface lit,
    count x footprint x cos(zenith) / |n . s| summed over the leaf's triangles, capped at the
    leaf's area (one ray on a grazing triangle stands for more than the triangle).
    """
    if result.first_hits is None or result.second_hits is None:
        raise MaizevizError("hit classes were not traced")
    area, normals = triangle_areas_normals(canopy.vertices, canopy.faces)
    s = result.direction
    cos_inc = np.abs(normals @ s)
    beam = result.ray_area_cm2 * s[2]
    nf = canopy.n_triangles
    keys = canopy.face_instance.astype(np.int64) * 10_000 + canopy.face_leaf
    first = result.first_hits[:nf]
    second = result.second_hits[:nf]
    # a grazing triangle can collect a ray "worth" more than its area; cap by leaf below
    lit1 = first * beam / np.maximum(cos_inc, 1e-6)
    lit2 = second * beam / np.maximum(cos_inc, 1e-6)
    touched = np.unique(keys[(first > 0) | (second > 0)])
    order = np.argsort(keys, kind="stable")
    sk = keys[order]
    rows: list[LightRow] = []
    for key in touched:
        a, b = np.searchsorted(sk, key, "left"), np.searchsorted(sk, key, "right")
        idx = order[a:b]
        inst = int(key // 10_000)
        leaf_area = float(area[idx].sum())
        rows.append({"instance": inst + 1, "plant": int(canopy.face_plant[idx[0]]),
                     "leaf": int(key % 10_000), "x_cm": canopy.layout.placements[inst].x,
                     "y_cm": canopy.layout.placements[inst].y,
                     "leaf_area_cm2": leaf_area,
                     "sunlit_area_cm2": min(float(lit1[idx].sum()), leaf_area),
                     "second_class_area_cm2": min(float(lit2[idx].sum()), leaf_area),
                     "sunlit_intercepted_cm2": float(first[idx].sum() * result.ray_area_cm2),
                     "second_class_intercepted_cm2": float(second[idx].sum() * result.ray_area_cm2)})
    return rows


def plant_light(rows: list[LightRow]) -> list[LightRow]:
    """:func:`leaf_light` rows summed per plant standing in the canopy (one row per placement)."""
    per: dict[int, LightRow] = {}
    for r in rows:
        d = per.setdefault(int(r["instance"]), {
            "instance": r["instance"], "plant": r["plant"], "x_cm": r["x_cm"], "y_cm": r["y_cm"],
            **({"level": r["level"]} if "level" in r else {}), "leaves_lit": 0,
            **{k: 0.0 for k in LIGHT_SUMS}})
        d["leaves_lit"] = int(d["leaves_lit"]) + 1
        for k in LIGHT_SUMS:
            d[k] = float(d[k]) + float(r[k])
    return list(per.values())


def triangle_light(canopy: Canopy, result: LightResult) -> np.ndarray:
    """Light class of every leaf triangle (F,) int8: 2 direct (some ray's first hit),
    1 second class only, 0 none; for colouring the canopy and exporting it."""
    if result.first_hits is None or result.second_hits is None:
        raise MaizevizError("hit classes were not traced")
    nf = canopy.n_triangles
    out = np.zeros(nf, np.int8)
    out[result.second_hits[:nf] > 0] = 1
    out[result.first_hits[:nf] > 0] = 2
    return out
