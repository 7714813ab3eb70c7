"""Project files: round trip, atomic save, and refusal of newer, damaged or hostile files."""

import io
import json
import os
import zipfile

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from maizeviz.errors import MaizevizError
from maizeviz.io.archive import (
    PROJECT_FORMAT,
    Project,
    ProjectError,
    Record,
    get,
    get_numbers,
    load_project,
    save_project,
)

CSV = b"plant,leaf,row,col,x,y,z\n1,1,0,0,0,0,10\n1,1,0,1,1,0,10\n"


def sample(results=True) -> Project:
    layout = {"maizeviz_layout": 1, "row_spacing": 60.0, "plant_spacing": 30.0,
              "north_deg": 0.0, "field": {"x0": 0.0, "y0": 0.0, "x1": 180.0, "y1": 90.0},
              "rows": [{"x": 30.1234567891, "plants": [{"y": 15.000000001, "plant": 1,
                                                        "azimuth_deg": 33.3}]}]}
    recs = ()
    if results:
        recs = (Record("light", {"level": "36 triangles", "heights_cm": [0, 50.5],
                                 "transmission": [0.07, 0.2], "warnings": ["a"]},
                       {"first_z": np.linspace(-1, 250, 1000).astype(np.float32),
                        "first_hits": np.arange(7, dtype=np.int64),
                        "flags": np.array([True, False])}),
                Record("light", {"level": "K=4"}, {}))
    return Project(CSV, "/somewhere/block.csv", layout,
                   {"canopy": {"tile": 3, "level": "36", "preserve_area": True},
                    "light": {"zenith_deg": 22.34, "heights_cm": [0, 50]}},
                   {"cells": np.arange(12.0).reshape(3, 4)}, recs)


def test_round_trip(tmp_path):
    p = sample()
    path = save_project(tmp_path / "study.maizeviz", p)
    back = load_project(path)
    assert back.points_csv == CSV and back.points_path == p.points_path
    assert back.points_sha256 == p.points_sha256
    assert back.layout == p.layout                       # floats exactly as they were
    assert back.settings == p.settings
    np.testing.assert_array_equal(back.arrays["cells"], p.arrays["cells"])
    assert [r.kind for r in back.results] == ["light", "light"]
    assert back.results[0].meta == p.results[0].meta
    for k, a in p.results[0].arrays.items():
        assert back.results[0].arrays[k].dtype == a.dtype
        np.testing.assert_array_equal(back.results[0].arrays[k], a)
    assert back.results[1].arrays == {}


def test_no_pickle_inside(tmp_path):
    path = save_project(tmp_path / "p.maizeviz", sample())
    with zipfile.ZipFile(path) as zf:
        assert sorted(zf.namelist()) == ["arrays.npz", "points.csv", "project.json"]
        doc = json.loads(zf.read("project.json"))
        assert doc["maizeviz_project"] == PROJECT_FORMAT
        inner = np.load(io.BytesIO(zf.read("arrays.npz")), allow_pickle=False)
        assert all(inner[k].dtype != object for k in inner.files)


def test_save_is_atomic_and_refuses_objects(tmp_path):
    path = tmp_path / "p.maizeviz"
    save_project(path, sample())
    before = path.read_bytes()
    bad = Project(CSV, "x.csv", arrays={"o": np.array([object()], dtype=object)})
    with pytest.raises(ProjectError, match="numbers and booleans only"):
        save_project(path, bad)
    with pytest.raises(ProjectError, match="JSON"):
        save_project(path, Project(CSV, "x.csv", settings={"x": float("nan")}))
    assert path.read_bytes() == before                   # the old project is intact
    assert sorted(os.listdir(tmp_path)) == ["p.maizeviz"]  # no temporary left behind
    with pytest.raises(MaizevizError, match="does not exist"):
        save_project(tmp_path / "missing" / "p.maizeviz", sample())


def rewrite(path, members: dict, out=None):
    """A copy of the archive at ``path`` with members replaced (None removes one)."""
    with zipfile.ZipFile(path) as zf:
        data = {n: zf.read(n) for n in zf.namelist()}
    data.update(members)
    out = out or path
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zf:
        for n, b in data.items():
            if b is not None:
                zf.writestr(n, b)
    return out


def doc_of(path):
    with zipfile.ZipFile(path) as zf:
        return json.loads(zf.read("project.json"))


@pytest.fixture
def saved(tmp_path):
    return save_project(tmp_path / "p.maizeviz", sample())


def test_newer_project_refused(saved):
    doc = doc_of(saved)
    doc["maizeviz_project"] = PROJECT_FORMAT + 1
    rewrite(saved, {"project.json": json.dumps(doc).encode()})
    with pytest.raises(ProjectError, match="newer maizeviz.*update maizeviz") as err:
        load_project(saved)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("change, message", [
    ({"project.json": b"{not json"}, "not valid JSON"),
    ({"project.json": b"[1, 2]"}, "must be a JSON object"),
    ({"project.json": b"\xff\xfe"}, "not UTF-8"),
    ({"points.csv": b"plant,leaf\n"}, "do not match their checksum"),
    ({"arrays.npz": b"garbage"}, "arrays.npz is damaged"),
    ({"arrays.npz": None}, "'arrays.npz' is missing"),
    ({"../evil.sh": b"rm -rf /"}, "unexpected file '../evil.sh'"),
    ({"/etc/passwd": b"x"}, "unexpected file"),
])
def test_damaged_or_hostile_refused(saved, change, message):
    if list(change) in (["../evil.sh"], ["/etc/passwd"]):
        rewrite(saved, {"arrays.npz": None})
    rewrite(saved, change)
    with pytest.raises(ProjectError, match=message):
        load_project(saved)


@pytest.mark.parametrize("path, value, message", [
    (("points", "path"), 7, "'points.path' must be text, got 7"),
    (("points",), "x", "'points' must be an object"),
    (("settings",), [1], "'settings' must be an object"),
    (("layout",), "grid", "'layout' must be an object"),
    (("results",), {"a": 1}, "'results' must be a list"),
    (("results", 0, "arrays"), ["nope"], "array 'nope'.*missing"),
    (("results", 0, "kind"), True, "results\\[0\\].kind must be text"),
    (("maizeviz_project",), "1", "not a project format"),
])
def test_wrong_types_refused(saved, path, value, message):
    doc = doc_of(saved)
    target = doc
    for k in path[:-1]:
        target = target[k]
    target[path[-1]] = value
    rewrite(saved, {"project.json": json.dumps(doc).encode()})
    with pytest.raises(ProjectError, match=message):
        load_project(saved)


def test_zip_bomb_and_huge_members_refused(saved, tmp_path):
    bomb = tmp_path / "bomb.maizeviz"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("project.json", b" " * (64 * 2**20))       # 64 MiB of spaces
        zf.writestr("points.csv", CSV)
        zf.writestr("arrays.npz", b"")
    with pytest.raises(ProjectError, match="more than a project holds"):
        load_project(bomb)
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("project.json", b"{" + b" " * (8 * 2**20) + b"}")
        zf.writestr("points.csv", CSV)
        zf.writestr("arrays.npz", b"")
    with pytest.raises(ProjectError, match="zip bomb"):
        load_project(bomb)


def npz_with(name, raw_npy: bytes) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr(name, raw_npy)
    return buf.getvalue()


def npy_bytes(a) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, a, allow_pickle=True)
    return buf.getvalue()


def test_hostile_arrays_refused(saved):
    # a header that claims 800 GB over 32 bytes of data: refused before any allocation
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f8", "fortran_order": False,
                                               "shape": (99_999_999_999,)})
    rewrite(saved, {"arrays.npz": npz_with("project.cells.npy", buf.getvalue() + b"\0" * 32)})
    with pytest.raises(ProjectError, match="says .* but holds 32 bytes"):
        load_project(saved)
    rewrite(saved, {"arrays.npz": npz_with("project.cells.npy",
                                           npy_bytes(np.array([{"a": 1}], dtype=object)))})
    with pytest.raises(ProjectError, match="type object"):
        load_project(saved)
    rewrite(saved, {"arrays.npz": npz_with("../../x.npy", npy_bytes(np.zeros(2)))})
    with pytest.raises(ProjectError, match="unexpected entry"):
        load_project(saved)


def test_not_a_project(tmp_path):
    for content, message in ((b"", "not a zip archive"), (b"plant,leaf\n", "not a zip"),
                             (os.urandom(5000), "not a zip")):
        p = tmp_path / "x.maizeviz"
        p.write_bytes(content)
        with pytest.raises(ProjectError, match=message):
            load_project(p)
    with pytest.raises(ProjectError, match="no such project file"):
        load_project(tmp_path / "absent.maizeviz")
    with pytest.raises(ProjectError, match="is a folder"):
        load_project(tmp_path)
    fifo = tmp_path / "pipe.maizeviz"
    os.mkfifo(fifo)                              # with nothing writing: reading would hang
    with pytest.raises(ProjectError, match="is a FIFO .* not a regular file"):
        load_project(fifo)


def test_typed_lookups():
    obj = {"a": 1, "b": True, "c": [1, 2.5], "d": "x", "e": [1, "x"]}
    assert get(obj, "a", (int, float)) == 1
    assert get(obj, "z", str, "dflt") == "dflt"
    with pytest.raises(ProjectError, match="'b' must be a number, got true"):
        get(obj, "b", (int, float))
    with pytest.raises(ProjectError, match="'z' is missing"):
        get(obj, "z", str)
    assert get_numbers(obj, "c") == (1.0, 2.5)
    with pytest.raises(ProjectError, match="an entry of 'e' must be a number"):
        get_numbers(obj, "e")


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=4000))
def test_fuzz_arbitrary_bytes(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("fuzz") / "f.maizeviz"
    p.write_bytes(data)
    with pytest.raises(MaizevizError):
        load_project(p)


_VALID = None


def valid_bytes(tmp_path_factory):
    global _VALID
    if _VALID is None:
        p = save_project(tmp_path_factory.mktemp("v") / "v.maizeviz", sample())
        _VALID = p.read_bytes()
    return _VALID


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_fuzz_damaged_projects(tmp_path_factory, data):
    """A real project with bytes flipped, cut or inserted: it opens or is refused, nothing else."""
    raw = bytearray(valid_bytes(tmp_path_factory))
    for _ in range(data.draw(st.integers(1, 6))):
        i = data.draw(st.integers(0, len(raw) - 1))
        op = data.draw(st.sampled_from(["flip", "cut", "insert"]))
        if op == "flip":
            raw[i] ^= data.draw(st.integers(1, 255))
        elif op == "cut":
            del raw[i:i + data.draw(st.integers(1, 50))]
        else:
            raw[i:i] = data.draw(st.binary(min_size=1, max_size=20))
        if not raw:
            break
    p = tmp_path_factory.mktemp("fz") / "d.maizeviz"
    p.write_bytes(bytes(raw))
    try:
        load_project(p)
    except MaizevizError as exc:
        assert "\n" not in str(exc)
