"""Mesh files as canopies (issue 18, "Canopies from elsewhere"): PLY and OBJ with a plant and a
leaf id per face, read exactly, traced like digitized canopies, and refused in one line when
they are broken."""

from __future__ import annotations

import csv
import json
import os
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from maizeviz.canopy.build import build_canopy
from maizeviz.canopy.export import canopy_cells, export_canopy
from maizeviz.canopy.from_mesh import canopy_from_mesh, read_mesh_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.cli import EXIT_FAIL, EXIT_OK, main
from maizeviz.errors import MaizevizError
from maizeviz.io.mesh_canopy import MeshFileError, parse_group_name, read_mesh
from maizeviz.leaf.fit import read_leaves
from maizeviz.mesh.levels import Level
from maizeviz.resources import example_points

B = str(example_points())
SUN = ["--sun-zenith", "30", "--sun-azimuth", "120"]

_CODES = {"float": "f4", "double": "f8", "int": "i4", "uint": "u4", "uchar": "u1",
          "short": "i2", "ushort": "u2", "char": "i1"}


# ------------------------------------------------------------------------------ writers
def write_ply(path, verts, faces, props=None, fmt="ascii", vtype="double", itype="int",
              ctype="uchar", ptypes=None):
    """A PLY file written here, byte by byte: ``faces`` lists of vertex indices, ``props``
    per-face values by name (int unless ``ptypes`` says otherwise)."""
    props = props or {}
    ptypes = {k: (ptypes or {}).get(k, "int") for k in props}
    head = ["ply", f"format {fmt} 1.0", "comment written by the test",
            f"element vertex {len(verts)}"] + [f"property {vtype} {a}" for a in "xyz"] + \
        [f"element face {len(faces)}", f"property list {ctype} {itype} vertex_indices"] + \
        [f"property {ptypes[k]} {k}" for k in props] + ["end_header"]
    out = ("\n".join(head) + "\n").encode("ascii")
    if fmt == "ascii":
        lines = [" ".join(repr(float(c)) for c in v) for v in verts]
        for i, f in enumerate(faces):
            vals = [str(len(f))] + [str(int(k)) for k in f] + \
                [repr(float(props[k][i])) if ptypes[k] in ("float", "double")
                 else str(int(props[k][i])) for k in props]
            lines.append(" ".join(vals))
        out += ("\n".join(lines) + "\n").encode("ascii")
    else:
        e = "<" if fmt == "binary_little_endian" else ">"
        out += np.asarray(verts, e + _CODES[vtype]).tobytes()
        for i, f in enumerate(faces):
            out += np.array([len(f)], e + _CODES[ctype]).tobytes()
            out += np.asarray(f, e + _CODES[itype]).tobytes()
            for k in props:
                out += np.array([props[k][i]], e + _CODES[ptypes[k]]).tobytes()
    path.write_bytes(out)
    return path


def write_obj(path, verts, faces, names):
    """An OBJ file: ``names[i]`` is the group of face i (a ``g`` line where it changes)."""
    lines = ["# written by the test"] + [f"v {float(x)!r} {float(y)!r} {float(z)!r}"
                                          for x, y, z in verts]
    last = None
    for f, name in zip(faces, names):
        if name != last:
            lines.append(f"g {name}")
            last = name
        lines.append("f " + " ".join(str(k + 1) for k in f))
    path.write_text("\n".join(lines) + "\n")
    return path


def _one_error(capsys) -> str:
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith(("error", "internal"))]
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert "Traceback" not in err
    return lines[0]


# a small two-plant mesh: a square leaf (two triangles) per plant, a stalk triangle on plant 2
V = np.array([[0, 0, 50], [10, 0, 50], [10, 10, 52], [0, 10, 52],
              [40, 0, 80], [50, 0, 80], [50, 10, 81], [40, 10, 81],
              [45, 5, 0], [46, 5, 0], [45, 5, 60]], float)
F = [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7], [8, 9, 10]]
PLANT = [3, 3, 7, 7, 7]
LEAF = [2, 2, 5, 5, 0]


# ------------------------------------------------------------------------------ reading
@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_ply_ids_vertices_and_triangles_come_back(tmp_path, fmt):
    p = write_ply(tmp_path / "m.ply", V, F, {"plant": PLANT, "leaf": LEAF}, fmt)
    mesh = read_mesh(p)
    assert np.array_equal(mesh.vertices, V)
    assert mesh.faces.tolist() == F
    assert mesh.plant.tolist() == PLANT and mesh.leaf.tolist() == LEAF
    canopy, notes = canopy_from_mesh(mesh, source=str(p))
    assert canopy.n_triangles == 4 and len(canopy.stalk_faces) == 1
    assert canopy.face_plant.tolist() == [3, 3, 7, 7] and canopy.face_leaf.tolist() == [2, 2, 5, 5]
    assert [pl.plant for pl in canopy.layout.placements] == [3, 7]
    assert canopy.face_instance.tolist() == [0, 0, 1, 1]
    assert canopy.leaves_per_instance.tolist() == [1, 1]
    # plant 7 stands where its stalk is; plant 3 (no stalk) at its leaf's centre
    assert canopy.layout.placements[1].x == pytest.approx(np.mean([45, 46, 45]))
    assert canopy.layout.placements[0].x == pytest.approx(5.0)
    assert canopy.layout.bounds == (0.0, 0.0, 50.0, 10.0)        # the bounding box
    assert np.array_equal(canopy.vertices, V[:8]) and np.array_equal(canopy.stalk_vertices, V[8:])


@pytest.mark.parametrize("names", [
    ["plant3_leaf2", "plant3_leaf2", "plant7_leaf5", "plant7_leaf5", "plant7_stalk"],
    ["plant3/leaf2", "plant3/leaf2", "plant7/leaf5", "plant7/leaf5", "plant7/leaf0"],
    ["p3_l2", "p3_l2", "p7_l5", "P07 L05", "p7_stem"],
])
def test_obj_group_names_give_the_ids(tmp_path, names):
    mesh = read_mesh(write_obj(tmp_path / "m.obj", V, F, names))
    assert np.array_equal(mesh.vertices, V) and mesh.faces.tolist() == F
    assert mesh.plant.tolist() == PLANT and mesh.leaf.tolist() == LEAF


@pytest.mark.parametrize("name, ids", [
    ("plant3_leaf7", (3, 7)), ("plant3/leaf7", (3, 7)), ("p3_l7", (3, 7)), ("P03 L07", (3, 7)),
    ("plant3leaf7", (3, 7)), ("Plant_3-Leaf_7", (3, 7)), ("leaf7", (None, 7)), ("l7", (None, 7)),
    ("plant3_stalk", (3, 0)), ("plant3_blade", (3, None)), ("blade.001", (None, None)),
    ("Plant/leaf7", (None, 7)), ("polygon5", (None, None)), ("plant3", (3, None)),
])
def test_group_names(name, ids):
    assert parse_group_name(name) == ids


def test_obj_forms_negative_indices_polygons_and_free_names(tmp_path):
    text = """# vertices with colours, faces of every form
mtllib x.mtl
v 0 0 10 1 0 0
v 10 0 10 1 0 0
v 10 10 12
v 0 10 12
vt 0 0
vt 1 0
vn 0 0 1
o Blade.001
usemtl green
s off
f 1/1 2/2 3/1
f 1//1 3//1 4//1
o Blade.002
v 20 0 30
v 30 0 30
v 30 10 31
v 20 10 31
v 25 15 31
f -5/1/1 -4/1/1 -3/2/1 -2/1/1 -1/1/1
g plant4_leaf9
f 1 2 4
l 1 2
"""
    p = tmp_path / "forms.obj"
    p.write_text(text)
    mesh = read_mesh(p)
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7], [4, 7, 8],
                                   [0, 1, 3]]
    assert mesh.triangle_face.tolist() == [0, 1, 2, 2, 2, 3]
    assert mesh.polygons == 1 and mesh.file_faces == 4
    # "Blade.001", "Blade.002" carry no number: leaves 1 and 2 of plant 1; "Blade.002/plant4_leaf9"
    assert mesh.plant.tolist() == [1, 1, 1, 1, 1, 4]
    assert mesh.leaf.tolist() == [1, 1, 2, 2, 2, 9]
    assert any("without a leaf number" in n for n in mesh.notes)
    assert mesh.vertices[0].tolist() == [0, 0, 10]


def test_ply_polygons_are_fans_with_the_faces_ids(tmp_path):
    verts = [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1], [0.5, 1.5, 1]]
    p = write_ply(tmp_path / "poly.ply", verts, [[0, 1, 2, 3, 4], [0, 1, 2]],
                  {"plant_id": [1, 2], "leaf_id": [4, 5]}, "binary_little_endian")
    mesh = read_mesh(p)
    assert mesh.faces.tolist() == [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 1, 2]]
    assert mesh.plant.tolist() == [1, 1, 1, 2] and mesh.leaf.tolist() == [4, 4, 4, 5]
    assert mesh.polygons == 1


@pytest.mark.parametrize("plant, leaf", [("plantid", "organ"), ("PLANT", "Label"),
                                         ("plant_id", "object_label")])
def test_ply_id_names(tmp_path, plant, leaf):
    p = write_ply(tmp_path / "n.ply", V, F, {leaf: LEAF, plant: PLANT}, "binary_big_endian",
                  ptypes={leaf: "ushort", plant: "uint"})
    mesh = read_mesh(p)
    assert mesh.plant.tolist() == PLANT and mesh.leaf.tolist() == LEAF


def test_ply_ids_named_by_the_user_and_float_ids(tmp_path):
    p = write_ply(tmp_path / "n.ply", V, F, {"segment": LEAF, "tree": PLANT, "label": [9] * 5},
                  ptypes={"segment": "float"})
    mesh = read_mesh(p, plant_property="tree", leaf_property="segment")
    assert mesh.plant.tolist() == PLANT and mesh.leaf.tolist() == LEAF
    with pytest.raises(MeshFileError, match="no face property 'nope'.*segment, tree, label"):
        read_mesh(p, leaf_property="nope")


def test_one_id_missing_takes_the_documented_default(tmp_path):
    mesh = read_mesh(write_ply(tmp_path / "l.ply", V, F, {"leaf": LEAF}))
    assert mesh.plant.tolist() == [1] * 5 and "all of them are plant 1" in mesh.notes[0]
    mesh = read_mesh(write_ply(tmp_path / "p.ply", V, F, {"plant": PLANT}))
    assert mesh.leaf.tolist() == [1] * 5 and "each plant is one leaf" in mesh.notes[0]


def test_an_ascii_ply_without_a_last_line_end(tmp_path):
    p = tmp_path / "n.ply"
    p.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y"
                  b"\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices"
                  b"\nproperty uchar leaf\nend_header\n0 0 9\n1 0 9\n0 1 9\n3 0 1 2 1")
    assert read_mesh(p).faces.tolist() == [[0, 1, 2]]


def test_extra_elements_and_properties_are_read_past(tmp_path):
    head = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nproperty uchar red\nelement material 2\nproperty list uchar int "
            "a\nproperty float b\nelement face 1\nproperty int leaf\nproperty list uchar uint "
            "vertex_indices\nproperty list uchar float texcoord\nend_header\n")
    body = ("0 0 10 255\n1 0 10 0\n0 1 10 7\n2 1 2 0.5\n\n0 1.5\n"
            "4 3 0 1 2 6 0 0 1 0 1 1\n")
    p = tmp_path / "x.ply"
    p.write_text(head + body)
    mesh = read_mesh(p)
    assert mesh.faces.tolist() == [[0, 1, 2]] and mesh.leaf.tolist() == [4]


def test_trimesh_files_read_back(tmp_path):
    """Files written by another library: trimesh's PLY (face attributes) and OBJ (o names)."""
    import trimesh

    rng = np.random.default_rng(3)
    verts = rng.uniform(0, 100, (30, 3))
    faces = rng.integers(0, 30, (20, 3))
    m = trimesh.Trimesh(vertices=verts, faces=faces, process=False)
    m.face_attributes["plant"] = rng.integers(1, 4, 20).astype(np.int32)
    m.face_attributes["leaf"] = rng.integers(1, 12, 20).astype(np.int32)
    for enc in ("binary", "ascii"):
        p = tmp_path / f"t_{enc}.ply"
        p.write_bytes(trimesh.exchange.ply.export_ply(m, encoding=enc, include_attributes=True))
        mesh = read_mesh(p)
        assert np.allclose(mesh.vertices, verts.astype(np.float32), rtol=1e-7, atol=1e-5)
        assert np.array_equal(mesh.faces, faces)
        assert np.array_equal(mesh.plant, m.face_attributes["plant"])
        assert np.array_equal(mesh.leaf, m.face_attributes["leaf"])
    scene = trimesh.Scene()
    for plant, leaf in ((1, 2), (2, 5), (2, 6)):
        scene.add_geometry(trimesh.Trimesh(vertices=rng.uniform(0, 80, (4, 3)),
                                           faces=[[0, 1, 2], [0, 2, 3]], process=False),
                           geom_name=f"plant{plant}_leaf{leaf}")
    p = tmp_path / "scene.obj"
    p.write_text(scene.export(file_type="obj"))
    mesh = read_mesh(p)
    assert mesh.n_triangles == 6
    assert mesh.plant.tolist() == [1, 1, 2, 2, 2, 2] and mesh.leaf.tolist() == [2, 2, 5, 5, 6, 6]


def test_meshio_files_without_ids_are_refused_with_a_hint(tmp_path):
    import meshio

    mesh = meshio.Mesh(V, [("triangle", np.array(F))])
    for ext in ("ply", "obj"):
        p = tmp_path / f"nm.{ext}"
        mesh.write(p)
        with pytest.raises(MeshFileError, match="carry no plant or leaf id") as exc:
            read_mesh(p)
        # a PLY's ids may be named (--mesh-plant/--mesh-leaf); an OBJ's come from its names
        assert exc.value.quantity == ("mesh_ids" if ext == "ply" else None)


# ------------------------------------------------------------------------------ properties
coord = st.floats(-1e4, 1e4, allow_nan=False, allow_infinity=False, width=64)


@st.composite
def meshes(draw):
    n_v = draw(st.integers(3, 25))
    verts = np.array(draw(st.lists(st.tuples(coord, coord, coord), min_size=n_v, max_size=n_v)))
    n_f = draw(st.integers(1, 30))
    faces = draw(st.lists(st.lists(st.integers(0, n_v - 1), min_size=3, max_size=3),
                          min_size=n_f, max_size=n_f))
    plant = draw(st.lists(st.integers(-10**9, 10**9), min_size=n_f, max_size=n_f))
    leaf = draw(st.lists(st.integers(0, 9999), min_size=n_f, max_size=n_f))
    return verts, faces, plant, leaf


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(m=meshes(), fmt=st.sampled_from(["ascii", "binary_little_endian", "binary_big_endian"]),
       vtype=st.sampled_from(["float", "double"]))
def test_random_ply_round_trips_exactly(tmp_path, m, fmt, vtype):
    verts, faces, plant, leaf = m
    p = write_ply(tmp_path / "r.ply", verts, faces, {"plant": plant, "leaf": leaf}, fmt, vtype)
    mesh = read_mesh(p)
    want = verts if fmt == "ascii" or vtype == "double" else verts.astype(np.float32)
    assert np.array_equal(mesh.vertices, want)
    assert mesh.faces.tolist() == faces
    assert mesh.plant.tolist() == plant and mesh.leaf.tolist() == leaf


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(m=meshes())
def test_random_obj_round_trips_exactly(tmp_path, m):
    verts, faces, plant, leaf = m
    names = [f"plant{abs(p)}_leaf{lf}" for p, lf in zip(plant, leaf)]
    mesh = read_mesh(write_obj(tmp_path / "r.obj", verts, faces, names))
    assert np.array_equal(mesh.vertices, verts)
    assert mesh.faces.tolist() == faces
    assert mesh.plant.tolist() == [abs(p) for p in plant] and mesh.leaf.tolist() == leaf


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data(), kind=st.sampled_from(["ascii", "binary_little_endian", "obj"]))
def test_damaged_files_give_only_mesh_errors(tmp_path, data, kind):
    """Bytes cut, flipped or inserted anywhere: a mesh or a one-line MaizevizError."""
    p = tmp_path / ("d.obj" if kind == "obj" else "d.ply")
    if kind == "obj":
        write_obj(p, V, F, ["plant3_leaf2"] * 2 + ["plant7_leaf5"] * 2 + ["plant7_stalk"])
    else:
        write_ply(p, V, F, {"plant": PLANT, "leaf": LEAF}, kind)
    raw = bytearray(p.read_bytes())
    for _ in range(data.draw(st.integers(1, 4))):
        op = data.draw(st.sampled_from(["cut", "flip", "insert"]))
        at = data.draw(st.integers(0, max(len(raw) - 1, 0)))
        if op == "cut":
            del raw[at:at + data.draw(st.integers(1, 40))]
        elif op == "flip" and raw:
            raw[at] = data.draw(st.integers(0, 255))
        else:
            raw[at:at] = data.draw(st.binary(min_size=1, max_size=12))
    p.write_bytes(bytes(raw))
    try:
        canopy_from_mesh(read_mesh(p), unit="cm", source=str(p))
    except MaizevizError as exc:
        assert "\n" not in str(exc) and str(p) in str(exc) or exc.quantity
    else:
        pass


# ------------------------------------------------------------------------------ units, axes
def test_units_up_axis_and_the_unit_guard(tmp_path):
    metres = V / 100
    p = write_ply(tmp_path / "m.ply", metres, F, {"plant": PLANT, "leaf": LEAF})
    with pytest.raises(MaizevizError, match="0.81 units tall.*metre") as exc:
        read_mesh_canopy(p)
    assert exc.value.quantity == "mesh_unit"
    canopy, _, _ = read_mesh_canopy(p, unit="m")
    assert np.allclose(canopy.vertices, V[:8], rtol=0, atol=1e-12)
    tall = V * [1, 1, 2]                                  # 162 cm tall: 1620 mm
    mm = write_ply(tmp_path / "mm.ply", tall * 10, F, {"plant": PLANT, "leaf": LEAF})
    with pytest.raises(MaizevizError, match="1620 units tall.*millimetre"):
        read_mesh_canopy(mm)
    assert np.allclose(read_mesh_canopy(mm, unit="mm")[0].vertices, tall[:8])
    assert read_mesh_canopy(p, unit="cm")[0].vertices.max() < 1          # told: read as it is
    yup = write_ply(tmp_path / "y.ply", V[:, [0, 2, 1]] * [1, 1, -1], F,
                    {"plant": PLANT, "leaf": LEAF})
    canopy, _, _ = read_mesh_canopy(yup, up="y")
    assert np.array_equal(canopy.vertices, V[:8])


def test_the_field_is_given_or_the_bounding_box(tmp_path):
    p = write_ply(tmp_path / "m.ply", V, F, {"plant": PLANT, "leaf": LEAF})
    canopy, _, notes = read_mesh_canopy(p, field=(-10, -20, 70, 30))
    assert canopy.layout.bounds == (-10, -20, 70, 30)
    assert canopy.layout.ground_area_cm2 == 80 * 50
    _, _, notes = read_mesh_canopy(p, field=(0, 0, 20, 20))
    assert any("stand outside the field: 7" in n for n in notes)
    for bad in [(0, 0, 0, 10), (0, 0, float("nan"), 1), (0, 0, 1e9, 1)]:
        with pytest.raises(MaizevizError) as exc:
            read_mesh_canopy(p, field=bad)
        assert exc.value.quantity == "field"


# ------------------------------------------------------------------------------ hostile input
def _hostile(tmp_path):
    """name -> (file bytes, words the error must hold)."""
    good = write_ply(tmp_path / "g.ply", V, F, {"plant": PLANT, "leaf": LEAF},
                     "binary_little_endian").read_bytes()
    asc = write_ply(tmp_path / "a.ply", V, F, {"plant": PLANT, "leaf": LEAF}).read_bytes()
    head = good[:good.index(b"end_header\n") + 11]
    cases = {
        "empty.ply": (b"", "empty"),
        "empty.obj": (b"", "empty"),
        "truncated.ply": (good[:-7], "cut short"),
        "truncated_vertices.ply": (good[:len(head) + 30], "cut short"),
        "more_data.ply": (good + b"\x01\x02\x03\x04", "do not match"),
        "ascii_more_lines.ply": (asc + b"3 0 1 2 1 1\n", "more lines than the header"),
        "ascii_fewer_lines.ply": (asc[:asc.rindex(b"3 8 9 10")], "cut short"),
        "huge_count.ply": (head.replace(b"element face 5", b"element face 1000000000000")
                           + good[len(head):], "1,000,000,000,000 face"),
        "huge_vertices.ply": (head.replace(b"element vertex 11", b"element vertex 99999999999")
                              + good[len(head):], "only"),
        "index.ply": (asc.replace(b"3 8 9 10", b"3 8 9 11"), "vertex index 11 is out of range"),
        "negative_index.ply": (asc.replace(b"3 8 9 10", b"3 8 -1 10"), "out of range"),
        "nan.ply": (asc.replace(b"45.0 5.0 0.0", b"45.0 nan 0.0"), "y is nan"),
        "inf.ply": (asc.replace(b"45.0 5.0 0.0", b"45.0 5.0 inf"), "z is inf"),
        "text.ply": (asc.replace(b"45.0 5.0 0.0", b"45.0 five 0.0"), "'five' is not a number"),
        "two_vertices.ply": (asc.replace(b"3 8 9 10 7 0", b"2 8 9 7 0"), "needs at least 3"),
        "leaf_id.ply": (asc.replace(b"3 8 9 10 7 0", b"3 8 9 10 7 2147483648"),
                        "leaf is 2147483648, beyond the range of its type int32"),
        "float_index.ply": (asc.replace(b"3 8 9 10 7 0", b"3 8 9.5 10 7 0"), "whole number"),
        "long_value.ply": (asc.replace(b"45.0 5.0 0.0", b"45.0 5.0 " + b"1" * 10_000_000),
                           "a value of 10,000,000 characters"),
        "junk.ply": (bytes(range(256)) * 20, "not a PLY file"),
        "junk_header.ply": (b"ply\nformat ascii 1.0\n\xff\xfe\nend_header\n", "not ASCII"),
        "no_end.ply": (b"ply\nformat ascii 1.0\nelement vertex 3\n", "end_header"),
        "format.ply": (b"ply\nformat binary_middle_endian 1.0\nend_header\n", "format"),
        "no_face.ply": (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                        b"property float y\nproperty float z\nend_header\n0 0 0\n", "no face"),
        "no_faces.ply": (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                         b"property float y\nproperty float z\nelement face 0\nproperty list "
                         b"uchar int vertex_indices\nproperty int leaf\nend_header\n0 0 0\n",
                         "no faces"),
        "no_ids.ply": (asc.replace(b"property int plant\nproperty int leaf\n",
                                   b"property int colour\nproperty int other\n"),
                       "carry no plant or leaf id (face properties: colour, other)"),
        "junk.obj": (bytes(range(256)) * 20, "not UTF-8"),
        "csv.obj": (b"plant,leaf,row,col,x,y,z\n1,1,0,0,0,0,0\n", "not an OBJ statement"),
        "index.obj": (b"v 0 0 1\nv 1 0 1\nv 0 1 1\ng leaf1\nf 1 2 4\n", "out of range"),
        "zero.obj": (b"v 0 0 1\nv 1 0 1\nv 0 1 1\ng leaf1\nf 0 1 2\n", "not a face"),
        "negative.obj": (b"v 0 0 1\nv 1 0 1\nv 0 1 1\ng leaf1\nf -1 -2 -4\n",
                         "before the first vertex"),
        "nan.obj": (b"v 0 0 1\nv 1 nan 1\nv 0 1 1\ng leaf1\nf 1 2 3\n", "y is nan"),
        "short.obj": (b"v 0 0 1\nv 1 0 1\ng leaf1\nf 1 2\n", "needs at least 3"),
        "nofaces.obj": (b"v 0 0 1\nv 1 0 1\nv 0 1 1\n", "no faces"),
        "nogroups.obj": (b"v 0 0 1\nv 1 0 1\nv 0 1 1\nf 1 2 3\n", "no o or g names"),
        "ungrouped.obj": (b"v 0 0 1\nv 1 0 1\nv 0 1 1\nf 1 2 3\ng leaf1\nf 1 2 3\n",
                          "line 4: a face before any o or g"),
        "surface.obj": (b"v 0 0 1\ncstype bspline\n", "free-form"),
        "degenerate.obj": (b"v 0 0 10\nv 1 0 10\nv 2 0 10\ng leaf1\nf 1 2 3\nf 1 1 2\n",
                           "degenerate"),
        "stalks_only.obj": (b"v 0 0 10\nv 1 0 10\nv 0 1 10\ng plant1_stalk\nf 1 2 3\n",
                            "no leaf triangle"),
        "far.obj": (b"v 0 0 10\nv 1 0 10\nv 0 1e12 10\ng leaf1\nf 1 2 3\n", "beyond"),
    }
    return cases


@pytest.mark.parametrize("name", [
    "empty.ply", "empty.obj", "truncated.ply", "truncated_vertices.ply", "more_data.ply",
    "ascii_more_lines.ply", "ascii_fewer_lines.ply", "huge_count.ply", "huge_vertices.ply",
    "index.ply", "negative_index.ply", "nan.ply", "inf.ply", "text.ply", "two_vertices.ply",
    "leaf_id.ply", "float_index.ply", "long_value.ply", "junk.ply", "junk_header.ply", "no_end.ply",
    "format.ply", "no_face.ply", "no_faces.ply", "no_ids.ply", "junk.obj", "csv.obj",
    "index.obj", "zero.obj", "negative.obj", "nan.obj", "short.obj", "nofaces.obj",
    "nogroups.obj", "ungrouped.obj", "surface.obj", "degenerate.obj", "stalks_only.obj",
    "far.obj"])
def test_hostile_mesh_files_are_one_line_naming_file_and_place(tmp_path, capsys, name):
    data, words = _hostile(tmp_path)[name]
    p = tmp_path / name
    p.write_bytes(data)
    out = tmp_path / "leaf.csv"
    t0 = time.perf_counter()
    code = main(["light", str(p), "--mesh-unit", "cm", *SUN, "--leaf-light", str(out)])
    assert time.perf_counter() - t0 < 20
    line = _one_error(capsys)
    assert code == EXIT_FAIL and words in line and str(p) in line, line
    assert not out.exists()


def test_a_huge_declared_count_is_refused_before_allocating(tmp_path):
    import resource

    p = tmp_path / "huge.ply"
    p.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                  b"property float y\nproperty float z\nelement face 1000000000000\n"
                  b"property list uchar int vertex_indices\nend_header\n" + b"\0" * 100)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.perf_counter()
    with pytest.raises(MeshFileError, match="1,000,000,000,000 face items"):
        read_mesh(p)
    assert time.perf_counter() - t0 < 1
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 50_000     # KiB


def test_not_a_regular_file_and_a_folder(tmp_path, capsys):
    fifo = tmp_path / "pipe.ply"
    os.mkfifo(fifo)
    assert main(["canopy", str(fifo)]) == EXIT_FAIL
    assert "FIFO" in _one_error(capsys)
    (tmp_path / "dir.obj").mkdir()
    assert main(["canopy", str(tmp_path / "dir.obj")]) == EXIT_FAIL
    assert "folder" in _one_error(capsys)


@pytest.mark.parametrize("argv, flag", [
    (["--tile", "3x3"], "--tile"), (["--interp", "2"], "--interp"),
    (["--levels"], "--levels"), (["--layout", "x.json"], "--layout"),
    (["--no-preserve-area"], "--no-preserve-area"),
])
def test_digitized_options_are_refused_with_a_mesh(tmp_path, capsys, argv, flag):
    p = write_ply(tmp_path / "m.ply", V, F, {"plant": PLANT, "leaf": LEAF})
    assert main(["light", str(p), *SUN, *argv]) == EXIT_FAIL
    line = _one_error(capsys)
    assert flag in line and "traced as it is" in line


@pytest.mark.parametrize("argv, flag", [
    (["--mesh-unit", "m"], "--mesh-unit"), (["--field", "0,0,1,1"], "--field"),
    (["--up", "y"], "--up")])
def test_mesh_options_are_refused_with_points(capsys, argv, flag):
    assert main(["canopy", B, *argv]) == EXIT_FAIL
    assert flag in _one_error(capsys)


def test_mesh_option_errors_name_their_flag(tmp_path, capsys):
    p = write_ply(tmp_path / "m.ply", V / 100, F, {"plant": PLANT, "leaf": LEAF})
    assert main(["canopy", str(p)]) == EXIT_FAIL
    assert _one_error(capsys).endswith("(--mesh-unit)")
    assert main(["canopy", str(p), "--mesh-unit", "m", "--field", "0,0,-1,1"]) == EXIT_FAIL
    assert _one_error(capsys).endswith("(--field)")
    assert main(["canopy", str(p), "--mesh-unit", "m", "--mesh-leaf", "nope"]) == EXIT_FAIL
    assert _one_error(capsys).endswith("(--mesh-plant/--mesh-leaf)")


# ------------------------------------------------------------------------------ light
@pytest.fixture(scope="module")
def digitized():
    """The bundled block tiled 3 x 3 at the standard mesh, and its PLY export."""
    found = read_leaves(B)
    layout = layout_for(found.leaves, (3, 3))
    return build_canopy(found.leaves, layout, Level(interp=0))


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_the_export_carries_ids_and_reads_back_exactly(tmp_path, digitized):
    for ext in ("ply", "obj"):
        p = export_canopy(tmp_path / f"c.{ext}", digitized)
        canopy, mesh, notes = read_mesh_canopy(p, unit="cm")
        assert canopy.n_triangles == digitized.n_triangles
        assert np.array_equal(canopy.faces, digitized.faces)
        assert np.array_equal(canopy.stalk_faces, digitized.stalk_faces)
        tol = 0 if ext == "ply" else 5e-7                  # OBJ is written with 6 decimals
        assert np.abs(canopy.vertices - digitized.vertices).max() <= tol
        assert np.array_equal(canopy.face_leaf, digitized.face_leaf)
        assert np.array_equal(canopy.face_instance, digitized.face_instance)
        assert np.array_equal(canopy.leaves_per_instance, digitized.leaves_per_instance)
        # plant ids of the file are the export's placement numbers
        assert np.array_equal(canopy.face_plant, digitized.face_instance + 1)
        # re-exported, the mesh canopy writes the same ids and stalks
        again = canopy_cells(canopy)
        first = canopy_cells(digitized)
        assert np.array_equal(again[2]["plant"], first[2]["plant"])
        assert np.array_equal(again[2]["leaf"], first[2]["leaf"])


@pytest.mark.parametrize("periodic", [False, True])
def test_light_of_the_exported_canopy_is_the_same(tmp_path, capsys, periodic):
    """`maizeviz canopy --export x.ply` then `maizeviz light x.ply`, no field nor rectangle
    given: the file carries its plot and its tiling's period, so the same sample rectangle,
    the same transmission and the same light per leaf as the digitized canopy (real Embree,
    through the CLI)."""
    ply = tmp_path / "c.ply"
    assert main(["canopy", B, "--tile", "3x3", "--interp", "0", "--export", str(ply),
                 "--json"]) == EXIT_OK
    common = [*SUN, "--density", "1", "--json", "--sky", "soc", "--sky-directions", "16",
              "--band", "par", "--depth", "2"] + (["--periodic"] if periodic else [])
    capsys.readouterr()
    assert main(["light", B, "--tile", "3x3", "--interp", "0", *common,
                 "--leaf-light", str(tmp_path / "o.csv")]) == EXIT_OK
    orig = json.loads(capsys.readouterr().out)
    assert main(["light", str(ply), *common, "--leaf-light", str(tmp_path / "m.csv")]) == EXIT_OK
    back = json.loads(capsys.readouterr().out)
    assert back["level"] == "mesh" and back["triangles"] == orig["triangles"]
    assert back["rect_cm"] == orig["rect_cm"]
    # in a periodic field the sensors are read over the carried period, checked against the
    # triangles, as over the digitized canopy's block: ray for ray the same
    assert back["transmission"] == orig["transmission"]
    assert back["diffuse"]["transmission"] == orig["diffuse"]["transmission"]
    assert back["diffuse"]["intercepted_fraction"] == orig["diffuse"]["intercepted_fraction"]
    assert back["balance"] == orig["balance"]                  # absorbed, with scattering
    o_rows, m_rows = _rows(tmp_path / "o.csv"), _rows(tmp_path / "m.csv")
    cols = ["sunlit_area_cm2", "second_class_area_cm2", "sunlit_intercepted_cm2",
            "second_class_intercepted_cm2", "diffuse_intercepted_cm2", "absorbed_w"]
    if not periodic:
        # leaf by leaf: the same leaves, the same light; the plant column is the file's id
        assert [(r["instance"], r["leaf"]) for r in m_rows] == \
            [(r["instance"], r["leaf"]) for r in o_rows]
        for o, m in zip(o_rows, m_rows):
            assert m["plant"] == o["instance"]
            for k in cols + ["leaf_area_cm2", "x_cm", "y_cm"]:
                assert float(m[k]) == pytest.approx(float(o[k]), rel=1e-12, abs=1e-9), k
    else:
        # the digitized canopy folds the copies of a plant into the copy inside the sample
        # rectangle; the mesh's plants are all different, so add its copies up
        found = read_leaves(B)
        layout = layout_for(found.leaves, (3, 3))
        from maizeviz.light.results.per_leaf import tile_representatives

        rep = tile_representatives(layout, tuple(orig["rect_cm"]), True)
        sums: dict = {}
        for m in m_rows:
            key = (int(rep[int(m["instance"]) - 1]) + 1, int(m["leaf"]))
            d = sums.setdefault(key, dict.fromkeys(cols, 0.0))
            for k in cols:
                d[k] += float(m[k])
        assert sorted(sums) == sorted((int(o["instance"]), int(o["leaf"])) for o in o_rows)
        for o in o_rows:
            d = sums[(int(o["instance"]), int(o["leaf"]))]
            for k in cols:
                if k.endswith("area_cm2"):             # capped per row at the leaf's area
                    continue
                assert d[k] == pytest.approx(float(o[k]), rel=1e-9, abs=1e-9), k


def test_a_day_through_the_exported_canopy_equals_the_points_run(tmp_path, capsys):
    """Issue 25 case 7: a periodic day through the exported mesh differed from the points run
    in one sensor of 1,764 (the mesh did not know its period); with the period carried every
    number of the day is the same."""
    ply = tmp_path / "c.ply"
    assert main(["canopy", B, "--tile", "3x3", "--triangles", "36", "--export", str(ply),
                 "--json"]) == EXIT_OK
    day = ["--periodic", "--density", "1", "--json", "--date", "2005-08-01", "--lat", "39.9",
           "--lon", "116.4", "--tz", "Asia/Shanghai", "--day", "--step", "120",
           "--sky-directions", "16"]
    capsys.readouterr()
    assert main(["light", B, "--tile", "3x3", "--triangles", "36", *day]) == EXIT_OK
    orig = json.loads(capsys.readouterr().out)
    assert main(["light", str(ply), *day]) == EXIT_OK
    back = json.loads(capsys.readouterr().out)
    for rec in (orig, back):
        for k in ("seconds", "level", "triangles"):
            rec.pop(k)
    assert back == orig


def test_light_and_canopy_on_a_small_mesh(tmp_path, capsys):
    """Per-leaf and per-plant tables name the file's ids; stalks count only when asked."""
    p = write_ply(tmp_path / "m.ply", V, F, {"plant": PLANT, "leaf": LEAF})
    leaf_csv, plant_csv = tmp_path / "l.csv", tmp_path / "p.csv"
    assert main(["light", str(p), "--sun-zenith", "0", "--sun-azimuth", "0", "--density", "4",
                 "--heights", "0", "--leaf-light", str(leaf_csv), "--plant-light",
                 str(plant_csv), "--json"]) == EXIT_OK
    rec = json.loads(capsys.readouterr().out)
    # two 10 x 10 squares over a 50 x 10 field: 40% intercepted from straight above
    assert rec["transmission"][0] == pytest.approx(0.6, abs=0.01)
    rows = _rows(leaf_csv)
    assert [(r["plant"], r["leaf"]) for r in rows] == [("3", "2"), ("7", "5")]
    assert [r["plant"] for r in _rows(plant_csv)] == ["3", "7"]
    assert main(["canopy", str(p), "--json", "--export", str(tmp_path / "o.obj")]) == EXIT_OK
    m = json.loads(capsys.readouterr().out)
    assert m["plants"] == 2 and m["leaves"] == 2 and m["triangles"] == 4
    assert m["leaf_area_m2"] == pytest.approx(200.0 / 1e4, rel=0.05)
    assert m["ground_area_m2"] == pytest.approx(500 / 1e4)
    text = (tmp_path / "o.obj").read_text()
    assert "g plant1_leaf2" in text and "g plant2_leaf5" in text and "g plant2_leaf0" in text


def test_degenerate_triangles_are_kept_and_said(tmp_path):
    faces = F + [[0, 0, 1], [0, 1, 1]]
    p = write_ply(tmp_path / "d.ply", V, faces, {"plant": PLANT + [3, 3], "leaf": LEAF + [2, 2]})
    canopy, mesh, notes = read_mesh_canopy(p)
    assert canopy.n_triangles == 6 and mesh.n_triangles == 7
    assert any("2 of the 6 leaf triangles have no area (first: face 5" in n for n in notes)


def test_stalks_intercept_unless_leaves_only(tmp_path, capsys):
    """Leaf 0 is the stalk: out of the leaves, in the light unless --leaves-only."""
    verts = np.vstack([V[:8], [[20, 0, 0], [30, 0, 0], [30, 10, 0.5], [20, 10, 0.5]]])
    faces = F[:4] + [[8, 9, 10], [8, 10, 11]]
    p = write_ply(tmp_path / "s.ply", verts, faces,
                  {"plant": [3, 3, 7, 7, 7, 7], "leaf": [2, 2, 5, 5, 0, 0]})
    runs = []
    for extra in (["--leaves-only"], []):
        assert main(["light", str(p), "--mesh-unit", "cm", "--sun-zenith", "0",
                     "--sun-azimuth", "0", "--heights", "0", "--density", "4", "--json",
                     *extra]) == EXIT_OK
        runs.append(json.loads(capsys.readouterr().out)["transmission"][0])
    assert runs[0] == pytest.approx(0.6, abs=0.01) and runs[1] == pytest.approx(0.4, abs=0.01)


@pytest.mark.parametrize("text, want", [("0, 0, 540, 270", (0.0, 0.0, 540.0, 270.0)),
                                        ("-10 -5 20.5 1e2", (-10.0, -5.0, 20.5, 100.0)),
                                        (" 1,2 ,3, 4 ", (1.0, 2.0, 3.0, 4.0))])
def test_a_field_typed_as_text_reads_as_its_four_numbers(text, want):
    from maizeviz.canopy.from_mesh import check_field

    assert check_field(text) == want


@pytest.mark.parametrize("text, says", [("", "got 0"), ("1, 2, 3", "got 3"),
                                        ("1, 2, x, 4", "'1, 2, x, 4'"), ("0 0 0 10", "x1 > x0"),
                                        ("0 0 nan 10", "finite"), ("0 0 1e9 10", "finite"),
                                        ("-0,-0,1e-300,1e-300", "less than 1 cm")])
def test_a_bad_field_text_is_one_line_naming_the_field(text, says):
    from maizeviz.canopy.from_mesh import check_field

    with pytest.raises(MaizevizError, match="field") as err:
        check_field(text)
    assert says in str(err.value) and err.value.quantity == "field"


def test_a_field_without_any_plant_is_one_line(tmp_path):
    from maizeviz.canopy.from_mesh import read_mesh_canopy

    ply = tmp_path / "c.ply"
    assert main(["canopy", B, "--tile", "1x1", "--interp", "0", "--export", str(ply)]) == EXIT_OK
    with pytest.raises(MaizevizError, match="none of the 9 plants stands in the field") as err:
        read_mesh_canopy(ply, "cm", "z", (1000.0, 1000.0, 1100.0, 1100.0))
    assert err.value.quantity == "field" and "\n" not in str(err.value)
