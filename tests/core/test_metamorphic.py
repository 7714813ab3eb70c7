"""Metamorphic tests: the oracle is the data itself.

A result may not depend on how its inputs are ordered (heights, levels, plants, rows of a
file) nor on a duplicate entry (refused in one line, or counted once and reported): each test
runs one computation twice, on inputs that mean the same thing, and compares the numbers.
"""

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import Phase, given, settings
from hypothesis import strategies as st

from maizeviz.canopy.build import Canopy
from maizeviz.canopy.layout import layout_from_dict
from maizeviz.cli import main
from maizeviz.light.scene.request import LightRequest, Sampling
from maizeviz.light.sources.irradiance import clear_sky_period
from maizeviz.light.sources.sky import make_sky
from maizeviz.light.sources.sun import Sun
from maizeviz.light.trace.beam import trace_light
from maizeviz.light.trace.directions import trace_period, trace_sky
from tests.core.test_mesh_canopy import write_obj, write_ply

BLOCK = str(Path(__file__).resolve().parents[2] / "maizeviz/resources/block3x3.csv")


def _plot():
    return layout_from_dict({"maizeviz_layout": 1, "row_spacing": 60, "plant_spacing": 30,
                             "field": {"x0": 0, "y0": 0, "x1": 100, "y1": 100},
                             "rows": [{"x": 50, "plants": [{"y": 50, "plant": 1}]}]})


def _squares(seed: int, n: int = 60) -> Canopy:
    """n horizontal squares at random places and heights (5 to 150 cm) in a 100 cm plot."""
    rng = np.random.default_rng(seed)
    v, f = [], []
    for k, (x, y, a, z) in enumerate(zip(rng.uniform(0, 90, n), rng.uniform(0, 90, n),
                                         rng.uniform(2, 15, n), rng.uniform(5, 150, n))):
        v += [[x, y, z], [x + a, y, z], [x + a, y + a, z], [x, y + a, z]]
        f += [[4 * k, 4 * k + 1, 4 * k + 2], [4 * k, 4 * k + 2, 4 * k + 3]]
    return Canopy.from_triangles(np.array(v, float), np.array(f), _plot(),
                                 np.repeat(np.arange(1, n + 1), 2))


HEIGHTS = (0.0, 20.0, 60.0, 100.0, 140.0, 200.0)


def _permutation(draw_seed: int, n: int) -> np.ndarray:
    return np.random.default_rng(draw_seed).permutation(n)


# ------------------------------------------------------------------ order of heights


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**31), st.integers(0, 2**31), st.floats(0, 70), st.floats(0, 360),
       st.booleans())
def test_sun_transmission_follows_its_height_whatever_the_order(seed, order, zenith, azimuth,
                                                                periodic):
    """T at each height is the same number, whichever place the height has in the list (issue
    25 case 1: T(0) was wrong whenever 0 was not the first height, the ground's rays then
    read from outside the traced family)."""
    canopy = _squares(seed)
    perm = _permutation(order, len(HEIGHTS))
    heights = tuple(HEIGHTS[i] for i in perm)
    rect = (10, 10, 90, 90) if not periodic else (0, 0, 100, 100)
    a = trace_light(canopy, LightRequest(Sun(zenith, azimuth),
                                         Sampling(HEIGHTS, 1.0, rect, periodic)))
    b = trace_light(canopy, LightRequest(Sun(zenith, azimuth),
                                         Sampling(heights, 1.0, rect, periodic)))
    assert list(b.transmission) == list(a.transmission[perm])
    assert np.array_equal(b.first_z, a.first_z)
    assert np.array_equal(b.first_hits, a.first_hits)
    for k, i in enumerate(perm):
        assert np.array_equal(b.lit(k), a.lit(int(i)))


def test_ground_transmission_of_the_bundled_block_with_zero_last():
    """The issue's own case: the 3x3 tiled example, sun at 30 deg zenith from the south,
    heights 100,0 against 0,100 (T(0) was 0.0342 against 0.1059)."""
    def run(heights):
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            assert main(["light", BLOCK, "--tile", "3x3", "--triangles", "36", "--sun-zenith",
                         "30", "--sun-azimuth", "180", "--density", "1", "--heights", heights,
                         "--json"]) == 0
        return json.loads(out.getvalue())["transmission"]

    assert run("100,0") == run("0,100")[::-1]


@settings(max_examples=6, deadline=None)
@given(st.integers(0, 2**31), st.integers(0, 2**31), st.booleans())
def test_sky_transmission_follows_its_height_whatever_the_order(seed, order, periodic):
    canopy = _squares(seed)
    perm = _permutation(order, len(HEIGHTS))
    heights = tuple(HEIGHTS[i] for i in perm)
    rect = (10, 10, 90, 90) if not periodic else (0, 0, 100, 100)
    sky = make_sky("soc", 16)
    a = trace_sky(canopy, sky, Sampling(HEIGHTS, 1.0, rect, periodic), bin_cm=10.0)
    b = trace_sky(canopy, sky, Sampling(heights, 1.0, rect, periodic), bin_cm=10.0)
    assert list(b.transmission) == list(a.transmission[perm])
    np.testing.assert_array_equal(b.per_direction, a.per_direction[:, perm])
    np.testing.assert_array_equal(b.maps, a.maps[perm])
    np.testing.assert_array_equal(b.triangle_share, a.triangle_share)


def test_day_transmission_follows_its_height_whatever_the_order():
    canopy = _squares(7)
    perm = np.array([3, 0, 5, 1, 4, 2])
    heights = tuple(HEIGHTS[i] for i in perm)
    period = clear_sky_period("2024-07-01", 43.6, 1.4, "Europe/Paris", step_min=120)
    sky = make_sky("uoc", 16)
    a = trace_period(canopy, period, Sampling(HEIGHTS, 1.0, (10, 10, 90, 90)), sky=sky,
                     bin_cm=10.0)
    b = trace_period(canopy, period, Sampling(heights, 1.0, (10, 10, 90, 90)), sky=sky,
                     bin_cm=10.0)
    np.testing.assert_array_equal(b.step_transmission, a.step_transmission[:, perm])
    np.testing.assert_array_equal(b.maps, a.maps[perm])
    np.testing.assert_array_equal(b.triangle_direct_mol, a.triangle_direct_mol)
    np.testing.assert_array_equal(b.triangle_diffuse_mol, a.triangle_diffuse_mol)


# ------------------------------------------------------------------ mesh files: faces


@pytest.fixture(scope="module")
def block_mesh(tmp_path_factory):
    """The bundled block's canopy at 36 triangles a leaf, exported as PLY and read back:
    (vertices (V, 3) cm, faces (T, 3), plant (T,), leaf (T,))."""
    from maizeviz.canopy.build import build_canopy
    from maizeviz.canopy.export import export_canopy
    from maizeviz.canopy.layout import layout_for
    from maizeviz.io.mesh_canopy import read_mesh
    from maizeviz.leaf.fit import read_leaves
    from maizeviz.mesh.levels import Level

    found = read_leaves(BLOCK)
    canopy = build_canopy(found.leaves, layout_for(found.leaves, (1, 1)), Level(triangles=36))
    mesh = read_mesh(export_canopy(tmp_path_factory.mktemp("mesh") / "c.ply", canopy))
    return mesh.vertices, mesh.faces, mesh.plant, mesh.leaf


def _canopy_json(capsys, path, *extra):
    capsys.readouterr()
    assert main(["canopy", str(path), "--mesh-unit", "cm", "--json", *extra]) == 0
    out, err = capsys.readouterr()
    return json.loads(out), err


def _measures(doc):
    """The canopy measures of `maizeviz canopy --json` (one level), without timings."""
    return {k: v for k, v in doc.items() if not k.endswith("_s")}


@pytest.mark.parametrize("how", ["same order", "reversed corners", "new vertices"])
def test_a_mesh_written_twice_measures_as_once(tmp_path, capsys, block_mesh, how):
    """Issue 25 case 3: every face written twice gave twice the leaf area and LAI, no word.
    A repeated triangle (the same three corners, by position, in any order) counts once, and
    a note says how many were left out."""
    v, f, plant, leaf = block_mesh
    once = write_ply(tmp_path / "once.ply", v, f, {"plant": plant, "leaf": leaf},
                     fmt="binary_little_endian")
    second = {"same order": f, "reversed corners": f[:, ::-1], "new vertices": f + len(v)}[how]
    verts = np.vstack([v, v]) if how == "new vertices" else v
    twice = write_ply(tmp_path / "twice.ply", verts, np.vstack([f, second]),
                      {"plant": np.concatenate([plant, plant]),
                       "leaf": np.concatenate([leaf, leaf])}, fmt="binary_little_endian")
    a, _ = _canopy_json(capsys, once)
    b, said = _canopy_json(capsys, twice)
    assert _measures(b) == _measures(a)
    assert f"{len(f):,} of the {2 * len(f):,} triangles repeat an earlier triangle" in said



# ------------------------------------------------------------------ sweep files


def test_a_sweep_file_with_a_byte_order_mark_lists_the_same_scenarios(tmp_path):
    """A sweep TOML saved by a Windows editor begins with a byte order mark; it was refused
    as invalid TOML at line 1. It reads as the same file without it."""
    from maizeviz.sweep.spec import load_spec

    text = (Path(BLOCK).with_name("sweep-example.toml").read_text()
            .replace('"block3x3.csv"', json.dumps(BLOCK)))
    plain, marked = tmp_path / "plain.toml", tmp_path / "marked.toml"
    plain.write_text(text)
    marked.write_bytes(b"\xef\xbb\xbf" + text.encode())
    a, b = load_spec(plain, yes=True), load_spec(marked, yes=True)
    assert len(a.scenarios) > 1
    assert [s.key for s in b.scenarios] == [s.key for s in a.scenarios]


def test_a_sweep_height_given_twice_is_refused_naming_it(tmp_path):
    from maizeviz.errors import MaizevizError
    from maizeviz.sweep.spec import load_spec

    text = (Path(BLOCK).with_name("sweep-example.toml").read_text()
            .replace('"block3x3.csv"', json.dumps(BLOCK)))
    assert "heights = [0, 50, 100, 150" in text
    path = tmp_path / "twice.toml"
    path.write_text(text.replace("heights = [0, 50, 100, 150", "heights = [0, 50, 50.0, 100, 150"))
    with pytest.raises(MaizevizError, match=r"light.heights\[2\]: height 50 cm is given twice"):
        load_spec(path, yes=True)


# ------------------------------------------------------------------ --json against another way


def _json(capsys, argv):
    capsys.readouterr()
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 0, err[-600:]
    return json.loads(out)


def _csv(path):
    import csv

    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


BASE = ["light", BLOCK, "--tile", "3x3", "--triangles", "36", "--density", "0.5",
        "--periodic"]
SUN_30 = ["--sun-zenith", "30", "--sun-azimuth", "150"]


def test_periodic_block_equals_its_tiling_traced_whole(capsys):
    """A periodic field repeats its plot: the bundled block alone, periodic, and the block
    tiled 3 x 3, periodic, sampled over its whole plot, are the same field on grids that
    coincide: every --json number of the one equals the other's."""
    from maizeviz.canopy.layout import layout_for
    from maizeviz.leaf.fit import read_leaves

    bounds = layout_for(read_leaves(BLOCK).leaves, (3, 3)).bounds
    common = ["--triangles", "36", *SUN_30, "--density", "1", "--periodic", "--heights",
              "0,50,100,150,250", "--json"]
    one = _json(capsys, ["light", BLOCK, "--tile", "1x1", *common])
    nine = _json(capsys, ["light", BLOCK, "--tile", "3x3", *common,
                          "--rect=" + ",".join(repr(v) for v in bounds)])
    assert nine["rays"] == 9 * one["rays"]
    assert nine["transmission"] == one["transmission"]
    assert nine["sunlit_intercepted_fraction"] == one["sunlit_intercepted_fraction"]
    assert 0 < one["transmission"][0] < one["transmission"][-1] <= 1.0


@pytest.mark.parametrize("kind", ["sun", "sky", "day", "absorbed", "photosynthesis"])
def test_plant_rows_add_up_to_the_canopy_total(capsys, tmp_path, kind):
    """Per-leaf rows sum to per-plant rows, and those to the canopy total --json gives,
    computed another way (from the rays, not the triangles)."""
    leaves, plants = tmp_path / "leaves.csv", tmp_path / "plants.csv"
    extra = {"sun": SUN_30,
             "sky": ["--sky", "soc", "--sky-directions", "16"],
             "day": ["--day", "--date", "2005-08-01", "--lat", "39.9", "--lon", "116.4",
                     "--tz", "Asia/Shanghai", "--step", "120", "--sky-directions", "16"],
             "absorbed": [*SUN_30, "--band", "par", "--irradiance", "400"],
             "photosynthesis": [*SUN_30, "--photosynthesis", "c4"]}[kind]
    doc = _json(capsys, [*BASE, *extra, "--leaf-light", str(leaves), "--plant-light",
                         str(plants), "--json"])
    x0, y0, x1, y1 = doc["rect_cm"] if "rect_cm" in doc else doc["diffuse"]["rect_cm"]
    area_cm2 = (x1 - x0) * (y1 - y0)
    column, total = {
        "sun": ("sunlit_intercepted_cm2", lambda: doc["sunlit_intercepted_fraction"] * area_cm2),
        "sky": ("diffuse_intercepted_cm2",
                lambda: doc["diffuse"]["intercepted_fraction"] * area_cm2),
        "day": ("par_intercepted_mol",
                lambda: doc["period"]["par_intercepted_mol_m2"] * area_cm2 * 1e-4),
        "absorbed": ("absorbed_w", lambda: doc["balance"]["absorbed_leaves"] * area_cm2 * 1e-4),
        "photosynthesis": ("gross_umol_s", lambda: doc["photosynthesis"]["canopy_gross_umol_m2_s"]
                           * area_cm2 * 1e-4),
    }[kind]
    leaf_rows, plant_rows = _csv(leaves), _csv(plants)
    assert len(plant_rows) > 1
    by_plant: dict = {}
    for r in leaf_rows:
        by_plant[r["instance"]] = by_plant.get(r["instance"], 0.0) + float(r[column])
    for p in plant_rows:
        assert float(p[column]) == pytest.approx(by_plant[p["instance"]], rel=1e-9)
    assert sum(float(p[column]) for p in plant_rows) == pytest.approx(total(), rel=1e-9)


# ------------------------------------------------------------------ order of a file's rows


def _shuffled(tmp_path, rename=None, seed=3):
    """The bundled points file with its lines in another order (header first), plant ids
    renamed by ``rename`` (a dict) if given."""
    lines = Path(BLOCK).read_text().splitlines()
    head, body = lines[0], lines[1:]
    if rename:
        body = [",".join([str(rename[int(f[0])]), *f[1:]]) for f in (b.split(",") for b in body)]
    order = np.random.default_rng(seed).permutation(len(body))
    path = tmp_path / f"shuffled{seed}.csv"
    path.write_text("\n".join([head, *(body[i] for i in order)]) + "\n")
    return path


def test_canopy_and_light_are_the_same_whatever_the_order_of_the_file(capsys, tmp_path):
    """Every line of the points file in another order: plants, leaves and rows read in
    another order build the same canopy and trace the same light."""
    argv = ["--tile", "3x3", "--triangles", "36"]
    for points in (BLOCK, _shuffled(tmp_path, seed=1), _shuffled(tmp_path, seed=2)):
        canopy = _measures(_json(capsys, ["canopy", str(points), *argv, "--json"]))
        light = _json(capsys, ["light", str(points), *argv, *SUN_30, "--density", "1",
                               "--heights", "0,100", "--json"])
        if points == BLOCK:
            want_canopy, want_light = canopy, light
        assert canopy == want_canopy
        assert light["transmission"] == want_light["transmission"]
        assert light["sunlit_intercepted_fraction"] == want_light["sunlit_intercepted_fraction"]


def test_renamed_plants_trace_the_same_light(capsys, tmp_path):
    """Plant ids renamed (near 2^31, in another order): the same light, each plant's row
    under its new name."""
    ids = sorted({int(line.split(",")[0]) for line in Path(BLOCK).read_text().splitlines()[1:]})
    rename = {p: 2**31 - 1 - 7 * k for k, p in enumerate(reversed(ids))}
    argv = ["--tile", "3x3", "--triangles", "36", *SUN_30, "--density", "1", "--heights",
            "0,100", "--json"]
    a_rows, b_rows = tmp_path / "a.csv", tmp_path / "b.csv"
    a = _json(capsys, ["light", BLOCK, *argv, "--plant-light", str(a_rows)])
    b = _json(capsys, ["light", str(_shuffled(tmp_path, rename)), *argv, "--plant-light",
                       str(b_rows)])
    assert b["transmission"] == a["transmission"]
    got = {(r["x_cm"], r["y_cm"]): (r["plant"], r["sunlit_intercepted_cm2"]) for r in _csv(b_rows)}
    for r in _csv(a_rows):
        plant, value = got[(r["x_cm"], r["y_cm"])]
        assert int(plant) == rename[int(r["plant"])] and value == r["sunlit_intercepted_cm2"]


def test_levels_in_any_order_give_the_same_numbers_per_level(capsys):
    a = _json(capsys, ["canopy", BLOCK, "--tile", "1x1", "--levels", "K1,36,8", "--json"])
    b = _json(capsys, ["canopy", BLOCK, "--tile", "1x1", "--levels", "8,K1,36", "--json"])
    per_a = {d["level"]: _measures(d) for d in a["levels"]}
    per_b = {d["level"]: _measures(d) for d in b["levels"]}
    assert per_a == per_b and {"K=1", "36 triangles", "8 triangles"} <= set(per_a)


def test_a_points_line_written_twice_is_reported_not_counted_twice(capsys, tmp_path):
    """A repeated line is a point recorded twice: its leaf is refused naming both lines,
    never counted twice; the other leaves are the same."""
    lines = Path(BLOCK).read_text().splitlines()
    path = tmp_path / "twice.csv"
    path.write_text("\n".join([*lines[:20], lines[10], *lines[20:]]) + "\n")
    capsys.readouterr()
    assert main(["leaf", str(path), "--interp", "0"]) == 3
    err = capsys.readouterr().err
    plant, leaf = lines[10].split(",")[:2]
    assert f"plant {plant}, leaf {leaf}: row 1, col 4 appears twice (lines 11 and 21)" in err


def test_a_stand_written_twice_in_a_layout_is_reported(capsys, tmp_path):
    """The same plant at the same place twice is two plants standing in one another: kept
    (a layout may overlap on purpose) but said, with the area counted twice."""
    layout = tmp_path / "twice.json"
    layout.write_text(json.dumps({
        "maizeviz_layout": 1, "row_spacing": 60, "plant_spacing": 30,
        "field": {"x0": -30, "y0": -30, "x1": 90, "y1": 30},
        "rows": [{"x": 0, "plants": [{"y": 0, "plant": 1}, {"y": 0, "plant": 1}]},
                 {"x": 60, "plants": [{"y": 0, "plant": 2}]}]}))
    capsys.readouterr()
    assert main(["canopy", BLOCK, "--layout", str(layout), "--triangles", "8"]) == 0
    err = capsys.readouterr().err
    assert "closer than the spacing" in err and "counted twice" in err


# ------------------------------------------------------------------ Parquet points files


def _parquet_of(tmp_path, csv_path, name):
    out = tmp_path / f"{name}.parquet"
    assert main(["convert", str(csv_path), "--out", str(out)]) == 0
    return out


@settings(max_examples=3, deadline=None, phases=(Phase.explicit, Phase.reuse, Phase.generate))
@given(st.integers(0, 2**31))
def test_a_parquet_file_in_any_row_order_builds_and_traces_the_same(tmp_path_factory, seed):
    """The bundled block's records shuffled, then written as Parquet (read column by column,
    not through the CSV reader): the same canopy and the same light as the CSV in its order."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    tmp = tmp_path_factory.mktemp("pq")
    table = pq.read_table(_parquet_of(tmp, BLOCK, "block"))
    order = np.random.default_rng(seed).permutation(table.num_rows)
    shuffled = tmp / "shuffled.parquet"
    pq.write_table(table.take(pa.array(order)), shuffled)
    argv = ["--tile", "3x3", "--triangles", "36"]
    light = [*argv, *SUN_30, "--density", "1", "--heights", "100,0,50", "--json"]
    with contextlib.redirect_stderr(io.StringIO()):
        for points in (BLOCK, shuffled):
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                assert main(["canopy", str(points), *argv, "--json"]) == 0
            canopy = _measures(json.loads(out.getvalue()))
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                assert main(["light", str(points), *light]) == 0
            doc = json.loads(out.getvalue())
            got = (canopy, doc["transmission"], doc["sunlit_intercepted_fraction"])
            if points == BLOCK:
                want = got
    assert got == want


def test_a_parquet_record_written_twice_is_reported_not_counted_twice(capsys, tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pq.read_table(_parquet_of(tmp_path, BLOCK, "block"))
    twice = tmp_path / "twice.parquet"
    pq.write_table(pa.concat_tables([table, table.slice(9, 1)]), twice)
    plant, leaf, row, col = (table.column(c)[9].as_py() for c in ("plant", "leaf", "row", "col"))
    capsys.readouterr()
    assert main(["leaf", str(twice), "--interp", "0"]) == 3
    err = capsys.readouterr().err
    assert (f"plant {plant}, leaf {leaf}: row {row}, col {col} appears twice (lines 11 and "
            f"{table.num_rows + 2})") in err


# ------------------------------------------------------------------ mesh files: face order


def _mesh_runs(capsys, path):
    """(canopy measures, light --json, leaf rows by (plant, leaf)) of a mesh file."""
    import csv

    table = Path(path).with_suffix(".leaves.csv")
    canopy, _ = _canopy_json(capsys, path)
    light = _json(capsys, ["light", str(path), "--mesh-unit", "cm", *SUN_30, "--density", "1",
                           "--heights", "0,50,100", "--leaf-light", str(table), "--json"])
    with open(table, newline="") as fh:
        rows = {(r["plant"], r["leaf"]): r for r in csv.DictReader(fh)}
    return _measures(canopy), light, rows


def _number(x):
    """A JSON value or a CSV cell as a float where it is a number, else as it is."""
    if isinstance(x, bool) or not isinstance(x, (int, float, str)):
        return x
    try:
        return float(x)
    except ValueError:
        return x


def _close(a: dict, b: dict, rel: float):
    assert set(a) == set(b)
    for k, x in a.items():
        x, y = _number(x), _number(b[k])
        if isinstance(x, float):
            assert y == pytest.approx(x, rel=rel, abs=1e-12), k
        else:
            assert y == x, k


@settings(max_examples=4, deadline=None, phases=(Phase.explicit, Phase.reuse, Phase.generate))
@given(st.integers(0, 2**31), st.sampled_from(["ascii", "binary_big_endian", "obj"]),
       st.integers(0, 2))
def test_mesh_faces_in_any_order_trace_the_same(tmp_path_factory, block_mesh, seed, fmt, turn):
    """A mesh file's faces permuted and each face's corners turned (its orientation kept):
    the same triangles, so the same canopy and light; sums of the same numbers in another
    order may differ in their last bits (relative 1e-15 seen), nothing more."""
    capsys = _Capture()
    v, f, plant, leaf = block_mesh
    tmp = tmp_path_factory.mktemp("faces")
    perm = np.random.default_rng(seed).permutation(len(f))
    g = np.roll(f[perm], turn, axis=1)

    def write(name, faces, p, lf):
        if fmt == "obj":
            return write_obj(tmp / f"{name}.obj", v, faces,
                             [f"plant{a}_leaf{b}" for a, b in zip(p, lf)])
        return write_ply(tmp / f"{name}.ply", v, faces, {"plant": p, "leaf": lf}, fmt=fmt)

    a = _mesh_runs(capsys, write("file", f, plant, leaf))
    b = _mesh_runs(capsys, write("permuted", g, plant[perm], leaf[perm]))
    _close(a[0], b[0], 1e-13)
    assert b[1]["transmission"] == a[1]["transmission"]
    assert b[1]["sunlit_intercepted_fraction"] == a[1]["sunlit_intercepted_fraction"]
    # the sunlit area is sampled from points drawn on the triangles in mesh order: the same
    # estimate drawn again, within the sample's error (a leaf of A cm2 sampled with n points
    # has a variance of at most A^2 / 4n; with n >= A, one point per cm2 at 1 ray per cm2, the
    # two sums' difference a variance of at most 2 sum(A) / 4; 4 of its standard errors are
    # 770 cm2 here, where 120 of 32,500 was the most seen). A leaf no ray reached is listed
    # when its sample finds some sun: in one of the two runs only, with nothing but that.
    assert len(a[2]) > 100
    for key in set(a[2]) ^ set(b[2]):
        row = a[2].get(key) or b[2][key]
        assert all(float(row[k]) == 0 for k in row if k.endswith("_intercepted_cm2")
                   or k == "second_class_area_cm2"), key
    keys = set(a[2]) & set(b[2])
    sunlit = [(float(a[2][key]["sunlit_area_cm2"]), float(b[2][key]["sunlit_area_cm2"]),
               float(a[2][key]["leaf_area_cm2"])) for key in keys]
    x, y, area = (np.array(c) for c in zip(*sunlit))
    assert np.all(y <= area * (1 + 1e-9)) and np.all(x <= area * (1 + 1e-9))
    assert abs(x.sum() - y.sum()) < 4 * np.sqrt(2 * np.sum(area / 4))
    for key in keys:
        _close({k: v for k, v in a[2][key].items() if k != "sunlit_area_cm2"},
               {k: v for k, v in b[2][key].items() if k != "sunlit_area_cm2"}, 1e-12)


class _Capture:
    """capsys for a hypothesis test (a function-scoped fixture cannot be given): stdout and
    stderr of one main() call."""

    def readouterr(self):
        out, err = self._out.getvalue(), self._err.getvalue()
        self._out, self._err = io.StringIO(), io.StringIO()
        self._redirect()
        return out, err

    def __init__(self):
        self._out, self._err = io.StringIO(), io.StringIO()
        self._stack = contextlib.ExitStack()
        self._redirect()

    def _redirect(self):
        self._stack.close()
        self._stack = contextlib.ExitStack()
        self._stack.enter_context(contextlib.redirect_stdout(self._out))
        self._stack.enter_context(contextlib.redirect_stderr(self._err))


@pytest.fixture(scope="module")
def exports(tmp_path_factory):
    """The bundled block's canopy (9 plants, 8 triangles a leaf) exported in every format:
    {ext: path}, and the plot it carries."""
    tmp = tmp_path_factory.mktemp("exports")
    paths = {}
    with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
        for ext in (".ply", ".obj", ".vtu", ".vtp", ".vtk", ".stl"):
            paths[ext] = tmp / f"canopy{ext}"
            assert main(["canopy", BLOCK, "--triangles", "8", "--export", str(paths[ext])]) == 0
    import pyvista

    field = tuple(float(v) for v in pyvista.read(paths[".vtu"]).field_data["field_cm"])
    return paths, field


@pytest.mark.parametrize("ext", [".obj", ".vtu", ".vtp", ".vtk", ".stl"])
def test_each_export_format_carries_the_canopy_the_ply_does(capsys, tmp_path, exports, ext):
    """A mesh round trip through each export format: its triangles and ids read back (OBJ by
    maizeviz, the VTK files and the STL by VTK's readers through pyvista), written as a PLY
    and measured and traced: every --json number is the PLY export's (STL, whose corners are
    float32 and which carries no ids, takes its ids from the PLY's faces in order, and
    agrees to float32's precision)."""
    import pyvista

    from maizeviz.io.mesh_canopy import read_mesh

    paths, field = exports
    ref = read_mesh(paths[".ply"])
    if ext == ".obj":
        got = read_mesh(paths[ext])
        v, f, plant, leaf = got.vertices, got.faces, got.plant, got.leaf
    else:
        mesh = pyvista.read(paths[ext])
        if not isinstance(mesh, pyvista.UnstructuredGrid):
            mesh = mesh.cast_to_unstructured_grid()
        assert set(mesh.celltypes.tolist()) == {5}                  # triangles only
        v = np.asarray(mesh.points, np.float64)
        f = mesh.cells.reshape(-1, 4)[:, 1:]
        if ext == ".stl":
            assert len(f) == len(ref.faces)
            plant, leaf = ref.plant, ref.leaf
        else:
            plant, leaf = mesh.cell_data["plant"], mesh.cell_data["leaf"]
    again = write_ply(tmp_path / "again.ply", v, f, {"plant": plant, "leaf": leaf},
                      fmt="binary_little_endian")
    common = ["--field=" + ",".join(repr(c) for c in field)]
    argv = ["--mesh-unit", "cm", *common, *SUN_30, "--density", "1", "--heights", "0,50,100",
            "--json"]
    a = _measures(_canopy_json(capsys, paths[".ply"], *common)[0])
    b = _measures(_canopy_json(capsys, again, *common)[0])
    la = _json(capsys, ["light", str(paths[".ply"]), *argv])
    lb = _json(capsys, ["light", str(again), *argv])
    if ext == ".stl":
        _close(a, b, 1e-6)
        for x, y in zip(la["transmission"], lb["transmission"]):
            assert y == pytest.approx(x, abs=2e-3)              # a ray in 500 on an edge
    else:
        assert b == a
        assert lb["transmission"] == la["transmission"]
        assert lb["sunlit_intercepted_fraction"] == la["sunlit_intercepted_fraction"]
    assert a["leaves"] == 140 and 0 < la["transmission"][0] < 1


# ------------------------------------------------------------------ order of a layout file


@settings(max_examples=3, deadline=None, phases=(Phase.explicit, Phase.reuse, Phase.generate))
@given(st.integers(0, 2**31))
def test_a_layout_in_any_order_traces_the_same_field(tmp_path_factory, seed):
    """The rows of a layout file, and the plants within each row, listed in another order:
    the same stands, so the same transmission, and each stand (plant id and place) the same
    light in the plant table."""
    import csv

    rng = np.random.default_rng(seed)
    tmp = tmp_path_factory.mktemp("layout")
    ids = sorted({int(line.split(",")[0]) for line in Path(BLOCK).read_text().splitlines()[1:]})
    rows = [{"x": 30 + 60 * i, "plants": [{"y": 15 + 30 * j, "plant": ids[(3 * i + j) % 9]}
                                          for j in range(3)]} for i in range(3)]
    shuffled = [{"x": r["x"], "plants": [r["plants"][k] for k in rng.permutation(3)]}
                for r in (rows[k] for k in rng.permutation(3))]
    runs = []
    for name, listed in (("a", rows), ("b", shuffled)):
        path = tmp / f"{name}.json"
        path.write_text(json.dumps({"maizeviz_layout": 1, "row_spacing": 60, "plant_spacing": 30,
                                    "field": {"x0": 0, "y0": 0, "x1": 180, "y1": 90},
                                    "rows": listed}))
        table = tmp / f"{name}.csv"
        out = io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
            assert main(["light", BLOCK, "--layout", str(path), "--triangles", "8", *SUN_30,
                         "--density", "1", "--periodic", "--heights", "0,100",
                         "--plant-light", str(table), "--json"]) == 0
        with open(table, newline="") as fh:
            plants = {(r["plant"], r["x_cm"], r["y_cm"]): r["sunlit_intercepted_cm2"]
                      for r in csv.DictReader(fh)}
        runs.append((json.loads(out.getvalue())["transmission"], plants))
    assert runs[1][0] == runs[0][0]
    assert runs[1][1] == runs[0][1] and len(runs[0][1]) == 9


@pytest.mark.parametrize("tile, copies", [("1x1", 1), ("2x3", 6)])
def test_the_leaf_table_adds_up_to_the_canopy(capsys, tmp_path, tile, copies):
    """`maizeviz leaf --json` measures each leaf; `maizeviz canopy --json` the field: its leaf
    area and triangles are the leaves' summed over the copies of the block, its LAI that area
    over the ground; and the light run's per-leaf table gives each leaf the same area."""
    import csv

    leaf = _json(capsys, ["leaf", BLOCK, "--triangles", "36", "--json"])
    canopy = _json(capsys, ["canopy", BLOCK, "--tile", tile, "--triangles", "36", "--json"])
    area = sum(r["area_cm2"] for r in leaf["leaves"])
    assert canopy["leaves"] == copies * len(leaf["leaves"]) == copies * 140
    assert canopy["triangles"] == copies * sum(r["triangles"] for r in leaf["leaves"])
    assert canopy["leaf_area_m2"] == pytest.approx(copies * area / 1e4, rel=1e-12)
    assert canopy["lai"] == pytest.approx(canopy["leaf_area_m2"] / canopy["ground_area_m2"],
                                          rel=1e-12)
    table = tmp_path / "leaves.csv"
    _json(capsys, ["light", BLOCK, "--tile", tile, "--triangles", "36", *SUN_30, "--density",
                   "1", "--periodic", "--leaf-light", str(table), "--json"])
    by = {(r["plant"], r["leaf"]): r["area_cm2"] for r in leaf["leaves"]}
    with open(table, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) > 100
    for r in rows:
        assert float(r["leaf_area_cm2"]) == pytest.approx(by[(int(r["plant"]), int(r["leaf"]))],
                                                          rel=1e-12)
