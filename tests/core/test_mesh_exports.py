"""Mesh exports open elsewhere with their arrays (issue 27): every format written by
``maizeviz light --export`` read back with pyvista (VTK's readers, as ParaView) and meshio,
each array compared with the per-leaf table of the same run, the plot and the period carried.

Where a reader cannot hold the values, the test says which and reads them another way: VTK's
PLY reader reads no face property (pyvista and ParaView show the PLY's geometry; plyfile and
trimesh read its arrays), meshio's binary PLY reader misreads any face property of a valid
binary PLY, meshio has no VTP reader, and OBJ and STL carry no arrays (OBJ its groups).
"""

from __future__ import annotations

import csv
import json

import meshio
import numpy as np
import pytest
import pyvista

from maizeviz.canopy.from_mesh import read_mesh_canopy
from maizeviz.canopy.layout import layout_for
from maizeviz.cli import EXIT_OK, main
from maizeviz.leaf.fit import read_leaves
from maizeviz.light.results.per_leaf import tile_representatives
from maizeviz.resources import example_points

B = str(example_points())
#: a sun, a 6-direction overcast sky and absorbed PAR, on the bundled block tiled 3 x 3 at 8
#: triangles a leaf in a periodic field: small and quick, every array of a light export
RUN = ["--tile", "3x3", "--triangles", "8", "--periodic", "--density", "1", "--sun-zenith",
       "30", "--sun-azimuth", "120", "--sky", "soc", "--sky-directions", "6", "--band", "par",
       "--depth", "1", "--json"]
LIGHT = ("sun_class", "diffuse_cm2_per_cm2_leaf", "absorbed_w_per_m2_leaf")


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """One light run exported in every format: {ext: path}, the leaf table, the JSON."""
    tmp = tmp_path_factory.mktemp("exports")
    paths = {}
    for ext in (".vtu", ".vtp", ".vtk", ".ply", ".obj", ".stl"):
        paths[ext] = tmp / f"light{ext}"
        table = tmp / f"leaves{ext}.csv"
        assert main(["light", B, *RUN, "--export", str(paths[ext]),
                     "--leaf-light", str(table)]) == EXIT_OK
    with open(table, newline="") as fh:
        rows = list(csv.DictReader(fh))
    found = read_leaves(B)
    layout = layout_for(found.leaves, (3, 3))
    return paths, rows, layout


def _expected(rows, layout, plant, leaf):
    """Per triangle (plant id = placement number, leaf rank) the table's values: the row of
    the copy standing for the triangle's plant in the sample rectangle (a tile-periodic
    field reports copies together)."""
    rect = layout.centre_bounds
    rep = tile_representatives(layout, rect, True)
    by = {(int(r["instance"]), int(r["leaf"])): r for r in rows}
    out = {k: np.full(len(plant), np.nan) for k in ("diffuse", "absorbed", "sunlit")}
    for t, (p, lf) in enumerate(zip(plant, leaf)):
        if lf == 0:
            continue
        r = by.get((int(rep[p - 1]) + 1, int(lf)))
        area = float(r["leaf_area_cm2"]) if r else 1.0
        out["diffuse"][t] = float(r["diffuse_intercepted_cm2"]) / area if r else 0.0
        out["absorbed"][t] = float(r["absorbed_w_m2_leaf"]) if r else 0.0
        out["sunlit"][t] = float(r["sunlit_intercepted_cm2"]) if r else 0.0
    return out


def _check_arrays(get, rows, layout):
    """The arrays of an export (``get(name)`` -> (F,) array) against the leaf table."""
    plant, leaf = np.asarray(get("plant")), np.asarray(get("leaf"))
    want = _expected(rows, layout, plant, leaf)
    is_leaf = leaf > 0
    np.testing.assert_allclose(np.asarray(get("diffuse_cm2_per_cm2_leaf"))[is_leaf],
                               want["diffuse"][is_leaf], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(np.asarray(get("absorbed_w_per_m2_leaf"))[is_leaf],
                               want["absorbed"][is_leaf], rtol=1e-12, atol=1e-12)
    sun = np.asarray(get("sun_class"))
    assert set(np.unique(sun[is_leaf])) <= {0, 1, 2} and (sun[is_leaf] == 2).any()
    # a triangle in direct light belongs to a leaf the table says is sunlit
    assert (want["sunlit"][is_leaf & (sun == 2)] > 0).all()
    # stalks: leaf 0, no light value
    assert np.isnan(np.asarray(get("absorbed_w_per_m2_leaf"))[~is_leaf]).all()
    assert (plant >= 1).all() and plant.max() == len(layout.placements)


@pytest.mark.parametrize("ext", [".vtu", ".vtp", ".vtk"])
def test_vtk_files_open_in_pyvista_with_every_array_and_the_plot(exported, ext):
    paths, rows, layout = exported
    mesh = pyvista.read(paths[ext])
    assert set(mesh.cell_data.keys()) == {"plant", "leaf", *LIGHT}
    assert mesh.cell_data["plant"].dtype == np.int32
    _check_arrays(lambda k: mesh.cell_data[k], rows, layout)
    assert tuple(mesh.field_data["field_cm"]) == layout.bounds
    assert tuple(mesh.field_data["period_cm"]) == layout.centre_bounds


@pytest.mark.parametrize("ext", [".vtu", ".vtk"])
def test_vtk_files_open_in_meshio_with_every_array(exported, ext):
    paths, rows, layout = exported
    mesh = meshio.read(paths[ext])
    assert [c.type for c in mesh.cells] == ["triangle"]
    data = {k: np.concatenate(v).ravel() for k, v in mesh.cell_data.items()}
    assert set(data) == {"plant", "leaf", *LIGHT}
    _check_arrays(data.__getitem__, rows, layout)
    if ext == ".vtu":                      # meshio's legacy reader keeps no field data
        assert tuple(mesh.field_data["field_cm"]) == layout.bounds


def test_the_three_vtk_files_hold_the_same_mesh(exported):
    paths, _, _ = exported
    meshes = [pyvista.read(paths[e]) for e in (".vtu", ".vtp", ".vtk")]
    for m in meshes[1:]:
        assert np.array_equal(m.points, meshes[0].points)
        assert m.n_cells == meshes[0].n_cells
        for k in meshes[0].cell_data.keys():
            np.testing.assert_array_equal(m.cell_data[k], meshes[0].cell_data[k])


def test_ply_arrays_read_by_plyfile_and_trimesh_geometry_by_pyvista(exported):
    import plyfile
    import trimesh

    paths, rows, layout = exported
    ply = plyfile.PlyData.read(str(paths[".ply"]))
    face = ply["face"]
    types = {p.name: p.val_dtype for p in face.properties}
    assert types["plant"] == "i4" and types["sun_class"] == "i4"
    assert types["absorbed_w_per_m2_leaf"] == "f8"
    header = paths[".ply"].read_bytes()[:2000]
    assert b"property int plant" in header and b"property double absorbed_w_per_m2_leaf" in header
    assert b"float64" not in header and b"int32" not in header     # the standard's names
    _check_arrays(lambda k: face.data[k], rows, layout)
    assert any(c.startswith("maizeviz field_cm") for c in ply.comments)
    raw = trimesh.load(paths[".ply"], process=False).metadata["_ply_raw"]["face"]["data"]
    np.testing.assert_array_equal(raw["absorbed_w_per_m2_leaf"], face.data["absorbed_w_per_m2_leaf"])
    vtk = pyvista.read(paths[".vtu"])
    geometry = pyvista.read(paths[".ply"])  # VTK's PLY reader: geometry only, float32 points
    assert geometry.n_cells == vtk.n_cells
    np.testing.assert_array_equal(geometry.points, vtk.points.astype(np.float32))


def test_obj_groups_are_leaves_in_pyvista_and_meshio(exported):
    paths, _, _ = exported
    vtk = pyvista.read(paths[".vtu"])
    plant, leaf = vtk.cell_data["plant"], vtk.cell_data["leaf"]
    key = plant.astype(np.int64) * 100_000 + leaf
    runs = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    obj = pyvista.read(paths[".obj"])
    groups = obj.cell_data["GroupIds"]
    assert obj.n_cells == vtk.n_cells and np.allclose(obj.points, vtk.points, rtol=0, atol=0)
    # one group per leaf run, in order: the group id changes exactly where the leaf does
    assert np.array_equal(np.flatnonzero(np.r_[True, groups[1:] != groups[:-1]]), runs)
    ids = np.concatenate(meshio.read(paths[".obj"]).cell_data["obj:group_ids"])
    assert len(np.unique(ids)) == len(runs)
    text = paths[".obj"].read_text()
    assert "# maizeviz field_cm" in text and "# maizeviz period_cm" in text


def test_stl_holds_the_triangles(exported):
    paths, _, _ = exported
    assert meshio.read(paths[".stl"]).cells[0].data.shape == (pyvista.read(paths[".vtu"]).n_cells, 3)


# ------------------------------------------------------------------------------ round trips
@pytest.mark.parametrize("ext", [".ply", ".obj"])
def test_an_exported_canopy_comes_back_with_its_plot_and_period(tmp_path, capsys, ext):
    """Read again without --field: the same ground, LAI and ground cover."""
    path = tmp_path / f"c{ext}"
    assert main(["canopy", B, "--tile", "3x3", "--triangles", "8", "--json", "--export",
                 str(path)]) == EXIT_OK
    orig = json.loads(capsys.readouterr().out)
    assert main(["canopy", str(path), "--json"]) == EXIT_OK
    back = json.loads(capsys.readouterr().out)
    for k in ("ground_area_m2", "lai", "ground_cover_m2", "leaf_area_m2", "plants", "leaves"):
        assert back[k] == orig[k], k
    canopy, _, notes = read_mesh_canopy(path)
    layout = layout_for(read_leaves(B).leaves, (3, 3))
    assert canopy.layout.bounds == layout.bounds
    assert canopy.layout.period == layout.centre_bounds == canopy.layout.centre_bounds
    assert any("the field is the file's" in n for n in canopy.layout.warnings)


def test_an_explicit_field_wins_and_a_plain_mesh_takes_its_bounding_box(tmp_path, capsys):
    path = tmp_path / "c.ply"
    assert main(["canopy", B, "--tile", "3x3", "--triangles", "8", "--export",
                 str(path)]) == EXIT_OK
    canopy, _, notes = read_mesh_canopy(path, field=(-200, -100, 400, 200))
    assert canopy.layout.bounds == (-200, -100, 400, 200) and canopy.layout.period is None
    assert any("period is for its own field" in n for n in notes)
    # the same mesh without the comments: the bounding box, as before
    raw = path.read_bytes()
    head = raw[:raw.index(b"end_header")]
    plain = tmp_path / "plain.ply"
    plain.write_bytes(b"".join(ln + b"\n" for ln in head.split(b"\n")
                               if not ln.startswith(b"comment maizeviz "))[:-1]
                      + raw[len(head):])
    canopy, _, _ = read_mesh_canopy(plain)
    assert canopy.layout.period is None
    assert canopy.layout.bounds != read_mesh_canopy(path)[0].layout.bounds
    assert "bounding box" in canopy.layout.warnings[0]


def test_a_broken_carried_field_is_one_line_naming_the_comment(tmp_path):
    from maizeviz.errors import MaizevizError

    path = tmp_path / "c.obj"
    assert main(["canopy", B, "--tile", "1x1", "--triangles", "4", "--export",
                 str(path)]) == EXIT_OK
    text = path.read_text().replace("# maizeviz field_cm ", "# maizeviz field_cm 5 ", 1)
    path.write_text(text)
    with pytest.raises(MaizevizError, match=r"line 2: the field_cm the file carries: the "
                                            r"field needs 4 numbers") as exc:
        read_mesh_canopy(path)
    assert exc.value.quantity == "field"
    # a field given does not read the comment
    assert read_mesh_canopy(path, field=(-100, -100, 200, 200))[0].layout.bounds == \
        (-100, -100, 200, 200)


def test_the_carried_period_is_used_only_when_the_triangles_repeat_with_it(tmp_path):
    """The light reads the sensors over a carried period only after checking it: a mesh one
    of whose leaves moved by a millimetre in one tile keeps the plot as its period."""
    from maizeviz.io.meshfile import write_mesh
    from maizeviz.light.scene.embree_scenes import light_scene

    path = tmp_path / "c.ply"
    assert main(["canopy", B, "--tile", "3x3", "--triangles", "8", "--export",
                 str(path)]) == EXIT_OK
    canopy, mesh, _ = read_mesh_canopy(path)
    scene = light_scene(canopy, periodic=True)
    assert (scene.period.w, scene.period.h) == (180.0, 90.0)          # the block, checked
    assert (scene.wrap.w, scene.wrap.h) == (540.0, 270.0)             # the plot
    v = mesh.vertices.copy()
    v[mesh.faces[len(mesh.faces) // 2, 0], 0] += 0.1                  # one vertex, 1 mm
    moved = tmp_path / "moved.ply"
    write_mesh(moved, v, mesh.faces, {"plant": mesh.plant, "leaf": mesh.leaf},
               field_cm=canopy.layout.bounds, period_cm=canopy.layout.period)
    bent, _, _ = read_mesh_canopy(moved)
    assert bent.layout.period == canopy.layout.period                  # claimed...
    scene = light_scene(bent, periodic=True)
    assert (scene.period.w, scene.period.h) == (540.0, 270.0)          # ...not believed


def test_a_leaf_models_assimilation_is_exported_per_triangle(tmp_path):
    """`--photosynthesis c4 --export`: each leaf triangle carries its leaf's gross umol CO2
    per m2 of leaf per s, the leaf table's gross_umol_s over its area (copies of a plant in
    the periodic field take their representative's); stalks none."""
    path, table = tmp_path / "carbon.vtp", tmp_path / "leaves.csv"
    assert main(["light", B, "--tile", "3x3", "--triangles", "8", "--periodic", "--density",
                 "1", "--sun-zenith", "30", "--sun-azimuth", "120", "--photosynthesis", "c4",
                 "--json", "--export", str(path), "--leaf-light", str(table)]) == EXIT_OK
    with open(table, newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r.get("gross_umol_s")]
    mesh = pyvista.read(path)
    plant, leaf = np.asarray(mesh.cell_data["plant"]), np.asarray(mesh.cell_data["leaf"])
    got = np.asarray(mesh.cell_data["gross_umol_co2_per_m2_leaf_s"])
    layout = layout_for(read_leaves(B).leaves, (3, 3))
    rep = tile_representatives(layout, layout.centre_bounds, True)
    by = {(int(r["instance"]), int(r["leaf"])): r for r in rows}
    want = np.full(len(plant), np.nan)
    for t, (p, lf) in enumerate(zip(plant, leaf)):
        if lf > 0:
            r = by.get((int(rep[p - 1]) + 1, int(lf)))
            want[t] = float(r["gross_umol_s"]) / (float(r["leaf_area_cm2"]) * 1e-4) \
                if r else 0.0
    is_leaf = leaf > 0
    np.testing.assert_allclose(got[is_leaf], want[is_leaf], rtol=1e-9, atol=1e-12)
    assert np.nanmax(got) > 1.0 and np.isnan(got[~is_leaf]).all()
