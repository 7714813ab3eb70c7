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

import io
import re
from dataclasses import replace
from pathlib import Path

from maizeviz.io.inputs import open_input
from maizeviz.io.mesh_data import (
    CARRIED,
    LEAF_PROPERTIES,
    MAX_BINARY_BYTES,
    MAX_HEADER_BYTES,
    MAX_LEAF_ID,
    MAX_PLANT_ID,
    MAX_POLYGON,
    MAX_TEXT_BYTES,
    MAX_VALUE_CHARS,
    MESH_SUFFIXES,
    PLANT_PROPERTIES,
    MeshData,
    MeshFileError,
)
from maizeviz.io.mesh_obj import parse_group_name, read_obj
from maizeviz.io.mesh_ply import read_ply
from maizeviz.io.points import zero_tail

__all__ = ["CARRIED", "LEAF_PROPERTIES", "MAX_BINARY_BYTES", "MAX_HEADER_BYTES", "MAX_LEAF_ID",
           "MAX_PLANT_ID", "MAX_POLYGON", "MAX_TEXT_BYTES", "MAX_VALUE_CHARS", "MESH_SUFFIXES",
           "PLANT_PROPERTIES", "MeshData", "MeshFileError", "is_mesh_path", "parse_group_name",
           "read_mesh"]


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
            head = fh.read(MAX_HEADER_LINE_BYTES)
            fh.seek(0)
            # zeros end a text file's lines; a binary PLY's last value may end in zero bytes
            text = ext == ".obj" or re.search(rb"[\r\n]format[ \t]+ascii", head) is not None
            size, notes = _zero_tail(fh, size, path) if text else (size, [])
            if ext == ".ply":
                if head.startswith(_BOM):
                    fh, size = _past_bom(fh, size, path)
                    notes.append(f"{path}: the file starts with a byte-order mark (as a text "
                                 "editor saves one): read past it")
                fh.seek(0)
                mesh = read_ply(fh, size, str(path), plant_property, leaf_property)
            else:
                if plant_property or leaf_property:
                    raise MeshFileError(f"{path}: an OBJ file takes its ids from its o/g names; "
                                        "face properties are for PLY files", quantity="mesh_ids")
                if size > MAX_TEXT_BYTES:
                    raise MeshFileError(f"{path}: {size:,} bytes, more than the "
                                        f"{MAX_TEXT_BYTES // 2**20} MiB limit for a text mesh")
                mesh = read_obj(fh.read(size), str(path))
        except OSError as exc:
            raise MeshFileError(f"{path}: cannot be read ({exc.strerror or exc})") from None
        except MemoryError:
            raise MeshFileError(f"{path}: not enough memory to read this mesh") from None
    return replace(mesh, notes=(*notes, *mesh.notes)) if notes else mesh


_BOM = b"\xef\xbb\xbf"
#: Bytes read to find a PLY's format line (the second line of its header).
MAX_HEADER_LINE_BYTES = 4096


def _zero_tail(fh, size: int, path: Path) -> tuple[int, list[str]]:
    """(bytes before the zero bytes ending the file, notes). A power cut while a file grows can
    leave its new length without its data: zeros after intact lines (or, in a binary PLY,
    after its last element). The mesh is read up to them, said in a note; a file of nothing
    but zeros is refused."""
    zeros = zero_tail(fh, size)
    if not zeros:
        return size, []
    if zeros == size:
        raise MeshFileError(f"{path}: only zero bytes; no mesh in it")
    return size - zeros, [f"{path}: the file ends in {zeros:,} zero bytes (as a power cut "
                          "leaves a file being written): read up to them"]


def _past_bom(fh, size: int, path: Path):
    """A PLY file that starts with a UTF-8 byte-order mark (an ascii PLY saved by a Windows
    editor), as a file of the bytes after it: (file, size)."""
    if size > MAX_TEXT_BYTES:
        raise MeshFileError(f"{path}: starts with a byte-order mark, as a text editor saves "
                            "one, and is too large for an ascii PLY; save it without the mark")
    fh.seek(len(_BOM))
    return io.BytesIO(fh.read(size - len(_BOM))), size - len(_BOM)
