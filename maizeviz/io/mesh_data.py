"""What a mesh file read as a canopy holds, and the checks every mesh format shares.

The format readers (:mod:`maizeviz.io.mesh_ply`, :mod:`maizeviz.io.mesh_obj`) turn a file into
vertices, face vertex lists and ids; the checks here (finite vertices, faces of at least 3
vertices within range, whole ids within their range) and the fan triangulation of polygons are
the same for both, and every refusal is one line naming the file and the place.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.points import MAX_ID

#: File name endings read as meshes.
MESH_SUFFIXES = (".ply", ".obj")
#: Largest text mesh (OBJ, ascii PLY) read, bytes: about 10 million triangles.
MAX_TEXT_BYTES = 512 * 2**20
#: Largest binary PLY read, bytes: about 100 million triangles.
MAX_BINARY_BYTES = 2 * 2**30
#: A PLY header must end within this many bytes.
MAX_HEADER_BYTES = 2**20
#: Face property names read as the plant id, in order of preference (any case).
PLANT_PROPERTIES = ("plant", "plant_id", "plantid")
#: Face property names read as the leaf id, in order of preference (any case).
LEAF_PROPERTIES = ("leaf", "leaf_id", "leafid", "organ", "organ_id", "label", "object_label")
#: Largest leaf id, as in points files; 0 is not a leaf.
MAX_LEAF_ID = MAX_ID
#: Largest plant id (absolute value), as in points files.
MAX_PLANT_ID = MAX_ID
#: Most vertices of one polygon face.
MAX_POLYGON = 100_000
#: Longest value in a text mesh (characters): a double needs 24.
MAX_VALUE_CHARS = 100
#: What maizeviz's own exports carry besides the triangles, as ``maizeviz <key> <values>``
#: comments (PLY ``comment``, OBJ ``#``) or VTK field data arrays of the same name: the plot
#: (x0, y0, x1, y1 cm) and, for a periodic field, the smallest rectangle it repeats.
CARRIED = ("field_cm", "period_cm")
#: The word starting a carried comment.
CARRIED_TAG = "maizeviz"


class MeshFileError(MaizevizError):
    """A mesh file that cannot be read; the message names the file and the place."""


@dataclass(frozen=True)
class MeshData:
    """The triangles of a mesh file, values as the file holds them.

    Attributes
    ----------
    vertices : (V, 3) float64, the file's units and axes
    faces : (T, 3) int64, triangles (polygons fan-triangulated), indices into ``vertices``
    triangle_face : (T,) int64, the file face (counting from 0) each triangle comes from
    plant, leaf : (T,) int64, the ids of each triangle's face
    kind : the format in words ("PLY binary little endian", "OBJ")
    ids : where the ids came from, in words
    file_faces : faces in the file; polygons : those with more than 3 vertices
    notes : what the reader decided (defaults taken, names numbered), one line each
    vertex_lines, face_lines : line number of each vertex and file face (text formats), or None
    carried : {key: (where, text)} for each :data:`CARRIED` comment the file holds, the text
        after the key ("0 0 540 270") and where it is ("header line 3")
    """

    vertices: np.ndarray
    faces: np.ndarray
    triangle_face: np.ndarray
    plant: np.ndarray
    leaf: np.ndarray
    kind: str
    ids: str
    file_faces: int
    polygons: int
    notes: tuple[str, ...] = ()
    vertex_lines: np.ndarray | None = None
    face_lines: np.ndarray | None = None
    carried: dict[str, tuple[str, str]] = field(default_factory=dict)

    @property
    def n_triangles(self) -> int:
        return len(self.faces)

    def where_vertex(self, i: int) -> str:
        """``"vertex 12 (line 25)"``: where vertex ``i`` is in the file."""
        line = f", line {int(self.vertex_lines[i])}" if self.vertex_lines is not None else ""
        return f"vertex {i} (counting from 0{line})"

    def where_triangle(self, t: int) -> str:
        """Where the face triangle ``t`` comes from is in the file."""
        f = int(self.triangle_face[t])
        line = f", line {int(self.face_lines[f])}" if self.face_lines is not None else ""
        return f"face {f} (counting from 0{line})"


def carried_comments(comments: list[tuple[str, str]]) -> dict[str, tuple[str, str]]:
    """The :data:`CARRIED` values among comments ``(where, text)``: ``maizeviz field_cm 0 0 9
    9`` gives ``{"field_cm": (where, "0 0 9 9")}`` (the first of each key)."""
    out: dict[str, tuple[str, str]] = {}
    for where, text in comments:
        words = text.split(None, 2)
        if len(words) >= 2 and words[0] == CARRIED_TAG and words[1] in CARRIED:
            out.setdefault(words[1], (where, words[2] if len(words) > 2 else ""))
    return out


def carried_lines(field: tuple[float, ...] | None,
                  period: tuple[float, ...] | None) -> list[str]:
    """The comment texts carrying a plot and a period (see :data:`CARRIED`), each value
    written so that it reads back as the same float64."""
    return [f"{CARRIED_TAG} {key} " + " ".join(repr(float(v)) for v in rect)
            for key, rect in zip(CARRIED, (field, period)) if rect is not None]


def check_finite(vertices: np.ndarray, src: str, lines: np.ndarray | None) -> None:
    """Refuse the first vertex with a coordinate that is NaN or infinite."""
    with np.errstate(over="ignore", invalid="ignore"):
        if np.isfinite(np.add.reduce(vertices, axis=None)):     # one pass when all are
            return
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if len(bad):
        i = int(bad[0])
        axis = int(np.flatnonzero(~np.isfinite(vertices[i]))[0])
        line = f", line {int(lines[i])}" if lines is not None else ""
        raise MeshFileError(f"{src}: vertex {i} (counting from 0{line}): {'xyz'[axis]} is "
                            f"{vertices[i, axis]}, not a finite number")


def fan(length: np.ndarray, flat: np.ndarray, n_vertices: int, at: Callable[[int], str],
        src: str, base: int = 0) -> tuple[np.ndarray, np.ndarray, int]:
    """Triangles (T, 3) int64, the face of each (T,) int64 and the number of polygons, from
    face vertex lists (``length`` (n,), ``flat`` indices from 0, flat or (n, k) when every face
    has k vertices); refuses short faces and indices out of range, said as the file counts
    them (``base``: 1 for OBJ); ``at(i)`` says where face ``i`` is."""
    short = np.flatnonzero(length < 3)
    if len(short):
        i = int(short[0])
        raise MeshFileError(f"{src}: {at(i)} has {int(length[i])} vertices; a face needs at "
                            "least 3")
    big = np.flatnonzero(length > MAX_POLYGON)
    if len(big):
        i = int(big[0])
        raise MeshFileError(f"{src}: {at(i)} has {int(length[i]):,} vertices, more than "
                            f"{MAX_POLYGON:,}")
    n = len(length)
    if n and int(length.min()) == int(length.max()) == 3:       # triangles: no fan to cut
        flat = flat.reshape(n, 3).astype(np.int64, copy=False)
    if flat.size and (flat.min() < 0 or flat.max() >= n_vertices):
        k = int(np.flatnonzero((flat < 0) | (flat >= n_vertices))[0])
        i = int(np.searchsorted(np.cumsum(length), k, "right"))
        span = f"{base} to {n_vertices - 1 + base}" if n_vertices else "none"
        raise MeshFileError(f"{src}: {at(i)}: vertex index {int(np.ravel(flat)[k]) + base} is out of "
                            f"range: the file has {n_vertices:,} vertices ({span})")
    if flat.ndim == 2 and flat.shape[1] == 3:
        return flat, np.arange(n, dtype=np.int64), 0
    flat = flat.reshape(-1)
    offs = np.cumsum(length) - length
    tris = length - 2
    n_tri = int(tris.sum())
    face_of = np.repeat(np.arange(n, dtype=np.int64), tris)
    k = np.arange(n_tri, dtype=np.int64) - np.repeat(np.cumsum(tris) - tris, tris) + 1
    first = offs[face_of]
    faces = np.column_stack([flat[first], flat[first + k], flat[first + k + 1]])
    return faces.astype(np.int64), face_of, int((length > 3).sum())


def shown_number(x: float) -> str:
    """A value for a message: whole numbers written out (2147483648, not 2.14748e+09)."""
    x = float(x)
    return f"{int(x)}" if math.isfinite(x) and x == round(x) and abs(x) < 1e18 else f"{x:g}"


def whole_ids(v: np.ndarray, name: str, what: str, low: int, high: int,
              at: Callable[[int], str], src: str) -> np.ndarray:
    """Ids ``v`` (n,) as int64, refusing the first that is not whole or outside [low, high]
    (``what``: "plant" or "leaf"; ``name`` the property or column holding it)."""
    v = np.asarray(v)
    if v.dtype.kind in "iu":
        v = v.astype(np.int64)                          # contiguous: the checks run faster
    if v.dtype.kind == "f":
        with np.errstate(invalid="ignore"):
            bad = np.flatnonzero(~(v == np.round(v)))
        if len(bad):
            i = int(bad[0])
            raise MeshFileError(f"{src}: {at(i)}: the {what} id ('{name}') is "
                                f"{shown_number(v[i])}, not a whole number")
    if len(v) and (v.min() < low or v.max() > high):
        i = int(np.flatnonzero((v < low) | (v > high))[0])
        rule = "0 (not a leaf: a stalk) to" if what == "leaf" else f"{low:,} to"
        raise MeshFileError(f"{src}: {at(i)}: the {what} id ('{name}') is "
                            f"{shown_number(v[i])}; {what} ids go from {rule} {high:,}")
    return v.astype(np.int64)


def pick_property(props: dict[str, str], asked: str | None, names: tuple[str, ...],
                  found: str, src: str, what: str) -> str | None:
    """The face property holding the ``what`` id: ``asked`` (any case; refused when absent),
    else the first of ``names`` present; ``props`` maps lower-case names to the file's,
    ``found`` lists the file's face properties for messages."""
    if asked:
        if asked.lower() not in props:
            raise MeshFileError(f"{src}: no face property '{asked}' for the {what} id (face "
                                f"properties: {found})", quantity="mesh_ids")
        return props[asked.lower()]
    return next((props[n] for n in names if n in props), None)


def ids_of_faces(scalars: dict[str, np.ndarray], n_faces: int, plant_property: str | None,
                 leaf_property: str | None, at: Callable[[int], str],
                 src: str) -> tuple[np.ndarray, np.ndarray, str, list[str]]:
    """Plant and leaf id of each face (n,) int64 from the faces' scalar properties (by the
    file's names), where they came from in words, and the notes on defaults taken."""
    props = {name.lower(): name for name in scalars}
    found = ", ".join(scalars) or "none"
    plant_name = pick_property(props, plant_property, PLANT_PROPERTIES, found, src, "plant")
    leaf_name = pick_property(props, leaf_property, LEAF_PROPERTIES, found, src, "leaf")
    if plant_name is None and leaf_name is None:
        raise MeshFileError(
            f"{src}: the faces carry no plant or leaf id (face properties: {found}); name "
            f"them {' or '.join(LEAF_PROPERTIES[:2])} for the leaf and plant or plant_id for "
            "the plant, or say which property holds them", quantity="mesh_ids")
    notes = []
    if plant_name is not None:
        plant = whole_ids(scalars[plant_name], plant_name, "plant", -MAX_PLANT_ID,
                          MAX_PLANT_ID, at, src)
    else:
        plant = np.ones(n_faces, np.int64)
        notes.append(f"{src}: no plant id on the faces: all of them are plant 1")
    if leaf_name is not None:
        leaf = whole_ids(scalars[leaf_name], leaf_name, "leaf", 0, MAX_LEAF_ID, at, src)
    else:
        leaf = np.ones(n_faces, np.int64)
        notes.append(f"{src}: no leaf id on the faces: each plant is one leaf (leaf 1)")
    ids = " and ".join(f"face property '{n}'" for n in (plant_name, leaf_name) if n)
    return plant, leaf, ids, notes
