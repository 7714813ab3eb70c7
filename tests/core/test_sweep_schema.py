"""The sweep file's declared schema (maizeviz.sweep.schema), without Dask: every wrong type of
every key refused in one line naming the file and the key's path, every valid file read (the
same scenarios however its one-value axes are written), scenario keys as the hand-written
checker gave them, and the documented example files holding every key and reading."""

from __future__ import annotations

import json
import re
import string
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

pytest.importorskip("pydantic")

from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import maizeviz  # noqa: E402
from maizeviz.sweep import spec as spec_module  # noqa: E402
from maizeviz.sweep.errors import SweepSpecError  # noqa: E402
from maizeviz.sweep.schema import Canopy, Light, OpticsTable, SunKeys  # noqa: E402
from maizeviz.sweep.spec import load_spec  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SETTINGS = settings(max_examples=60, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture,
                                           HealthCheck.too_slow])


def write_inputs(folder: Path) -> None:
    """The files the sweep files below name: load_spec hashes them, never parses them."""
    (folder / "a.csv").write_bytes(b"plant,leaf,row,col,x,y,z\n1,1,0,0,0,0,0\n")
    (folder / "b.csv").write_bytes(b"plant,leaf,row,col,x,y,z\n2,1,0,0,0,0,0\n")
    (folder / "field.json").write_bytes(b'{"plants": []}\n')
    (folder / "block3x3.csv").write_bytes(b"plant,leaf\n3,3\n")
    (folder / "genotypes").mkdir(exist_ok=True)
    (folder / "genotypes" / "g1.csv").write_bytes(b"plant,leaf\n4,4\n")


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    d = tmp_path_factory.mktemp("sweep-schema")
    write_inputs(d)
    return d


def toml(v) -> str:
    """A value as TOML (inline)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml(x) for x in v) + "]"
    return "{" + ", ".join(f"{k} = {toml(x)}" for k, x in v.items()) + "}"


def dump(doc: dict) -> str:
    """A sweep document as a file: ``exclude`` first, then the [canopy] and [light] tables."""
    head = f"exclude = {toml(doc['exclude'])}\n" if "exclude" in doc else ""
    return head + "".join(f"[{sec}]\n" + "".join(f"{k} = {toml(v)}\n" for k, v in
                                                 doc[sec].items()) for sec in ("canopy", "light"))


# --------------------------------------------------------------- scenario keys, pinned
RICH = {
    "tilings": """
[canopy]
points = ["a.csv", "b.csv"]
tile = ["1x1", "2x3"]
row_spacing = [60, 75.5]
plant_spacing = 25
block = "1x2"
level = ["K4", "standard", 36, "8"]
preserve_area = [true, false]
cover_resolution = 1
[light]
sun = [{zenith = 30, azimuth = 180}, {zenith = 45.5, azimuth = -10}]
density = [0.5, 2]
heights = [0, 50.5, 100]
periodic = [true, false]
rect = [0, 0, 180, 90.5]
""",
    "layouts_and_suns": """
exclude = [{level = "8", sun = {zenith = 0}}, {points = "b*", layout = "field.json"}]
[canopy]
points = "*.csv"
tile = "2x2"
layout = "field.json"
level = ["standard", "8"]
[light]
sun = [{zenith = 0, azimuth = 0},
       {date = "2005-08-01", time = "12:00", lat = 39.9, lon = 116.4, tz = "Asia/Shanghai"},
       {date = 2005-08-01, time = 10:30:00, lat = 40, lon = 116, tz = "Asia/Shanghai", altitude = 50},
       {date = "2005-08-01", solar_noon = true, lat = 39.9, lon = 116.4}]
""",
    "optics_and_carbon": """
[canopy]
points = "a.csv"
level = "8"
[light]
sun = {zenith = 30, azimuth = 180}
optics = ["black", {band = "par"}, {band = "NIR", reflectance = 0.4, transmittance = 0.4, ground_reflectance = 0.2, depth = 2},
          {band = "par", seed = 3, direct_w_m2 = 520, diffuse_w_m2 = 60, ranks = [[1, 0.12, 0], [2, 0.1, 0.05]]}]
photosynthesis = ["none", {model = "c4", temperature = 30}, {model = "wofost", amax = 60},
                  {model = "c4", temperature = 38, temperature_response = "clm45", co2_ppm = 400}]
""",
}
#: (scenarios, fingerprint) of RICH under maizeviz "0.0.0", as the hand-written checker
#: (spec.py before the schema, e2766fe) listed them: results on disk must keep matching
PINNED = {"tilings": (512, "ff49a496070ca548658cb9c4"),
          "layouts_and_suns": (28, "9e1b76650dca6274bd2075ab"),
          "optics_and_carbon": (10, "3d3e3722ac33e8c13e005ba9")}


@pytest.mark.parametrize("name", sorted(RICH))
def test_scenario_keys_are_those_of_the_hand_written_checker(folder, monkeypatch, name):
    monkeypatch.setattr(maizeviz, "__version__", "0.0.0")
    path = folder / f"{name}.toml"
    path.write_text(RICH[name])
    spec = load_spec(path, yes=True)
    assert (len(spec.scenarios), spec.fingerprint) == PINNED[name]


# ------------------------------------------------------------- wrong types, any key
#: A valid file every wrong value is put into.
BASE = {"canopy": {"points": "a.csv", "level": "8"},
        "light": {"sun": [{"zenith": 30, "azimuth": 180},
                          {"date": "2005-08-01", "time": "12:00", "lat": 39.9, "lon": 116.4,
                           "tz": "Asia/Shanghai", "altitude": 50}],
                  "optics": [{"band": "par"}],
                  "photosynthesis": ["none", {"model": "c4", "temperature": 30}]}}
TEXT = st.text(alphabet=string.ascii_letters + string.digits + " .", max_size=6)
NUMBER = st.one_of(st.integers(-10**6, 10**6), st.floats(-1e6, 1e6, allow_nan=False))
TABLE = st.just({"a": 1})
WRONG = {"number": st.one_of(TEXT, st.booleans(), TABLE),
         "whole": st.one_of(st.floats(0, 10).map(lambda x: x + 0.5), TEXT, st.booleans()),
         "bool": st.one_of(NUMBER, TEXT, TABLE),
         "text": st.one_of(NUMBER, st.booleans(), TABLE),
         "level": st.one_of(st.floats(1, 100).map(lambda x: x + 0.5), st.booleans(), TABLE),
         "shape": st.one_of(NUMBER, st.booleans(), TABLE)}
#: (path to the key, its kind, an axis: a list or a single value)
KEYS = [(("canopy", "points"), "text", True), (("canopy", "tile"), "shape", True),
        (("canopy", "row_spacing"), "number", True),
        (("canopy", "plant_spacing"), "number", True), (("canopy", "block"), "shape", False),
        (("canopy", "layout"), "text", True), (("canopy", "level"), "level", True),
        (("canopy", "preserve_area"), "bool", True),
        (("canopy", "cover_resolution"), "number", False),
        (("light", "sun", 0, "zenith"), "number", False),
        (("light", "sun", 0, "azimuth"), "number", False),
        (("light", "sun", 1, "date"), "text", False), (("light", "sun", 1, "time"), "text", False),
        (("light", "sun", 1, "lat"), "number", False), (("light", "sun", 1, "lon"), "number", False),
        (("light", "sun", 1, "tz"), "text", False),
        (("light", "sun", 1, "altitude"), "number", False),
        (("light", "density"), "number", True), (("light", "periodic"), "bool", True),
        (("light", "heights", 1), "number", False), (("light", "rect", 2), "number", False),
        (("light", "optics", 0, "band"), "text", False),
        (("light", "optics", 0, "reflectance"), "number", False),
        (("light", "optics", 0, "ground_reflectance"), "number", False),
        (("light", "optics", 0, "direct_w_m2"), "number", False),
        (("light", "optics", 0, "diffuse_w_m2"), "number", False),
        (("light", "optics", 0, "depth"), "whole", False),
        (("light", "optics", 0, "seed"), "whole", False),
        (("light", "photosynthesis", 1, "model"), "text", False),
        (("light", "photosynthesis", 1, "temperature"), "number", False),
        (("light", "photosynthesis", 1, "vmax"), "number", False),
        (("exclude", 0, "level"), "level", False), (("exclude", 0, "density"), "number", False),
        (("exclude", 0, "periodic"), "bool", False), (("exclude", 0, "tile"), "shape", False),
        (("exclude", 0, "points"), "text", False),
        (("exclude", 0, "sun", "zenith"), "number", False)]
#: a valid value beside the wrong one in an axis written as a list
VALID = {"points": "a.csv", "tile": "1x1", "row_spacing": 60, "plant_spacing": 30,
         "layout": "field.json", "level": "36", "preserve_area": True, "density": 4,
         "periodic": False}


def _path(keys: tuple) -> str:
    return "".join(f"[{k}]" if isinstance(k, int) else f".{k}" for k in keys).lstrip(".")


@pytest.mark.parametrize("keys, kind, axis", KEYS, ids=[_path(k[0]) for k in KEYS])
@settings(SETTINGS, max_examples=12)
@given(data=st.data())
def test_any_wrong_type_for_any_key_is_refused_naming_its_path(folder, data, keys, kind,
                                                                axis):
    wrong = data.draw(WRONG[kind], label="wrong")
    doc = json.loads(json.dumps(BASE))
    doc["light"]["heights"] = [0, 50, 100]
    doc["light"]["rect"] = [0, 0, 90, 90]
    if keys[0] == "exclude":
        doc["exclude"] = [{}] if len(keys) == 3 else [{"sun": {}}]
    node = doc
    for k in keys[:-1]:
        node = node[k]
    path = _path(keys)
    if axis and data.draw(st.booleans(), label="as a list"):
        node[keys[-1]] = [VALID[keys[-1]], wrong]
        path += "[1]"
    else:
        node[keys[-1]] = wrong
    file = folder / "wrong.toml"
    file.write_text(dump(doc))
    with pytest.raises(SweepSpecError) as info:
        load_spec(file)
    message = str(info.value)
    assert message.startswith(f"{file}: {path}: ") and "\n" not in message, message


def test_the_file_the_wrong_values_go_into_is_valid(folder):
    doc = json.loads(json.dumps(BASE))
    doc["light"]["heights"] = [0, 50, 100]
    doc["light"]["rect"] = [0, 0, 90, 90]
    file = folder / "valid.toml"
    file.write_text(dump(doc))
    assert len(load_spec(file).scenarios) == 2 * 2      # 2 suns x (PAR: none, C4)


# ------------------------------------------------------------------ valid files, any
def _same(v):
    """A value as the schema compares an axis's values (1 and 1.0 are one value)."""
    if isinstance(v, dict):
        return json.dumps({k: _same(x) for k, x in v.items()}, sort_keys=True)
    return json.dumps(float(v) if isinstance(v, int) and not isinstance(v, bool) else v)


def axis(values: st.SearchStrategy, max_size: int = 2) -> st.SearchStrategy:
    """An axis of distinct values, as a list (or its one value alone)."""
    return st.lists(values, min_size=1, max_size=max_size, unique_by=_same)


def whole_or_float(lo: int, hi: int) -> st.SearchStrategy:
    return st.one_of(st.integers(lo, hi), st.floats(lo, hi, allow_nan=False))


@st.composite
def valid_sweep(draw) -> dict:
    canopy = {"points": draw(st.sampled_from([["a.csv"], ["a.csv", "b.csv"], ["?.csv"]])),
              "level": draw(axis(st.sampled_from(["K2", "K4", "standard", "36", "8", 16])))}
    if draw(st.booleans()):
        canopy["tile"] = draw(axis(st.tuples(st.integers(1, 4), st.integers(1, 4)).map(
            lambda t: f"{t[0]}x{t[1]}")))
        canopy["row_spacing"] = draw(axis(whole_or_float(1, 500).map(lambda x: round(x, 1))))
        canopy["plant_spacing"] = draw(axis(st.integers(1, 300)))
    if draw(st.booleans()):
        canopy["layout"] = ["field.json"]
    canopy["preserve_area"] = draw(axis(st.booleans()))
    suns = axis(st.fixed_dictionaries({"zenith": whole_or_float(0, 89).map(lambda x: round(x, 2)),
                                       "azimuth": whole_or_float(-360, 360)}))
    light = {"sun": draw(suns), "density": draw(axis(st.integers(1, 64))),
             "periodic": draw(axis(st.booleans()))}
    if draw(st.booleans()):
        light["heights"] = draw(st.lists(st.integers(0, 300), min_size=1, max_size=5,
                                         unique=True))
    if draw(st.booleans()):
        x0, y0 = draw(st.integers(-100, 100)), draw(st.integers(-100, 100))
        light["rect"] = [x0, y0, x0 + draw(st.integers(1, 200)), y0 + draw(st.integers(1, 200))]
    optics = st.one_of(st.just("black"), st.just({"band": "par"}),
                       st.builds(lambda r, t, d: {"band": "nir", "reflectance": r,
                                                  "transmittance": t, "depth": d},
                                 st.floats(0, 0.5), st.floats(0, 0.5), st.integers(0, 50)))
    light["optics"] = draw(axis(optics, 3))
    light["photosynthesis"] = draw(axis(st.sampled_from(
        ["none", {"model": "c4", "temperature": 30}, {"model": "wofost", "amax": 60}]), 3))
    return {"canopy": canopy, "light": light}


def expected_count(doc: dict) -> int:
    c, lt = doc["canopy"], doc["light"]
    files = 2 if c["points"] != ["a.csv"] else 1
    tilings = (len(c.get("tile", [1])) * len(c.get("row_spacing", [1]))
               * len(c.get("plant_spacing", [1]))) if "tile" in c or "layout" not in c else 0
    arrangements = tilings + ("layout" in c)
    carbon = sum(1 if ph == "none" else 0 for ph in lt["photosynthesis"])
    par = sum(1 for o in lt["optics"] if o == {"band": "par"})
    light_axes = par * len(lt["photosynthesis"]) + (len(lt["optics"]) - par) * carbon
    return (files * arrangements * len(c["level"]) * len(c["preserve_area"]) * len(lt["sun"])
            * len(lt["density"]) * len(lt["periodic"]) * light_axes)


def one_value_axes_swapped(doc: dict) -> dict:
    """The same file written otherwise: keys in reverse order, one-value axes as the value
    alone and the value alone as a one-value list."""
    out = {}
    for sec in ("light", "canopy"):
        table = {}
        for k, v in reversed(list(doc[sec].items())):
            if k in ("heights", "rect"):                       # lists, not axes
                table[k] = v
            elif isinstance(v, list) and len(v) == 1:
                table[k] = v[0]
            else:
                table[k] = v if isinstance(v, list) else [v]
        out[sec] = table
    return out


@SETTINGS
@given(doc=valid_sweep())
def test_any_valid_file_loads_and_reads_the_same_written_otherwise(folder, doc):
    file, other = folder / "any.toml", folder / "other.toml"
    file.write_text(dump(doc))
    other.write_text(dump(one_value_axes_swapped(doc)))
    count = expected_count(doc)
    if count == 0:                                   # leaf models and no PAR optics
        with pytest.raises(SweepSpecError, match=r"light.photosynthesis: a leaf model needs PAR"):
            load_spec(file, yes=True)
        return
    spec = load_spec(file, yes=True)
    assert len(spec.scenarios) == count
    keys = [s.key for s in spec.scenarios]
    assert len(set(keys)) == len(keys) and all(re.fullmatch(r"[0-9a-f]{24}", k) for k in keys)
    assert sorted(s.key for s in load_spec(other, yes=True).scenarios) == sorted(keys)


@SETTINGS
@given(doc=valid_sweep(), key=st.sampled_from(["level", "density", "periodic", "preserve_area"]),
       data=st.data())
def test_an_exclude_drops_exactly_the_scenarios_holding_its_value(folder, doc, key, data):
    if expected_count(doc) == 0:
        return
    table = doc["canopy"] if key in doc["canopy"] else doc["light"]
    value = data.draw(st.sampled_from(table[key]), label="excluded")
    file = folder / "excluded.toml"
    file.write_text(dump({**doc, "exclude": [{key: value}]}))
    if len(table[key]) == 1:
        with pytest.raises(SweepSpecError, match=r"exclude drops every scenario"):
            load_spec(file, yes=True)
        return
    spec = load_spec(file, yes=True)
    count = expected_count(doc)
    assert spec.excluded == count // len(table[key])
    assert len(spec.scenarios) == count - spec.excluded
    kept = {getattr(s, key) for s in spec.scenarios}
    assert len(kept) == len(table[key]) - 1


# ---------------------------------------------------------- the documented examples
def _keys(obj, out: set) -> set:
    if isinstance(obj, dict):
        for k, v in obj.items():
            out.add(k)
            _keys(v, out)
    elif isinstance(obj, list):
        for v in obj:
            _keys(v, out)
    return out


def test_the_modules_example_file_reads_and_shows_every_key(folder):
    """spec.py's docstring is the sweep file's documentation: it reads, and it names every
    key of the canopy, the light, a sun and an optics table."""
    text = spec_module.__doc__.split("::\n\n", 1)[1].split("\nAn inline table")[0]
    file = folder / "example.toml"
    file.write_text(textwrap.dedent(text))
    spec = load_spec(file, yes=True)
    assert spec.scenarios and spec.excluded
    shown = _keys(tomllib.loads(file.read_text()), set())
    declared = {*Canopy.model_fields, *Light.model_fields, *SunKeys.model_fields,
                *OpticsTable.model_fields, "model", "temperature", "exclude"}
    assert declared - shown == set()


def test_every_key_of_the_schema_says_what_it_is_and_its_unit():
    from maizeviz.sweep.schema import LeafModelTable

    for table in (Canopy, Light, SunKeys, OpticsTable, LeafModelTable):
        for name, field in table.model_fields.items():
            assert field.description, f"{table.__name__}.{name}"
    units = {Canopy: ("row_spacing", "plant_spacing", "cover_resolution"),
             Light: ("density", "heights", "rect"), SunKeys: ("zenith", "azimuth", "altitude")}
    for table, names in units.items():
        for name in names:
            assert re.search(r"\b(cm|cm2|deg|m)\b", table.model_fields[name].description), name


def test_the_docs_example_file_reads(folder):
    text = (ROOT / "docs" / "sweep.md").read_text()
    block = re.search(r"```toml\n(.*?)```", text, re.S).group(1)
    file = folder / "docs-example.toml"
    file.write_text(block)
    spec = load_spec(file, yes=True)
    assert spec.scenarios and spec.excluded


def test_without_pydantic_a_sweep_file_is_one_line_away(folder):
    """pydantic is the sweep extra's: without it the command line says what to install
    (``maizeviz --help`` does not need it)."""
    code = ("import sys; sys.modules['pydantic'] = None\n"
            "from maizeviz.cli import build_parser, main\n"
            "build_parser()\n"
            f"sys.exit(main(['sweep', {str(folder / 'valid.toml')!r}, '--dry-run']))")
    (folder / "valid.toml").write_text(dump(BASE))
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 1, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and re.fullmatch(r"error: reading a sweep file needs pydantic "
                                            r"\(.*\): pip install 'maizeviz\[sweep\]'",
                                            lines[0]), proc.stderr


def test_a_key_holding_a_line_break_is_named_on_one_line(folder):
    """TOML's quoted keys may hold any character; the refusal stays one line."""
    file = folder / "newline.toml"
    file.write_text('[canopy]\n"a\\nb" = 1\n')
    with pytest.raises(SweepSpecError, match=r"unknown key 'canopy.a b' \(known in canopy: "
                                             r"points, ") as info:
        load_spec(file)
    assert "\n" not in str(info.value)
