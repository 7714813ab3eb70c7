"""A canopy from a mesh file made elsewhere (OpenAlea/PlantGL, Helios, 3D scans): one placement
per plant of the file, its leaf ids kept, so every light computation and table works on it.

What is taken from the file, and nothing else changed:

- **units**: the file's lengths are cm unless told (m, cm, mm); told nothing, a mesh whose
  height (extent along the up axis) is below :data:`GUESS_MIN_HEIGHT` or above
  :data:`GUESS_MAX_HEIGHT` units is refused, since it is most likely in metres or millimetres
  (a maize canopy in cm is 5 to 1000 units tall); saying the unit, even ``cm``, reads it as is;
- **up axis**: z (OpenAlea, Helios and maizeviz write z up) or y (many scanners): field
  (x, y, z) = file (x, -z, y), a rotation, so triangles keep their orientation;
- **ground**: z = 0 in field coordinates, as for digitized plants (a note says when the
  mesh's lowest point is far from it);
- **stalks**: triangles of leaf id 0 are the stalk (or another organ that is not a leaf), as
  maizeviz exports stalks: left out of the leaves, traced only with the stalks;
- **plants**: one placement per plant id, in increasing id order; it stands at the mean x, y
  of its stalk's vertices, or, without a stalk, at the area-weighted centre of its leaves
  seen from above (only the tables' ``x_cm, y_cm`` and which plants a sample rectangle holds
  depend on it);
- **field** (the ground: LAI, ground cover, the periodic field's tile, the default sample
  rectangle): a rectangle x0, y0, x1, y1 in cm if given, else the one the file carries (a
  ``maizeviz field_cm`` comment, as maizeviz's exports write it), else the mesh's bounding
  box seen from above;
- **period**: a file that carries its field may also carry the block its periodic field
  repeats (``maizeviz period_cm``: a tiled canopy's central tile). With the file's field it
  is the default sample rectangle and, once the light has checked that the triangles do
  repeat with it, the period the periodic field's sensors are read over, as for the tiled
  canopy the file came from (:func:`maizeviz.light.scene.tiling.carried_period`). A field given
  wins over the file's, and then the file's period is not used.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from maizeviz import loops
from maizeviz.canopy.build import Canopy
from maizeviz.canopy.layout import MAX_COORD_CM, CanopyLayout, Placement
from maizeviz.errors import MaizevizError
from maizeviz.ids import groups
from maizeviz.io.mesh_data import CARRIED, MeshData
from maizeviz.numbers import number

#: cm per unit of a mesh file.
UNITS = {"m": 100.0, "cm": 1.0, "mm": 0.1}
#: Up axes a mesh file may have.
UP_AXES = ("z", "y")
#: Without a unit, a mesh of a height outside these (file units) is refused as most likely in
#: metres (below) or millimetres (above).
GUESS_MIN_HEIGHT = 5.0
GUESS_MAX_HEIGHT = 1000.0
#: The mesh's level label (a mesh file is traced as it is: it has no mesh levels).
MESH_LEVEL = "mesh"


#: Smallest side of a field, cm (a plot narrower than a leaf is not one).
MIN_FIELD_CM = 1.0


def check_field(field: tuple[float, float, float, float] | list[float] | str
                ) -> tuple[float, ...]:
    """A field rectangle x0, y0, x1, y1 (cm): finite, within 1 km, x1 > x0 and y1 > y0.

    ``field`` may be text, four numbers separated by commas or spaces ("0, 0, 540, 270")."""
    if isinstance(field, str):
        words = field.replace(",", " ").split()
        try:
            vals = tuple(number(w) for w in words)
        except ValueError:
            raise MaizevizError(f"the field needs 4 numbers x0, y0, x1, y1 (cm), got "
                                f"'{field[:60]}'", quantity="field") from None
    else:
        vals = tuple(number(v) if isinstance(v, (str, bytes)) else float(v) for v in field)
    if len(vals) != 4:
        raise MaizevizError(f"the field needs 4 numbers x0, y0, x1, y1 (cm), got {len(vals)}",
                            quantity="field")
    if not all(math.isfinite(v) and abs(v) <= MAX_COORD_CM for v in vals):
        raise MaizevizError(f"the field {vals} must be finite numbers of at most "
                            f"{MAX_COORD_CM:g} cm in size", quantity="field")
    x0, y0, x1, y1 = vals
    if not (x1 > x0 and y1 > y0):
        raise MaizevizError(f"the field x0, y0, x1, y1 = {x0:g}, {y0:g}, {x1:g}, {y1:g} cm needs "
                            "x1 > x0 and y1 > y0", quantity="field")
    if x1 - x0 < MIN_FIELD_CM or y1 - y0 < MIN_FIELD_CM:
        raise MaizevizError(f"the field x0, y0, x1, y1 = {x0:g}, {y0:g}, {x1:g}, {y1:g} cm is "
                            f"less than {MIN_FIELD_CM:g} cm across: is it in cm?",
                            quantity="field")
    return vals


def _carried(mesh: MeshData, unit: str | None, up: str, source: str, notes: list[str],
             strict: bool) -> tuple[tuple[float, ...] | None, tuple[float, ...] | None]:
    """The plot and period the file carries (``field_cm``, ``period_cm`` comments or field
    data: :data:`maizeviz.io.mesh_data.CARRIED`) in cm, or None; a broken one is refused
    when ``strict`` (no field given), else said in a note."""
    if not mesh.carried:
        return None, None
    if up != "z":
        notes.append(f"{source}: the file's field and period are written for z up: not used "
                     "with the y axis up")
        return None, None
    scale = UNITS[unit or "cm"]
    out: list[tuple[float, ...] | None] = []
    for key in CARRIED:
        if key not in mesh.carried:
            out.append(None)
            continue
        where, text = mesh.carried[key]
        try:
            rect = check_field(text)
        except MaizevizError as exc:
            if not strict:                          # a field given: the file's is not needed
                notes.append(f"{source}: {where}: the {key} the file carries is not read: "
                             f"{exc}")
                return None, None
            raise MaizevizError(f"{source}: {where}: the {key} the file carries: {exc}",
                                quantity="field") from None
        out.append(tuple(v * scale for v in rect))
    return out[0], out[1]


def _period_in(period: tuple[float, ...] | None, field: tuple[float, ...], source: str,
               notes: list[str]) -> tuple[float, float, float, float] | None:
    """The carried period if the field holds a whole number of it (more than one), else
    None with a note."""
    if period is None:
        return None
    x0, y0, x1, y1 = field
    px0, py0, px1, py1 = period
    counts = ((x1 - x0) / (px1 - px0), (y1 - y0) / (py1 - py0))
    whole = all(abs(c - round(c)) <= 1e-9 * c for c in counts)
    inside = x0 - 1e-6 <= px0 and px1 <= x1 + 1e-6 and y0 - 1e-6 <= py0 and py1 <= y1 + 1e-6
    if not (whole and inside) or round(counts[0]) * round(counts[1]) < 2:
        notes.append(f"{source}: the file's period x {px0:g}..{px1:g}, y {py0:g}..{py1:g} cm is "
                     "not a block the field holds a whole number of times: not used")
        return None
    return (float(px0), float(py0), float(px1), float(py1))


def _field_coordinates(mesh: MeshData, unit: str | None, up: str, src: str,
                       used: np.ndarray | None = None) -> np.ndarray:
    """The vertices (V, 3) in cm, z up; ``used`` (V,) bool, if known: the vertices the faces
    use (the unit is guessed from their height alone)."""
    if unit is not None and unit not in UNITS:
        raise MaizevizError(f"the mesh unit must be one of {', '.join(UNITS)}, got '{unit}'",
                            quantity="mesh_unit")
    if up not in UP_AXES:
        raise MaizevizError(f"the up axis must be z or y, got '{up}'", quantity="up")
    v = mesh.vertices
    height_axis = 2 if up == "z" else 1
    if unit is None:
        if used is None:
            used = np.zeros(len(v), bool)
            used[mesh.faces.ravel()] = True
        heights = v[:, height_axis] if used.all() else v[used, height_axis]
        h = float(np.ptp(heights)) if len(heights) else 0.0
        if h < GUESS_MIN_HEIGHT:
            raise MaizevizError(
                f"{src}: the mesh is {h:.4g} units tall: in cm that is not a maize canopy; if "
                "its unit is the metre say so (m), or say cm to read it as it is",
                quantity="mesh_unit")
        if h > GUESS_MAX_HEIGHT:
            raise MaizevizError(
                f"{src}: the mesh is {h:.4g} units tall: in cm that is more than "
                f"{GUESS_MAX_HEIGHT / 100:g} m; if its unit is the millimetre say so (mm), or "
                "say cm to read it as it is", quantity="mesh_unit")
    scale = UNITS[unit or "cm"]
    if up == "y":
        out = np.column_stack([v[:, 0], -v[:, 2], v[:, 1]])
    else:
        out = v.copy() if scale != 1.0 else v
    if scale != 1.0:
        out = out * scale
    # a column's extremes first: the rows are looked at only when one is too far
    if len(out) and any(max(-out[:, k].min(), out[:, k].max()) > MAX_COORD_CM
                        for k in range(3)):
        i = int(np.flatnonzero(np.abs(out).max(axis=1) > MAX_COORD_CM)[0])
        raise MaizevizError(f"{src}: {mesh.where_vertex(i)} lies {np.abs(out[i]).max():.4g} cm "
                            f"from the origin, beyond {MAX_COORD_CM / 100:g} m: not a field plot "
                            "(is the unit right?)", quantity="mesh_unit")
    return out


def _distinct(a: np.ndarray) -> np.ndarray:
    """Sorted distinct values of ``a``, fast where equal values come in runs (a file's faces
    come leaf by leaf)."""
    if not len(a):
        return a
    return np.unique(a[_run_starts(a)])


def _run_starts(*columns: np.ndarray) -> np.ndarray:
    """(R,) intp: where a run of equal rows of the columns (each (n,), n > 0) starts."""
    new = np.zeros(len(columns[0]), bool)
    new[0] = True
    for c in columns:
        new[1:] |= c[1:] != c[:-1]
    return np.flatnonzero(new)


def _mix(h: np.ndarray, v: np.ndarray) -> np.ndarray:
    """A 64-bit hash ``h`` (n,) uint64 with the words ``v`` (n,) uint64 folded in."""
    with np.errstate(over="ignore"):
        h = (h ^ v) * np.uint64(0x9E3779B97F4A7C15)
        return h ^ (h >> np.uint64(31))


def _not_alone(key: np.ndarray) -> np.ndarray:
    """(m,) intp, ascending: the entries of ``key`` (n,) uint64 that may share their value with
    another entry (all that do, and a few that do not).

    Two rounds of a hash table: an entry alone in its slot (the key's top bits, then, of those
    left, its low bits) has a value no other entry has. An entry written to a slot holds it,
    whichever wins: the slot's other entries and the holder are kept. Each round touches each
    key once, where sorting the keys compares each twenty times (at K = 4 a third of the
    time, leaving a twentieth of the keys)."""
    keep = np.arange(len(key))
    for extra, top in ((2, True), (1, False)):
        if len(key) < 2:
            return keep[:0]
        bits = max(int(len(key) - 1).bit_length() + extra, 4)
        slot = (key >> np.uint64(64 - bits)) if top else key & np.uint64((1 << bits) - 1)
        slot = slot.astype(np.intp)
        table = np.empty(1 << bits, np.int32)       # read only where written
        mine = np.arange(len(key), dtype=np.int32)
        table[slot] = mine
        holder = table[slot]
        shared = holder != mine
        shared[holder[shared]] = True
        keep, key = keep[shared], key[shared]
    return keep


def repeated_triangles(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(T,) bool: the triangles whose three corners (by position, in any order and either
    orientation) are those of an earlier triangle.

    vertices : (V, 3) float64; faces : (T, 3) int64. A surface written twice (a file
    concatenated with itself, a double-sided export) would otherwise count its area, and
    intercept its light, twice. Each vertex is given a 64-bit hash of its coordinates, each
    triangle the sum of its corners' hashes (the same in any order): a repeated triangle has
    the sum of the one it repeats. The compiled loops (:func:`maizeviz.loops.repeated_triangles`)
    put the triangles in a hash table in one pass, comparing exactly those of equal sums (at
    K = 4 a fifth of numpy's time); numpy's passes, where they are not built, set aside the
    triangles whose sum no other has (:func:`_not_alone`, the usual case is all of them) and
    compare the few others exactly.
    """
    compiled = loops.repeated_triangles(vertices, faces)
    if compiled is not None:
        return compiled[0]
    out = np.zeros(len(faces), dtype=bool)
    if len(faces) < 2:
        return out
    bits = np.ascontiguousarray(vertices + 0.0).view(np.uint64)   # + 0.0: -0.0 is 0.0
    at = np.zeros(len(vertices), np.uint64)
    for k in range(3):
        at = _mix(at, bits[:, k])
    ft = np.ascontiguousarray(faces.T)
    with np.errstate(over="ignore"):
        key = at[ft[0]] + at[ft[1]]
        key += at[ft[2]]
    cand = _not_alone(key)
    if len(cand) < 2:
        return out
    ranked = np.sort(key[cand])
    twin = np.isin(key[cand], ranked[1:][ranked[1:] == ranked[:-1]])
    cand = cand[twin]
    if not len(cand):
        return out
    # the corners by position: their coordinates' bit patterns (-0.0 made 0.0) grouped as
    # int64 columns, whose sort releases the GIL (np.unique(axis=0) sorts rows as one
    # structured type, holding it)
    used, local = np.unique(faces[cand].reshape(-1), return_inverse=True)
    pos = np.ascontiguousarray(np.asarray(vertices, dtype=np.float64)[used] + 0.0).view(np.int64)
    _, same = groups(pos[:, 0], pos[:, 1], pos[:, 2])
    corners = np.sort(same[local.reshape(-1)].reshape(-1, 3), axis=1)
    order = np.lexsort(corners.T[::-1])                # stable: the first of equals first
    ranked_c = corners[order]
    out[cand[order[1:][np.all(ranked_c[1:] == ranked_c[:-1], axis=1)]]] = True
    return out


def _without_repeats(mesh: MeshData, source: str
                     ) -> tuple[MeshData, list[str], np.ndarray | None]:
    """The mesh with each repeated triangle (:func:`repeated_triangles`) left out, the note
    saying so, and the vertices the triangles use where the compiled loops tell them in the
    same pass (else None). A repeated triangle's corners are at the places of its original's,
    so the used vertices' places are the same with or without it."""
    compiled = loops.repeated_triangles(mesh.vertices, mesh.faces, used=True)
    repeat, used = compiled if compiled is not None else \
        (repeated_triangles(mesh.vertices, mesh.faces), None)
    n = int(repeat.sum())
    if not n:
        return mesh, [], used
    t = int(np.flatnonzero(repeat)[0])
    keep = ~repeat
    note = (f"{source}: {n:,} of the {mesh.n_triangles:,} triangles repeat an earlier triangle "
            f"(the same three corners; first: {mesh.where_triangle(t)}): each surface is "
            "counted once")
    return replace(mesh, faces=mesh.faces[keep], triangle_face=mesh.triangle_face[keep],
                   plant=mesh.plant[keep], leaf=mesh.leaf[keep]), [note], used


def _split(vertices: np.ndarray, faces: np.ndarray, is_leaf: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Leaf vertices and faces, stalk vertices and faces, each renumbered, vertices in file
    order. The stalk's vertices are those only stalk triangles use; the leaves keep every
    other vertex (also those no face uses: the file's vertices come back as they were)."""
    if is_leaf.all():
        return vertices, faces, np.empty((0, 3)), np.empty((0, 3), np.int64)
    n_leaf = int(is_leaf.sum())
    if is_leaf[:n_leaf].all():                    # the leaves first, as maizeviz writes them
        leaf_f, stalk_f = faces[:n_leaf], faces[n_leaf:]
    else:
        leaf_f = faces.take(np.flatnonzero(is_leaf), axis=0)
        stalk_f = faces.take(np.flatnonzero(~is_leaf), axis=0)
    in_stalk = np.zeros(len(vertices), bool)
    in_stalk[stalk_f.ravel()] = True
    if len(leaf_f) and leaf_f.max() < stalk_f.min():
        stalk_only = in_stalk                     # no leaf reaches the stalks' vertices
    else:
        used_by_leaf = np.zeros(len(vertices), bool)
        used_by_leaf[leaf_f.ravel()] = True
        stalk_only = in_stalk & ~used_by_leaf
    gone = np.flatnonzero(stalk_only)
    if not len(gone) or gone[0] + len(gone) == len(vertices):
        # the stalks' own vertices come after every leaf vertex (as maizeviz writes them):
        # the leaves' numbers stay
        leaf_v = vertices[:len(vertices) - len(gone)]
        leaf_faces = leaf_f
    else:
        keep_leaf = ~stalk_only
        leaf_v = vertices[keep_leaf]
        leaf_faces = (np.cumsum(keep_leaf) - 1)[leaf_f]
    # a vertex both organs use is copied into the stalk's vertices
    new_stalk = np.cumsum(in_stalk) - 1
    return leaf_v, leaf_faces, vertices[in_stalk], new_stalk[stalk_f]


def _areas_centres(v: np.ndarray, f: np.ndarray, centres: bool = True
                   ) -> tuple[np.ndarray, np.ndarray | None]:
    """Areas (F,) cm2 and centroids seen from above (F, 2) cm (None unless ``centres``) of
    triangles ``f`` (F, 3) of vertices ``v`` (V, 3) cm, a coordinate at a time from contiguous
    columns (at K = 4 a seventh of the time of gathering the triangles whole and crossing
    their edges; the compiled loops, :func:`maizeviz.loops.triangle_areas`, the same numbers
    in one pass)."""
    compiled = loops.triangle_areas(v, f, centres)
    if compiled is not None:
        return compiled
    vt, ft = np.ascontiguousarray(v.T), np.ascontiguousarray(f.T)
    e1, e2 = [], []
    centre = np.empty((len(f), 2)) if centres else None
    for k in range(3):
        a, b, d = (vt[k][ft[j]] for j in range(3))
        if centre is not None and k < 2:
            centre[:, k] = (a + b + d) / 3.0
        b -= a
        d -= a
        e1.append(b)
        e2.append(d)
    cross2 = (e1[1] * e2[2] - e1[2] * e2[1]) ** 2
    cross2 += (e1[2] * e2[0] - e1[0] * e2[2]) ** 2
    cross2 += (e1[0] * e2[1] - e1[1] * e2[0]) ** 2
    return 0.5 * np.sqrt(cross2), centre


def _positions(n: int, centre: np.ndarray | None, area: np.ndarray, leaf_inst: np.ndarray,
               stalk_v: np.ndarray, stalk_f: np.ndarray, stalk_inst: np.ndarray) -> np.ndarray:
    """(P, 2) cm: the mean of each plant's stalk vertices, or its leaves' area-weighted centre
    (``centre``, ``area``: of each leaf triangle; ``centre`` None: every plant has a
    stalk)."""
    out = np.zeros((n, 2))
    if centre is not None:
        weight = np.bincount(leaf_inst, area, n)
        count = np.bincount(leaf_inst, minlength=n).astype(np.float64)
    for k in range(2 if centre is not None else 0):
        assert centre is not None
        wsum = np.bincount(leaf_inst, area * centre[:, k], n)
        plain = np.bincount(leaf_inst, centre[:, k], n)
        out[:, k] = np.where(weight > 0, wsum / np.where(weight > 0, weight, 1),
                             plain / np.maximum(count, 1))
    if len(stalk_f):
        # each stalk vertex once per plant that uses it
        used, _ = groups(np.repeat(stalk_inst, 3), stalk_f.ravel())
        owner, vert = used[:, 0], used[:, 1]
        has = np.bincount(owner, minlength=n) > 0
        for k in range(2):
            mean = np.bincount(owner, stalk_v[vert, k], n) / np.maximum(
                np.bincount(owner, minlength=n), 1)
            out[has, k] = mean[has]
    return out


def canopy_from_mesh(mesh: MeshData, unit: str | None = None, up: str = "z",
                     field: tuple[float, float, float, float] | None = None,
                     source: str = "mesh") -> tuple[Canopy, list[str]]:
    """A canopy of the mesh's triangles, and notes on what was decided (one line each).

    Parameters
    ----------
    mesh : as :func:`maizeviz.io.mesh_canopy.read_mesh` reads it
    unit : "m", "cm" or "mm"; None: cm, refusing a height that suggests another unit
    up : "z" or "y", the file's up axis
    field : x0, y0, x1, y1 cm; None: the file's, else the mesh's bounding box seen from above
    source : the file, for messages

    Raises
    ------
    MaizevizError
        The unit or field is wrong (``quantity`` says which), no leaf triangle, or every leaf
        triangle has no area.
    """
    notes = list(mesh.notes)
    if field is not None:
        field = check_field(field)                                    # type: ignore[assignment]
    mesh, said, used = _without_repeats(mesh, source)
    notes += said
    carried_field, period = _carried(mesh, unit, up, source, notes, strict=field is None)
    if field is None and carried_field is not None:
        field, fsrc = carried_field, "the file's"                     # type: ignore[assignment]
    elif field is not None:
        fsrc = "given"
    if period is not None and field != carried_field:
        notes.append(f"{source}: the file's period is for its own field, not the one given: "
                     "not used")
        period = None
    verts = _field_coordinates(mesh, unit, up, source, used)
    is_leaf = mesh.leaf != 0
    n_leaf = int(is_leaf.sum())
    if n_leaf == 0:
        raise MaizevizError(f"{source}: no leaf triangle: all {mesh.n_triangles:,} have leaf id "
                            "0 (a stalk or another organ that is not a leaf)")
    leaf_v, leaf_f, stalk_v, stalk_f = _split(verts, mesh.faces, is_leaf)
    plants = _distinct(mesh.plant)
    runs = _run_starts(mesh.plant)
    inst = np.repeat(np.searchsorted(plants, mesh.plant[runs]).astype(np.int32),
                     np.diff(runs, append=len(mesh.plant)))
    leaf_inst, stalk_inst = inst[is_leaf], inst[~is_leaf]
    # a plant's place is its stalk's: the leaves' centres only for plants without one
    stalked = np.bincount(stalk_inst, minlength=len(plants)) > 0
    area, centre = _areas_centres(leaf_v, leaf_f, centres=not stalked.all())
    flat = int((area == 0).sum())
    if flat == n_leaf:
        raise MaizevizError(f"{source}: all {n_leaf:,} leaf triangles are degenerate (no area: "
                            "repeated or aligned vertices): no surface to trace")
    if flat:
        t = int(np.flatnonzero(is_leaf)[int(np.flatnonzero(area == 0)[0])])
        notes.append(f"{source}: {flat:,} of the {n_leaf:,} leaf triangles have no area (first: "
                     f"{mesh.where_triangle(t)}); kept, they receive no light")
    # the ids as the file gives them (the canopy narrows them once)
    leaf_ids = mesh.leaf if n_leaf == len(is_leaf) else mesh.leaf[is_leaf]
    heads = _run_starts(leaf_inst, leaf_ids)            # a file's faces come leaf by leaf
    pairs, _ = groups(leaf_inst[heads], leaf_ids[heads])
    leaves_per = np.bincount(pairs[:, 0], minlength=len(plants)).astype(np.int32)
    xy = _positions(len(plants), centre, area, leaf_inst, stalk_v, stalk_f, stalk_inst)
    del centre
    placements = tuple(Placement(int(p), float(x), float(y)) for p, (x, y) in zip(plants, xy))
    if field is None:
        parts = [a[:, :2] for a in (leaf_v, stalk_v) if len(a)]
        lo = np.min([a.min(axis=0) for a in parts], axis=0)
        hi = np.max([a.max(axis=0) for a in parts], axis=0)
        if not (hi[0] > lo[0] and hi[1] > lo[1]):
            raise MaizevizError(f"{source}: the mesh has no extent in "
                                f"{'x' if not hi[0] > lo[0] else 'y'} seen from above: give "
                                "the field rectangle (is the up axis right?)", quantity="field")
        field = (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))
        fsrc = "the mesh's bounding box"
    else:
        x0, y0, x1, y1 = field
        outside = [p.plant for p in placements if not (x0 <= p.x <= x1 and y0 <= p.y <= y1)]
        if len(outside) == len(placements):
            raise MaizevizError(f"{source}: none of the {len(placements):,} plants stands in the "
                                f"field x {x0:g}..{x1:g}, y {y0:g}..{y1:g} cm (the plants stand "
                                f"in x {min(p.x for p in placements):.1f}.."
                                f"{max(p.x for p in placements):.1f}, y "
                                f"{min(p.y for p in placements):.1f}.."
                                f"{max(p.y for p in placements):.1f} cm)", quantity="field")
        if outside:
            shown = ", ".join(map(str, outside[:5])) + (", ..." if len(outside) > 5 else "")
            notes.append(f"{source}: {len(outside):,} plant(s) stand outside the field: "
                         f"{shown}")
    zmin = float(min(leaf_v[:, 2].min(), stalk_v[:, 2].min() if len(stalk_v) else np.inf))
    if zmin < -1.0 or zmin > 100.0:
        notes.append(f"{source}: the mesh's lowest point is at z = {zmin:.1f} cm; the ground is "
                     "z = 0 (sensor heights count from it)")
    x0, y0, x1, y1 = field
    cells = np.array([field], np.float64)
    period = _period_in(period, field, source, notes)
    field_said = f"the field is {fsrc}: x {x0:.1f}..{x1:.1f}, y {y0:.1f}..{y1:.1f} cm"
    if period is not None:
        px0, py0, px1, py1 = period
        field_said += (f", repeating every {px1 - px0:.1f} x {py1 - py0:.1f} cm in a periodic field "
                 "(the file's period; its block is the default sample rectangle)")
    layout = CanopyLayout(placements, cells, x1 - x0, y1 - y0, 0.0,
                          np.array([period], np.float64) if period else cells.copy(),
                          (field_said,), (x1 - x0) * (y1 - y0), "mesh", period)
    canopy = Canopy(leaf_v, leaf_f, leaf_inst,
                    mesh.plant if n_leaf == len(is_leaf) else mesh.plant[is_leaf], leaf_ids,
                    layout, MESH_LEVEL, stalk_v, stalk_f, leaves_per,
                    stalk_instance=stalk_inst)
    return canopy, notes


def read_mesh_canopy(path: str | Path, unit: str | None = None, up: str = "z",
                     field: tuple[float, float, float, float] | None = None,
                     plant_property: str | None = None,
                     leaf_property: str | None = None) -> tuple[Canopy, MeshData, list[str]]:
    """Read a mesh file as a canopy.

    The file's triangles with plant and leaf ids (:func:`maizeviz.io.mesh_canopy.read_mesh`)
    become a canopy (:func:`canopy_from_mesh`).

    Parameters
    ----------
    path : str or Path
        A PLY or OBJ file with plant and leaf ids.
    unit : {"m", "cm", "mm"}, optional
        The file's length unit; None: cm, refusing a height that suggests another unit.
    up : {"z", "y"}
        The file's up axis.
    field : (x0, y0, x1, y1) tuple of float, optional
        The plot [cm]; None: the mesh's bounding box seen from above.
    plant_property, leaf_property : str, optional
        Names of the per-face plant and leaf id properties, where not the usual ones.

    Returns
    -------
    canopy : Canopy
        The canopy of the mesh's triangles.
    mesh : MeshData
        The file's mesh as read.
    notes : list of str
        What was decided (one line each).
    """
    from maizeviz.io.mesh_canopy import read_mesh  # the parsers (plyfile): when a mesh is read

    mesh = read_mesh(path, plant_property, leaf_property)
    canopy, notes = canopy_from_mesh(mesh, unit, up, field, str(path))
    return canopy, mesh, notes
