"""OBJ meshes, read with numpy a statement kind at a time: vertices, faces and a plant and a
leaf id per face from the ``o`` and ``g`` names.

``v`` (x y z, then any colour or weight ignored), ``f`` with ``v``, ``v/vt``, ``v//vn`` or
``v/vt/vn`` vertices, negative (relative) indices, polygons fan-triangulated; ``o`` and ``g``
name the faces that follow (a ``g`` after an ``o`` gives ``o-name/g-name``). ``vt``, ``vn``,
``s``, ``usemtl``, ``mtllib``, ``l`` and ``p`` are read past; free-form geometry (``curv``,
``surf``...) is refused. Comments (``#``) and line continuations (``\\``) are honoured, and
``# maizeviz field_cm ...`` comments are kept (:data:`~maizeviz.io.mesh_data.CARRIED`).

The lines are sorted by their first bytes with numpy; the vertex lines and the triangle face
lines are then read as tables by pandas' C parser (floats to the nearest double, as Python
reads them), so a file of millions of faces is read in seconds. Lines that do not make such a
table (vertex colours, polygons of several sizes, a broken line) are read one by one, which
also says what is wrong and on which line.
"""

from __future__ import annotations

import io
import re

import numpy as np

from maizeviz.io.mesh_data import (
    MAX_LEAF_ID,
    MAX_PLANT_ID,
    MAX_VALUE_CHARS,
    MeshData,
    MeshFileError,
    carried_comments,
    check_finite,
    fan,
)
from maizeviz.numbers import number, whole

_IGNORED = {b"vt", b"vn", b"vp", b"s", b"usemtl", b"mtllib", b"l", b"p", b"mg", b"lod",
            b"shadow_obj", b"trace_obj", b"bevel", b"c_interp", b"d_interp", b"maplib",
            b"usemap"}
_FREE_FORM = {b"cstype", b"deg", b"bmat", b"step", b"curv", b"curv2", b"surf", b"parm",
              b"trim", b"hole", b"scrv", b"sp", b"end", b"con", b"ctech", b"stech"}
# a face vertex: v, v/vt, v//vn or v/vt/vn, whole numbers (0 is refused later, as said)
_VERTEX_REF = rb"-?\d+(?:/-?\d*(?:/-?\d+)?)?"
_BAD_REF = re.compile(rb"(?<!\S)(?!" + _VERTEX_REF + rb"(?!\S))\S+")
# after a face vertex's first "/": what may follow (vt, then /vn)
_BAD_SLASH = re.compile(rb"/(?!-?\d*(?:/-?\d+)?(?:\s|$))")
_SLASH_PART = re.compile(rb"/\S*")
_SPACES = re.compile(rb"[ \t]+")
_LINE_END_SPACES = re.compile(rb" ?\n ?")
_CARRIED = re.compile(rb"#[ \t]*(maizeviz[ \t][^\n]*?)[ \t\r]*(?:\n|$)")
_SEP = r"[\s_./:|\-]*"
_PLANT_NAME = re.compile(r"^(?:plant|p)[\s_\-]*(\d+)(?:" + _SEP + r"(.*))?$", re.I | re.S)
_LEAF_NAME = re.compile(r"^(?:leaf|l)[\s_\-]*(\d+)$", re.I)
_STALK_NAME = re.compile(r"^(?:stalk|stem)$", re.I)
_SPACE, _TAB, _NL = 32, 9, 10
_NEWLINE = b"\n"


def _check_text(data: bytes, src: str) -> bytes:
    """The file's bytes without a byte-order mark, refused unless UTF-8 text."""
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as exc:
        bad_line = data.count(b"\n", 0, exc.start) + 1
        raise MeshFileError(f"{src}: line {bad_line}: not UTF-8 text (byte "
                            f"0x{data[exc.start]:02x}); an OBJ file is text") from None
    return data[3:] if data.startswith(b"\xef\xbb\xbf") else data


def _shown(line: bytes) -> str:
    return line.strip()[:60].decode("utf-8", "replace")


def _lines(data: bytes) -> tuple[list[bytes], np.ndarray, np.ndarray]:
    """Lines without comments, continuations joined; the file line each starts on; and the
    first three bytes of each (n, 3) uint8 (newline past its end), read with numpy."""
    if b"#" in data:
        data = re.sub(rb"#[^\n]*", b"", data)
    if b"\r" in data:
        data = data.replace(b"\r", b" ")
    if b"\\" in data:                                  # line continuations: rare, line by line
        lines: list[bytes] = []
        numbers: list[int] = []
        pending, start = b"", 0
        for no, line in enumerate(data.split(b"\n"), 1):
            if not pending:
                start = no
            if line.rstrip(b" ").endswith(b"\\"):
                pending += line.rstrip(b" ")[:-1] + b" "
                continue
            lines.append(pending + line)
            numbers.append(start)
            pending = b""
        if pending:
            lines.append(pending)
            numbers.append(start)
        data = b"\n".join(lines)
        number = np.asarray(numbers, np.int64)
    else:
        lines = data.split(b"\n")
        number = np.arange(1, len(lines) + 1, dtype=np.int64)
    buf = np.frombuffer(data + b"\n\n\n", np.uint8)
    starts = np.concatenate([[0], np.flatnonzero(buf[:len(data)] == _NL) + 1])
    heads = buf[starts[:, None] + np.arange(3)]
    for i in np.flatnonzero(np.isin(heads[:, 0], (_SPACE, _TAB))).tolist():
        lines[i] = lines[i].strip()                         # indented lines: rare
        heads[i] = np.frombuffer((lines[i] + b"\n\n\n")[:3], np.uint8)
    # a byte past a line's end is its newline: stop there
    heads[heads[:, 0] == _NL, 1:] = _NL
    heads[heads[:, 1] == _NL, 2] = _NL
    return lines, number, heads


def _statements(lines: list[bytes], heads: np.ndarray, numbers: np.ndarray, src: str
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Indices of the vertex, face and o/g lines, and how many line and point statements
    (no surface) were passed over; refuses the first line that is no OBJ statement."""
    c0, c1, c2 = heads.T
    blank1 = (c1 == _SPACE) | (c1 == _TAB)
    is_v = (c0 == ord("v")) & blank1
    is_f = (c0 == ord("f")) & blank1
    is_name = ((c0 == ord("o")) | (c0 == ord("g"))) & (blank1 | (c1 == _NL))
    # vt, vn, vp: texture, normals, parameters, read past
    passed = (c0 == ord("v")) & np.isin(c1, (ord("t"), ord("n"), ord("p"))) & \
        np.isin(c2, (_SPACE, _TAB, _NL))
    other = ~(is_v | is_f | is_name | passed | (c0 == _NL))
    ignored = 0
    for i in np.flatnonzero(other).tolist():
        words = lines[i].split()
        if not words:
            continue
        key = words[0]
        shown = key[:30].decode("utf-8", "replace")
        if key in _IGNORED:
            ignored += key in (b"l", b"p")
        elif key in _FREE_FORM:
            raise MeshFileError(f"{src}: line {numbers[i]}: free-form geometry ('{shown}') is "
                                "not read; export triangles or polygons")
        elif key == b"v":
            raise MeshFileError(f"{src}: line {numbers[i]}: a vertex needs x, y and z numbers, "
                                f"got '{_shown(lines[i])}'")
        elif key == b"f":
            raise MeshFileError(f"{src}: line {numbers[i]}: a face has 0 vertices; a face "
                                "needs at least 3")
        else:
            raise MeshFileError(f"{src}: line {numbers[i]}: '{shown}' is not an OBJ "
                                "statement")
    return np.flatnonzero(is_v), np.flatnonzero(is_f), np.flatnonzero(is_name), ignored


def _joined(lines: list[bytes], rows: np.ndarray) -> bytes:
    return b"\n".join(map(lines.__getitem__, rows.tolist()))


def _table(text: bytes, n: int, columns: int, dtype) -> np.ndarray | None:
    """``n`` lines ``text`` read as a table of a keyword and ``columns`` numbers each, by
    pandas' C parser (floats to the nearest double, as Python reads them); None when they are
    not all such lines (the caller then reads them one by one and says what is wrong)."""
    import pandas as pd

    if not n:
        return np.zeros((0, columns), dtype)
    if b"\t" in text or b"  " in text or b" \n" in text or b"\n " in text or \
            text[:1] == b" " or text[-1:] == b" ":
        text = _SPACES.sub(b" ", text)
        text = _LINE_END_SPACES.sub(b"\n", text).strip(b" ")
    # pandas would take extra words for an index, or pad a short line: count them first. The
    # spaces, taken ``columns`` at a time in order, must each fall within their own line
    buf = np.frombuffer(text, np.uint8)
    ends = np.flatnonzero(buf == _NL)
    spaces = np.flatnonzero(buf == _SPACE)
    if len(ends) != n - 1 or len(spaces) != n * columns:
        return None
    grouped = spaces.reshape(n, columns)
    if (grouped[1:, 0] < ends).any() or (grouped[:-1, -1] > ends).any():
        return None
    try:                                    # pandas 3 reads floats to the nearest double
        table = pd.read_csv(io.BytesIO(text), sep=" ", header=None,
                            names=range(columns + 1), usecols=range(1, columns + 1),
                            dtype=dtype, na_filter=False, engine="c")
    except (ValueError, TypeError, OverflowError, pd.errors.ParserError):
        return None
    if len(table) != n:                                                # pragma: no cover
        return None
    return table.to_numpy(dtype)


def _vertices(lines: list[bytes], rows: np.ndarray, numbers: np.ndarray,
              src: str) -> np.ndarray:
    fast = _table(_joined(lines, rows), len(rows), 3, np.float64)
    if fast is not None:
        return fast
    coords = np.empty((len(rows), 3))
    for k, i in enumerate(rows.tolist()):                 # colours, odd numbers: one by one
        words = lines[i].split()[1:4]
        try:
            if len(words) < 3 or max(map(len, words)) > MAX_VALUE_CHARS:
                raise ValueError
            coords[k] = [number(w) for w in words]
        except ValueError:
            raise MeshFileError(f"{src}: line {numbers[i]}: a vertex needs x, y and z "
                                f"numbers, got '{_shown(lines[i])}'") from None
    return coords


def _not_a_face(src: str, line: int, text: bytes) -> MeshFileError:
    return MeshFileError(f"{src}: line {line}: '{_shown(text)}' is not a face: f then "
                         "vertices v, v/vt, v//vn or v/vt/vn (whole numbers, not 0)")


def _face_lists(lines: list[bytes], rows: np.ndarray, numbers: np.ndarray,
                src: str) -> tuple[np.ndarray, np.ndarray]:
    """(lengths (n,), vertex indices as the file writes them) of the face lines: triangles
    as one table, other faces line by line."""
    text = _joined(lines, rows)
    slashed = b"/" in text
    # faces of one size (triangles, or quads) as one table
    size = len(lines[rows[0]].split()) - 1
    if slashed:
        fast = None if _BAD_SLASH.search(text) else \
            _table(_SLASH_PART.sub(b"", text), len(rows), size, np.int64)
    else:
        fast = _table(text, len(rows), size, np.int64)
    del text
    if fast is not None:
        return np.full(len(rows), size, np.int64), fast.reshape(-1)
    counts = np.empty(len(rows), np.int64)
    flat: list[int] = []
    for k, i in enumerate(rows.tolist()):
        words = lines[i].split()[1:]
        try:
            if slashed:
                if _BAD_REF.search(b" ".join(words)):
                    raise ValueError
                words = [w.partition(b"/")[0] for w in words]
            if max(map(len, words), default=0) > 18:          # no file has 10^18 vertices
                raise ValueError
            flat.extend(map(whole, words))
        except ValueError:
            raise _not_a_face(src, int(numbers[i]), lines[i]) from None
        counts[k] = len(words)
    return counts, np.asarray(flat, np.int64)


def _faces(lines: list[bytes], rows: np.ndarray, numbers: np.ndarray, v_rows: np.ndarray,
           src: str) -> tuple[np.ndarray, np.ndarray]:
    """Face lengths (n,) and vertex indices from 0 (flat), relative indices resolved."""
    counts, idx = _face_lists(lines, rows, numbers, src)
    zero = np.flatnonzero(idx == 0)
    if len(zero):
        k = int(np.searchsorted(np.cumsum(counts), zero[0], "right"))
        raise _not_a_face(src, int(numbers[rows[k]]), lines[rows[k]])
    short = np.flatnonzero(counts < 3)
    if len(short):
        k = int(short[0])
        raise MeshFileError(f"{src}: line {numbers[rows[k]]}: a face has {int(counts[k])} "
                            "vertices; a face needs at least 3")
    neg = np.flatnonzero(idx < 0)
    if len(neg):
        # a relative index counts back from the vertices defined before its line
        face_of = np.repeat(np.arange(len(rows)), counts)[neg]
        defined = np.searchsorted(v_rows, rows[face_of])
        early = np.flatnonzero(idx[neg] < -defined)
        if len(early):
            j = int(early[0])
            raise MeshFileError(f"{src}: line {numbers[rows[face_of[j]]]}: vertex index "
                                f"{int(idx[neg[j]])} reaches before the first vertex "
                                f"({int(defined[j]):,} defined so far)")
        idx[neg] += defined + 1
    return counts, idx - 1


def _group_names(lines: list[bytes], rows: np.ndarray) -> list[str]:
    """The name each o/g line gives the faces after it (``o`` name, then ``o/g``)."""
    names = []
    obj_name: str | None = None
    grp_name: str | None = None
    for i in rows.tolist():
        words = lines[i].decode("utf-8").split()
        name = " ".join(words[1:]) or "default"
        if words[0] == "o":
            obj_name, grp_name = name, None
        else:
            grp_name = name
        names.append("/".join(n for n in (obj_name, grp_name) if n is not None))
    return names


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


def _face_groups(lines: list[bytes], f_rows: np.ndarray, g_rows: np.ndarray,
                 numbers: np.ndarray) -> tuple[np.ndarray, dict[str, int], dict[str, int]]:
    """Each face's group (-1: before any name), the groups by name in the order their first
    face comes, and the line of that face."""
    names = _group_names(lines, g_rows)
    stmt = np.searchsorted(g_rows, f_rows) - 1
    groups: dict[str, int] = {}
    group_line: dict[str, int] = {}
    named = stmt >= 0
    used, first = np.unique(stmt[named], return_index=True)
    first_face = np.flatnonzero(named)[first]
    of_stmt = np.full(len(names), -1, np.int64)
    for s, f in sorted(zip(used.tolist(), first_face.tolist()), key=lambda sf: sf[1]):
        name = names[s]
        if name not in groups:
            groups[name] = len(groups)
            group_line[name] = int(numbers[f_rows[f]])
        of_stmt[s] = groups[name]
    return np.where(named, of_stmt[np.maximum(stmt, 0)], -1), groups, group_line


def _carried(data: bytes) -> dict[str, tuple[str, str]]:
    """The ``# maizeviz ...`` comment lines (:data:`~maizeviz.io.mesh_data.CARRIED`)."""
    found = []
    for m in _CARRIED.finditer(data):
        line_start = data.rfind(b"\n", 0, m.start()) + 1
        if not data[line_start:m.start()].strip():                # a comment line of its own
            found.append((f"line {data.count(_NEWLINE, 0, m.start()) + 1}",
                          m.group(1).decode("utf-8")))
    return carried_comments(found)


def read_obj(data: bytes, src: str) -> MeshData:
    """The mesh of an OBJ file's bytes (``src`` names it in messages); see
    :func:`maizeviz.io.mesh_canopy.read_mesh`."""
    data = _check_text(data, src)
    carried = _carried(data) if b"maizeviz" in data else {}
    lines, numbers, heads = _lines(data)
    del data
    v_rows, f_rows, g_rows, ignored = _statements(lines, heads, numbers, src)
    if not len(f_rows):
        raise MeshFileError(f"{src}: the file has no faces (no 'f' line): no surface to trace")
    vertices = _vertices(lines, v_rows, numbers, src)
    vline = numbers[v_rows]
    check_finite(vertices, src, vline)
    length, flat = _faces(lines, f_rows, numbers, v_rows, src)
    face_lines = numbers[f_rows]

    def at(i: int) -> str:
        return f"face {i} (counting from 0, line {int(face_lines[i])})"

    faces, tri_face, polygons = fan(length, flat, len(vertices), at, src, base=1)
    if not len(g_rows):
        raise MeshFileError(f"{src}: the faces carry no plant or leaf id (no o or g names): "
                            "name each leaf's faces with a 'g' line (g plant1_leaf3)")
    fg, groups, group_line = _face_groups(lines, f_rows, g_rows, numbers)
    if (fg < 0).any():
        i = int(np.flatnonzero(fg < 0)[0])
        raise MeshFileError(f"{src}: line {face_lines[i]}: a face before any o or g name while "
                            "other faces are named: its plant and leaf are unknown")
    gp, gl, notes = _group_ids(groups, group_line, src)
    notes = ([f"{src}: {ignored:,} line and point statements (no surface) ignored"]
             if ignored else []) + notes
    plant, leaf = gp[fg], gl[fg]
    if polygons:
        plant, leaf = plant[tri_face], leaf[tri_face]
    return MeshData(vertices, faces, tri_face, plant, leaf, "OBJ", "o/g names", len(length),
                    polygons, tuple(notes), vline, face_lines, carried)
