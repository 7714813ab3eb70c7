"""Write triangle meshes that ParaView, pyvista, meshio, MeshLab and Blender open with their
arrays, the format chosen by file extension.

Per-triangle values (plant and leaf ids, received light...) travel as cell data where the
format allows, under their names (which say their units: ``par_mol_per_m2_leaf``):

- ``.vtu`` (VTK XML unstructured grid) and ``.vtp`` (VTK XML polydata): the VTK formats
  ParaView and pyvista read natively; cell arrays keep their type (Int32, Float32, Float64);
- ``.vtk`` (legacy VTK unstructured grid, binary): written with the type names every VTK reader knows (``int``,
  ``float``, ``double``; meshio 5.3 writes ``vtktypeint32``, which VTK 9.7 refuses, dropping
  every array);
- in every format integer arrays are written as 32-bit ``int`` (small and boolean ones
  widened: meshio reads PLY's ``uchar`` as signed and knows no ``char`` nor ``short``),
  floats as ``float`` or ``double`` as they are;
- ``.ply``: face properties with the PLY standard's type names (``int``, ``float``,
  ``double``: meshio refuses numpy's ``float64``), read by meshio, plyfile, trimesh and
  maizeviz (VTK's PLY reader, and so ParaView and ``pyvista.read``, reads no face property
  at all: use ``.vtu`` there, or ``pyvista.read(path, file_format="ply")`` through meshio);
- ``.obj``: one group per leaf (``g plant3_leaf7``) when ``plant`` and ``leaf`` ids are given
  (pyvista shows them as ``GroupIds``, meshio as ``obj:group_ids``); no other values;
- ``.stl``: triangles only.

The plot and the periodic field's period (``field_cm``, ``period_cm``: x0, y0, x1, y1 cm;
:data:`maizeviz.io.mesh_data.CARRIED`) travel as ``comment maizeviz field_cm ...`` lines in
PLY, ``# maizeviz field_cm ...`` in OBJ and field data arrays in VTK files, so a canopy read
back knows its ground. Coordinates are written as float64 (OBJ: shortest decimal that reads
back as the same float64). Every file is written atomically.

meshio writes only the STL; its VTU writer drops field data and it has no VTP writer, so the
VTK files are written here (a few lines of XML or of the legacy header each).
"""

from __future__ import annotations

import base64
from pathlib import Path

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.atomic import atomic_open, atomic_path, check_output
from maizeviz.io.mesh_data import CARRIED, carried_lines

FORMATS = (".ply", ".obj", ".vtk", ".vtu", ".vtp", ".stl")

CellData = dict[str, np.ndarray]
Rect = tuple[float, float, float, float]

#: numpy kind and size -> (PLY type name, legacy VTK type name, VTK XML type name): the PLY
#: standard's names that meshio reads (it knows no "char", "short" nor "float64")
_TYPES = {("i", 4): ("int", "int", "Int32"), ("u", 4): ("uint", "unsigned_int", "UInt32"),
          ("f", 4): ("float", "float", "Float32"), ("f", 8): ("double", "double", "Float64")}


def _typed(a: np.ndarray) -> tuple[np.ndarray, tuple[str, str, str]]:
    """The array in a type every format and reader holds (booleans and small integers as
    int32, 64-bit integers as int32 when they fit, else refused), with its names."""
    a = np.asarray(a)
    if a.dtype.kind == "b" or (a.dtype.kind in "iu" and a.dtype.itemsize < 4):
        a = a.astype(np.int32)
    elif a.dtype.kind in "iu" and a.dtype.itemsize == 8:
        if len(a) and (a.min() < -2**31 or a.max() >= 2**31):
            raise MaizevizError("an integer cell array beyond 32 bits cannot be exported")
        a = a.astype(np.int32)
    elif a.dtype.kind == "f" and a.dtype.itemsize not in (4, 8):
        a = a.astype(np.float64)
    key = (a.dtype.kind, a.dtype.itemsize)
    if key not in _TYPES:
        raise MaizevizError(f"a cell array of type {a.dtype} cannot be exported")
    return a, _TYPES[key]


def _carried(field_cm: Rect | None, period_cm: Rect | None) -> dict[str, np.ndarray]:
    return {k: np.asarray(v, np.float64) for k, v in zip(CARRIED, (field_cm, period_cm))
            if v is not None}


# ------------------------------------------------------------------------------ PLY, OBJ
def _write_ply(path: Path, pts: np.ndarray, faces: np.ndarray, cells: CellData,
               carried: list[str]) -> None:
    typed = {name: _typed(a) for name, a in cells.items()}
    header = ("ply\nformat binary_little_endian 1.0\ncomment maizeviz mesh, units cm\n"
              + "".join(f"comment {c}\n" for c in carried)
              + f"element vertex {len(pts)}\nproperty double x\nproperty double y\n"
              f"property double z\nelement face {len(faces)}\n"
              "property list uchar int vertex_indices\n"
              + "".join(f"property {names[0]} {name}\n" for name, (_, names) in typed.items())
              + "end_header\n")
    rec = np.zeros(len(faces), dtype=[("n", "u1"), ("v", "<i4", 3)]
                   + [(name, a.dtype.newbyteorder("<")) for name, (a, _) in typed.items()])
    rec["n"] = 3
    rec["v"] = faces
    for name, (a, _) in typed.items():
        rec[name] = a
    with atomic_open(path, "wb") as fh:
        fh.write(header.encode("ascii"))
        fh.write(pts.astype("<f8").tobytes())
        fh.write(rec.tobytes())


def _write_obj(path: Path, pts: np.ndarray, faces: np.ndarray, cells: CellData,
               carried: list[str]) -> None:
    with atomic_open(path, "w") as fh:
        fh.write("# maizeviz mesh, units cm\n" + "".join(f"# {c}\n" for c in carried))
        # repr: the shortest decimal that reads back as the same float64
        fh.write("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in pts.tolist()))
        if "plant" in cells and "leaf" in cells:
            plant, leaf = cells["plant"], cells["leaf"]
            changes = (plant[1:] != plant[:-1]) | (leaf[1:] != leaf[:-1])
            starts = np.flatnonzero(np.concatenate([[True], changes]))
            ends = np.concatenate([starts[1:], [len(faces)]])
            for a, b in zip(starts, ends):
                fh.write(f"g plant{plant[a]}_leaf{leaf[a]}\n")
                np.savetxt(fh, faces[a:b] + 1, fmt="f %d %d %d")
        else:
            np.savetxt(fh, faces + 1, fmt="f %d %d %d")


# ------------------------------------------------------------------------------ VTK XML
def _b64(arr: np.ndarray) -> str:
    raw = np.ascontiguousarray(arr).tobytes()
    return base64.b64encode(np.uint64(len(raw)).tobytes() + raw).decode("ascii")


def _quoteattr(text: str) -> str:
    """``text`` as an XML attribute value, quotes included (xml.sax.saxutils, which imports
    urllib.request and with it http, email and ssl, imported only when a VTK file is
    written)."""
    from xml.sax.saxutils import quoteattr

    return quoteattr(text)


def _xml_array(name: str | None, a: np.ndarray, components: int = 1) -> str:
    a, (_, _, vtk_type) = _typed(a)
    named = f" Name={_quoteattr(name)}" if name is not None else ""
    comps = f' NumberOfComponents="{components}"' if components > 1 else ""
    return (f'<DataArray type="{vtk_type}"{named}{comps} format="binary">'
            f'{_b64(a.astype(a.dtype.newbyteorder("<")))}</DataArray>')


def _write_xml(path: Path, pts: np.ndarray, faces: np.ndarray, cells: CellData,
               field: dict[str, np.ndarray], kind: str) -> None:
    """A VTK XML file: ``kind`` "PolyData" (.vtp) or "UnstructuredGrid" (.vtu), binary
    (base64, little endian, 64-bit block headers), as VTK's own writers make them."""
    n = len(faces)
    index = np.int32 if len(pts) < 2**31 and 3 * n < 2**31 else np.int64
    conn = _xml_array("connectivity", faces.astype(index).ravel())
    offs = _xml_array("offsets", np.arange(1, n + 1, dtype=index) * 3)
    if kind == "PolyData":
        piece = f'NumberOfPoints="{len(pts)}" NumberOfPolys="{n}"'
        topology = f"<Polys>\n        {conn}\n        {offs}\n      </Polys>"
    else:
        piece = f'NumberOfPoints="{len(pts)}" NumberOfCells="{n}"'
        types = _xml_array("types", np.full(n, 5, np.uint8))             # 5: VTK_TRIANGLE
        topology = f"<Cells>\n        {conn}\n        {offs}\n        {types}\n      </Cells>"
    scalars = f" Scalars={_quoteattr(next(iter(cells)))}" if cells else ""
    arrays = "\n        ".join(_xml_array(k, a) for k, a in cells.items())
    fields = "".join("\n    " + _xml_array(k, v).replace(
        "<DataArray ", f'<DataArray NumberOfTuples="{len(v)}" ', 1) for k, v in field.items())
    field_block = f"\n    <FieldData>{fields}\n    </FieldData>" if field else ""
    xml = f"""<?xml version="1.0"?>
<VTKFile type="{kind}" version="1.0" byte_order="LittleEndian" header_type="UInt64">
  <!-- maizeviz mesh, units cm -->
  <{kind}>{field_block}
    <Piece {piece}>
      <Points>
        {_xml_array(None, pts.astype(np.float64), 3)}
      </Points>
      <CellData{scalars}>
        {arrays}
      </CellData>
      {topology}
    </Piece>
  </{kind}>
</VTKFile>
"""
    with atomic_open(path, "w") as fh:
        fh.write(xml)


# ------------------------------------------------------------------------------ legacy VTK
def _write_legacy(path: Path, pts: np.ndarray, faces: np.ndarray, cells: CellData,
                  field: dict[str, np.ndarray]) -> None:
    """A legacy VTK unstructured grid (the legacy dataset meshio reads), binary (big endian,
    as the format wants), arrays under the type names every VTK version reads."""
    n = len(faces)
    with atomic_open(path, "wb") as fh:
        fh.write(b"# vtk DataFile Version 3.0\nmaizeviz mesh, units cm\nBINARY\n"
                 b"DATASET UNSTRUCTURED_GRID\n")
        if field:
            fh.write(f"FIELD FieldData {len(field)}\n".encode("ascii"))
            for name, v in field.items():
                fh.write(f"{name} 1 {len(v)} double\n".encode("ascii"))
                fh.write(v.astype(">f8").tobytes() + b"\n")
        fh.write(f"POINTS {len(pts)} double\n".encode("ascii"))
        fh.write(pts.astype(">f8").tobytes() + b"\n")
        cells_ = np.empty((n, 4), ">i4")
        cells_[:, 0] = 3
        cells_[:, 1:] = faces
        fh.write(f"CELLS {n} {4 * n}\n".encode("ascii"))
        fh.write(cells_.tobytes() + b"\n")
        fh.write(f"CELL_TYPES {n}\n".encode("ascii"))
        fh.write(np.full(n, 5, ">i4").tobytes() + b"\n")                  # 5: VTK_TRIANGLE
        if cells:
            fh.write(f"CELL_DATA {n}\n".encode("ascii"))
            for name, a in cells.items():
                a, (_, vtk_type, _) = _typed(a)
                fh.write(f"SCALARS {name} {vtk_type} 1\nLOOKUP_TABLE default\n".encode("ascii"))
                fh.write(a.astype(a.dtype.newbyteorder(">")).tobytes() + b"\n")


def _write_stl(path: Path, pts: np.ndarray, faces: np.ndarray) -> None:
    import meshio

    mesh = meshio.Mesh(pts, [("triangle", faces.astype(np.int32))])
    with atomic_path(path) as tmp:
        mesh.write(tmp, file_format="stl", binary=True)


def check_mesh_path(path: str | Path) -> Path:
    """The path, if its extension is a mesh format and its folder exists; else
    :class:`MaizevizError`."""
    path = check_output(path)
    ext = path.suffix.lower()
    if ext not in FORMATS:
        raise MaizevizError(f"{path}: unknown mesh format '{ext or '(none)'}'; "
                            f"use one of {', '.join(FORMATS)}")
    return path


def write_mesh(path: str | Path, points: np.ndarray, faces: np.ndarray,
               cell_data: CellData | None = None, field_cm: Rect | None = None,
               period_cm: Rect | None = None) -> Path:
    """Write triangles with per-triangle values; the format follows the extension.

    Parameters
    ----------
    points : (V, 3) float64, cm
    faces : (F, 3) int
    cell_data : {name: (F,) int, float or bool array}, optional
        Per-triangle values, named with their units; ``plant`` and ``leaf`` ids also name
        OBJ groups. Names are letters, digits and underscores (every format takes them).
    field_cm, period_cm : x0, y0, x1, y1 cm, optional
        The plot the triangles stand on and the smallest rectangle a periodic field repeats
        (see the module's text); STL carries neither.

    Raises
    ------
    MaizevizError
        Unknown extension, mismatched or badly named cell data, or the file cannot be
        written (an existing file is then left as it was).
    """
    path = check_mesh_path(path)
    cells = {k: np.asarray(a) for k, a in (cell_data or {}).items()}
    for name, a in cells.items():
        if not name.isidentifier() or not name.isascii():
            raise MaizevizError(f"cell data name '{name}' must be letters, digits and "
                                "underscores")
        if a.shape != (len(faces),):
            raise MaizevizError(f"cell data '{name}' has shape {a.shape}, expected "
                                f"({len(faces)},): one value per triangle")
    pts, tri = np.asarray(points, np.float64), np.asarray(faces, np.int64)
    field = _carried(field_cm, period_cm)
    ext = path.suffix.lower()
    if ext == ".ply":
        _write_ply(path, pts, tri, cells, carried_lines(field_cm, period_cm))
    elif ext == ".obj":
        _write_obj(path, pts, tri, cells, carried_lines(field_cm, period_cm))
    elif ext in (".vtu", ".vtp"):
        _write_xml(path, pts, tri, cells, field,
                   "PolyData" if ext == ".vtp" else "UnstructuredGrid")
    elif ext == ".vtk":
        _write_legacy(path, pts, tri, cells, field)
    else:
        _write_stl(path, pts, tri)
    return path
