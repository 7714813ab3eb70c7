"""Malformed Phenomenal plants: a valid file's structure mutated anywhere (wrong types, missing
keys, empty lists, NaN and infinities, huge numbers, ragged arrays, deep nesting, a wrong
top level) is refused in one line naming the place, or imported exactly as before for every
leaf the mutation did not touch. Nothing is written on a refusal."""

import gzip
import json
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from maizeviz.cli import EXIT_FAIL, EXIT_OK, main
from maizeviz.io.points import read_points
from maizeviz.resources import example_phenomenal

#: What a value may be replaced by: every JSON kind, empty containers, non-finite and huge
#: numbers, ragged rows, nesting.
REPLACEMENTS = [None, True, "x", "", 0, -1, 1.5, 10**30, -(10**400), 1e308, math.nan,
                math.inf, -math.inf, [], {}, [1, 2], [[1, 2, 3], [4, 5]], [["a", "b", "c"]],
                {"polyline": 3}, [[[[[[1]]]]]]]


@pytest.fixture(scope="module")
def small_plant():
    """The bundled plant cut to its first three ranked leaves (voxels and midribs thinned)."""
    data = json.loads(gzip.open(example_phenomenal()).read())
    organs, leaves = [], 0
    for organ in data["voxel_organs"]:
        if organ["label"] in ("mature_leaf", "growing_leaf"):
            if leaves == 3:
                continue
            leaves += 1
            for seg in organ["voxel_segments"]:
                seg["voxels_position"] = seg["voxels_position"][::40]
        else:
            for seg in organ["voxel_segments"]:
                seg["voxels_position"] = seg["voxels_position"][:5]
        organs.append(organ)
    data["voxel_organs"] = organs
    return data


def _paths(node, path=()):
    """Every place in a JSON tree (keys and indices), the root first; runs of numbers inside
    coordinate lists count once per row so the tree's structure dominates the draw."""
    yield path
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, (*path, k))
    elif isinstance(node, list):
        rows = node if len(node) <= 3 else node[:2] + node[-1:]
        for i, v in enumerate(rows):
            yield from _paths(v, (*path, i if i < 2 else len(node) - 1))


def _mutated(data, path, kind, value):
    """A copy of ``data`` with the value at ``path`` replaced, deleted, wrapped in a list or
    nested 50,000 deep."""
    copy = json.loads(json.dumps(data))
    if not path:
        return value if kind == "replace" else [copy]
    parent = copy
    for k in path[:-1]:
        parent = parent[k]
    last = path[-1]
    if kind == "delete":
        del parent[last]
    elif kind == "wrap":
        parent[last] = [parent[last]]
    else:
        parent[last] = value
    return copy


def _import(tmp_path, text, name="p.json"):
    src, out = tmp_path / name, tmp_path / "out.csv"
    out.unlink(missing_ok=True)
    src.write_text(text)
    return main(["import-phenomenal", str(src), "--out", str(out)]), out


def _leaves(out):
    table = read_points(out)
    leaves = {}
    for (_plant, leaf, row, col), xyz in zip(table.ids.tolist(), table.xyz.tolist()):
        leaves.setdefault(leaf, {})[(row, col)] = xyz
    return leaves


@pytest.fixture(scope="module")
def baseline(small_plant, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("base")
    code, out = _import(tmp, json.dumps(small_plant))
    assert code == EXIT_OK
    return _leaves(out)


def _organ_rank(data, path):
    """The rank of the leaf organ a path lies in, or None."""
    if len(path) >= 2 and path[0] == "voxel_organs" and isinstance(path[1], int):
        organ = data["voxel_organs"][path[1]]
        return (organ.get("info") or {}).get("pm_leaf_number")
    return None


@settings(max_examples=250, deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_a_mutated_plant_is_refused_in_one_line_or_imported_as_before(
        tmp_path, capsys, small_plant, baseline, data):
    paths = list(_paths(small_plant))
    path = data.draw(st.sampled_from(paths), label="path")
    kind = data.draw(st.sampled_from(["replace", "delete", "wrap"] if path else
                                     ["replace", "wrap"]), label="kind")
    value = data.draw(st.sampled_from(REPLACEMENTS), label="value")
    mutated = _mutated(small_plant, path, kind, value)
    code, out = _import(tmp_path, json.dumps(mutated))
    err = capsys.readouterr().err
    assert "internal error" not in err and "Traceback" not in err, err[-400:]
    if code != EXIT_OK:
        errors = [ln for ln in err.splitlines() if ln.startswith("error")]
        assert code == EXIT_FAIL and len(errors) == 1, err
        assert not out.exists()
        return
    got = _leaves(out)
    touched = _organ_rank(small_plant, path)
    for leaf, points in got.items():
        assert all(math.isfinite(v) for xyz in points.values() for v in xyz)
        if leaf != touched and leaf in baseline:
            assert points == baseline[leaf], f"leaf {leaf} changed by a mutation elsewhere"
    for leaf in baseline:                    # an untouched leaf is never lost
        if leaf != touched and touched is not None:
            assert leaf in got, f"leaf {leaf} lost"


@pytest.mark.parametrize("text", [
    "[]", "1", '"plant"', "null", "{}", '{"voxel_organs": {}}', '{"voxel_organs": []}',
    '{"voxel_organs": [NaN]}', "[" * 50_000 + "]" * 50_000,
    '{"voxel_organs": [{"label": "mature_leaf", "info": {"pm_leaf_number": 1' + "0" * 5000
    + '}, "voxel_segments": []}]}',
])
def test_malformed_shapes_are_one_line(tmp_path, capsys, text):
    code, out = _import(tmp_path, text)
    err = capsys.readouterr().err
    errors = [ln for ln in err.splitlines() if ln.startswith(("error", "internal"))]
    assert code == EXIT_FAIL and len(errors) == 1 and errors[0].startswith("error: "), err
    assert not out.exists()
