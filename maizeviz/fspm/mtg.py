"""Digitized plants as an MTG, OpenAlea's multiscale tree graph, in its text form (FORM-A,
Godin & Caraglio 1998, as ``openalea.mtg.io`` reads and writes it), and back.

The graph written (:func:`write_mtg`): the scene (``$``, scale 0) holds one ``P`` a plant
(scale 1); each plant is decomposed into its stalk ``S`` (scale 2), which bears its leaves
``L`` (scale 2) as branches (``+``), leaf ``Lk`` of rank ``k`` (the file's leaf id). Features:

====================  ======  =================================================================
feature               type    what
====================  ======  =================================================================
``x``, ``y``          REAL    plant: its stalk base in the field, cm
``height``            REAL    stalk: the highest leaf insertion, cm
``rank``              INT     leaf: its rank (leaf id of the points file)
``rows``, ``cols``    INT     leaf: the digitized grid's cross-sections and points per section
``area``              REAL    leaf: area of its mesh, cm2
``points``            STRING  leaf: the digitized points, row by row, ``x y z`` separated by ``;``
``vertices``          STRING  leaf: its mesh's vertices, ``x y z`` separated by ``;`` (cm)
``faces``             STRING  leaf: its mesh's triangles, ``i j k`` separated by ``;`` (from 0)
====================  ======  =================================================================

Numbers are written in fixed point (no exponent: OpenAlea's reader splits its code on ``+``),
and a value holds none of the characters the MTG code gives a meaning (``/ + < [ ] ( ) , =``).
A feature column is separated by tabs, the entity code indented by tabs, as the format says.

:func:`read_mtg` reads such a file back, and any FORM-A file whose leaves (a symbol chosen by
the caller, ``L`` by default) carry ``points`` in this form, into the point grids the rest of
maizeviz takes (:class:`~maizeviz.leaf.grid.LeafGrid`); its topology parser follows the
grammar of the format (indentation, ``^``, ``/``, ``+``, ``<``) for graphs whose edges join
entities of one scale, which is what plant-and-organ files are.

References
----------
Godin, C. & Caraglio, Y. (1998). A multiscale model of plant topological structures. Journal
of Theoretical Biology 191, 1-46. https://doi.org/10.1006/jtbi.1997.0561
Pradal, C., Godin, C. & Cokelaer, T. (2023). MTG as a standard representation of plants in
OpenAlea. https://mtg.readthedocs.io (the file format and ``openalea.mtg.io``).
"""

from __future__ import annotations

import re
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.inputs import read_input
from maizeviz.numbers import number, whole

#: Largest MTG file read.
MAX_MTG_BYTES = 1 << 30
#: Decimals of the coordinates written (cm: 1/1000 mm).
DECIMALS = 4

_FEATURES = (("x", "REAL"), ("y", "REAL"), ("height", "REAL"), ("rank", "INT"),
             ("rows", "INT"), ("cols", "INT"), ("area", "REAL"), ("points", "STRING"),
             ("vertices", "STRING"), ("faces", "STRING"))
_TYPES = {"INT", "REAL", "STRING", "ALPHA", "DD/MM/YY", "DD/MM/YYYY"}
_ELEMENT = re.compile(r"([/+<])([A-Za-z]+)(\d*)")


class MTGFileError(MaizevizError):
    """An MTG file cannot be read (named with its line)."""


def _fixed(values: np.ndarray) -> str:
    """``x y z;x y z...`` of an (n, 3) array, fixed point (no exponent, no ``+``)."""
    rows = np.asarray(values, np.float64).reshape(-1, 3)
    if not np.all(np.isfinite(rows)):
        raise MaizevizError("an MTG value cannot carry a NaN or infinite coordinate")
    text = ";".join(" ".join(f"{v:.{DECIMALS}f}" for v in r) for r in rows)
    return text.replace("-0.0000 ", "0.0000 ")


def mtg_text(leaves, level=None) -> str:
    """The MTG (FORM-A) text of fitted leaves (see the module docstring).

    Parameters
    ----------
    leaves : list of Leaf
        Fitted leaves (:func:`maizeviz.read_points`' ``leaves``), whole plants.
    level : Level, optional
        Mesh level of the leaves' ``vertices`` and ``faces`` (default: the standard mesh, the
        digitized points only); ``False``: no mesh, the points alone.

    Returns
    -------
    str
        The file's text.
    """
    from maizeviz.canopy.build import plant_tops
    from maizeviz.canopy.layout import plant_bases

    if not leaves:
        raise MaizevizError("no leaf to write as an MTG")
    meshes: dict[tuple[int, int], object] = {}
    if level is not False:
        from maizeviz.mesh.levels import mesh_leaves, parse_level

        lvl = parse_level("standard") if level is None else level
        for lf, m in zip(leaves, mesh_leaves(list(leaves), lvl)):
            meshes[lf.key] = m
    bases = plant_bases(list(leaves))
    tops = plant_tops(list(leaves))
    by_plant: dict[int, list] = defaultdict(list)
    for lf in leaves:
        by_plant[lf.grid.plant].append(lf)
    names = [n for n, _ in _FEATURES]
    width = 4                                   # entity-code columns: /Pp, ^/S1, <tab>+Lk
    lines = ["# maizeviz: digitized maize plants (cm); plant > stalk + leaves",
             "CODE:\tFORM-A", "", "CLASSES:",
             "SYMBOL\tSCALE\tDECOMPOSITION\tINDEXATION\tDEFINITION",
             "$\t0\tFREE\tFREE\tIMPLICIT", "P\t1\tFREE\tFREE\tEXPLICIT",
             "S\t2\tFREE\tFREE\tEXPLICIT", "L\t2\tFREE\tFREE\tEXPLICIT", "",
             "DESCRIPTION:", "LEFT\tRIGHT\tRELTYPE\tMAX", "S\tL\t+\t?", "",
             "FEATURES:", "NAME\tTYPE", *(f"{n}\t{t}" for n, t in _FEATURES), "",
             "MTG:", "ENTITY-CODE" + "\t" * width + "\t".join(names)]

    def row(indent: int, code: str, values: dict) -> str:
        cells = [str(values.get(n, "")) for n in names]
        return "\t" * indent + code + "\t" * (width - indent) + "\t".join(cells).rstrip("\t")

    for p in sorted(by_plant):
        x, y = bases[p]
        lines.append(row(0, f"/P{p}", {"x": f"{x:.{DECIMALS}f}", "y": f"{y:.{DECIMALS}f}"}))
        lines.append(row(0, "^/S1", {"height": f"{tops[p]:.{DECIMALS}f}"}))
        for lf in sorted(by_plant[p], key=lambda leaf: leaf.grid.leaf):
            g = lf.grid
            m, n = g.shape
            values = {"rank": g.leaf, "rows": m, "cols": n, "points": _fixed(g.points)}
            mesh = meshes.get(lf.key)
            if mesh is not None:
                verts = np.asarray(mesh.points, np.float64).reshape(-1, 3)   # type: ignore[attr-defined]
                faces = np.asarray(mesh.faces, np.int64)                       # type: ignore[attr-defined]
                tri = verts[faces]
                area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0],
                                                     tri[:, 2] - tri[:, 0]), axis=1).sum()
                values.update(area=f"{area:.{DECIMALS}f}", vertices=_fixed(verts),
                              faces=";".join(" ".join(map(str, f)) for f in faces))
            lines.append(row(1, f"+L{g.leaf}", values))
    return "\n".join(lines) + "\n"


def write_mtg(path: str | Path, leaves, level=None) -> Path:
    """Write fitted leaves as an MTG file (:func:`mtg_text`), atomically; returns the path."""
    from maizeviz.io.atomic import write_text

    write_text(path, mtg_text(leaves, level))
    return Path(path)


@dataclass
class Vertex:
    """One entity of an MTG read by :func:`parse_mtg`.

    Attributes
    ----------
    label : str, e.g. ``"L3"``; symbol : str, e.g. ``"L"``; index : int or None
    scale : int; complex : int or None (the entity it decomposes); parent : int or None (the
    entity it follows ``<`` or branches from ``+``, at its scale); edge : ``"<"``, ``"+"`` or
    ``"/"``; line : 1-based line of the file; features : dict of name to value
    """

    label: str
    symbol: str
    index: int | None
    scale: int
    complex: int | None
    parent: int | None
    edge: str
    line: int
    features: dict = field(default_factory=dict)


def _sections(lines: list[tuple[int, str]], path) -> dict[str, int]:
    found = {}
    for k, (_, text) in enumerate(lines):
        head = text.split("#")[0].strip().replace(" ", "")
        for name in ("CODE:", "CLASSES:", "DESCRIPTION:", "FEATURES:", "MTG:"):
            if head.startswith(name) and name not in found:
                found[name] = k
    missing = [n for n in ("CODE:", "CLASSES:", "FEATURES:", "MTG:") if n not in found]
    if missing:
        raise MTGFileError(f"{path}: not an MTG file: no {', '.join(missing)} section")
    return found


def _classes(lines, sec, path) -> dict[str, int]:
    scales: dict[str, int] = {}
    end = sec.get("DESCRIPTION:", sec["FEATURES:"])
    for no, t in lines[sec["CLASSES:"] + 2:end]:
        parts = t.split("#")[0].split()
        if len(parts) != 5:
            raise MTGFileError(f"{path}: line {no}: a class is SYMBOL SCALE DECOMPOSITION "
                               "INDEXATION DEFINITION")
        try:
            scales[parts[0]] = whole(parts[1])
        except ValueError:
            raise MTGFileError(f"{path}: line {no}: the scale {parts[1]!r} is not a whole "
                               "number") from None
    return scales


def _features(lines, sec, path) -> dict[str, str]:
    types: dict[str, str] = {}
    for no, t in lines[sec["FEATURES:"] + 2:sec["MTG:"]]:
        parts = t.split("#")[0].split()
        if len(parts) != 2 or parts[1] not in _TYPES:
            raise MTGFileError(f"{path}: line {no}: a feature is NAME TYPE (TYPE one of "
                               f"{', '.join(sorted(_TYPES))})")
        types[parts[0]] = parts[1]
    return types


def _columns(head_no: int, head: str, types: dict[str, str], path) -> dict[int, str]:
    """Feature of each tab column of the code (the ``ENTITY-CODE`` line sets them)."""
    if not head.startswith(("ENTITY-CODE", "TOPO")):
        raise MTGFileError(f"{path}: line {head_no}: the MTG section starts with ENTITY-CODE")
    cols = head.split("\t")
    names = [c.strip() for c in cols[1:] if c.strip()]
    unknown = [n for n in names if n not in types]
    if unknown:
        raise MTGFileError(f"{path}: line {head_no}: feature {unknown[0]} is not declared in "
                           "FEATURES")
    first = next((k for k, c in enumerate(cols) if k > 0 and c.strip()), len(cols))
    return {k: c.strip() for k, c in enumerate(cols) if k >= first and c.strip()}


def _start(t: str, no: int, last_at: dict[int, int], path) -> tuple[int, str, int]:
    """(indentation, entity code without ``^``, vertex it starts from) of a code line."""
    indent = len(t) - len(t.lstrip("\t"))
    entity = t.strip().split("\t")[0].split()[0]
    if entity.startswith("^"):
        if indent not in last_at:
            raise MTGFileError(f"{path}: line {no}: '^' with no entity before it at this "
                               "indentation")
        return indent, entity[1:], last_at[indent]
    if indent == 0:
        return indent, entity, 0
    if indent - 1 in last_at:
        return indent, entity, last_at[indent - 1]
    raise MTGFileError(f"{path}: line {no}: indented under no entity")


def _add(verts: list[Vertex], current: int, edge: str, symbol: str, index: str,
         scales: dict[str, int], no: int, path) -> int:
    """Add one element of an entity code after ``current``; its vertex."""
    if symbol not in scales:
        raise MTGFileError(f"{path}: line {no}: symbol {symbol} is not in CLASSES")
    scale = scales[symbol]
    cur = verts[current]
    parent: int | None = None
    if edge == "/":
        complex_: int | None = current
        if scale <= cur.scale:
            # /P2 after a plant's organs: a new component of the complex at that scale
            up: int | None = current
            while up is not None and verts[up].scale >= scale:
                up = verts[up].complex
            complex_ = 0 if up is None else up
    else:
        if scale != cur.scale:
            raise MTGFileError(f"{path}: line {no}: {edge}{symbol}{index} joins scale "
                               f"{cur.scale} to scale {scale}: edges between scales are not "
                               "read here")
        complex_, parent = cur.complex, current
    verts.append(Vertex(f"{symbol}{index}", symbol, int(index) if index else None, scale,
                        complex_, parent, edge, no))
    return len(verts) - 1


def _value(kind: str, name: str, value: str, no: int, path):
    try:
        return whole(value) if kind == "INT" else number(value) if kind == "REAL" else value
    except ValueError:
        raise MTGFileError(f"{path}: line {no}: feature {name} {value[:30]!r} is not "
                           f"{'a whole number' if kind == 'INT' else 'a number'}") from None


def parse_mtg(path: str | Path) -> list[Vertex]:
    """The entities of an MTG file (FORM-A), in file order (index 0 is the scene, ``$``).

    Raises
    ------
    MTGFileError
        A header section missing or malformed, an unknown symbol, a feature value not of its
        declared type, an edge between entities of different scales, each naming its line.
    """
    raw = read_input(path, "MTG file", MAX_MTG_BYTES, MTGFileError)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    lines = [(no, t) for no, t in enumerate(text.splitlines(), start=1)
             if t.strip() and not t.strip().startswith("#")]
    sec = _sections(lines, path)
    code_no, code = lines[sec["CODE:"]]
    if "FORM-A" not in code and "FORM-B" not in code:
        raise MTGFileError(f"{path}: line {code_no}: the CODE is not FORM-A or FORM-B")
    scales = _classes(lines, sec, path)
    types = _features(lines, sec, path)
    if sec["MTG:"] + 1 >= len(lines):
        raise MTGFileError(f"{path}: the MTG section is empty")
    head_no, head = lines[sec["MTG:"] + 1]
    columns = _columns(head_no, head, types, path)
    verts = [Vertex("", "$", None, 0, None, None, "/", head_no)]
    last_at: dict[int, int] = {}                      # indentation -> last vertex of that line
    for no, t in lines[sec["MTG:"] + 2:]:
        indent, entity, current = _start(t, no, last_at, path)
        elements = _ELEMENT.findall(entity)
        if not elements or "".join("".join(e) for e in elements) != entity:
            raise MTGFileError(f"{path}: line {no}: {entity[:40]!r} is not an entity code "
                               "(/X1, +X1, <X1 ...)")
        for edge, symbol, index in elements:
            current = _add(verts, current, edge, symbol, index, scales, no, path)
        last_at[indent] = current
        for deeper in [k for k in last_at if k > indent]:
            del last_at[deeper]
        cells = t.split("\t")
        feats = verts[current].features
        for k, name in columns.items():
            value = cells[k].strip() if k < len(cells) else ""
            if value:
                feats[name] = _value(types[name], name, value, no, path)
    return verts


def _points(text: str, where: str) -> np.ndarray:
    try:
        pts = [[number(v) for v in p.split()] for p in text.split(";")]
    except ValueError as exc:
        raise MTGFileError(f"{where}: {exc}") from None
    if any(len(p) != 3 for p in pts):
        raise MTGFileError(f"{where}: points are 'x y z' separated by ';'")
    arr = np.array(pts, np.float64)
    if not np.all(np.isfinite(arr)):
        raise MTGFileError(f"{where}: a coordinate is not finite")
    return arr


def read_mtg(path: str | Path, leaf_symbol: str = "L", plant_symbol: str = "P") -> list:
    """The digitized point grids of an MTG's leaves, ready to fit.

    Parameters
    ----------
    path : the MTG file
    leaf_symbol, plant_symbol : str
        Symbols of the leaves (which carry ``points``, ``rows``, ``cols``) and of the plants
        they belong to (a leaf's plant is its nearest complex of that symbol; its id, the
        plant's index).

    Returns
    -------
    list of LeafGrid
        One per leaf carrying points, plant and leaf ids from the plant's index and the leaf's
        ``rank`` (else its index).

    Raises
    ------
    MTGFileError
        No leaf with points, a grid whose point count is not ``rows x cols``, a leaf outside
        any plant, two leaves of one plant with the same rank.
    """
    from maizeviz.leaf.grid import LeafGrid

    verts = parse_mtg(path)
    grids, seen = [], set()
    for v in verts:
        if v.symbol != leaf_symbol or "points" not in v.features:
            continue
        where = f"{path}: line {v.line}"
        up = v.complex
        while up is not None and verts[up].symbol != plant_symbol:
            up = verts[up].complex
        if up is None or verts[up].index is None:
            raise MTGFileError(f"{where}: leaf {v.label} belongs to no plant {plant_symbol}<n>")
        plant = int(verts[up].index or 0)
        leaf = int(v.features.get("rank", v.index if v.index is not None else 0))
        if (plant, leaf) in seen:
            raise MTGFileError(f"{where}: plant {plant} has two leaves of rank {leaf}")
        seen.add((plant, leaf))
        pts = _points(str(v.features["points"]), where)
        rows = v.features.get("rows")
        cols = v.features.get("cols")
        if rows is None or cols is None:
            raise MTGFileError(f"{where}: leaf {v.label} has points but no rows and cols")
        if rows * cols != len(pts) or rows < 2 or cols < 2:
            raise MTGFileError(f"{where}: leaf {v.label}: {len(pts)} points for a grid of "
                               f"{rows} x {cols}")
        grid = pts.reshape(rows, cols, 3)
        grids.append(LeafGrid(plant, leaf, grid, bool(np.all(grid[-1] == grid[-1, :1])),
                              rows=tuple(range(rows))))
    if not grids:
        raise MTGFileError(f"{path}: no {leaf_symbol} entity carries points")
    return grids
