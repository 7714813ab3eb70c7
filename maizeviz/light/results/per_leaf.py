"""Light received per leaf and per plant: the hit classes of a sun (:func:`leaf_light`), and any
per-triangle quantity such as diffuse light or a period's PAR (:func:`leaf_sums`)."""

from __future__ import annotations

import numpy as np

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.layout import CanopyLayout
from maizeviz.errors import MaizevizError
from maizeviz.ids import groups
from maizeviz.light.scene.rays import Rect
from maizeviz.mesh.tessellate import triangle_areas_normals

#: Per-leaf sums that :func:`plant_light` adds up per plant (those present in the rows).
LIGHT_SUMS = ("sunlit_area_cm2", "second_class_area_cm2", "sunlit_intercepted_cm2",
              "second_class_intercepted_cm2", "diffuse_intercepted_cm2", "par_intercepted_mol",
              "direct_par_intercepted_mol", "diffuse_par_intercepted_mol", "absorbed_w",
              "absorbed_mj", "absorbed_mol", "gross_umol_s", "gross_mol", "gross_g_co2")
#: Columns that identify a leaf row.
LEAF_KEYS = ("instance", "plant", "leaf", "x_cm", "y_cm", "leaf_area_cm2")

LightRow = dict[str, "int | float | str"]


def tile_representatives(layout: CanopyLayout, rect: Rect | None, periodic: bool) -> np.ndarray:
    """Instance each placement's light is reported under: (P,) int64 indices of placements.

    In a periodic field whose plants repeat with the sample rectangle as their tile (the paper's
    tiled block, sampled on its central tile), the rays over the rectangle reach every copy of
    a plant, and the copies of one plant together receive exactly what that plant receives in
    the infinite field (by periodicity): each copy is then mapped to the copy standing inside
    the rectangle. Otherwise every placement stands for itself.

    Parameters
    ----------
    layout : CanopyLayout; rect : (x0, y0, x1, y1) cm, the sample rectangle (None: identity)
    periodic : whether rays wrap across the plot
    """
    n = len(layout.placements)
    identity = np.arange(n, dtype=np.int64)
    if not periodic or rect is None or n == 0:
        return identity
    x0, y0, x1, y1 = rect
    px0, py0, px1, py1 = layout.bounds
    w, h = x1 - x0, y1 - y0
    kx, ky = (px1 - px0) / w, (py1 - py0) / h
    if min(kx, ky) < 1.5 or abs(kx - round(kx)) > 1e-6 or abs(ky - round(ky)) > 1e-6:
        return identity
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    # stalk positions folded into one tile; copies lie within 0.01 cm of each other there
    xy = np.array([[pl.x - x0, pl.y - y0] for pl in layout.placements]) % [w, h]
    xy = np.minimum(xy, np.nextafter([w, h], 0))    # keep inside [0, box) for the tree
    pairs = cKDTree(xy, boxsize=[w, h]).query_pairs(0.01, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    copies = int(round(kx)) * int(round(ky))
    keys: dict[int, list[int]] = {}
    for i, lab in enumerate(label):
        keys.setdefault(int(lab), []).append(i)
    for members in keys.values():
        first = layout.placements[members[0]]
        if len(members) != copies or any(
                layout.placements[i].plant != first.plant
                or abs((layout.placements[i].azimuth_deg - first.azimuth_deg + 180) % 360 - 180)
                > 1e-6 for i in members):
            return identity
    rep = identity.copy()
    for members in keys.values():
        inside = [i for i in members if x0 <= layout.placements[i].x < x1
                  and y0 <= layout.placements[i].y < y1]
        rep[members] = inside[0] if inside else members[0]
    return rep


def leaf_part(canopy: Canopy, values: np.ndarray, what: str) -> np.ndarray:
    """The leaf triangles' part (F,) of light given per scene triangle (F,) or (F + G,): the
    canopy's F leaf triangles, then its G stalk triangles when they were traced.

    Raises
    ------
    MaizevizError
        ``values`` has another length: it was traced on another canopy (or read damaged), and
        its light would be summed on other leaves (or fail to broadcast).
    """
    nf, ns = canopy.n_triangles, len(canopy.stalk_faces)
    values = np.asarray(values)
    if values.ndim != 1 or len(values) not in (nf, nf + ns):
        raise MaizevizError(f"{what} holds light for {len(values):,} triangles, but the canopy "
                            f"has {nf:,} leaf triangles ({nf + ns:,} with its stalks): it was "
                            "traced on another canopy")
    return values[:nf]


def leaf_light(canopy: Canopy, first_hits: np.ndarray | None, second_hits: np.ndarray | None,
               direction: np.ndarray, ray_area_cm2: float, rect: Rect,
               periodic: bool, sunlit_cm2: np.ndarray | None = None) -> list[LightRow]:
    """Per leaf of the canopy that received rays: sunlit and second-class areas (cm2).

    In a tile-periodic field the copies of a plant are reported as one
    (:func:`tile_representatives`).

    ``*_intercepted_cm2`` is the rays' horizontal footprint (ray count x cell area: the share of
    the sample rectangle's sunlight the leaf takes). ``sunlit_area_cm2`` is the leaf surface
    lit: the sunlit area sampled from each triangle toward the sun (``sunlit_cm2``, see
    :mod:`maizeviz.light.trace.sunlit`), at most the leaf's area and unbiased. Without it
    (results traced by ``trace_light`` alone, or saved before maizeviz sampled it) the rays'
    count x footprint x cos(zenith) / |n . s| summed over the leaf's triangles, capped at
    the leaf's area: one ray on a small or grazing triangle stands for more than the triangle,
    and the cap biases the sum low (by 18 % on 2 cm leaves at 1 ray per cm2). (A sampled
    leaf of a tiled periodic field, whose copies' samples add up, is held to its area too: its
    expectation is within it, and only a whole-lit leaf's sampling noise is cut.)
    ``second_class_area_cm2`` is that rays' estimate for the second hits, not capped, so that
    leaves add up to the rays' total without bias; on a leaf of a few rays it can exceed what
    its area leaves unlit (``leaf_area_cm2 - sunlit_area_cm2``, its bound), which the table
    holds beside it.

    Parameters
    ----------
    canopy : Canopy
        The canopy the sun was traced on.
    first_hits, second_hits : (F',) int64
        Rays whose first and second hit is each scene triangle (leaves first, then stalks);
        None when hit classes were not traced (refused).
    direction : (3,) float64
        Unit vector toward the sun, field coordinates.
    ray_area_cm2 : float
        Horizontal footprint of one ray [cm2].
    rect : (x0, y0, x1, y1) float
        The sample rectangle [cm].
    periodic : bool
        Rays wrapped across the plot.
    sunlit_cm2 : (F',) float64 or None
        The sampled sunlit area of each scene triangle [cm2]; None: the rays' capped count.
    """
    if first_hits is None or second_hits is None:
        raise MaizevizError("hit classes were not traced")
    _, normals = triangle_areas_normals(canopy.vertices, canopy.faces)
    s = direction
    # a ray on a grazing triangle stands for more than the triangle
    lit = ray_area_cm2 * s[2] / np.maximum(np.abs(normals @ s), 1e-6)
    first = leaf_part(canopy, first_hits, "the first hits").astype(np.float64)
    second = leaf_part(canopy, second_hits, "the second hits").astype(np.float64)
    sunlit = first * lit if sunlit_cm2 is None else \
        leaf_part(canopy, sunlit_cm2, "the sampled sunlit area")
    rows = leaf_sums(canopy, {"sunlit_area_cm2": sunlit,
                              "second_class_area_cm2": second * lit,
                              "sunlit_intercepted_cm2": first * ray_area_cm2,
                              "second_class_intercepted_cm2": second * ray_area_cm2},
                     rect, periodic)
    # the rays' count alone: capped (biased), as it was. Sampled, each triangle is within its
    # area; the copies of a plant in a tiled periodic field add up to at most the leaf's area
    # in expectation (each point of the leaf lands in the rectangle from one copy), and only
    # their sampling noise can pass it, on a leaf lit whole: held to the leaf's area there
    for r in rows:
        r["sunlit_area_cm2"] = min(float(r["sunlit_area_cm2"]), float(r["leaf_area_cm2"]))
    return rows


def leaf_sums(canopy: Canopy, columns: dict[str, np.ndarray], rect: Rect | None = None,
              periodic: bool = False) -> list[LightRow]:
    """Per leaf of the canopy where any column is non-zero: the columns summed over the leaf's
    triangles (and over the copies of its plant in a tile-periodic field sampled on ``rect``,
    see :func:`tile_representatives`).

    Parameters
    ----------
    columns : name -> (F',) float64 per scene triangle (F' >= F: stalk triangles after the
        canopy's F leaf triangles are left out)
    rect : (x0, y0, x1, y1) cm, the sample rectangle; periodic : rays wrapped across the plot

    Returns
    -------
    rows with ``instance, plant, leaf, x_cm, y_cm, leaf_area_cm2`` and the columns
    """
    area, _ = triangle_areas_normals(canopy.vertices, canopy.faces)
    nf = canopy.n_triangles
    cols = {k: leaf_part(canopy, v, f"the column {k}").astype(np.float64)
            for k, v in columns.items()}
    rep = tile_representatives(canopy.layout, rect, periodic)
    keys, leaf_of = groups(rep[canopy.face_instance], canopy.face_leaf)
    any_light = np.zeros(nf, dtype=bool)
    for v in cols.values():
        any_light |= v != 0
    touched = np.unique(leaf_of[any_light])
    n_keys = len(keys)
    # per leaf at once (bincounts): its area over its copies, its plant, the columns' sums
    pairs, _ = groups(leaf_of, canopy.face_instance)
    copies = np.bincount(pairs[:, 0], minlength=n_keys)
    leaf_area = np.bincount(leaf_of, weights=area[:nf], minlength=n_keys)
    first = np.full(n_keys, nf, np.int64)
    np.minimum.at(first, leaf_of, np.arange(nf))
    sums = {k: np.bincount(leaf_of, weights=v, minlength=n_keys) for k, v in cols.items()}
    places = canopy.layout.placements
    rows: list[LightRow] = []
    for k in touched:
        inst, leaf = (int(x) for x in keys[k])
        row: LightRow = {"instance": inst + 1, "plant": int(canopy.face_plant[first[k]]),
                         "leaf": leaf, "x_cm": places[inst].x, "y_cm": places[inst].y,
                         "leaf_area_cm2": float(leaf_area[k]) / int(copies[k])}
        for name, total in sums.items():
            row[name] = float(total[k])
        rows.append(row)
    return rows


def merge_rows(*tables: list[LightRow]) -> list[LightRow]:
    """Leaf rows of several tables joined by (instance, leaf); a column a leaf lacks is 0."""
    merged: dict[tuple[int, int], LightRow] = {}
    columns: list[str] = []
    for rows in tables:
        for r in rows:
            d = merged.setdefault((int(r["instance"]), int(r["leaf"])), {})
            for k, v in r.items():
                d.setdefault(k, v)
                if k not in LEAF_KEYS:
                    d[k] = v
                if k not in columns:
                    columns.append(k)
    out = []
    for key in sorted(merged):
        d = merged[key]
        out.append({k: d.get(k, 0.0) for k in columns})
    return out


def plant_light(rows: list[LightRow]) -> list[LightRow]:
    """Leaf rows summed per plant standing in the canopy (one row per placement): the columns
    of :data:`LIGHT_SUMS` present in the rows, and ``leaves_lit``."""
    sums = [k for k in LIGHT_SUMS if rows and k in rows[0]]
    per: dict[int, LightRow] = {}
    for r in rows:
        d = per.setdefault(int(r["instance"]), {
            "instance": r["instance"], "plant": r["plant"], "x_cm": r["x_cm"], "y_cm": r["y_cm"],
            **({"level": r["level"]} if "level" in r else {}), "leaves_lit": 0,
            **dict.fromkeys(sums, 0.0)})
        d["leaves_lit"] = int(d["leaves_lit"]) + 1
        for k in sums:
            d[k] = float(d[k]) + float(r[k])
    return list(per.values())


#: :func:`triangle_light`'s value for a triangle no traced ray could reach.
NOT_TRACED = -1


def triangle_light(canopy: Canopy, first_hits: np.ndarray | None,
                   second_hits: np.ndarray | None, direction: np.ndarray, rect: Rect,
                   periodic: bool) -> np.ndarray:
    """Light class of every leaf triangle (F,) int8, for colouring the canopy and exporting it:
    2 direct (some ray's first hit), 1 second class only, 0 none, and :data:`NOT_TRACED` (-1)
    where no traced ray could reach the triangle (it stands outside the sample rectangle seen
    from the sun).

    In a tile-periodic field (see :func:`tile_representatives`) every copy of a plant receives
    what the copies receive together, so each copy gets the classes of its plant's triangles
    summed over the copies: the whole field is classified, not only the sampled tile.

    Parameters
    ----------
    canopy : Canopy
        The canopy the sun was traced on.
    first_hits, second_hits : (F',) int64
        Rays whose first and second hit is each scene triangle; None: refused (no hit classes).
    direction : (3,) float64
        Unit vector toward the sun, field coordinates.
    rect : (x0, y0, x1, y1) float
        The sample rectangle [cm].
    periodic : bool
        Rays wrapped across the plot.
    """
    if first_hits is None or second_hits is None:
        raise MaizevizError("hit classes were not traced")
    nf = canopy.n_triangles
    first = leaf_part(canopy, first_hits, "the first hits")
    second = leaf_part(canopy, second_hits, "the second hits")
    rep = tile_representatives(canopy.layout, rect, periodic)
    inst = canopy.face_instance.astype(np.int64)
    if nf and (rep != np.arange(len(rep))).any() and np.all(np.diff(inst) >= 0):
        # copies of a plant have the same triangles in the same order: fold hits by
        # (representative placement, triangle index within the placement)
        starts = np.searchsorted(inst, np.arange(len(rep)))
        local = np.arange(nf) - starts[inst]
        _, slot = groups(rep[inst], local)
        first = np.bincount(slot, weights=first)[slot]
        second = np.bincount(slot, weights=second)[slot]
        traced = np.ones(nf, bool)
    else:
        centroid = canopy.vertices[canopy.faces].mean(axis=1)                       # (F, 3)
        s = direction
        ground = centroid[:, :2] - centroid[:, 2:3] / s[2] * s[:2]      # along the sun ray
        if periodic:
            px0, py0, px1, py1 = canopy.layout.bounds
            ground = np.column_stack([px0 + np.mod(ground[:, 0] - px0, px1 - px0),
                                      py0 + np.mod(ground[:, 1] - py0, py1 - py0)])
        x0, y0, x1, y1 = rect
        traced = ((ground[:, 0] >= x0) & (ground[:, 0] <= x1) &
                  (ground[:, 1] >= y0) & (ground[:, 1] <= y1))
    out = np.where(traced, 0, NOT_TRACED).astype(np.int8)
    out[second > 0] = 1
    out[first > 0] = 2
    return out
