"""Write triangle meshes for ParaView, MeshLab and Blender, the format chosen by file extension.

Per-triangle values (plant and leaf ids, received light...) travel as cell data where the
format allows: face properties in PLY, cell arrays in VTK/VTU/VTP, and in OBJ one group per
leaf (``g plant3_leaf7``) when ``plant`` and ``leaf`` ids are given. STL has no place for them.
meshio writes .vtk, .vtu and .stl; it drops PLY face properties and OBJ groups and has no .vtp
writer, so those three small formats are written here. Every file is written atomically.
"""

from __future__ import annotations

import base64
from pathlib import Path

import numpy as np

from maizeviz.errors import MaizevizError
from maizeviz.io.atomic import atomic_open, atomic_path, check_output

FORMATS = (".ply", ".obj", ".vtk", ".vtu", ".vtp", ".stl")

CellData = dict[str, np.ndarray]


def _ply_type(a: np.ndarray) -> tuple[str, str]:
    return ("int32", "<i4") if np.issubdtype(a.dtype, np.integer) else ("float64", "<f8")


def _write_ply(path: Path, pts: np.ndarray, faces: np.ndarray, cells: CellData) -> None:
    props = [(name, *_ply_type(a)) for name, a in cells.items()]
    header = ("ply\nformat binary_little_endian 1.0\ncomment maizeviz mesh, units cm\n"
              f"element vertex {len(pts)}\nproperty float64 x\nproperty float64 y\n"
              f"property float64 z\nelement face {len(faces)}\n"
              "property list uint8 int32 vertex_indices\n"
              + "".join(f"property {t} {name}\n" for name, t, _ in props) + "end_header\n")
    rec = np.zeros(len(faces), dtype=[("n", "u1"), ("v", "<i4", 3)]
                   + [(name, code) for name, _, code in props])
    rec["n"] = 3
    rec["v"] = faces
    for name, _, _ in props:
        rec[name] = cells[name]
    with atomic_open(path, "wb") as fh:
        fh.write(header.encode("ascii"))
        fh.write(pts.astype("<f8").tobytes())
        fh.write(rec.tobytes())


def _write_obj(path: Path, pts: np.ndarray, faces: np.ndarray, cells: CellData) -> None:
    with atomic_open(path, "w") as fh:
        fh.write("# maizeviz mesh, units cm\n")
        np.savetxt(fh, pts, fmt="v %.6f %.6f %.6f")
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


def _b64(arr: np.ndarray) -> str:
    raw = arr.tobytes()
    return base64.b64encode(np.uint64(len(raw)).tobytes() + raw).decode("ascii")


def _vtp_array(name: str, a: np.ndarray) -> str:
    if np.issubdtype(a.dtype, np.integer):
        return f'<DataArray type="Int32" Name="{name}" format="binary">{_b64(a.astype("<i4"))}</DataArray>'
    return f'<DataArray type="Float64" Name="{name}" format="binary">{_b64(a.astype("<f8"))}</DataArray>'


def _write_vtp(path: Path, pts: np.ndarray, faces: np.ndarray, cells: CellData) -> None:
    n = len(faces)
    conn = _b64(faces.astype("<i8").ravel())
    offs = _b64(np.arange(1, n + 1, dtype="<i8") * 3)
    scalars = f' Scalars="{next(iter(cells))}"' if cells else ""
    arrays = "\n        ".join(_vtp_array(k, a) for k, a in cells.items())
    xml = f"""<?xml version="1.0"?>
<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">
  <PolyData>
    <Piece NumberOfPoints="{len(pts)}" NumberOfPolys="{n}">
      <Points>
        <DataArray type="Float64" NumberOfComponents="3" format="binary">{_b64(pts.astype("<f8"))}</DataArray>
      </Points>
      <CellData{scalars}>
        {arrays}
      </CellData>
      <Polys>
        <DataArray type="Int64" Name="connectivity" format="binary">{conn}</DataArray>
        <DataArray type="Int64" Name="offsets" format="binary">{offs}</DataArray>
      </Polys>
    </Piece>
  </PolyData>
</VTKFile>
"""
    with atomic_open(path, "w") as fh:
        fh.write(xml)


def _write_meshio(path: Path, pts: np.ndarray, faces: np.ndarray, cells: CellData) -> None:
    import meshio

    cell_data = {} if path.suffix.lower() == ".stl" else {k: [a] for k, a in cells.items()}
    mesh = meshio.Mesh(pts, [("triangle", faces.astype(np.int32))], cell_data=cell_data)
    with atomic_path(path) as tmp:
        mesh.write(tmp, file_format=None, binary=True)


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
               cell_data: CellData | None = None) -> Path:
    """Write triangles with per-triangle values; the format follows the extension.

    Parameters
    ----------
    points : (V, 3) float64, cm
    faces : (F, 3) int
    cell_data : {name: (F,) int or float array}, optional
        Per-triangle values; ``plant`` and ``leaf`` ids also name OBJ groups.

    Raises
    ------
    MaizevizError
        Unknown extension, mismatched cell data, or the file cannot be written (an existing
        file is then left as it was).
    """
    path = check_mesh_path(path)
    cells = {k: np.asarray(a) for k, a in (cell_data or {}).items()}
    for name, a in cells.items():
        if a.shape != (len(faces),):
            raise MaizevizError(f"cell data '{name}' has shape {a.shape}, expected "
                                f"({len(faces)},): one value per triangle")
    writer = {".ply": _write_ply, ".obj": _write_obj, ".vtp": _write_vtp}.get(
        path.suffix.lower(), _write_meshio)
    writer(path, np.asarray(points, np.float64), np.asarray(faces, np.int64), cells)
    return path
