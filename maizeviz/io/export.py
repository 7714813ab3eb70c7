"""Write leaf and canopy meshes for ParaView, MeshLab and Blender, by file extension.

Plant and leaf ids travel as cell data where the format allows: face properties in PLY, one
group per leaf in OBJ (``g plant3_leaf7``), cell arrays in VTK/VTU/VTP. STL has no place for
them. meshio writes .vtk, .vtu and .stl; it drops PLY face properties and OBJ groups and has
no .vtp writer, so those three small formats are written here.
"""

from __future__ import annotations

import base64
from pathlib import Path

import numpy as np

from maizeviz.errors import MaizevizError

FORMATS = (".ply", ".obj", ".vtk", ".vtu", ".vtp", ".stl")


def merge_meshes(meshes) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Concatenate leaf meshes.

    Returns
    -------
    points : (V, 3) float64 cm, faces : (F, 3) int64, plant : (F,) int32, leaf : (F,) int32
    """
    pts, faces, plant, leaf = [], [], [], []
    offset = 0
    for m in meshes:
        p = m.points
        pts.append(p)
        faces.append(m.faces.astype(np.int64) + offset)
        plant.append(np.full(len(m.faces), m.plant, dtype=np.int32))
        leaf.append(np.full(len(m.faces), m.leaf, dtype=np.int32))
        offset += len(p)
    if not pts:
        raise MaizevizError("nothing to export: no leaf mesh")
    return (np.concatenate(pts), np.concatenate(faces), np.concatenate(plant),
            np.concatenate(leaf))


def _write_ply(path, pts, faces, plant, leaf):
    header = ("ply\nformat binary_little_endian 1.0\ncomment maizeviz leaf mesh, units cm\n"
              f"element vertex {len(pts)}\nproperty float64 x\nproperty float64 y\n"
              f"property float64 z\nelement face {len(faces)}\n"
              "property list uint8 int32 vertex_indices\nproperty int32 plant\n"
              "property int32 leaf\nend_header\n")
    rec = np.zeros(len(faces), dtype=[("n", "u1"), ("v", "<i4", 3), ("plant", "<i4"),
                                      ("leaf", "<i4")])
    rec["n"] = 3
    rec["v"] = faces
    rec["plant"] = plant
    rec["leaf"] = leaf
    with open(path, "wb") as fh:
        fh.write(header.encode("ascii"))
        fh.write(pts.astype("<f8").tobytes())
        fh.write(rec.tobytes())


def _write_obj(path, pts, faces, plant, leaf):
    with open(path, "w") as fh:
        fh.write("# maizeviz leaf mesh, units cm\n")
        np.savetxt(fh, pts, fmt="v %.6f %.6f %.6f")
        key = plant.astype(np.int64) * (1 << 32) + leaf
        starts = np.flatnonzero(np.concatenate([[True], key[1:] != key[:-1]]))
        ends = np.concatenate([starts[1:], [len(faces)]])
        for a, b in zip(starts, ends):
            fh.write(f"g plant{plant[a]}_leaf{leaf[a]}\n")
            np.savetxt(fh, faces[a:b] + 1, fmt="f %d %d %d")


def _b64(arr: np.ndarray) -> str:
    raw = arr.tobytes()
    return base64.b64encode(np.uint64(len(raw)).tobytes() + raw).decode("ascii")


def _write_vtp(path, pts, faces, plant, leaf):
    n = len(faces)
    conn = _b64(faces.astype("<i8").ravel())
    offs = _b64((np.arange(1, n + 1, dtype="<i8") * 3))
    xml = f"""<?xml version="1.0"?>
<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">
  <PolyData>
    <Piece NumberOfPoints="{len(pts)}" NumberOfPolys="{n}">
      <Points>
        <DataArray type="Float64" NumberOfComponents="3" format="binary">{_b64(pts.astype("<f8"))}</DataArray>
      </Points>
      <CellData Scalars="leaf">
        <DataArray type="Int32" Name="plant" format="binary">{_b64(plant.astype("<i4"))}</DataArray>
        <DataArray type="Int32" Name="leaf" format="binary">{_b64(leaf.astype("<i4"))}</DataArray>
      </CellData>
      <Polys>
        <DataArray type="Int64" Name="connectivity" format="binary">{conn}</DataArray>
        <DataArray type="Int64" Name="offsets" format="binary">{offs}</DataArray>
      </Polys>
    </Piece>
  </PolyData>
</VTKFile>
"""
    Path(path).write_text(xml)


def _write_meshio(path, pts, faces, plant, leaf):
    import meshio

    cell_data = {} if path.suffix.lower() == ".stl" else {"plant": [plant], "leaf": [leaf]}
    mesh = meshio.Mesh(pts, [("triangle", faces.astype(np.int32))], cell_data=cell_data)
    mesh.write(path, binary=True)


def write_mesh(path: str | Path, points: np.ndarray, faces: np.ndarray, plant: np.ndarray,
               leaf: np.ndarray) -> Path:
    """Write triangles with per-triangle plant and leaf ids; the format follows the extension.

    Parameters
    ----------
    points : (V, 3) float64, cm; faces : (F, 3) int; plant, leaf : (F,) int32

    Raises
    ------
    MaizevizError
        Unknown extension, or the file cannot be written.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in FORMATS:
        raise MaizevizError(f"{path}: unknown mesh format '{ext or '(none)'}'; "
                            f"use one of {', '.join(FORMATS)}")
    writer = {".ply": _write_ply, ".obj": _write_obj, ".vtp": _write_vtp}.get(ext, _write_meshio)
    try:
        writer(path, points, faces, plant, leaf)
    except OSError as exc:
        raise MaizevizError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return path


def export_meshes(path: str | Path, meshes) -> Path:
    """Write leaf meshes to ``path`` (see :data:`FORMATS`), plant and leaf ids per triangle."""
    return write_mesh(path, *merge_meshes(meshes))


def export_canopy(path: str | Path, canopy) -> Path:
    """Write a canopy: its leaves (``plant`` = placement number from 1, ``leaf`` = rank) and
    its stalk cylinders (``leaf`` = 0)."""
    plant = (canopy.face_instance + 1).astype(np.int32)
    leaf = canopy.face_leaf.astype(np.int32)
    per_stalk = len(canopy.stalk_faces) // max(canopy.n_plants, 1)
    points = np.vstack([canopy.vertices, canopy.stalk_vertices])
    faces = np.vstack([canopy.faces, canopy.stalk_faces + len(canopy.vertices)])
    plant = np.concatenate([plant, np.repeat(np.arange(1, canopy.n_plants + 1, dtype=np.int32),
                                             per_stalk)])
    leaf = np.concatenate([leaf, np.zeros(len(canopy.stalk_faces), np.int32)])
    return write_mesh(path, points, faces, plant, leaf)
