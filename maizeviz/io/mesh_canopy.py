"""Read plant meshes made elsewhere (OpenAlea/PlantGL, Helios, 3D scans): PLY and OBJ triangles
with a plant and a leaf id per face.

This module only parses: it returns the file's vertices (its own units and axes), its faces
fan-triangulated, and a plant and a leaf id per triangle, every value exactly as the file
holds it (binary floats widened to float64, text numbers read as float64). Turning them into a
canopy (units, up axis, stalks, field) is :mod:`maizeviz.canopy.from_mesh`'s job.

**PLY** (ascii, binary little and big endian). The ``vertex`` element needs ``x, y, z``; the
``face`` element a list property ``vertex_indices`` (or ``vertex_index``) of at least 3
vertices (polygons are cut into triangles as a fan from their first vertex) and integer face
properties naming the plant and the leaf, found by name whatever their case:

- plant: :data:`PLANT_PROPERTIES` (``plant``, ``plant_id``, ``plantid``);
- leaf: :data:`LEAF_PROPERTIES` (``leaf``, ``leaf_id``, ``leafid``, ``organ``, ``organ_id``,
  ``label``, ``object_label``), the first one present in that order.

A file with a leaf id but no plant id is one plant (plant 1); with a plant id but no leaf id,
each plant is one leaf (leaf 1); with neither, it is refused (the message lists the face
properties the file has, so the right one can be named). Other elements and properties are
read past and ignored.

**OBJ**. ``v`` (x y z, then any colour or weight ignored), ``f`` with ``v``, ``v/vt``,
``v//vn`` or ``v/vt/vn`` vertices, negative (relative) indices, polygons fan-triangulated;
``o`` and ``g`` name the faces that follow (a ``g`` after an ``o`` gives ``o-name/g-name``).
A name gives the ids: ``plant3_leaf7``, ``plant3/leaf7``, ``p3_l7``, ``P03 L07``,
``plant3leaf7`` (plant 3, leaf 7); ``leaf7`` or ``l7`` (plant 1, leaf 7); ``plant3_stalk`` or
``plant3_stem`` (leaf 0); any other name is a leaf of its plant (plant 1 unless the name starts
with a plant number, ``plant3_blade``), numbered after the plant's numbered leaves in the order
the names first appear. Faces before any ``o``/``g`` in a file that has names are refused;
a file without names is refused like a PLY without ids. ``vt``, ``vn``, ``s``, ``usemtl``,
``mtllib``, ``l`` and ``p`` are read past; free-form geometry (``curv``, ``surf``...) is
refused.

**Ids**: leaf ids from 0 to :data:`MAX_LEAF_ID` (0 is a stalk or another organ that is not a
leaf, as maizeviz's own exports write stalks), plant ids up to :data:`MAX_PLANT_ID` in size.

**Refused with one line naming the file and the place** (line for text, face or vertex number
counting from 0 for binary): an empty file, a broken header, counts the file cannot hold
(checked against the file's size before anything is allocated, so a header declaring 10^12
faces is refused at once), a truncated body, more data than declared, a value that is not a
number, a vertex coordinate that is NaN or infinite, a face of fewer than 3 vertices, a vertex
index out of range, an id that is not a whole number or out of range, text that is not UTF-8
(OBJ) or ASCII (PLY header and ascii body), a file larger than :data:`MAX_TEXT_BYTES` (text)
or :data:`MAX_BINARY_BYTES` (binary PLY).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.inputs import open_input
from maizeviz.io.points import MAX_ID
from maizeviz.numbers import first_unplain, number, whole

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
#: Longest value in an ascii PLY (characters): a double needs 24.
MAX_VALUE_CHARS = 100

_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
              "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
              "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
              "float64": "f8"}
_FORMATS = {"ascii": "", "binary_little_endian": "<", "binary_big_endian": ">"}
_INDEX_NAMES = ("vertex_indices", "vertex_index")


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


def is_mesh_path(path: str | Path) -> bool:
    """Whether ``path`` names a mesh file by its ending (.ply, .obj, any case)."""
    return Path(path).suffix.lower() in MESH_SUFFIXES


def read_mesh(path: str | Path, plant_property: str | None = None,
              leaf_property: str | None = None) -> MeshData:
    """Read a PLY or OBJ mesh with a plant and a leaf id per face (see the module's text).

    Parameters
    ----------
    path : .ply or .obj
    plant_property, leaf_property : PLY face properties to read the ids from instead of the
        usual names (:data:`PLANT_PROPERTIES`, :data:`LEAF_PROPERTIES`); OBJ files take their
        ids from group names and refuse these

    Raises
    ------
    MeshFileError
        One line naming the file and what is wrong where.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in MESH_SUFFIXES:
        raise MeshFileError(f"{path}: not a mesh file by its name ('{ext or '(none)'}'); "
                            f"use {' or '.join(MESH_SUFFIXES)}")
    fh, size = open_input(path, "mesh file", MeshFileError)
    with fh:
        if size == 0:
            raise MeshFileError(f"{path}: the file is empty; no mesh in it")
        try:
            if ext == ".ply":
                return _read_ply(fh, size, str(path), plant_property, leaf_property)
            if plant_property or leaf_property:
                raise MeshFileError(f"{path}: an OBJ file takes its ids from its o/g names; "
                                    "face properties are for PLY files", quantity="mesh_ids")
            if size > MAX_TEXT_BYTES:
                raise MeshFileError(f"{path}: {size:,} bytes, more than the "
                                    f"{MAX_TEXT_BYTES // 2**20} MiB limit for a text mesh")
            return _read_obj(fh.read(), str(path))
        except OSError as exc:
            raise MeshFileError(f"{path}: cannot be read ({exc.strerror or exc})") from None
        except MemoryError:
            raise MeshFileError(f"{path}: not enough memory to read this mesh") from None


# ------------------------------------------------------------------------------ PLY
@dataclass
class _Prop:
    name: str
    code: str                      # numpy type code without byte order: "f4", "u1"...
    count_code: str | None = None  # list properties: the type of the count

    @property
    def is_list(self) -> bool:
        return self.count_code is not None


@dataclass
class _Element:
    name: str
    count: int
    line: int
    props: list[_Prop]


@dataclass
class _Values:
    """An element's values: scalars by property name, lists as (lengths, flat values)."""

    scalars: dict[str, np.ndarray]
    lists: dict[str, tuple[np.ndarray, np.ndarray]]
    lines: np.ndarray | None      # line number of each item (ascii)


def _find_end_header(head: bytes) -> int | None:
    m = re.search(rb"(?:^|\n)end_header[ \t]*\r?\n", head)
    return m.end() if m else None


def _read_ply(fh, size: int, src: str, plant_property: str | None,
              leaf_property: str | None) -> MeshData:
    head = fh.read(min(size, MAX_HEADER_BYTES))
    if not head.startswith(b"ply") or head[3:4] not in (b"\n", b"\r"):
        raise MeshFileError(f"{src}: not a PLY file (it does not start with a 'ply' line)")
    end = _find_end_header(head)
    if end is None:
        within = "the file" if size <= MAX_HEADER_BYTES else \
            f"the first {MAX_HEADER_BYTES // 2**20} MiB"
        raise MeshFileError(f"{src}: no 'end_header' line in {within}: the PLY header is "
                            "broken or the file is cut short")
    fmt, elements, header_lines = _ply_header(head[:end], src)
    binary = fmt != ""
    limit = MAX_BINARY_BYTES if binary else MAX_TEXT_BYTES
    if size > limit:
        raise MeshFileError(f"{src}: {size:,} bytes, more than the {limit // 2**20} MiB limit "
                            f"for {'a binary' if binary else 'an ascii'} PLY")
    _check_counts(elements, size - end, binary, src)
    body = head[end:] + fh.read(size - len(head))
    if binary:
        values = _ply_binary(body, elements, fmt, src)
        kind = "PLY binary " + ("little" if fmt == "<" else "big") + " endian"
    else:
        values = _ply_ascii(body, elements, header_lines, src)
        kind = "PLY ascii"
    return _ply_mesh(elements, values, src, kind, plant_property, leaf_property)


def _ply_header(head: bytes, src: str) -> tuple[str, list[_Element], int]:
    """Format ("" ascii, "<" or ">"), elements, and the number of header lines."""
    lines = head.split(b"\n")
    if lines and lines[-1] == b"":
        lines.pop()
    fmt: str | None = None
    elements: list[_Element] = []
    for no, raw in enumerate(lines, 1):
        try:
            text = raw.decode("ascii").strip()
        except UnicodeDecodeError:
            raise MeshFileError(f"{src}: header line {no} is not ASCII text; not a PLY "
                                "header") from None
        words = text.split()
        if no == 1 or not words or words[0] in ("comment", "obj_info"):
            continue
        where = f"{src}: header line {no}"
        key = words[0]
        if key == "format":
            fmt = _ply_format(words, text, where)
        elif key == "element":
            if len(words) != 3 or not (words[2].isascii() and words[2].isdigit()):
                raise MeshFileError(f"{where}: '{text[:60]}': an element needs a name and a "
                                    "count (a whole number >= 0)")
            if any(e.name == words[1] for e in elements):
                raise MeshFileError(f"{where}: element '{words[1][:40]}' declared twice")
            elements.append(_Element(words[1], int(words[2]), no, []))
        elif key == "property":
            _ply_property(words, text, where, elements)
        elif key == "end_header":
            break
        else:
            raise MeshFileError(f"{where}: '{text[:60]}' is not a PLY header line")
    if fmt is None:
        raise MeshFileError(f"{src}: the PLY header has no format line")
    _check_ply_elements(elements, src)
    return fmt, elements, len(lines)


def _ply_format(words: list[str], text: str, where: str) -> str:
    """The byte order of a ``format`` line ("" ascii, "<" or ">"), version 1.0."""
    if len(words) != 3 or words[1] not in _FORMATS:
        raise MeshFileError(f"{where}: '{text[:60]}': the format must be ascii, "
                            "binary_little_endian or binary_big_endian")
    if words[2] not in ("1.0", "1"):
        raise MeshFileError(f"{where}: PLY version {words[2][:20]}, only 1.0 is known")
    return _FORMATS[words[1]]


def _ply_property(words: list[str], text: str, where: str, elements: list[_Element]) -> None:
    """A ``property`` line added to the last element: a scalar or a list of a known type,
    not declared twice."""
    if not elements:
        raise MeshFileError(f"{where}: a property before any element")
    el = elements[-1]
    if len(words) == 3 and words[1] in _PLY_TYPES:
        prop = _Prop(words[2], _PLY_TYPES[words[1]])
    elif len(words) == 5 and words[1] == "list" and words[2] in _PLY_TYPES \
            and words[3] in _PLY_TYPES:
        if _PLY_TYPES[words[2]][0] == "f":
            raise MeshFileError(f"{where}: a list count must be of an integer type, "
                                f"got {words[2]}")
        prop = _Prop(words[4], _PLY_TYPES[words[3]], _PLY_TYPES[words[2]])
    else:
        raise MeshFileError(f"{where}: '{text[:60]}': not a property of a known type "
                            f"({', '.join(sorted(set(_PLY_TYPES)))})")
    if any(p.name == prop.name for p in el.props):
        raise MeshFileError(f"{where}: property '{prop.name[:40]}' declared twice in "
                            f"element {el.name[:40]}")
    el.props.append(prop)


def _check_ply_elements(elements: list[_Element], src: str) -> None:
    """A vertex element with x, y and z, and a face element with its vertex indices."""
    vertex = next((e for e in elements if e.name == "vertex"), None)
    face = next((e for e in elements if e.name == "face"), None)
    if vertex is None:
        raise MeshFileError(f"{src}: the PLY header declares no vertex element")
    names = {p.name: p for p in vertex.props}
    for axis in "xyz":
        if axis not in names or names[axis].is_list:
            raise MeshFileError(f"{src}: header line {vertex.line}: the vertex element has no "
                                f"'{axis}' property")
    if face is None:
        raise MeshFileError(f"{src}: the PLY header declares no face element: points only, "
                            "no surface to trace")
    if _index_prop(face) is None:
        raise MeshFileError(f"{src}: header line {face.line}: the face element has no "
                            "'vertex_indices' list")


def _index_prop(face: _Element) -> _Prop | None:
    for name in _INDEX_NAMES:
        p = next((p for p in face.props if p.name == name and p.is_list), None)
        if p is not None:
            return p
    lists = [p for p in face.props if p.is_list]
    return lists[0] if len(lists) == 1 else None


def _min_entries(el: _Element, p: _Prop) -> int:
    """Fewest entries a list property can hold: 3 for the faces' vertices, else 0."""
    return 3 if el.name == "face" and p is _index_prop(el) else 0


def _check_counts(elements: list[_Element], remaining: int, binary: bool, src: str) -> None:
    """Refuse counts the rest of the file cannot hold, before allocating anything."""
    need = 0
    for el in elements:
        if binary:
            per = sum(np.dtype(p.count_code).itemsize + _min_entries(el, p)
                      * np.dtype(p.code).itemsize if p.is_list else np.dtype(p.code).itemsize
                      for p in el.props)
        else:                                 # a value is at least a character and a space
            per = 2 * sum(1 + _min_entries(el, p) if p.is_list else 1 for p in el.props)
        need += el.count * per
        if need > remaining + (0 if binary else 1):      # the last value needs no space
            raise MeshFileError(
                f"{src}: the header declares {el.count:,} {el.name} items, which take at least "
                f"{need:,} bytes with those before them, but only {remaining:,} bytes follow "
                "the header: the file is cut short or its header is wrong")


def _ply_binary(body: bytes, elements: list[_Element], order: str, src: str) -> list[_Values]:
    out = []
    pos = 0
    for el in elements:
        vals, pos = _binary_element(body, pos, el, order, src)
        out.append(vals)
    rest = body[pos:]
    if rest.strip(b" \t\r\n"):
        raise MeshFileError(f"{src}: {len(rest):,} bytes follow the last element the header "
                            "declares: the counts in the header do not match the data")
    return out


def _binary_element(body: bytes, pos: int, el: _Element, order: str,
                    src: str) -> tuple[_Values, int]:
    n = el.count
    left = len(body) - pos
    if not any(p.is_list for p in el.props) or n == 0:
        dt = np.dtype([(f"p{i}", order + p.code) for i, p in enumerate(el.props)]) \
            if not any(p.is_list for p in el.props) else np.dtype([])
        if n and dt.itemsize * n > left:
            raise MeshFileError(f"{src}: the file is cut short: it ends within {el.name} "
                                f"{left // max(dt.itemsize, 1):,} (counting from 0) of the "
                                f"{n:,} the header declares")
        arr = np.frombuffer(body, dt, n, pos) if n and dt.itemsize else None
        scalars = {p.name: (arr[f"p{i}"] if arr is not None else np.zeros(0, order + p.code))
                   for i, p in enumerate(el.props) if not p.is_list}
        lists = {p.name: (np.zeros(0, np.int64), np.zeros(0, order + p.code))
                 for p in el.props if p.is_list}
        return _Values(scalars, lists, None), pos + dt.itemsize * n
    # lists: assume every item has the first item's list lengths; check, else walk
    lengths = []
    at = pos
    for p in el.props:
        if p.is_list:
            cdt = np.dtype(order + str(p.count_code))
            if at + cdt.itemsize > len(body):
                raise MeshFileError(f"{src}: the file is cut short: it ends within {el.name} 0")
            c = int(np.frombuffer(body, cdt, 1, at)[0])
            lengths.append(c)
            at += cdt.itemsize + c * np.dtype(p.code).itemsize
        else:
            at += np.dtype(p.code).itemsize
    fields: list[tuple] = []
    k = 0
    for i, p in enumerate(el.props):
        if p.is_list:
            fields.append((f"c{i}", order + str(p.count_code)))
            if lengths[k] > 0:
                fields.append((f"p{i}", order + p.code, (lengths[k],)))
            k += 1
        else:
            fields.append((f"p{i}", order + p.code))
    dt = np.dtype(fields)
    if dt.itemsize * n <= left:
        arr = np.frombuffer(body, dt, n, pos)
        list_at = [i for i, p in enumerate(el.props) if p.is_list]
        if all(np.all(arr[f"c{i}"] == c) for i, c in zip(list_at, lengths)):
            scalars = {p.name: arr[f"p{i}"] for i, p in enumerate(el.props) if not p.is_list}
            lists = {}
            j = 0
            for i, p in enumerate(el.props):
                if p.is_list:
                    c = lengths[j]
                    j += 1
                    flat = arr[f"p{i}"].reshape(-1) if c > 0 else np.zeros(0, order + p.code)
                    lists[p.name] = (np.full(n, c, np.int64), flat)
            return _Values(scalars, lists, None), pos + dt.itemsize * n
    return _binary_walk(body, pos, el, order, src)


def _binary_walk(body: bytes, pos: int, el: _Element, order: str,
                 src: str) -> tuple[_Values, int]:
    """An element whose list lengths vary: item by item."""
    n = el.count
    size = len(body)
    scal = {p.name: np.empty(n, order + p.code) for p in el.props if not p.is_list}
    lens = {p.name: np.empty(n, np.int64) for p in el.props if p.is_list}
    chunks: dict[str, list[np.ndarray]] = {p.name: [] for p in el.props if p.is_list}
    plan = [(p, np.dtype(order + p.code), np.dtype(order + str(p.count_code))
             if p.is_list else None) for p in el.props]
    for item in range(n):
        for p, dt, cdt in plan:
            if cdt is None:
                if pos + dt.itemsize > size:
                    raise _cut(src, el, item)
                scal[p.name][item] = np.frombuffer(body, dt, 1, pos)[0]
                pos += dt.itemsize
            else:
                if pos + cdt.itemsize > size:
                    raise _cut(src, el, item)
                c = int(np.frombuffer(body, cdt, 1, pos)[0])
                pos += cdt.itemsize
                if c < 0:
                    raise MeshFileError(f"{src}: {el.name} {item} (counting from 0): a list of "
                                        f"{c} entries")
                if pos + c * dt.itemsize > size:
                    raise _cut(src, el, item)
                lens[p.name][item] = c
                chunks[p.name].append(np.frombuffer(body, dt, c, pos))
                pos += c * dt.itemsize
    lists = {k: (lens[k], np.concatenate(v) if v else np.zeros(0)) for k, v in chunks.items()}
    return _Values(scal, lists, None), pos


def _cut(src: str, el: _Element, item: int) -> MeshFileError:
    return MeshFileError(f"{src}: the file is cut short: it ends within {el.name} {item:,} "
                         f"(counting from 0) of the {el.count:,} the header declares")


def _ply_ascii(body: bytes, elements: list[_Element], header_lines: int,
               src: str) -> list[_Values]:
    lines = body.split(b"\n")
    filled = [i for i, ln in enumerate(lines) if ln.strip()]
    out = []
    at = 0
    for el in elements:
        take = filled[at:at + el.count]
        if len(take) < el.count:
            last = header_lines + (filled[-1] + 1 if filled else 0)
            raise MeshFileError(f"{src}: the file is cut short: the header declares "
                                f"{el.count:,} {el.name} items but the file ends after "
                                f"{len(take):,} of them (line {last})")
        numbers = np.array(take, np.int64) + header_lines + 1
        out.append(_ascii_element([lines[i] for i in take], numbers, el, src))
        at += el.count
    if at < len(filled):
        raise MeshFileError(f"{src}: line {header_lines + filled[at] + 1}: more lines than the "
                            "header declares: the counts in the header do not match the data")
    return out


def _numbers(tokens: list[bytes], counts: np.ndarray, line_no: np.ndarray, src: str) -> np.ndarray:
    """Tokens as float64; the first one that is not a number is named with its line."""
    longest = max(map(len, tokens), default=0)
    if longest > MAX_VALUE_CHARS:
        k = next(i for i, t in enumerate(tokens) if len(t) == longest)
        line = int(line_no[int(np.searchsorted(np.cumsum(counts), k, "right"))])
        raise MeshFileError(f"{src}: line {line}: a value of {longest:,} characters; a number "
                            f"has at most {MAX_VALUE_CHARS}")
    try:
        if first_unplain(tokens) is None:        # numpy reads 1_000 as float does
            return np.array(tokens, dtype=bytes).astype(np.float64) if tokens else np.zeros(0)
    except (ValueError, OverflowError):
        pass
    ends = np.cumsum(counts)
    for k, tok in enumerate(tokens):
        try:
            number(tok)
        except ValueError:
            line = int(line_no[int(np.searchsorted(ends, k, "right"))])
            shown = tok[:30].decode("ascii", "backslashreplace")
            raise MeshFileError(f"{src}: line {line}: '{shown}' is not a number") from None
    raise MeshFileError(f"{src}: a value is not a number")            # pragma: no cover


_Lists = dict[str, tuple[np.ndarray, np.ndarray]]


def _ascii_element(lines: list[bytes], line_no: np.ndarray, el: _Element, src: str) -> _Values:
    n = len(lines)
    split = [ln.split() for ln in lines]
    counts = np.fromiter((len(s) for s in split), np.int64, n)
    tokens = [t for s in split for t in s]
    vals = _numbers(tokens, counts, line_no, src)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    n_list = sum(p.is_list for p in el.props)
    lists: _Lists = {}
    if n_list == 0:
        scalars = _ascii_scalars(vals, counts, starts, line_no, el, src)
    elif n_list == 1:
        scalars, lists = _ascii_one_list(vals, counts, starts, line_no, el, src)
    else:
        scalars, lists = _ascii_lists(vals, counts, starts, line_no, el, src)
    return _Values(scalars, lists, line_no)



def _ascii_scalars(vals: np.ndarray, counts: np.ndarray, starts: np.ndarray,
                   line_no: np.ndarray, el: _Element, src: str) -> dict[str, np.ndarray]:
    """An ASCII element of scalar properties only: every line holds one value each."""
    props = el.props
    bad = np.flatnonzero(counts != len(props))
    if len(bad):
        i = int(bad[0])
        raise MeshFileError(f"{src}: line {int(line_no[i])}: {el.name} {i} has "
                            f"{int(counts[i])} values, the header declares {len(props)}")
    return {p.name: _typed(vals[starts + j], p.code, el, p.name, line_no, src)
            for j, p in enumerate(props)}


def _ascii_one_list(vals: np.ndarray, counts: np.ndarray, starts: np.ndarray,
                    line_no: np.ndarray, el: _Element, src: str
                    ) -> tuple[dict[str, np.ndarray], _Lists]:
    """An ASCII element with one list property (a face's vertex indices), read whole."""
    props = el.props
    n = len(counts)
    scalars: dict[str, np.ndarray] = {}
    pos = next(j for j, p in enumerate(props) if p.is_list)
    lp = props[pos]
    fixed = len(props) - 1
    if n and np.any(counts <= pos):
        i = int(np.flatnonzero(counts <= pos)[0])
        raise MeshFileError(f"{src}: line {int(line_no[i])}: {el.name} {i} has "
                            f"{int(counts[i])} values, too few for its properties")
    length = _typed(vals[starts + pos], lp.count_code or "u4", el, f"{lp.name} count",
                    line_no, src).astype(np.int64) if n else np.zeros(0, np.int64)
    bad = np.flatnonzero(counts != fixed + 1 + length)
    if len(bad):
        i = int(bad[0])
        raise MeshFileError(f"{src}: line {int(line_no[i])}: {el.name} {i} has "
                            f"{int(counts[i])} values; its list of {int(length[i])} and "
                            f"{fixed} other properties make {fixed + 1 + int(length[i])}")
    first = starts + pos + 1
    total = int(length.sum())
    ends = np.cumsum(length)
    take = np.repeat(first - (ends - length), length) + np.arange(total)
    lists = {lp.name: (length, _typed(vals[take], lp.code, el, lp.name, line_no, src,
                                      np.repeat(np.arange(n), length)))}
    for j, p in enumerate(props):
        if j < pos:
            scalars[p.name] = _typed(vals[starts + j], p.code, el, p.name, line_no, src)
        elif j > pos:
            scalars[p.name] = _typed(vals[first + length + (j - pos - 1)], p.code, el,
                                     p.name, line_no, src)
    return scalars, lists


def _ascii_lists(vals: np.ndarray, counts: np.ndarray, starts: np.ndarray,
                 line_no: np.ndarray, el: _Element, src: str
                 ) -> tuple[dict[str, np.ndarray], _Lists]:
    """An ASCII element with several list properties, read line by line."""
    props = el.props
    scal_l: dict[str, list[float]] = {p.name: [] for p in props if not p.is_list}
    lens: dict[str, list[int]] = {p.name: [] for p in props if p.is_list}
    flat: dict[str, list[float]] = {p.name: [] for p in props if p.is_list}
    item_of: dict[str, list[int]] = {p.name: [] for p in props if p.is_list}
    for i in range(len(counts)):
        k, end = int(starts[i]), int(starts[i] + counts[i])
        for p in props:
            if k >= end:
                raise MeshFileError(f"{src}: line {int(line_no[i])}: {el.name} {i} has "
                                    "too few values for its properties")
            if p.is_list:
                c = _list_count(vals[k], k, end, i, line_no, el, src)
                lens[p.name].append(c)
                flat[p.name].extend(vals[k + 1:k + 1 + c].tolist())
                item_of[p.name].extend([i] * c)
                k += 1 + c
            else:
                scal_l[p.name].append(float(vals[k]))
                k += 1
        if k != end:
            raise MeshFileError(f"{src}: line {int(line_no[i])}: {el.name} {i} has "
                                f"{int(counts[i])} values, more than its properties take")
    scalars: dict[str, np.ndarray] = {}
    lists: _Lists = {}
    for p in props:                                 # in the header's order
        if p.is_list:
            lists[p.name] = (np.array(lens[p.name], np.int64),
                             _typed(np.array(flat[p.name], np.float64), p.code, el, p.name,
                                    line_no, src, np.array(item_of[p.name], np.int64)))
        else:
            scalars[p.name] = _typed(np.array(scal_l[p.name], np.float64), p.code, el,
                                     p.name, line_no, src)
    return scalars, lists


def _list_count(c: float, k: int, end: int, i: int, line_no: np.ndarray, el: _Element,
                src: str) -> int:
    """A list's count on line ``i``: a whole number >= 0 whose values fit the line."""
    if not (c >= 0 and float(c).is_integer()):
        raise MeshFileError(f"{src}: line {int(line_no[i])}: a list count of {c:g}")
    if k + 1 + int(c) > end:
        raise MeshFileError(f"{src}: line {int(line_no[i])}: {el.name} {i} has "
                            "too few values for its properties")
    return int(c)


def _typed(v: np.ndarray, code: str, el: _Element, name: str, line_no: np.ndarray, src: str,
           item: np.ndarray | None = None) -> np.ndarray:
    """Text values of an integer property checked whole and within their type; float
    properties stay float64 (the text's value, not rounded to float32)."""
    if code[0] == "f":
        return v
    info = np.iinfo(np.dtype(code))
    with np.errstate(invalid="ignore"):
        bad = np.flatnonzero(~((v == np.round(v)) & (v >= info.min) & (v <= info.max)))
    if len(bad):
        k = int(bad[0])
        i = int(item[k]) if item is not None else k
        kind = np.dtype(code).name
        why = (f"beyond the range of its type {kind} ({info.min:,} to {info.max:,})"
               if v[k] == np.round(v[k]) else f"not a whole number of type {kind}")
        raise MeshFileError(f"{src}: line {int(line_no[i])}: {el.name} {i}: {name} is "
                            f"{_number(v[k])}, {why}")
    return v.astype(np.int64)


def _number(x: float) -> str:
    """A value for a message: whole numbers written out (2147483648, not 2.14748e+09)."""
    x = float(x)
    return f"{int(x)}" if math.isfinite(x) and x == round(x) and abs(x) < 1e18 else f"{x:g}"


def _ply_mesh(elements: list[_Element], values: list[_Values], src: str, kind: str,
              plant_property: str | None, leaf_property: str | None) -> MeshData:
    by_name = {el.name: (el, v) for el, v in zip(elements, values)}
    vel, vv = by_name["vertex"]
    vertices = np.column_stack([np.asarray(vv.scalars[a], np.float64) for a in "xyz"]) \
        if vel.count else np.zeros((0, 3))
    _check_finite(vertices, src, vv.lines)
    fel, fv = by_name["face"]
    index = _index_prop(fel)
    assert index is not None
    if fel.count == 0:
        raise MeshFileError(f"{src}: the file has no faces (element face 0): no surface to "
                            "trace")
    length, flat = fv.lists[index.name]
    flat = np.asarray(flat)
    if flat.dtype.kind == "f":
        raise MeshFileError(f"{src}: the face vertex indices are of a float type; they must be "
                            "integers")
    lines = fv.lines

    def at(i: int) -> str:
        return f"face {i} (counting from 0{f', line {int(lines[i])}' if lines is not None else ''})"

    faces, tri_face, polygons = _fan(length, flat.astype(np.int64), len(vertices), at, src)
    # ids
    props = {p.name.lower(): p.name for p in fel.props if not p.is_list}
    plant_name = _pick(props, plant_property, PLANT_PROPERTIES, src, fel, "plant")
    leaf_name = _pick(props, leaf_property, LEAF_PROPERTIES, src, fel, "leaf")
    notes = []
    if plant_name is None and leaf_name is None:
        found = ", ".join(p.name for p in fel.props if not p.is_list) or "none"
        raise MeshFileError(
            f"{src}: the faces carry no plant or leaf id (face properties: {found}); name "
            f"them {' or '.join(LEAF_PROPERTIES[:2])} for the leaf and plant or plant_id for "
            "the plant, or say which property holds them", quantity="mesh_ids")
    if plant_name is not None:
        plant = _ids(fv.scalars[plant_name], plant_name, "plant", -MAX_PLANT_ID, MAX_PLANT_ID,
                     at, src)
    else:
        plant = np.ones(fel.count, np.int64)
        notes.append(f"{src}: no plant id on the faces: all of them are plant 1")
    if leaf_name is not None:
        leaf = _ids(fv.scalars[leaf_name], leaf_name, "leaf", 0, MAX_LEAF_ID, at, src)
    else:
        leaf = np.ones(fel.count, np.int64)
        notes.append(f"{src}: no leaf id on the faces: each plant is one leaf (leaf 1)")
    ids = " and ".join(f"face property '{n}'" for n in (plant_name, leaf_name) if n)
    return MeshData(vertices, faces, tri_face, plant[tri_face], leaf[tri_face], kind, ids,
                    fel.count, polygons, tuple(notes),
                    vv.lines, fv.lines)


def _pick(props: dict[str, str], asked: str | None, names: tuple[str, ...], src: str,
          fel: _Element, what: str) -> str | None:
    if asked:
        if asked.lower() not in props:
            found = ", ".join(p.name for p in fel.props if not p.is_list) or "none"
            raise MeshFileError(f"{src}: no face property '{asked}' for the {what} id (face "
                                f"properties: {found})", quantity="mesh_ids")
        return props[asked.lower()]
    return next((props[n] for n in names if n in props), None)


def _ids(v: np.ndarray, name: str, what: str, low: int, high: int, at, src: str) -> np.ndarray:
    v = np.asarray(v)
    if v.dtype.kind == "f":
        with np.errstate(invalid="ignore"):
            bad = np.flatnonzero(~(v == np.round(v)))
        if len(bad):
            i = int(bad[0])
            raise MeshFileError(f"{src}: {at(i)}: the {what} id ('{name}') is "
                                f"{_number(v[i])}, not a whole number")
    with np.errstate(invalid="ignore"):
        bad = np.flatnonzero((v < low) | (v > high))
    if len(bad):
        i = int(bad[0])
        rule = "0 (not a leaf: a stalk) to" if what == "leaf" else f"{low:,} to"
        raise MeshFileError(f"{src}: {at(i)}: the {what} id ('{name}') is {_number(v[i])}; "
                            f"{what} ids go from {rule} {high:,}")
    return v.astype(np.int64)


def _check_finite(vertices: np.ndarray, src: str, lines: np.ndarray | None) -> None:
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if len(bad):
        i = int(bad[0])
        axis = "xyz"[int(np.flatnonzero(~np.isfinite(vertices[i]))[0])]
        line = f", line {int(lines[i])}" if lines is not None else ""
        raise MeshFileError(f"{src}: vertex {i} (counting from 0{line}): {axis} is "
                            f"{vertices[i, 'xyz'.index(axis)]}, not a finite number")


def _fan(length: np.ndarray, flat: np.ndarray, n_vertices: int, at, src: str,
         base: int = 0) -> tuple[np.ndarray, np.ndarray, int]:
    """Triangles (T, 3), the face of each, and the number of polygons, from face vertex lists
    (lengths, flat indices from 0); refuses short faces and indices out of range, said as the
    file counts them (``base``: 1 for OBJ)."""
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
    out = np.flatnonzero((flat < 0) | (flat >= n_vertices))
    if len(out):
        k = int(out[0])
        i = int(np.searchsorted(np.cumsum(length), k, "right"))
        span = f"{base} to {n_vertices - 1 + base}" if n_vertices else "none"
        raise MeshFileError(f"{src}: {at(i)}: vertex index {int(flat[k]) + base} is out of "
                            f"range: the file has {n_vertices:,} vertices ({span})")
    offs = np.cumsum(length) - length
    tris = length - 2
    n_tri = int(tris.sum())
    face_of = np.repeat(np.arange(len(length), dtype=np.int64), tris)
    k = np.arange(n_tri, dtype=np.int64) - np.repeat(np.cumsum(tris) - tris, tris) + 1
    base = offs[face_of]
    faces = np.column_stack([flat[base], flat[base + k], flat[base + k + 1]])
    return faces.astype(np.int64), face_of, int((length > 3).sum())


# ------------------------------------------------------------------------------ OBJ
_IGNORED = {"vt", "vn", "vp", "s", "usemtl", "mtllib", "l", "p", "mg", "lod", "shadow_obj",
            "trace_obj", "bevel", "c_interp", "d_interp", "maplib", "usemap"}
_FREE_FORM = {"cstype", "deg", "bmat", "step", "curv", "curv2", "surf", "parm", "trim", "hole",
              "scrv", "sp", "end", "con", "ctech", "stech"}
_F_LINE = re.compile(r"f(?:[ \t]+-?\d+(?:/-?\d*(?:/-?\d+)?)?)+", re.ASCII)
_SEP = r"[\s_./:|\-]*"
_PLANT_NAME = re.compile(r"^(?:plant|p)[\s_\-]*(\d+)(?:" + _SEP + r"(.*))?$", re.I | re.S)
_LEAF_NAME = re.compile(r"^(?:leaf|l)[\s_\-]*(\d+)$", re.I)
_STALK_NAME = re.compile(r"^(?:stalk|stem)$", re.I)


def _read_obj(data: bytes, src: str) -> MeshData:
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        bad_line = data.count(b"\n", 0, exc.start) + 1
        raise MeshFileError(f"{src}: line {bad_line}: not UTF-8 text (byte 0x{data[exc.start]:02x}); "
                            "an OBJ file is text") from None
    if text.startswith("\ufeff"):
        text = text[1:]
    lines = text.split("\n")
    del text
    return _obj_mesh(*_obj_statements(lines, src), src)


def _obj_vertex(words: list[str], line: str, no: int, src: str) -> list[float]:
    """A ``v`` statement's x, y and z."""
    try:
        if len(words) < 4:
            raise ValueError
        return list(map(number, words[1:4]))
    except ValueError:
        raise MeshFileError(f"{src}: line {no}: a vertex needs x, y and z numbers, got "
                            f"'{line.strip()[:60]}'") from None


def _obj_face(words: list[str], line: str, no: int, nv: int, src: str) -> list[int]:
    """An ``f`` statement's vertex indices from 0 (negative ones counted back from the
    ``nv`` vertices defined so far), at least 3."""
    try:
        if "/" in line:
            if not _F_LINE.fullmatch(line.strip()):
                raise ValueError
            idx = [whole(w.partition("/")[0]) for w in words[1:]]
        else:
            idx = list(map(whole, words[1:]))
        if 0 in idx:
            raise ValueError
    except ValueError:
        raise MeshFileError(f"{src}: line {no}: '{line.strip()[:60]}' is not a face: "
                            "f then vertices v, v/vt, v//vn or v/vt/vn (whole numbers, "
                            "not 0)") from None
    if len(idx) < 3:
        raise MeshFileError(f"{src}: line {no}: a face has {len(idx)} vertices; a face "
                            "needs at least 3")
    if min(idx) < 0:
        if min(idx) < -nv:
            raise MeshFileError(f"{src}: line {no}: vertex index {min(idx)} reaches "
                                f"before the first vertex ({nv:,} defined so far)")
        return [i + nv if i < 0 else i - 1 for i in idx]
    return [i - 1 for i in idx]


def _obj_statements(lines: list[str], src: str) -> tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
        dict[str, int], dict[str, int], int]:
    """The OBJ statements line by line: vertices and their lines, face vertex indices (from
    0), face lengths and lines, each face's group, the groups by name and the line of their
    first face, and how many line and point statements were passed over."""
    coords: list[float] = []
    vlines: list[int] = []
    flat: list[int] = []
    lengths: list[int] = []
    flines: list[int] = []
    fgroup: list[int] = []
    groups: dict[str, int] = {}
    group_line: dict[str, int] = {}
    obj_name: str | None = None
    grp_name: str | None = None
    current = -1
    ignored = 0
    pending = ""
    for no, line in enumerate(lines, 1):
        if pending or line.endswith(("\\", "\\\r")) or "#" in line:
            line = pending + line.rstrip("\r")
            if line.endswith("\\"):
                pending = line[:-1] + " "
                continue
            pending = ""
            line = line.split("#", 1)[0]
        words = line.split()
        if not words:
            continue
        key = words[0]
        if key == "v":
            coords.extend(_obj_vertex(words, line, no, src))
            vlines.append(no)
        elif key == "f":
            idx = _obj_face(words, line, no, len(vlines), src)
            flat.extend(idx)
            lengths.append(len(idx))
            flines.append(no)
            if current < 0 and (obj_name is not None or grp_name is not None):
                current = _group(groups, group_line, obj_name, grp_name, no)
            fgroup.append(current)
        elif key in ("o", "g"):
            name = " ".join(words[1:]) or "default"
            if key == "o":
                obj_name, grp_name = name, None
            else:
                grp_name = name
            current = -1                       # set at the next face
        elif key in _IGNORED:
            ignored += key in ("l", "p")
        elif key in _FREE_FORM:
            raise MeshFileError(f"{src}: line {no}: free-form geometry ('{key}') is not read; "
                                "export triangles or polygons")
        else:
            raise MeshFileError(f"{src}: line {no}: '{key[:30]}' is not an OBJ statement")
    return (np.array(coords, np.float64).reshape(-1, 3), np.array(vlines, np.int64),
            np.array(flat, np.int64), np.array(lengths, np.int64), np.array(flines, np.int64),
            np.array(fgroup, np.int64), groups, group_line, ignored)


def _obj_mesh(vertices: np.ndarray, vline_arr: np.ndarray, flat: np.ndarray,
              length: np.ndarray, face_lines: np.ndarray, fg: np.ndarray,
              groups: dict[str, int], group_line: dict[str, int], ignored: int,
              src: str) -> MeshData:
    if not len(length):
        raise MeshFileError(f"{src}: the file has no faces (no 'f' line): no surface to trace")
    _check_finite(vertices, src, vline_arr)

    def at(i: int) -> str:
        return f"face {i} (counting from 0, line {int(face_lines[i])})"

    faces, tri_face, polygons = _fan(length, flat, len(vertices), at, src, base=1)
    if not groups:
        raise MeshFileError(f"{src}: the faces carry no plant or leaf id (no o or g names): "
                            "name each leaf's faces with a 'g' line (g plant1_leaf3)")
    if (fg < 0).any():
        i = int(np.flatnonzero(fg < 0)[0])
        raise MeshFileError(f"{src}: line {face_lines[i]}: a face before any o or g name while "
                            "other faces are named: its plant and leaf are unknown")
    gp, gl, notes = _group_ids(groups, group_line, src)
    notes = ([f"{src}: {ignored:,} line and point statements (no surface) ignored"]
             if ignored else []) + notes
    plant, leaf = gp[fg], gl[fg]
    return MeshData(vertices, faces, tri_face, plant[tri_face], leaf[tri_face], "OBJ",
                    "o/g names", len(length), polygons, tuple(notes), vline_arr, face_lines)


def _is_float(w: str) -> bool:
    try:
        number(w)
        return True
    except ValueError:
        return False


def _group(groups: dict[str, int], group_line: dict[str, int], obj_name: str | None,
           grp_name: str | None, no: int) -> int:
    name = "/".join(n for n in (obj_name, grp_name) if n is not None)
    if name not in groups:
        groups[name] = len(groups)
        group_line[name] = no
    return groups[name]


def parse_group_name(name: str) -> tuple[int | None, int | None]:
    """(plant, leaf) a group name carries: ``plant3_leaf7`` -> (3, 7), ``leaf7`` -> (None, 7),
    ``plant3_stalk`` -> (3, 0), ``plant3_blade`` -> (3, None), ``blade`` -> (None, None).
    A name of parts (``Plant 3/leaf7``, an ``o`` name and a ``g`` name) is also read part by
    part: the plant from the first part that carries one, the leaf likewise."""
    plant, leaf = _parse_name(name)
    if "/" in name and (plant is None or leaf is None):
        for part in name.split("/"):
            p, lf = _parse_name(part)
            plant = p if plant is None else plant
            leaf = lf if leaf is None else leaf
    return plant, leaf


def _parse_name(name: str) -> tuple[int | None, int | None]:
    plant = None
    rest = name.strip()
    m = _PLANT_NAME.match(rest)
    if m:
        plant = int(m.group(1))
        rest = (m.group(2) or "").strip()
    m = _LEAF_NAME.match(rest)
    if m:
        return plant, int(m.group(1))
    if _STALK_NAME.match(rest):
        return plant, 0
    return plant, None


def _group_ids(groups: dict[str, int], group_line: dict[str, int],
               src: str) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Plant and leaf id of each group, numbering the leaves whose names carry none."""
    n = len(groups)
    plant = np.ones(n, np.int64)
    leaf = np.zeros(n, np.int64)
    unnamed: dict[int, list[str]] = {}
    used: dict[int, int] = {}
    for name, g in groups.items():
        p, lf = parse_group_name(name)
        p = 1 if p is None else p
        where = f"{src}: line {group_line[name]}: group '{name[:60]}'"
        if p > MAX_PLANT_ID:
            raise MeshFileError(f"{where}: plant id {p} is beyond {MAX_PLANT_ID:,}")
        plant[g] = p
        if lf is None:
            unnamed.setdefault(p, []).append(name)
        else:
            if lf > MAX_LEAF_ID:
                raise MeshFileError(f"{where}: leaf id {lf} is beyond {MAX_LEAF_ID:,}")
            leaf[g] = lf
            used[p] = max(used.get(p, 0), lf)
    notes = []
    for p, names in unnamed.items():
        first = used.get(p, 0) + 1
        if first + len(names) - 1 > MAX_LEAF_ID:
            raise MeshFileError(f"{src}: plant {p} has {len(names):,} groups without a leaf "
                                f"number, more than leaf ids up to {MAX_LEAF_ID:,} can number")
        for k, name in enumerate(names):
            leaf[groups[name]] = first + k
        shown = ", ".join(f"'{nm[:30]}' = {first + k}" for k, nm in enumerate(names[:3]))
        more = f", ... ({len(names):,} in all)" if len(names) > 3 else ""
        notes.append(f"{src}: {len(names):,} group name(s) without a leaf number became leaves "
                     f"{first}..{first + len(names) - 1} of plant {p} in file order: "
                     f"{shown}{more}")
    return plant, leaf, notes
