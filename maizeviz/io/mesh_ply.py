"""PLY meshes through plyfile (ascii, binary little and big endian): vertices, faces and a plant
and a leaf id per face, every value as the file holds it.

plyfile parses the header and the body. Around it, what a file from anywhere needs before and
after: the header must end within :data:`~maizeviz.io.mesh_data.MAX_HEADER_BYTES` and be ASCII;
the counts it declares must fit in the bytes that follow it (checked before anything is
allocated: a header declaring 10^12 faces is refused at once, where plyfile would first ask for
the memory); no data may follow the last element; an ascii body is ASCII with values of at most
:data:`~maizeviz.io.mesh_data.MAX_VALUE_CHARS` characters, and blank lines in it are read past
(as VTK's reader does). A binary element whose lists all have the length of its first item's
(triangles) is memory-mapped by plyfile, the lengths checked in one pass; other elements are
read item by item. plyfile's errors become one line naming the file and the line (ascii) or the
item (binary).
"""

from __future__ import annotations

import io
import math
import re
import warnings
from typing import Any, BinaryIO

import numpy as np
import plyfile

from maizeviz.io.mesh_data import (
    MAX_BINARY_BYTES,
    MAX_HEADER_BYTES,
    MAX_TEXT_BYTES,
    MAX_VALUE_CHARS,
    MeshData,
    MeshFileError,
    carried_comments,
    check_finite,
    fan,
    ids_of_faces,
    shown_number,
)
from maizeviz.numbers import number

#: Names of the face list holding vertex indices, in order of preference.
INDEX_NAMES = ("vertex_indices", "vertex_index")
_FORMATS = {"ascii": "PLY ascii", "binary_little_endian": "PLY binary little endian",
            "binary_big_endian": "PLY binary big endian"}
_END_HEADER = re.compile(rb"(?:^|\r\n|\r|\n)end_header[ \t]*(?:\r\n|\r|\n)")
_LONG_VALUE = re.compile(rb"[^ \t\r\n]{%d,}" % (MAX_VALUE_CHARS + 1))
_BLANK_LINE = re.compile(rb"(?:^|\n)[ \t]*(?:\n|$)")
_READABLE = "is readable"
_TEXT_FLOAT = re.compile(rb"(?m)^(property(?:[ \t]+list[ \t]+\w+)?)[ \t]+(?:float32|float)[ \t]+")


def _is_list(p) -> bool:
    return isinstance(p, plyfile.PlyListProperty)


def _index_prop(face) -> plyfile.PlyListProperty | None:
    lists = [p for p in face.properties if _is_list(p)]
    for name in INDEX_NAMES:
        found = next((p for p in lists if p.name == name), None)
        if found is not None:
            return found
    return lists[0] if len(lists) == 1 else None


def _header(head: bytes, size: int, src: str):
    """(plyfile's PlyData without data, bytes of the header, its lines, carried comments)."""
    if not head.startswith(b"ply") or head[3:4] not in (b"\n", b"\r"):
        raise MeshFileError(f"{src}: not a PLY file (it does not start with a 'ply' line)")
    m = _END_HEADER.search(head)
    if m is None:
        within = "the file" if size <= MAX_HEADER_BYTES else \
            f"the first {MAX_HEADER_BYTES // 2**20} MiB"
        raise MeshFileError(f"{src}: no 'end_header' line in {within}: the PLY header is "
                            "broken or the file is cut short")
    end = m.end()
    lines = head[:end].replace(b"\r\n", b"\n").replace(b"\r", b"\n").split(b"\n")[:-1]
    comments = []
    for no, raw in enumerate(lines, 1):
        if not raw.isascii():
            raise MeshFileError(f"{src}: header line {no} is not ASCII text; not a PLY header")
        words = raw.decode("ascii").split(None, 1)
        if len(words) == 2 and words[0] == "comment":
            comments.append((f"header line {no}", words[1].strip()))
        elif words and words[0] == "element":
            parts = raw.decode("ascii").split()
            if len(parts) != 3 or not parts[2].isdigit():     # plyfile's int() reads 1_000
                raise MeshFileError(f"{src}: header line {no}: '{raw.decode()[:60]}': an "
                                    "element needs a name and a count (a whole number >= 0)")
    try:
        ply = plyfile.PlyData._parse_header(io.BytesIO(head[:end]))
    except plyfile.PlyHeaderParseError as exc:
        raise MeshFileError(f"{src}: header line {exc.line}: {exc.message}") from None
    except (ValueError, UnicodeDecodeError) as exc:          # names plyfile refuses
        raise MeshFileError(f"{src}: the PLY header is broken ({exc})") from None
    return ply, end, len(lines), carried_comments(comments)


def _check_elements(ply, src: str) -> None:
    seen = set()
    for el in ply.elements:
        if el.name in seen:
            raise MeshFileError(f"{src}: element '{el.name[:40]}' declared twice")
        seen.add(el.name)
        if el.count < 0:
            raise MeshFileError(f"{src}: element '{el.name[:40]}' has a count of {el.count}; "
                                "a count is a whole number >= 0")
        names = [p.name for p in el.properties]
        if len(set(names)) != len(names):
            twice = next(n for n in names if names.count(n) > 1)
            raise MeshFileError(f"{src}: property '{twice[:40]}' declared twice in element "
                                f"{el.name[:40]}")
    by_name = {el.name: el for el in ply.elements}
    vertex, face = by_name.get("vertex"), by_name.get("face")
    if vertex is None:
        raise MeshFileError(f"{src}: the PLY header declares no vertex element")
    for axis in "xyz":
        p = next((p for p in vertex.properties if p.name == axis), None)
        if p is None or _is_list(p):
            raise MeshFileError(f"{src}: the vertex element has no '{axis}' property")
    if face is None:
        raise MeshFileError(f"{src}: the PLY header declares no face element: points only, "
                            "no surface to trace")
    index = _index_prop(face)
    if index is None:
        raise MeshFileError(f"{src}: the face element has no 'vertex_indices' list")
    if np.dtype(index.len_dtype).kind == "f":
        raise MeshFileError(f"{src}: a list count must be of an integer type, got "
                            f"{index.len_dtype}")


def _min_entries(el, p) -> int:
    """Fewest entries a list property can hold: 3 for the faces' vertices, else 0."""
    return 3 if el.name == "face" and p is _index_prop(el) else 0


def _check_counts(ply, remaining: int, src: str) -> None:
    """Refuse counts the rest of the file cannot hold, before anything is allocated."""
    need = 0
    for el in ply.elements:
        if ply.text:                          # a value is at least a character and a space
            per = 2 * sum(1 + _min_entries(el, p) if _is_list(p) else 1
                          for p in el.properties)
        else:
            per = sum(np.dtype(p.len_dtype).itemsize + _min_entries(el, p)
                      * np.dtype(p.val_dtype).itemsize if _is_list(p)
                      else np.dtype(p.val_dtype).itemsize for p in el.properties)
        need += el.count * per
        if need > remaining + (1 if ply.text else 0):      # the last value needs no space
            raise MeshFileError(
                f"{src}: the header declares {el.count:,} {el.name} items, which take at least "
                f"{need:,} bytes with those before them, but only {remaining:,} bytes follow "
                "the header: the file is cut short or its header is wrong")


# ------------------------------------------------------------------------------ binary
def _peek_lengths(fh: BinaryIO, start: int, ply) -> dict[str, dict[str, int]]:
    """The list lengths of the first item of each element with lists, as long as the
    elements before it have a known size: plyfile memory-maps those elements."""
    order = ply.byte_order
    known: dict[str, dict[str, int]] = {}
    pos = start
    for el in ply.elements:
        lengths = {}
        item = 0
        for p in el.properties:
            if _is_list(p):
                fh.seek(pos + item)
                raw = fh.read(np.dtype(p.len_dtype).itemsize)
                if len(raw) < np.dtype(p.len_dtype).itemsize:
                    return known
                c = int(np.frombuffer(raw, order + p.len_dtype)[0])
                if c < 0:
                    return known
                lengths[p.name] = c
                item += np.dtype(p.len_dtype).itemsize + c * np.dtype(p.val_dtype).itemsize
            else:
                item += np.dtype(p.val_dtype).itemsize
        if lengths and el.count:
            known[el.name] = lengths
        pos += item * el.count
    return known


def _cut(src: str, el, row: int) -> MeshFileError:
    return MeshFileError(f"{src}: the file is cut short: it ends within {el.name} {row:,} "
                         f"(counting from 0) of the {el.count:,} the header declares")


def _read_binary(fh: BinaryIO, end: int, size: int, head, src: str):
    known = _peek_lengths(fh, end, head)
    for attempt in (known, None):
        fh.seek(0)
        try:
            if attempt:
                ply = plyfile.PlyData.read(fh, mmap="c", known_list_len=attempt)
            else:
                ply = plyfile.PlyData.read(fh, mmap=False)
            break
        except plyfile.PlyElementParseError as exc:
            if attempt and exc.element is not None and exc.element.name in attempt:
                continue            # list lengths vary: item by item tells where it ends
            if exc.element is not None and "end-of-file" in exc.message:
                raise _cut(src, exc.element, int(exc.row or 0)) from None
            raise MeshFileError(f"{src}: {exc}") from None
    rest = size - fh.tell()
    zeros = 0
    if rest > 0:
        tail = fh.read(min(rest, 1 << 20))
        if len(tail) == rest and not tail.strip(b"\x00"):
            zeros = rest                    # a power cut's zeros after the last element
        elif rest > 4096 or tail.strip(b" \t\r\n"):
            raise MeshFileError(f"{src}: {rest:,} bytes follow the last element the header "
                                "declares: the counts in the header do not match the data")
    return ply, zeros


# ------------------------------------------------------------------------------ ascii
def _ascii_problem(tokens: list[bytes], el) -> str:
    """What is wrong with one ascii item (its tokens), as plyfile reads it."""
    k = 0
    for p in el.properties:
        kinds = [("count", p.len_dtype), ("value", p.val_dtype)] if _is_list(p) else \
            [("value", p.val_dtype)]
        n = 1
        for role, code in kinds:
            for _ in range(n):
                if k >= len(tokens):
                    return (f"{len(tokens)} values, too few for its properties "
                            f"({', '.join(q.name for q in el.properties)})")
                text = tokens[k].decode("ascii")
                k += 1
                try:
                    value = number(text)
                except ValueError:
                    return f"'{text[:30]}' is not a number"
                dt = np.dtype(code)
                if dt.kind in "iu" or role == "count":
                    info = np.iinfo(dt)
                    if not (math.isfinite(value) and value == round(value)):
                        return (f"{p.name} is {text[:30]}, not a whole number of type "
                                f"{dt.name}")
                    if not info.min <= value <= info.max:
                        return (f"{p.name} is {shown_number(value)}, beyond the range of its "
                                f"type {dt.name} ({info.min:,} to {info.max:,})")
                if role == "count":
                    n = int(value)
    if k < len(tokens):
        return f"{len(tokens)} values, more than its properties take"
    return _READABLE


def _first_problem(lines: list[bytes], head) -> tuple[int, Any, str] | None:
    """(index in ``lines``, element, what is wrong) of the first ascii item plyfile cannot
    read, walking the items as it does (only when plyfile failed without saying where)."""
    at = 0
    for el in head.elements:
        for row in range(el.count):
            problem = _ascii_problem(lines[at + row].split(), el)
            if problem != _READABLE:
                return at + row, el, problem
        at += el.count
    return None


def _read_ascii(fh: BinaryIO, end: int, size: int, head, header_lines: int, src: str):
    fh.seek(end)
    body = fh.read(size - end)
    if not body.isascii():
        at = next(i for i, b in enumerate(body) if b > 127)
        line = header_lines + body.count(b"\n", 0, at) + 1
        raise MeshFileError(f"{src}: line {line}: not ASCII text (byte 0x{body[at]:02x}); an "
                            "ascii PLY holds numbers")
    if b"\r" in body:
        body = body.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    if b"_" in body:                          # plyfile's float() and int() read 1_000
        line_no = header_lines + body.count(b"\n", 0, body.index(b"_")) + 1
        underscored = re.search(rb"[^ \t\r\n]*_[^ \t\r\n]*", body)
        token = (underscored.group(0) if underscored else b"_")[:30].decode("ascii")
        raise MeshFileError(f"{src}: line {line_no}: '{token}' is not a number")
    long = _LONG_VALUE.search(body)
    if long is not None:
        line = header_lines + body.count(b"\n", 0, long.start()) + 1
        raise MeshFileError(f"{src}: line {line}: a value of {long.end() - long.start():,} "
                            f"characters; a number has at most {MAX_VALUE_CHARS}")
    if body.endswith(b"\n"):
        body = body[:-1]
    lines = body.split(b"\n")
    if _BLANK_LINE.search(body):
        # blank lines are read past (plyfile would take them for items); keep each item's line
        keep = [i for i, ln in enumerate(lines) if ln.strip()]
        lines = [lines[i] for i in keep]
        line_of = np.asarray(keep, np.int64) + header_lines + 1
    else:
        line_of = np.arange(len(lines), dtype=np.int64) + header_lines + 1
    total = sum(el.count for el in head.elements)
    if len(lines) > total:
        raise MeshFileError(f"{src}: line {int(line_of[total])}: more lines than the header "
                            "declares: the counts in the header do not match the data")
    fh.seek(0)
    # text floats are read as float64, the value written, whatever type the header names
    header = _TEXT_FLOAT.sub(rb"\1 double ", fh.read(end))
    text = header + b"\n".join(lines) + b"\n"
    first = np.cumsum([0] + [el.count for el in head.elements])
    try:
        with warnings.catch_warnings():        # plyfile's loadtxt on an empty list warns
            warnings.simplefilter("ignore", UserWarning)
            # numpy 2.0-2.2's loadtxt reads 9.5 as an integer 9 with this warning: refuse it
            warnings.filterwarnings("error", ".*integer via a float", DeprecationWarning)
            ply = plyfile.PlyData.read(io.BytesIO(text))
    except plyfile.PlyElementParseError as exc:
        el, row = exc.element, int(exc.row or 0)
        if "end-of-file" in exc.message:
            last = int(line_of[-1]) if len(line_of) else header_lines
            raise MeshFileError(f"{src}: the file is cut short: the header declares "
                                f"{el.count:,} {el.name} items but the file ends after "
                                f"{row:,} of them (line {last})") from None
        k = [e.name for e in head.elements].index(el.name)
        at = int(first[k]) + row
        problem = _ascii_problem(lines[at].split(), el)
        raise MeshFileError(f"{src}: line {int(line_of[at])}: {el.name} {row} (counting from "
                            f"0): {problem}") from None
    except (ValueError, OverflowError, DeprecationWarning) as exc:  # a number beyond its type
        found = _first_problem(lines, head)
        if found is None:                                             # pragma: no cover
            raise MeshFileError(f"{src}: a value cannot be read ({exc})") from None
        at, el, problem = found
        row = at - int(first[[e.name for e in head.elements].index(el.name)])
        raise MeshFileError(f"{src}: line {int(line_of[at])}: {el.name} {row} (counting from "
                            f"0): {problem}") from None
    lines_by = {el.name: line_of[first[k]:first[k + 1]] for k, el in enumerate(head.elements)}
    return ply, lines_by


# ------------------------------------------------------------------------------ both
def _face_lists(col: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(lengths (n,) int64, flat values) of a list property as plyfile gives it: (n, k) when
    memory-mapped, else an object array of 1-D arrays."""
    if col.dtype != object:
        return np.full(n, col.shape[1] if col.ndim == 2 else 0, np.int64), col
    lengths = np.fromiter(map(len, col), np.int64, n)
    flat = np.concatenate(list(col)) if n and lengths.sum() else np.zeros(0, np.int64)
    return lengths, flat


def read_ply(fh: BinaryIO, size: int, src: str, plant_property: str | None,
             leaf_property: str | None) -> MeshData:
    """The mesh of an open PLY file of ``size`` bytes (``src`` names it in messages); see
    :func:`maizeviz.io.mesh_canopy.read_mesh`."""
    head_bytes = fh.read(min(size, MAX_HEADER_BYTES))
    head, end, header_lines, carried = _header(head_bytes, size, src)
    _check_elements(head, src)
    limit = MAX_TEXT_BYTES if head.text else MAX_BINARY_BYTES
    if size > limit:
        raise MeshFileError(f"{src}: {size:,} bytes, more than the {limit // 2**20} MiB limit "
                            f"for {'an ascii' if head.text else 'a binary'} PLY")
    _check_counts(head, size - end, src)
    carried_notes: list[str] = []
    fmt = "ascii" if head.text else \
        "binary_little_endian" if head.byte_order == "<" else "binary_big_endian"
    if head.text:
        ply, lines_by = _read_ascii(fh, end, size, head, header_lines, src)
        vlines, flines = lines_by["vertex"], lines_by["face"]
    else:
        ply, zeros = _read_binary(fh, end, size, head, src)
        vlines = flines = None
        if zeros:
            carried_notes.append(f"{src}: {zeros:,} zero bytes follow the last element the "
                                 "header declares (as a power cut leaves a file being "
                                 "written): read up to them")
    vdata = np.asarray(ply["vertex"].data)            # a plain array, not plyfile's memmap
    vertices = np.empty((len(vdata), 3), np.float64)
    for k, axis in enumerate("xyz"):
        vertices[:, k] = vdata[axis]
    check_finite(vertices, src, vlines)
    face = ply["face"]
    n = face.count
    if n == 0:
        raise MeshFileError(f"{src}: the file has no faces (element face 0): no surface to "
                            "trace")
    index = _index_prop(face)
    assert index is not None
    fdata = np.asarray(face.data)
    length, flat = _face_lists(fdata[index.name], n)
    if np.dtype(index.val_dtype).kind == "f":
        raise MeshFileError(f"{src}: the face vertex indices are of a float type; they must be "
                            "integers")

    def at(i: int) -> str:
        return f"face {i} (counting from 0{f', line {int(flines[i])}' if flines is not None else ''})"

    faces, tri_face, polygons = fan(length, flat, len(vertices), at, src)
    scalars = {p.name: fdata[p.name] for p in face.properties if not _is_list(p)}
    plant, leaf, ids, notes = ids_of_faces(scalars, n, plant_property, leaf_property, at, src)
    if polygons:
        plant, leaf = plant[tri_face], leaf[tri_face]
    return MeshData(vertices, faces, tri_face, plant, leaf, _FORMATS[fmt], ids, n, polygons,
                    (*carried_notes, *notes), vlines, flines, carried)
